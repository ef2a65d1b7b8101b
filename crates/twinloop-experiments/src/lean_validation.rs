//! The lean validation of seed 001 (section F, Figs 10-11): a robot's lean beside a
//! simulated one, joint by joint. The seed overlaid the ankle and knee torques of the
//! real and the simulated KM robot and judged the trend by eye; here the two records
//! are put on one time axis and the difference is summed up as an RMS per joint, for
//! the torque and (when both records have them) the measured angle.
//!
//! Time alignment: both records count time from the start of the lean (the `t` of
//! [`crate::lean::run_lean`]), so they align on `t`; a record whose clock started
//! elsewhere (another tool's log) is shifted by the lag that best matches the two
//! runs' measured (else commanded) angles ([`estimate_shift`]). The robot is sampled
//! far more sparsely than the simulator (the seed's ratio was about 1:20), so the
//! denser record is interpolated linearly at the other's sample times, over the span
//! both cover.
//!
//! [`lean_comparison`] is the adaptation's check: the lean a robot did, replayed on a
//! model before and on one after adaptation, and each compared with the robot.

use crate::error::ExperimentError;
use crate::lean::{LeanConfig, LeanRecord, lean_simulator, replay_lean};
use serde::Serialize;
use std::ops::Range;
use twinloop_description::Description;
use twinloop_io::{IoError, Table};

/// A lean record from a table: `t` and `tau:<joint>` columns are needed, `goal:<joint>`
/// and `q:<joint>` are read when every recorded joint has one. Every cell must be
/// finite and `t` must increase; the error names the file, line and column.
pub fn read_lean_record(table: &Table) -> Result<LeanRecord, IoError> {
    let fail = |row: Option<usize>, column: Option<&str>, message: String| IoError {
        file: table.path.clone(),
        line: row.and_then(|r| table.line_of_row(r)),
        column: column.map(str::to_string),
        message: match row {
            Some(r) if table.line_of_row(r).is_none() => format!("data row {}: {message}", r + 1),
            _ => message,
        },
    };
    let t_col = table.column_index("t").ok_or_else(|| {
        fail(
            None,
            None,
            "no column \"t\" (time from the start of the lean, s)".into(),
        )
    })?;
    let joints: Vec<String> = table
        .columns
        .iter()
        .filter_map(|c| c.strip_prefix("tau:").map(str::to_string))
        .collect();
    if joints.is_empty() {
        return Err(fail(
            None,
            None,
            "no tau:<joint> columns (joint torques, N m)".into(),
        ));
    }
    let column_of = |prefix: &str| -> Option<Vec<usize>> {
        joints
            .iter()
            .map(|j| table.column_index(&format!("{prefix}:{j}")))
            .collect()
    };
    let tau = column_of("tau").unwrap_or_default();
    let goal = column_of("goal");
    let q = column_of("q");
    let mut used = vec![t_col];
    used.extend(&tau);
    used.extend(goal.iter().flatten());
    used.extend(q.iter().flatten());
    for (r, row) in table.rows.iter().enumerate() {
        if let Some(&c) = used.iter().find(|&&c| !row[c].is_finite()) {
            return Err(fail(
                Some(r),
                Some(&table.columns[c]),
                format!("{} is not a finite number", row[c]),
            ));
        }
        if r > 0 && row[t_col] <= table.rows[r - 1][t_col] {
            return Err(fail(
                Some(r),
                Some("t"),
                format!(
                    "time {} does not increase (previous row {})",
                    row[t_col],
                    table.rows[r - 1][t_col]
                ),
            ));
        }
    }
    if table.rows.len() < 2 {
        return Err(fail(None, None, "fewer than two data rows".into()));
    }
    let series = |cols: &[usize]| -> Vec<Vec<f64>> {
        cols.iter()
            .map(|&c| table.rows.iter().map(|r| r[c]).collect())
            .collect()
    };
    let n = joints.len();
    Ok(LeanRecord {
        t: table.rows.iter().map(|r| r[t_col]).collect(),
        tilt: table
            .column_index("tilt:pitch")
            .map(|c| table.rows.iter().map(|r| r[c]).collect())
            .unwrap_or_default(),
        goal: goal
            .map(|c| series(&c))
            .unwrap_or_else(|| vec![Vec::new(); n]),
        q: q.map(|c| series(&c)).unwrap_or_else(|| vec![Vec::new(); n]),
        tau: series(&tau),
        joints,
    })
}

