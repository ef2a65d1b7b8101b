//! Topics recorded at their own times put on one time base.
use crate::error::{LogError, format_ns};
use twinloop_io::Table;

/// One stream of rows with its own times: a topic, or one child frame of a TF topic.
#[derive(Debug, Default)]
pub(crate) struct Series {
    pub topic: String,
    pub columns: Vec<String>,
    pub times: Vec<i64>,
    /// One row a message: a slot for `t` (0 until merged), then `columns.len()`
    /// values; the time base's rows become the table's without a copy.
    pub rows: Vec<Vec<f64>>,
    /// Index of the first of four quaternion columns (x, y, z, w), if any.
    pub quaternion: Option<usize>,
    /// Time from the header stamp (else from the log time: stamps all zero).
    pub stamped: Option<bool>,
}

impl Series {
    pub(crate) fn new(topic: &str) -> Self {
        Series {
            topic: topic.to_string(),
            ..Series::default()
        }
    }

    /// Append one row at `stamp` (or `log_time` when this topic's stamps are unset).
    pub(crate) fn push(
        &mut self,
        stamp: i64,
        log_time: i64,
        row: impl IntoIterator<Item = f64>,
    ) -> Result<(), LogError> {
        let stamped = *self.stamped.get_or_insert(stamp != 0);
        let t = if stamped { stamp } else { log_time };
        if let Some(&prev) = self.times.last()
            && t < prev
        {
            return Err(LogError::new(format!(
                "time goes backwards (the previous message was at {} s)",
                format_ns(prev)
            ))
            .at(&self.topic, t));
        }
        self.times.push(t);
        let mut r = Vec::with_capacity(1 + self.columns.len());
        r.push(0.0);
        r.extend(row);
        self.rows.push(r);
        Ok(())
    }
}

/// At most this many resampled rows (a `dt` typo should not fill the memory).
const MAX_ROWS: f64 = 1e8;

/// One table from `series`: rows at the first series' times (`explicit`: the user
/// chose the order) or the longest series', or on a fixed `dt` grid; each other
/// series interpolated linearly at those times, quaternions normalised after.
/// `absolute`: `t` is the stamp (else the time since the first row).
pub(crate) fn merge(
    mut series: Vec<Series>,
    dt: Option<f64>,
    explicit: bool,
    absolute: bool,
) -> Result<Table, LogError> {
    if !explicit
        && let Some(base) =
            (0..series.len()).max_by_key(|&i| (series[i].times.len(), usize::MAX - i))
    {
        // The longest series gives the rows: it goes first.
        let b = series.remove(base);
        series.insert(0, b);
    }
    let mut columns = vec!["t".to_string()];
    let mut owner: Vec<&str> = vec![""];
    for s in &series {
        if s.times.is_empty() {
            return Err(LogError::new("no message on this topic").on_topic(&s.topic));
        }
        for c in &s.columns {
            if let Some(k) = columns.iter().position(|x| x == c) {
                return Err(LogError::new(format!(
                    "topics {} and {} both give column {c}: pick one with --topic",
                    owner[k], s.topic
                )));
            }
            columns.push(c.clone());
            owner.push(&s.topic);
        }
    }
    let start = series.iter().map(|s| s.times[0]).max().expect("a series");
    let end = series
        .iter()
        .map(|s| *s.times.last().expect("a row"))
        .min()
        .expect("a series");
    if start > end {
        return Err(LogError::new(format!(
            "the topics do not overlap in time (the latest first message is at {} s, the earliest last one at {} s)",
            format_ns(start),
            format_ns(end)
        )));
    }
    let (times, mut rows, rest) = match dt {
        Some(dt) => {
            let times = grid(start, end, dt)?;
            let rows = times
                .iter()
                .map(|_| Vec::with_capacity(columns.len()))
                .collect();
            (times, rows, &series[..])
        }
        None => {
            // The first series' own rows, inside every series' span, are the table's.
            let base = &mut series[0];
            let (times, rows): (Vec<i64>, Vec<Vec<f64>>) = std::mem::take(&mut base.times)
                .into_iter()
                .zip(std::mem::take(&mut base.rows))
                .filter(|(t, _)| *t >= start && *t <= end)
                .unzip();
            (times, rows, &series[1..])
        }
    };
    let Some(&t0) = times.first() else {
        return Err(LogError::new(format!(
            "no message falls inside the other topics' span ({} s to {} s)",
            format_ns(start),
            format_ns(end)
        ))
        .on_topic(&series[0].topic));
    };
    let t0 = if absolute { 0 } else { t0 };
    for (r, &t) in rows.iter_mut().zip(&times) {
        let t = (t - t0) as f64 / 1e9;
        match r.first_mut() {
            Some(slot) => *slot = t,
            None => r.push(t),
        }
    }
    for s in rest {
        interpolate_into(s, &times, &mut rows);
    }
    let mut table = Table::new(columns);
    table.rows = rows;
    Ok(table)
}

