//! The floor a robot was measured on (`adapt`'s protocol passes). How early a robot
//! tips depends on its floor as much as on its CoM: a floor (or a sole) that gives
//! under the edge of a foot lets the foot roll onto it, and a served OP3 on a floor
//! that sinks 1 mm tips 2.8 deg earlier sideways (0.5 deg fore and aft) than on one
//! that sinks 0.1 mm. Replaying the protocol on a floor other than the robot's puts
//! that difference into the bias and so into the CoM (14-21 mm on km20, 10 mm on
//! OP3). The sideways pair shows the floor best: the adapted part's height comes from
//! the fore-aft pair and its side from the left-right difference, so what the
//! left-right mean of the replay misses is the floor (and the frontal lever the exact
//! method leaves free). The replay's floor is the one on which that mean matches the
//! robot's: a bracketing search on the logarithm of the sink. (The feet's roll at the
//! onsets was tried as the floor's reading first: it is a tenth of a degree noisy
//! where the floor is firm, and put a 0.1 mm floor at 0.3 mm.)

use crate::LoopError;
use serde::Serialize;

/// The sinks the search may try, m: from a near-rigid floor to a mattress.
pub const SINK_RANGE_M: (f64, f64) = (1e-5, 1e-2);
/// Sideways mean within which the replay matches the robot, deg: a thirtieth of what a
/// decade of floor moves it on OP3.
const TOLERANCE_DEG: f64 = 0.1;
/// Replays the search may run.
const MAX_TRIES: usize = 6;
/// The step until the robot's floor is bracketed, decades of sink.
const FIRST_STEP_DECADES: f64 = 0.5;

/// One replay of the search.
#[derive(Debug, Clone, Serialize)]
pub struct FloorTry {
    /// The floor's sink under the robot's weight, m.
    pub sink_m: f64,
    /// The replay's left and right fall angles' mean, deg.
    pub sideways_deg: f64,
}

/// The floor found (the JSON's `calibration.floor`).
#[derive(Debug, Clone, Serialize)]
pub struct FloorFit {
    /// The robot's left and right fall angles' mean, deg.
    pub measured_sideways_deg: f64,
    /// The sink kept, m: the try whose sideways mean came nearest the robot's.
    pub sink_m: f64,
    pub tries: Vec<FloorTry>,
}

impl FloorFit {
    /// Whether the search stopped at an end of [`SINK_RANGE_M`] short of the robot's
    /// sideways tips: no floor in the range lets the model tip as the robot did, so the
    /// model is wrong, not the floor (the OP3 demo's part on a foot, placed on a hip
    /// link: on the firmest floor its replay still tipped 0.45 deg short sideways, and
    /// its CoM came 10 mm off with every other check passed).
    pub fn at_bound(&self) -> bool {
        let end = |r: f64| (self.sink_m / r - 1.0).abs() < 1e-6;
        let miss = self
            .tries
            .iter()
            .find(|t| t.sink_m == self.sink_m)
            .map_or(0.0, |t| (t.sideways_deg - self.measured_sideways_deg).abs());
        (end(SINK_RANGE_M.0) || end(SINK_RANGE_M.1)) && miss >= TOLERANCE_DEG
    }

    /// The `floor-found` check: failed when [`FloorFit::at_bound`].
    pub fn check(&self) -> twinloop_ident::adapt_checks::AdaptCheck {
        let passed = !self.at_bound();
        let kept = self.tries.iter().find(|t| t.sink_m == self.sink_m);
        let replay = kept.map_or(f64::NAN, |t| t.sideways_deg);
        twinloop_ident::adapt_checks::AdaptCheck {
            name: "floor-found".into(),
            passed,
            detail: if passed {
                format!(
                    "the replay tips sideways as the robot did ({replay:.2} deg, the robot \
                     {:.2}) on a floor sinking {:.3} mm",
                    self.measured_sideways_deg,
                    self.sink_m * 1e3
                )
            } else {
                format!(
                    "on the floor the search stopped at, the end of its range ({:.3} mm), the \
                     replay tips sideways at {replay:.2} deg, the robot at {:.2}: no floor \
                     explains the sideways tips with the part where it was placed (a part \
                     below the ankles?); name the link (--where) or the floor (--ground-sink)",
                    self.sink_m * 1e3,
                    self.measured_sideways_deg
                )
            },
        }
    }
}

