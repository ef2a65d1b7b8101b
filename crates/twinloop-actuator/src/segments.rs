//! Which rows of a servo's logs a fit uses and which it holds out, and what is read
//! off the fitted rows' residuals: their time blocks (for the robust covariance)
//! and the position residuals' sum of squares. Shared by the one-servo fit
//! (`identify.rs`) and the group fit (`group.rs`).

use crate::log::ServoLog;
use crate::robust_covariance::BLOCK_SECONDS;
use std::ops::Range;

/// Which rows of which log.
#[derive(Debug, Clone)]
pub(crate) struct Segment {
    pub(crate) log: usize,
    pub(crate) rows: Range<usize>,
    /// Whether current residuals are used.
    pub(crate) current: bool,
}

impl Segment {
    /// Residual rows: a position per row, and a current per row where used.
    pub(crate) fn residual_rows(&self) -> usize {
        self.rows.len() * if self.current { 2 } else { 1 }
    }
}

/// The fitted rows of each of `logs` (the first `1 - holdout_fraction` of each, or
/// all of it when separate held-out logs exist) and, per log, the rows held out
/// (from the last fitted row on, so the replay starts where the fit ended).
pub(crate) fn split_logs(
    logs: &[ServoLog],
    separate_holdout: bool,
    holdout_fraction: f64,
    current: impl Fn(&ServoLog) -> bool,
) -> (Vec<Segment>, Vec<(usize, Range<usize>)>) {
    let mut segments = Vec::with_capacity(logs.len());
    let mut held = Vec::new();
    for (k, l) in logs.iter().enumerate() {
        let split = if separate_holdout {
            l.len()
        } else {
            ((l.len() as f64) * (1.0 - holdout_fraction)).round() as usize
        };
        let split = split.clamp(2, l.len());
        segments.push(Segment {
            log: k,
            rows: 0..split,
            current: current(l),
        });
        if split + 2 < l.len() {
            held.push((k, split - 1..l.len()));
        }
    }
    (segments, held)
}

/// The mean logged supply voltage over every row of `logs`.
pub(crate) fn mean_voltage(logs: &[ServoLog]) -> f64 {
    let n: usize = logs.iter().map(|l| l.voltage.len()).sum();
    logs.iter().flat_map(|l| &l.voltage).sum::<f64>() / n as f64
}

/// Appends the time block of each residual row of `segments` (in their order, a
/// current row in its position row's block) to `block`, numbering on from its last,
/// blocks of [`BLOCK_SECONDS`].
pub(crate) fn residual_blocks(logs: &[ServoLog], segments: &[Segment], block: &mut Vec<usize>) {
    for seg in segments {
        let l = &logs[seg.log];
        let t0 = l.t[seg.rows.start];
        let first = block.last().map_or(0, |b| b + 1);
        let ids: Vec<usize> = seg
            .rows
            .clone()
            .map(|r| first + ((l.t[r] - t0) / BLOCK_SECONDS) as usize)
            .collect();
        block.extend(&ids);
        if seg.current {
            block.extend(&ids);
        }
    }
}

/// The sum of squares and the count of the position residuals in `residuals`, laid
/// out segment by segment as the fits write them (a segment's positions, then its
/// currents where used).
pub(crate) fn position_sum_squares(residuals: &[f64], segments: &[Segment]) -> (f64, usize) {
    let (mut sq, mut count, mut o) = (0.0, 0usize, 0usize);
    for seg in segments {
        let q = &residuals[o..o + seg.rows.len()];
        sq += q.iter().map(|e| e * e).sum::<f64>();
        count += q.len();
        o += seg.residual_rows();
    }
    (sq, count)
}