/// One joint of a comparison (differences are robot minus simulation).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointComparison {
    pub joint: String,
    /// RMS of the torque difference, N m.
    pub torque_rms: f64,
    /// Mean torque difference (the static part an added mass leaves), N m.
    pub torque_mean: f64,
    /// Largest absolute torque difference, N m.
    pub torque_max_abs: f64,
    /// RMS of the robot's own torque over the same samples, N m (the scale).
    pub torque_rms_robot: f64,
    /// RMS of the measured angle difference, rad (when both records have angles).
    pub angle_rms: Option<f64>,
}

/// A lean compared with another: per joint, over the samples of the sparser record
/// that both cover.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeanComparison {
    pub joints: Vec<JointComparison>,
    /// Shift added to the simulation's time before comparing, s.
    pub shift_s: f64,
    /// Samples compared, and the time span, s.
    pub samples: usize,
    pub t_start: f64,
    pub t_end: f64,
}

/// Which of two records is the sparser (its samples are compared) and which the denser
/// (interpolated): (sparse, dense, sign of robot minus simulation).
fn sparse_dense<'a>(a: &'a LeanRecord, b: &'a LeanRecord) -> (&'a LeanRecord, &'a LeanRecord, f64) {
    let rate = |r: &LeanRecord| r.t.len() as f64 / (r.t[r.t.len() - 1] - r.t[0]).max(1e-12);
    if rate(a) <= rate(b) {
        (a, b, 1.0)
    } else {
        (b, a, -1.0)
    }
}

/// Where `x` falls in `t` (increasing, `x` within its span): the sample before it and
/// the weight of the one after; `at` is the search position, carried between calls
/// with increasing `x`.
fn bracket(t: &[f64], x: f64, at: &mut usize) -> (usize, f64) {
    while *at + 2 < t.len() && t[*at + 1] < x {
        *at += 1;
    }
    let (ta, tb) = (t[*at], t[*at + 1]);
    (*at, ((x - ta) / (tb - ta)).clamp(0.0, 1.0))
}

/// Linear interpolation of `y(t)` at `x` (see [`bracket`]).
fn interpolate(t: &[f64], y: &[f64], x: f64, at: &mut usize) -> f64 {
    let (i, w) = bracket(t, x, at);
    // This form gives the samples themselves exactly at w = 0 and 1.
    (1.0 - w) * y[i] + w * y[i + 1]
}

/// `run` with its clock moved by `shift` s (the simulation, shifted as
/// [`align_and_compare`] found), interpolated linearly at each of `times`
/// (increasing) that falls within its span, as the comparison interpolates it: the
/// samples themselves where the times coincide. Returns the range of `times` kept
/// and the record at them (`goal`, `q`, `tilt` empty where `run`'s are).
pub fn resample_at(run: &LeanRecord, shift: f64, times: &[f64]) -> (Range<usize>, LeanRecord) {
    let t: Vec<f64> = run.t.iter().map(|t| t + shift).collect();
    let mut out = LeanRecord::new(run.joints.clone());
    let (lo, hi) = match (t.first(), t.last()) {
        (Some(&lo), Some(&hi)) if t.len() >= 2 => (lo, hi),
        _ => return (0..0, out),
    };
    let start = times.partition_point(|&x| x < lo);
    let end = times.partition_point(|&x| x <= hi).max(start);
    let kept = &times[start..end];
    let at = |y: &[f64]| -> Vec<f64> {
        let mut cursor = 0;
        if y.is_empty() {
            return Vec::new();
        }
        kept.iter()
            .map(|&x| interpolate(&t, y, x, &mut cursor))
            .collect()
    };
    out.t = kept.to_vec();
    out.tilt = at(&run.tilt);
    out.goal = run.goal.iter().map(|y| at(y)).collect();
    out.q = run.q.iter().map(|y| at(y)).collect();
    out.tau = run.tau.iter().map(|y| at(y)).collect();
    (start..end, out)
}