/// The left and right angles' mean of four (forward, backward, left, right), deg.
pub fn sideways_mean(angles: &[f64; 4]) -> f64 {
    0.5 * (angles[2] + angles[3])
}

/// The floor on which `replay(sink)` (the protocol replayed on the adapted model:
/// its four angles, deg) reads the robot's sideways mean `measured_deg`, starting
/// from `start_m`, and that sink's four angles. A floor that gives more tips the
/// robot earlier: the search steps softer while the replay tips later than the robot
/// (half a decade, then as far as the last two tries' slope says, a quarter to a
/// half decade) until the robot lies between two tries, then closes
/// in by false position on log10(sink) (Illinois: a bracket end kept twice has its
/// weight halved), inside [`SINK_RANGE_M`]. The effect grows faster than the
/// logarithm (0.1 to 0.3 mm moves OP3's sideways tips 0.6 deg, 0.3 to 1 mm 2.2 deg),
/// which plain secant steps overshoot.
pub fn fit_floor(
    measured_deg: f64,
    start_m: f64,
    replay: &mut dyn FnMut(f64) -> Result<[f64; 4], LoopError>,
) -> Result<(FloorFit, [f64; 4]), LoopError> {
    let (best, tries) = search(start_m, &mut |sink| {
        let read = replay(sink)?;
        Ok((sideways_mean(&read) - measured_deg, read))
    })?;
    let fit = FloorFit {
        measured_sideways_deg: measured_deg,
        sink_m: tries[best].sink_m,
        tries: tries
            .iter()
            .map(|t| FloorTry {
                sink_m: t.sink_m,
                sideways_deg: sideways_mean(&t.read),
            })
            .collect(),
    };
    Ok((fit, tries[best].read))
}

/// One try of [`search`]: the sink (m), the replay's error and what it read.
pub struct SinkTry<T> {
    pub sink_m: f64,
    pub error: f64,
    pub read: T,
}