/// `start, start + dt, ..` up to `end`, in ns (each point rounded to the ns).
fn grid(start: i64, end: i64, dt: f64) -> Result<Vec<i64>, LogError> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(LogError::new(format!(
            "--dt {dt}: a positive step is needed"
        )));
    }
    let n = ((end - start) as f64 / 1e9 / dt).floor();
    if n > MAX_ROWS {
        return Err(LogError::new(format!(
            "--dt {dt} over {} s would make {n:e} rows",
            format_ns(end - start)
        )));
    }
    Ok((0..=n as i64)
        .map(|k| start + (k as f64 * dt * 1e9).round() as i64)
        .filter(|&t| t <= end)
        .collect())
}

/// Append `s`'s columns to every row, interpolated linearly at `times` (all inside
/// its span). A row at one of its own times gets its values unchanged, bit for bit.
fn interpolate_into(s: &Series, times: &[i64], rows: &mut [Vec<f64>]) {
    let mut j = 0;
    for (&t, row) in times.iter().zip(rows.iter_mut()) {
        while j + 1 < s.times.len() && s.times[j + 1] <= t {
            j += 1;
        }
        let a = &s.rows[j][1..];
        if s.times[j] == t || j + 1 == s.times.len() {
            row.extend_from_slice(a);
            continue;
        }
        let b = &s.rows[j + 1][1..];
        let f = (t - s.times[j]) as f64 / (s.times[j + 1] - s.times[j]) as f64;
        let from = row.len();
        row.extend(a.iter().zip(b).map(|(&x, &y)| x + f * (y - x)));
        if let Some(q) = s.quaternion {
            nlerp_fix(
                &mut row[from + q..from + q + 4],
                &a[q..q + 4],
                &b[q..q + 4],
                f,
            );
        }
    }
}

/// Quaternions: interpolate along the shorter arc (q and -q are one rotation) and
/// renormalise (nlerp), since a componentwise blend is not of unit norm.
fn nlerp_fix(out: &mut [f64], a: &[f64], b: &[f64], f: f64) {
    let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let sign = if dot < 0.0 { -1.0 } else { 1.0 };
    for k in 0..4 {
        out[k] = a[k] + f * (sign * b[k] - a[k]);
    }
    let n = out.iter().map(|x| x * x).sum::<f64>().sqrt();
    if n > 0.0 {
        out.iter_mut().for_each(|x| *x /= n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(topic: &str, col: &str, times: &[i64], values: &[f64]) -> Series {
        Series {
            topic: topic.into(),
            columns: vec![col.into()],
            times: times.to_vec(),
            rows: values.iter().map(|&x| vec![0.0, x]).collect(),
            quaternion: None,
            stamped: Some(true),
        }
    }

    #[test]
    fn a_second_topic_is_interpolated_at_the_first_topics_times_inside_its_span() {
        let a = series("/a", "x", &[0, 10, 20, 30], &[1.0, 2.0, 3.0, 4.0]);
        let b = series("/b", "y", &[5, 25], &[0.0, 20.0]);
        let t = merge(vec![a, b], None, true, false).unwrap();
        assert_eq!(t.columns, ["t", "x", "y"]);
        assert_eq!(t.rows, vec![vec![0.0, 2.0, 5.0], vec![10e-9, 3.0, 15.0]]);
    }

    #[test]
    fn a_fixed_step_resamples_every_topic() {
        let a = series("/a", "x", &[0, 1_000_000_000], &[0.0, 1.0]);
        let t = merge(vec![a], Some(0.25), true, false).unwrap();
        let x: Vec<f64> = t.rows.iter().map(|r| r[1]).collect();
        assert_eq!(x, [0.0, 0.25, 0.5, 0.75, 1.0]);
    }

    #[test]
    fn two_topics_giving_one_column_is_an_error_naming_both() {
        let a = series("/a", "q:j", &[0], &[0.0]);
        let b = series("/b", "q:j", &[0], &[0.0]);
        let e = merge(vec![a, b], None, true, false).unwrap_err();
        assert!(
            e.to_string().contains("/a and /b both give column q:j"),
            "{e}"
        );
    }
}