/// Compare a robot's lean with a simulated one (seed 001, Figs 10-11): align on `t`,
/// interpolate the denser record at the sparser one's samples, and sum up the torque
/// and angle differences per joint. The two must record the same joints; `robot_name`
/// and `sim_name` name them in the errors.
pub fn compare_leans(
    robot: &LeanRecord,
    sim: &LeanRecord,
    robot_name: &str,
    sim_name: &str,
) -> Result<LeanComparison, IoError> {
    let mut a = robot.joints.clone();
    let mut b = sim.joints.clone();
    a.sort();
    b.sort();
    if a != b {
        let only = |x: &[String], y: &[String]| -> String {
            let v: Vec<&str> = x
                .iter()
                .filter(|j| !y.contains(j))
                .map(|s| s.as_str())
                .collect();
            if v.is_empty() {
                "none".into()
            } else {
                v.join(", ")
            }
        };
        return Err(IoError::new(format!(
            "the two runs record different joints: only in {robot_name}: {}; only in {sim_name}: {}",
            only(&a, &b),
            only(&b, &a)
        )));
    }
    if robot.t.len() < 2 || sim.t.len() < 2 {
        return Err(IoError::new("each run needs two rows or more"));
    }
    let (sparse, dense, sign) = sparse_dense(robot, sim);
    let (lo, hi) = (
        sparse.t[0].max(dense.t[0]),
        sparse.t[sparse.t.len() - 1].min(dense.t[dense.t.len() - 1]),
    );
    let idx: Vec<usize> = (0..sparse.t.len())
        .filter(|&i| sparse.t[i] >= lo && sparse.t[i] <= hi)
        .collect();
    if idx.is_empty() {
        return Err(IoError::new(format!(
            "the runs do not overlap in time ({robot_name}: {} to {} s, {sim_name}: {} to {} s)",
            robot.t[0],
            robot.t[robot.t.len() - 1],
            sim.t[0],
            sim.t[sim.t.len() - 1]
        )));
    }
    let mut joints = Vec::with_capacity(robot.joints.len());
    for (k, name) in robot.joints.iter().enumerate() {
        let ks = sparse.joints.iter().position(|j| j == name).unwrap_or(k);
        let kd = dense.joints.iter().position(|j| j == name).unwrap_or(k);
        let robot_k = robot.joints.iter().position(|j| j == name).unwrap_or(k);
        let diffs = |ys: &[f64], yd: &[f64]| -> Vec<f64> {
            let mut at = 0;
            idx.iter()
                .map(|&i| sign * (ys[i] - interpolate(&dense.t, yd, sparse.t[i], &mut at)))
                .collect()
        };
        let d = diffs(&sparse.tau[ks], &dense.tau[kd]);
        let angle_rms = (!sparse.q[ks].is_empty() && !dense.q[kd].is_empty())
            .then(|| rms(&diffs(&sparse.q[ks], &dense.q[kd])));
        let own: Vec<f64> = if std::ptr::eq(sparse, robot) {
            idx.iter().map(|&i| robot.tau[robot_k][i]).collect()
        } else {
            let mut at = 0;
            idx.iter()
                .map(|&i| interpolate(&robot.t, &robot.tau[robot_k], sparse.t[i], &mut at))
                .collect()
        };
        joints.push(JointComparison {
            joint: name.clone(),
            torque_rms: rms(&d),
            torque_mean: d.iter().sum::<f64>() / d.len() as f64,
            torque_max_abs: d.iter().fold(0.0, |m, x| m.max(x.abs())),
            torque_rms_robot: rms(&own),
            angle_rms,
        });
    }
    Ok(LeanComparison {
        joints,
        shift_s: 0.0,
        samples: idx.len(),
        t_start: sparse.t[idx[0]],
        t_end: sparse.t[idx[idx.len() - 1]],
    })
}