/// The floor on which `replay(sink)`'s error is nearest zero, by the same search as
/// [`fit_floor`]: an error above zero means the floor must give more (the replay tips
/// later, or rolls its feet less, than the robot). Each try: (sink m, error, what the
/// replay read); the index of the one kept.
pub fn search<T>(
    start_m: f64,
    replay: &mut dyn FnMut(f64) -> Result<(f64, T), LoopError>,
) -> Result<(usize, Vec<SinkTry<T>>), LoopError> {
    let (lo, hi) = (SINK_RANGE_M.0.log10(), SINK_RANGE_M.1.log10());
    let mut tries: Vec<SinkTry<T>> = Vec::with_capacity(MAX_TRIES);
    // The bracket: a firmer floor where the replay tips later (error > 0), a softer
    // one where it tips earlier, each (log10 sink, error as weighted).
    let mut firm: Option<(f64, f64)> = None;
    let mut soft: Option<(f64, f64)> = None;
    let mut kept_side = 0i8;
    let mut x = start_m.log10().clamp(lo, hi);
    loop {
        let (e, read) = replay(10f64.powf(x))?;
        tries.push(SinkTry {
            sink_m: 10f64.powf(x),
            error: e,
            read,
        });
        if e.abs() < TOLERANCE_DEG || tries.len() == MAX_TRIES {
            break;
        }
        let side = if e > 0.0 { 1 } else { -1 };
        if side > 0 {
            firm = Some((x, e));
        } else {
            soft = Some((x, e));
        }
        // Illinois: the end not replaced twice running counts for half.
        if side == kept_side {
            match side {
                1 => soft = soft.map(|(x, e)| (x, 0.5 * e)),
                _ => firm = firm.map(|(x, e)| (x, 0.5 * e)),
            }
        }
        kept_side = side;
        let next = match (firm, soft) {
            (Some((xf, ef)), Some((xs, es))) => xf - ef * (xs - xf) / (es - ef),
            // Not yet bracketed: half a decade, then the secant's reach (a quarter
            // to a half decade) in the same direction.
            _ => {
                let reach = match tries.len() {
                    1 => FIRST_STEP_DECADES,
                    n => {
                        let (x0, e0) = (tries[n - 2].sink_m.log10(), tries[n - 2].error);
                        (e * (x - x0) / (e0 - e)).abs().clamp(0.25, 0.5)
                    }
                };
                x + reach * e.signum()
            }
        }
        .clamp(lo, hi);
        if (next - x).abs() < 1e-3 {
            // At the end of the range: the floor is beyond it.
            break;
        }
        x = next;
    }
    let best = (0..tries.len())
        .min_by(|&a, &b| tries[a].error.abs().total_cmp(&tries[b].error.abs()))
        .unwrap_or(0);
    Ok((best, tries))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// OP3's sideways tips fall about 2.8 deg per decade of floor (25.7 deg at
    /// 0.1 mm, 22.9 at 1 mm, both measured over the bus); a floor in the range is
    /// found within the tolerance and a tenth of a decade.
    #[test]
    fn finds_the_floor_that_reads_the_robots_sideways_tips() {
        // 0.6 deg from 0.1 to 0.3 mm, 2.2 deg from 0.3 to 1 mm, as measured.
        let law = |s: f64| {
            let d = (s / 1e-4).log10();
            25.7 - 1.4 * d - 1.6 * d * d.abs()
        };
        for truth in [2e-5, 1e-4, 3e-4, 1e-3, 4e-3] {
            let mut calls = 0;
            let (fit, read) = fit_floor(law(truth), 1e-4, &mut |s| {
                calls += 1;
                Ok([15.0, 12.0, law(s), law(s)])
            })
            .unwrap();
            assert!(calls <= MAX_TRIES);
            assert!((sideways_mean(&read) - law(truth)).abs() < TOLERANCE_DEG);
            assert!(
                (fit.sink_m / truth).log10().abs() < 0.1,
                "{truth} -> {}",
                fit.sink_m
            );
        }
    }

    /// A robot that tips earlier than on any floor in the range gives the softest
    /// one, and the search stops there: the `floor-found` check fails; a floor inside
    /// the range passes it.
    #[test]
    fn stops_at_the_end_of_the_range() {
        let (fit, _) = fit_floor(1.0, 1e-4, &mut |s| Ok([0.0, 0.0, 20.0 - s, 20.0 - s])).unwrap();
        assert_eq!(fit.sink_m, SINK_RANGE_M.1);
        assert!(fit.at_bound() && !fit.check().passed);
        // The OP3 demo's: 27.58 / 28.20 / 28.54 deg at 0.1 / 0.032 / 0.01 mm, the
        // robot 28.99: stopped at the firmest floor.
        let law = |s: f64| 28.54 - 0.48 * (s / 1e-5).log10();
        let (fit, _) = fit_floor(28.99, 1e-4, &mut |s| Ok([0.0, 0.0, law(s), law(s)])).unwrap();
        assert_eq!(fit.sink_m, SINK_RANGE_M.0);
        assert!(!fit.check().passed, "{}", fit.check().detail);
        let (fit, _) = fit_floor(law(3e-4), 1e-4, &mut |s| Ok([0.0, 0.0, law(s), law(s)])).unwrap();
        assert!(fit.check().passed, "{}", fit.check().detail);
    }
}