/// The shift (s, added to the simulation's time) within `max_shift_s` that best
/// matches the two runs' angles: the measured ones when both runs have them, else the
/// commanded ones; `None` when they share no angle series. (A row's goal is the one in
/// force when the row was read, which over a bus was sent a cycle or two earlier than
/// in the simulator: aligning the goals would shift the runs by that latency.) A grid search at the denser run's sample period: the error is a smooth
/// function of the shift only within a sample.
pub fn estimate_shift(robot: &LeanRecord, sim: &LeanRecord, max_shift_s: f64) -> Option<f64> {
    let (a, b) = match (angles(robot, robot, false), angles(sim, robot, false)) {
        (Some(a), Some(b)) => (a, b),
        _ => (angles(robot, robot, true)?, angles(sim, robot, true)?),
    };
    let step = (sim.t[sim.t.len() - 1] - sim.t[0]) / (sim.t.len() - 1) as f64;
    let steps = (max_shift_s / step).floor() as i64;
    let cost = |shift: f64| -> f64 {
        let (mut sum, mut n, mut at) = (0.0, 0usize, 0usize);
        for (i, &t) in robot.t.iter().enumerate() {
            let x = t - shift;
            if x < sim.t[0] || x > sim.t[sim.t.len() - 1] {
                continue;
            }
            let (j, w) = bracket(&sim.t, x, &mut at);
            for (ya, yb) in a.iter().zip(&b) {
                let d = ya[i] - ((1.0 - w) * yb[j] + w * yb[j + 1]);
                sum += d * d;
            }
            n += 1;
        }
        // Half the robot's run at least must overlap, or a far shift wins on little.
        if 2 * n < robot.t.len() {
            f64::INFINITY
        } else {
            sum / n as f64
        }
    };
    (-steps..=steps)
        .map(|k| k as f64 * step)
        .map(|s| (s, cost(s)))
        .filter(|(_, c)| c.is_finite())
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map(|(s, _)| s)
}

/// The commanded (`goal`) or measured angle series of `r` for the joints of `of`, if
/// it has them all.
fn angles<'a>(r: &'a LeanRecord, of: &LeanRecord, goal: bool) -> Option<Vec<&'a [f64]>> {
    of.joints
        .iter()
        .map(|j| {
            let k = r.joints.iter().position(|x| x == j)?;
            let s = if goal { &r.goal[k] } else { &r.q[k] };
            (!s.is_empty()).then_some(s.as_slice())
        })
        .collect()
}

/// [`compare_leans`] after shifting the simulation's time by [`estimate_shift`] (within
/// `max_shift_s`; no shift when the runs share no angles or `max_shift_s` is 0).
pub fn align_and_compare(
    robot: &LeanRecord,
    sim: &LeanRecord,
    robot_name: &str,
    sim_name: &str,
    max_shift_s: f64,
) -> Result<LeanComparison, IoError> {
    // The joint sets are checked (and named) first.
    compare_leans(robot, sim, robot_name, sim_name)?;
    let shift = if max_shift_s > 0.0 {
        estimate_shift(robot, sim, max_shift_s).unwrap_or(0.0)
    } else {
        0.0
    };
    let mut shifted = sim.clone();
    shifted.t.iter_mut().for_each(|t| *t += shift);
    let mut c = compare_leans(robot, &shifted, robot_name, sim_name)?;
    c.shift_s = shift;
    check_coverage(&c, &[(robot, robot_name, 0.0), (sim, sim_name, shift)])?;
    Ok(c)
}

/// The least part of each run's span the comparison must cover.
pub const MIN_COVERAGE: f64 = 0.8;

/// A run cut short (a copy interrupted, a recording stopped early) overlaps the other
/// only where it has data, and would compare as a match over that part alone: the
/// compared span must cover [`MIN_COVERAGE`] of each run (issue 29, class 3).
fn check_coverage(c: &LeanComparison, runs: &[(&LeanRecord, &str, f64)]) -> Result<(), IoError> {
    let covered = c.t_end - c.t_start;
    for (r, name, shift) in runs {
        let (a, b) = (r.t[0] + shift, r.t[r.t.len() - 1] + shift);
        if covered < MIN_COVERAGE * (b - a) {
            let spans: Vec<String> = runs
                .iter()
                .map(|(r, n, _)| format!("{n}: {} to {} s", r.t[0], r.t[r.t.len() - 1]))
                .collect();
            // The place at fault is the run that ends early: the shortest.
            let span = |r: &LeanRecord| r.t[r.t.len() - 1] - r.t[0];
            let short = runs
                .iter()
                .min_by(|x, y| span(x.0).total_cmp(&span(y.0)))
                .map_or(*name, |x| x.1);
            return Err(IoError::new(format!(
                "cut short: the runs overlap over {covered:.3} s, {:.0} % of {name}'s {:.3} s \
                 ({}); compare runs of the whole lean",
                100.0 * covered / (b - a),
                b - a,
                spans.join(", ")
            ))
            .in_file(short.to_string()));
        }
    }
    Ok(())
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// How a recorded lean is simulated on a model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeanSimOptions {
    /// Standing still before the replay, s.
    pub settle_s: f64,
    /// Recording period of the simulated run, s.
    pub period_s: f64,
    /// Servo compliance slope (RX units) of the simulated servos; `None` keeps the
    /// factory settings (see [`lean_simulator`]). Use what the robot's servos had.
    pub compliance_slope: Option<f64>,
}

impl Default for LeanSimOptions {
    fn default() -> Self {
        LeanSimOptions {
            settle_s: 1.0,
            period_s: 0.005,
            compliance_slope: None,
        }
    }
}

/// The lean before and after adaptation, each compared with the robot's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeanAdaptationCheck {
    pub before: LeanComparison,
    pub after: LeanComparison,
    /// What was compared: the robot's record and its replay on each model (before,
    /// after), on their own clocks (each comparison's `shift_s` aligns them); for a
    /// caller that shows the torques themselves (`adapt --mcap`).
    #[serde(skip)]
    pub robot: LeanRecord,
    #[serde(skip)]
    pub replays: [LeanRecord; 2],
}

/// Simulate the lean a robot did (`robot_run`: a table of `twinloop experiment lean`,
/// whose `goal:<joint>` columns are replayed) on `model_before` and `model_after`, each
/// on its servos in the simulator as [`lean_simulator`] builds it, and compare both
/// with the robot (seed 001's validation, before and after seed 000's adaptation).
pub fn lean_comparison(
    robot_run: &Table,
    model_before: &Description,
    model_after: &Description,
    options: &LeanSimOptions,
) -> Result<LeanAdaptationCheck, ExperimentError> {
    let robot = read_lean_record(robot_run).map_err(|e| ExperimentError(e.to_string()))?;
    let run_name = robot_run
        .path
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "the robot's run".into());
    let simulate = |d: &Description| -> Result<(LeanComparison, LeanRecord), ExperimentError> {
        let sim_run = simulate_replay(d, &robot, options)?;
        let c = compare_leans(
            &robot,
            &sim_run,
            &run_name,
            &format!("model \"{}\"", d.name),
        )
        .map_err(|e| ExperimentError(e.to_string()))?;
        Ok((c, sim_run))
    };
    let (before, before_run) = simulate(model_before)?;
    let (after, after_run) = simulate(model_after)?;
    Ok(LeanAdaptationCheck {
        before,
        after,
        robot,
        replays: [before_run, after_run],
    })
}

/// The lean of `robot` replayed on `description` in the simulator.
pub fn simulate_replay(
    description: &Description,
    robot: &LeanRecord,
    options: &LeanSimOptions,
) -> Result<LeanRecord, ExperimentError> {
    let (mut sim, standing) = lean_simulator(description, options.compliance_slope)?;
    let names = sim.model.joint_names.clone();
    let recorded = robot
        .joints
        .iter()
        .map(|j| {
            names.iter().position(|n| n == j).ok_or_else(|| {
                ExperimentError(format!(
                    "model \"{}\": no joint \"{j}\" (the robot's run records it)",
                    description.name
                ))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut cfg = LeanConfig::new([recorded[0], recorded[0]], [1.0, 1.0], 1.0);
    cfg.recorded = recorded;
    cfg.recorded_names = robot.joints.clone();
    cfg.settle_s = options.settle_s;
    cfg.period_s = options.period_s;
    Ok(replay_lean(&mut sim, &standing, robot, &cfg)?)
}
