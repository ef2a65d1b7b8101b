//! Validation by inverse dynamics (seed 004, section 3.4): for a recorded motion
//! (configuration over time, velocities and accelerations by zero-phase Butterworth
//! smoothing and central differences) and the force plate's ground reaction, the 6-D
//! wrench at the floating base that the model cannot explain:
//!
//! ```text
//! residual = RNEA(q, v, a)[base] - ground reaction (both about the base origin)
//! ```
//!
//! A perfect model leaves only the differentiation error; a model 10 kg too light
//! leaves about 98 N of vertical force (seed 004, Table 1: Fz 103 N -> 2.7 N).
//!
//! Also the squat-like validation motion of the seed's Fig. 4: the pelvis goes down
//! and up while the arms swing forward and the CoM stays over the feet, with the
//! plate readings the truth model gives.

use crate::anatomy::{Anatomy, link_placement};
use crate::error::IdentError;
use crate::filter::butter_lowpass;
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use std::path::Path;
use twinloop_description::Description;
use twinloop_dynamics::{Data, Model, rnea};
use twinloop_gait::ik::{Ik, Task};
use twinloop_io::{Quantity, StateColumns, Table};
use twinloop_spatial::{Force, Se3, quaternion_xyzw_to_matrix};

/// One force-plate sample: the ground reaction on the robot, world frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlateSample {
    /// Force the ground applies to the robot, N (`grf.fx .. grf.fz`).
    pub force: [f64; 3],
    /// Centre of pressure on the ground plane z = 0, m (`cop.x`, `cop.y`).
    pub cop: [f64; 2],
    /// Free moment about the vertical through the CoP, N m (`grf.tz`).
    pub free_moment: f64,
}

impl PlateSample {
    /// The plate wrench from a total contact wrench about the world origin (world axes).
    pub fn from_wrench(f: &Vector3<f64>, n: &Vector3<f64>) -> PlateSample {
        // n = c x f + (0, 0, tz) with c = (x, y, 0): solve for x, y from nx, ny.
        let x = -n.y / f.z;
        let y = n.x / f.z;
        let tz = n.z - (x * f.y - y * f.x);
        PlateSample {
            force: [f.x, f.y, f.z],
            cop: [x, y],
            free_moment: tz,
        }
    }

    /// The wrench about the world origin, world axes.
    pub fn wrench(&self) -> Force {
        let f = Vector3::new(self.force[0], self.force[1], self.force[2]);
        let c = Vector3::new(self.cop[0], self.cop[1], 0.0);
        Force::new(f, c.cross(&f) + Vector3::new(0.0, 0.0, self.free_moment))
    }
}

/// Column names of the plate readings.
pub const PLATE_COLUMNS: [&str; 6] = ["grf.fx", "grf.fy", "grf.fz", "cop.x", "cop.y", "grf.tz"];

/// A recorded motion: time, configuration per frame and, if measured, the plate.
#[derive(Debug, Clone, Default)]
pub struct Motion {
    pub t: Vec<f64>,
    pub q: Vec<Vec<f64>>,
    pub plate: Option<Vec<PlateSample>>,
}

/// Read the plate columns of a table (all six, or none: `None`).
pub fn read_plate(table: &Table) -> Result<Option<Vec<PlateSample>>, IdentError> {
    let idx: Vec<Option<usize>> = PLATE_COLUMNS
        .iter()
        .map(|c| table.column_index(c))
        .collect();
    if idx.iter().all(Option::is_none) {
        return Ok(None);
    }
    let mut cols = [0usize; 6];
    for (k, i) in idx.iter().enumerate() {
        cols[k] = i.ok_or_else(|| {
            IdentError::new(
                "the force-plate columns come as a set: grf.fx grf.fy grf.fz cop.x cop.y grf.tz",
            )
            .field(PLATE_COLUMNS[k])
        })?;
    }
    let mut out = Vec::with_capacity(table.rows.len());
    for (r, row) in table.rows.iter().enumerate() {
        for (k, &c) in cols.iter().enumerate() {
            if !row[c].is_finite() {
                return Err(
                    IdentError::new(format!("{} is not a finite number", row[c]))
                        .at_row(r)
                        .field(PLATE_COLUMNS[k]),
                );
            }
        }
        out.push(PlateSample {
            force: [row[cols[0]], row[cols[1]], row[cols[2]]],
            cop: [row[cols[3]], row[cols[4]]],
            free_moment: row[cols[5]],
        });
    }
    Ok(Some(out))
}

/// Plate readings from their own file are paired with the motion frame by frame: when
/// the file has a `t` column, its times must be the motion's (to a thousandth of a
/// step), so a plate out of step with the motion (its clock started 0.5 s late) is an
/// error naming the row, never a residual computed on mismatched frames. A file
/// without `t` pairs by row (the row counts are checked by [`residual_wrench`]).
pub fn check_paired_times(motion_t: &[f64], table: &Table) -> Result<(), IdentError> {
    let Some(tc) = table.column_index("t") else {
        return Ok(());
    };
    if table.rows.len() != motion_t.len() {
        return Err(IdentError::new(format!(
            "{} plate rows for {} motion frames: the plate is read frame by frame",
            table.rows.len(),
            motion_t.len()
        )));
    }
    let step = match motion_t {
        [a, .., b] => (b - a) / (motion_t.len() - 1) as f64,
        _ => 1.0,
    };
    for (r, (row, &tm)) in table.rows.iter().zip(motion_t).enumerate() {
        let tp = row[tc];
        if (tp - tm).abs() > 1e-3 * step {
            return Err(IdentError::new(format!(
                "time {tp} s, but the motion's frame {} is at {tm} s ({:+} s out of step): \
                 the plate's rows must be the motion's frames",
                r + 1,
                tp - tm
            ))
            .at_row(r)
            .field("t"));
        }
    }
    Ok(())
}

/// Read a motion: `t` and the `q:` columns (and the plate columns if present).
/// Errors name the file, row and column: a missing `t`, time not increasing, a
/// non-finite cell, a base quaternion that is not unit.
pub fn read_motion(path: &Path, model: &Model) -> Result<Motion, IdentError> {
    let table = Table::read(path)?;
    parse_motion(&table, model).map_err(|e| if e.file.is_none() { e.in_file(path) } else { e })
}

/// [`read_motion`] on a table already read.
pub fn parse_motion(table: &Table, model: &Model) -> Result<Motion, IdentError> {
    let tc = table
        .column_index("t")
        .ok_or_else(|| IdentError::new("a time column is needed (seconds)").field("t"))?;
    let qc = StateColumns::find(table, Quantity::Q, &model.q_names())?;
    let mut m = Motion::default();
    for (r, row) in table.rows.iter().enumerate() {
        let t = row[tc];
        if !t.is_finite() {
            return Err(IdentError::new(format!("{t} is not a time"))
                .at_row(r)
                .field("t"));
        }
        if let Some(&prev) = m.t.last()
            && t <= prev
        {
            return Err(IdentError::new(format!(
                "time {t} s does not increase (previous row: {prev} s)"
            ))
            .at_row(r)
            .field("t"));
        }
        let mut q = vec![0.0; model.nq];
        qc.gather(row, &mut q);
        for (k, x) in q.iter().enumerate() {
            if !x.is_finite() {
                return Err(IdentError::new(format!("{x} is not a finite number"))
                    .at_row(r)
                    .field(format!("q:{}", model.q_names()[k])));
            }
        }
        if model.is_floating() {
            let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
            if (n - 1.0).abs() > 1e-6 {
                return Err(
                    IdentError::new(format!("the base quaternion has norm {n}, not 1"))
                        .at_row(r)
                        .field("q:base.qw"),
                );
            }
        }
        m.t.push(t);
        m.q.push(q);
    }
    m.plate = read_plate(table)?;
    Ok(m)
}

/// Smoothing settings (seed 004: bi-directional Butterworth, 10 Hz).
#[derive(Debug, Clone, Copy)]
pub struct Smoothing {
    pub cutoff_hz: f64,
    pub order: usize,
}

impl Default for Smoothing {
    fn default() -> Self {
        Smoothing {
            cutoff_hz: 10.0,
            order: 4,
        }
    }
}

/// Configurations, velocities and accelerations, one vector per frame.
pub type States = (Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<Vec<f64>>);

/// Smoothed configuration, velocities and accelerations: every configuration
/// coordinate (joints, base position, base quaternion made sign-continuous) filtered
/// by a zero-phase Butterworth low-pass, the quaternion renormalised, then central
/// differences (one-sided at the ends). Base velocities are Pinocchio's: linear
/// velocity of the base origin and angular velocity, both in the base frame; the
/// accelerations are their time derivatives. The sampling must be (nearly) uniform.
pub fn smooth_differentiate(
    model: &Model,
    t: &[f64],
    q: &[Vec<f64>],
    smoothing: Option<Smoothing>,
) -> Result<States, IdentError> {
    let n = t.len();
    if n < 3 {
        return Err(IdentError::new(format!(
            "{n} frames: at least 3 are needed to differentiate"
        )));
    }
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    for k in 1..n {
        let d = t[k] - t[k - 1];
        if (d - dt).abs() > 0.01 * dt {
            return Err(IdentError::new(format!(
                "the sampling is not uniform: step {d} s here, {dt} s on average"
            ))
            .at_row(k)
            .field("t"));
        }
    }
    let mut qs: Vec<Vec<f64>> = q.to_vec();
    if model.is_floating() {
        // Same hemisphere frame to frame, so the components are smooth.
        for k in 1..n {
            let dot: f64 = (3..7).map(|i| qs[k][i] * qs[k - 1][i]).sum();
            if dot < 0.0 {
                for x in &mut qs[k][3..7] {
                    *x = -*x;
                }
            }
        }
    }
    if let Some(s) = smoothing {
        let f = butter_lowpass(s.order, s.cutoff_hz, 1.0 / dt)?;
        let mut col = vec![0.0; n];
        for i in 0..model.nq {
            for (c, qk) in col.iter_mut().zip(&qs) {
                *c = qk[i];
            }
            let y = f.filtfilt(&col).map_err(|e| e.field("t"))?;
            for (qk, yk) in qs.iter_mut().zip(&y) {
                qk[i] = *yk;
            }
        }
        if model.is_floating() {
            for qk in qs.iter_mut() {
                let nn = (3..7).map(|i| qk[i] * qk[i]).sum::<f64>().sqrt();
                for x in &mut qk[3..7] {
                    *x /= nn;
                }
            }
        }
    }
    let nv = model.nv;
    let (qo, vo) = (model.q_offset, model.v_offset);
    let rot = |qk: &[f64]| quaternion_xyzw_to_matrix(qk[3], qk[4], qk[5], qk[6]);
    let mut v = vec![vec![0.0; nv]; n];
    for k in 0..n {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let h = t[b] - t[a];
        for i in 0..model.nbodies {
            v[k][vo + i] = (qs[b][qo + i] - qs[a][qo + i]) / h;
        }
        if model.is_floating() {
            let r = rot(&qs[k]);
            let pdot = Vector3::new(
                qs[b][0] - qs[a][0],
                qs[b][1] - qs[a][1],
                qs[b][2] - qs[a][2],
            ) / h;
            let lin = r.tr_mul(&pdot);
            // R^T R' = [w]x (body-frame angular velocity), from the central difference.
            let rdot: Matrix3<f64> = (rot(&qs[b]) - rot(&qs[a])) / h;
            let s = r.tr_mul(&rdot);
            let w = Vector3::new(
                0.5 * (s[(2, 1)] - s[(1, 2)]),
                0.5 * (s[(0, 2)] - s[(2, 0)]),
                0.5 * (s[(1, 0)] - s[(0, 1)]),
            );
            v[k][0..3].copy_from_slice(lin.as_slice());
            v[k][3..6].copy_from_slice(w.as_slice());
        }
    }
    let mut a = vec![vec![0.0; nv]; n];
    for (k, ak) in a.iter_mut().enumerate() {
        let (lo, hi) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let h = t[hi] - t[lo];
        for (i, x) in ak.iter_mut().enumerate() {
            *x = (v[hi][i] - v[lo][i]) / h;
        }
    }
    Ok((qs, v, a))
}

/// Mean and standard deviation of the absolute value of each component (seed 004,
/// Table 1: "Avg. [std] of the absolute values").
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct ResidualSummary {
    /// |Fx| |Fy| |Fz| (N), |Tx| |Ty| |Tz| (N m).
    pub mean_abs: [f64; 6],
    pub std_abs: [f64; 6],
}

/// The residual base wrench over time.
#[derive(Debug, Clone, Serialize)]
pub struct ResidualSeries {
    pub t: Vec<f64>,
    /// Fx Fy Fz Tx Ty Tz per frame: world-aligned axes, about the base origin.
    pub wrench: Vec<[f64; 6]>,
    /// What the plate would read were the model right: inverse dynamics' base
    /// wrench (the ground reaction the motion needs) as plate readings.
    #[serde(skip)]
    pub predicted: Vec<PlateSample>,
    pub summary: ResidualSummary,
}

pub fn summarize(w: &[[f64; 6]]) -> ResidualSummary {
    let mut s = ResidualSummary::default();
    let n = w.len().max(1) as f64;
    for k in 0..6 {
        let mean = w.iter().map(|x| x[k].abs()).sum::<f64>() / n;
        let var = w.iter().map(|x| (x[k].abs() - mean).powi(2)).sum::<f64>() / n;
        s.mean_abs[k] = mean;
        s.std_abs[k] = var.sqrt();
    }
    s
}

/// The residual 6-D base wrench of seed 004, section 3.4, for a motion with plate
/// readings: inverse dynamics' base wrench minus the ground reaction, both about the
/// base origin, reported in world-aligned axes.
pub fn residual_wrench(
    model: &Model,
    motion: &Motion,
    smoothing: Option<Smoothing>,
) -> Result<ResidualSeries, IdentError> {
    if !model.is_floating() {
        return Err(IdentError::new(
            "the base residual needs a floating-base model",
        ));
    }
    let plate = motion.plate.as_ref().ok_or_else(|| {
        IdentError::new(
            "no force-plate columns (grf.fx grf.fy grf.fz cop.x cop.y grf.tz): the residual is the \
             base wrench minus the measured ground reaction",
        )
        .field("grf.fz")
    })?;
    if plate.len() != motion.t.len() {
        return Err(IdentError::new(format!(
            "{} plate rows for {} motion frames",
            plate.len(),
            motion.t.len()
        ))
        .option("plate"));
    }
    let (qs, v, a) = smooth_differentiate(model, &motion.t, &motion.q, smoothing)?;
    let mut data = Data::new(model);
    let mut wrench = Vec::with_capacity(qs.len());
    let mut predicted = Vec::with_capacity(qs.len());
    for k in 0..qs.len() {
        let tau = rnea(model, &mut data, &qs[k], &v[k], &a[k]);
        let need = Force::from_slice(&tau.as_slice()[0..6]);
        let base = data.base_placement;
        let world = base.act_force(&need);
        predicted.push(PlateSample::from_wrench(&world.f, &world.n));
        let ground = base.act_inv_force(&plate[k].wrench());
        let res = need - ground;
        let f = base.rotation * res.f;
        let n = base.rotation * res.n;
        wrench.push([f.x, f.y, f.z, n.x, n.y, n.z]);
    }
    Ok(ResidualSeries {
        t: motion.t.clone(),
        summary: summarize(&wrench),
        wrench,
        predicted,
    })
}

/// Settings of the squat-like validation motion.
#[derive(Debug, Clone)]
pub struct SquatOptions {
    /// Rest before and after the motion, s.
    pub rest: f64,
    /// Duration of the down-and-up motion, s (seed 004: 5 s).
    pub duration: f64,
    /// Sampling rate of the recording, Hz (seed 004's motion capture: 150 Hz).
    pub rate: f64,
    /// How far the pelvis goes down, m (`None`: 12 % of its standing height).
    pub depth: Option<f64>,
    /// How far the arms swing forward at the bottom, as a fraction of their range.
    pub arm_swing: f64,
    pub feet: Option<(String, String)>,
}

impl Default for SquatOptions {
    fn default() -> Self {
        SquatOptions {
            rest: 1.0,
            duration: 5.0,
            rate: 150.0,
            depth: None,
            arm_swing: 0.35,
            feet: None,
        }
    }
}

/// Where the squat stands: the neutral stance on the ground and the heights of the
/// pelvis.
struct SquatStance {
    /// The neutral configuration with the soles on z = 0.
    q0: Vec<f64>,
    /// Sole centres (left, right) on the ground, and their middle.
    soles: [Vector3<f64>; 2],
    mid: Vector3<f64>,
    /// Standing pelvis height, and how far the squat lowers it, m.
    stand: f64,
    depth: f64,
}

/// The neutral stance's soles (the base at the origin) put on z = 0, the pelvis height
/// that stands with the knees a little bent, and the squat's depth (the option, or
/// 12 % of the straight-legged height).
fn squat_stance(
    model: &Model,
    anatomy: &Anatomy,
    data: &mut Data,
    options: &SquatOptions,
) -> SquatStance {
    let mut q0 = model.neutral_configuration();
    twinloop_dynamics::forward_kinematics(model, data, &q0);
    let (lf, rf) = (&anatomy.left_foot, &anatomy.right_foot);
    let sole = |f: &crate::anatomy::Foot, d: &Data| {
        link_placement(model, d, f.link).act_point(&f.sole_center)
    };
    let (sl, sr) = (sole(lf, data), sole(rf, data));
    let ground = sl.z.min(sr.z);
    q0[2] = -ground;
    let depth = options.depth.unwrap_or(0.12 * q0[2]);
    // Stand with the knees a little bent (4 % lower than straight legs): straight
    // knees are a singular point of the leg's kinematics.
    let stand = 0.96 * q0[2];
    let sl = Vector3::new(sl.x, sl.y, 0.0);
    let sr = Vector3::new(sr.x, sr.y, 0.0);
    let mid = (sl + sr) * 0.5;
    SquatStance {
        q0,
        soles: [sl, sr],
        mid,
        stand,
        depth,
    }
}

/// The joint posture the squat projects from: joints at zero, or 5 % inside their
/// range where zero is a limit; knees slightly bent (a straight knee is a singular
/// start for IK).
fn squat_reference_posture(model: &Model, anatomy: &Anatomy) -> Vec<f64> {
    let mut reference: Vec<f64> = (0..model.nbodies)
        .map(|i| {
            let (lo, hi) = (model.lower_limits[i], model.upper_limits[i]);
            if lo.is_finite() && hi.is_finite() && lo < hi {
                0.0f64.clamp(lo + 0.05 * (hi - lo), hi - 0.05 * (hi - lo))
            } else {
                0.0
            }
        })
        .collect();
    for leg in [&anatomy.left_leg, &anatomy.right_leg] {
        if let Some((k, sign)) = crate::plate::knee_of(model, leg) {
            let ext = if sign > 0.0 {
                model.upper_limits[k]
            } else {
                model.lower_limits[k]
            };
            reference[k] = 0.1 * ext;
        }
    }
    reference
}

/// Each arm's first joint that swings the hand forward, with the limit in that
/// direction.
fn arm_swings(model: &Model, anatomy: &Anatomy, data: &mut Data) -> Vec<(usize, f64)> {
    let mut swings: Vec<(usize, f64)> = Vec::new();
    for arm in [&anatomy.left_arm, &anatomy.right_arm] {
        let Some(&first) = arm.first() else { continue };
        let tip = *arm.last().unwrap_or(&first);
        let mut q = model.neutral_configuration();
        let x_of = |q: &[f64], d: &mut Data| {
            twinloop_dynamics::forward_kinematics(model, d, q);
            d.o_m_i[tip].translation.x
        };
        q[model.q_offset + first] = 0.3;
        let plus = x_of(&q, data);
        q[model.q_offset + first] = -0.3;
        let minus = x_of(&q, data);
        let (lo, hi) = (model.lower_limits[first], model.upper_limits[first]);
        let ext = if plus > minus { hi } else { lo };
        if ext.is_finite() {
            swings.push((first, ext));
        }
    }
    swings
}

/// A foot flat (its down axis down, its forward axis without sideways yaw) with its
/// sole centre at `target`.
fn flat_foot_tasks(f: &crate::anatomy::Foot, target: Vector3<f64>) -> Vec<Task> {
    vec![
        Task::Axis {
            frame: f.frame,
            axis: f.down,
            target: Vector3::new(0.0, 0.0, -1.0),
            weight: Vector3::new(1.0, 1.0, 0.0),
        },
        Task::Axis {
            frame: f.frame,
            axis: f.forward,
            target: Vector3::new(1.0, 0.0, 0.0),
            weight: Vector3::new(0.0, 1.0, 0.0),
        },
        Task::Point {
            frame: f.frame,
            point: f.sole_center,
            target,
            weight: Vector3::repeat(1.0),
        },
    ]
}

/// The squat's IK and the index of its pelvis-height task: each frame is the
/// least-norm projection of a smooth reference configuration onto the constraints
/// (feet flat where they stand, CoM over their middle, pelvis at its height, not
/// pitching). Arms and torso follow their prescribed motion; base and legs keep the
/// balance.
fn squat_ik(
    model: &Model,
    anatomy: &Anatomy,
    data: &mut Data,
    stance: &SquatStance,
) -> Result<(Ik, usize), IdentError> {
    let base_frame = model
        .frames
        .iter()
        .position(|f| f.name == model.base_link)
        .ok_or_else(|| IdentError::new("the base link has no frame"))?;
    let mut tasks = flat_foot_tasks(&anatomy.left_foot, stance.soles[0]);
    tasks.extend(flat_foot_tasks(&anatomy.right_foot, stance.soles[1]));
    // Fore-aft balance: the CoM over the middle of the feet (the symmetric motion keeps
    // it central sideways; H1's parallel legs could not move it sideways anyway).
    tasks.push(Task::Com {
        target: stance.mid,
        weight: Vector3::new(1.0, 0.0, 0.0),
    });
    tasks.push(Task::Point {
        frame: base_frame,
        point: Vector3::zeros(),
        target: Vector3::new(0.0, 0.0, stance.stand),
        weight: Vector3::new(0.0, 0.0, 1.0),
    });
    let base_task = tasks.len() - 1;
    // The pelvis does not pitch: its forward axis stays horizontal.
    let q_neutral = model.neutral_configuration();
    twinloop_dynamics::forward_kinematics(model, data, &q_neutral);
    let base_forward = data.base_placement.rotation.tr_mul(&Vector3::x());
    tasks.push(Task::Axis {
        frame: base_frame,
        axis: base_forward,
        target: Vector3::x(),
        weight: Vector3::new(0.0, 0.0, 1.0),
    });
    let mut ik = Ik::new(model, tasks);
    let balance: Vec<usize> = anatomy
        .left_leg
        .iter()
        .chain(&anatomy.right_leg)
        .copied()
        .collect();
    let vo = model.v_offset;
    ik.set_free(|k| k < vo || balance.contains(&(k - vo)));
    Ok((ik, base_task))
}

/// The squat's depth profile over time, 0 to 1 and back: down and up, each a
/// minimum-jerk move (rest to rest, no jump in acceleration).
fn squat_profile(options: &SquatOptions, t: f64) -> f64 {
    let s = ((t - options.rest) / options.duration).clamp(0.0, 1.0);
    let x = if s < 0.5 { 2.0 * s } else { 2.0 - 2.0 * s };
    x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
}

/// The squat's configuration as a function of time alone. Continuation: every frame
/// starts from the same standing solution and moves to its depth in a fixed number of
/// projections, so the result depends on t alone and can be differentiated.
struct SquatFrames<'a> {
    model: &'a Model,
    options: &'a SquatOptions,
    stance: &'a SquatStance,
    reference: &'a [f64],
    swings: &'a [(usize, f64)],
    ik: Ik,
    base_task: usize,
    data: &'a mut Data,
    /// The standing solution, once solved.
    stand_q: Option<Vec<f64>>,
}

impl SquatFrames<'_> {
    /// Projections per frame from the standing solution to its depth.
    const STEPS: usize = 4;

    /// The configuration at `t` into `q` (the first call solves the standing pose).
    fn solve_at(&mut self, t: f64, q: &mut [f64]) -> Result<(), IdentError> {
        let (model, stance) = (self.model, self.stance);
        let s_end = squat_profile(self.options, t);
        let fail = |rep: twinloop_gait::ik::IkReport| {
            IdentError::new(format!(
                "the squat at t = {t:.3} s cannot keep the feet flat where they stand with the CoM \
                 over them (residual {:.2e}): try a smaller squat depth",
                rep.max_residual
            ))
            .option("depth")
        };
        let start = self.stand_q.is_none();
        if start {
            q.copy_from_slice(&stance.q0);
            q[0] = stance.mid.x;
            q[1] = stance.mid.y;
            q[2] = stance.stand;
            q[model.q_offset..].copy_from_slice(self.reference);
        } else if let Some(sq) = &self.stand_q {
            q.copy_from_slice(sq);
        }
        let steps = if start { 0 } else { Self::STEPS };
        for j in 0..=steps {
            let s = if steps == 0 {
                0.0
            } else {
                s_end * j as f64 / steps as f64
            };
            for &(a, ext) in self.swings {
                q[model.q_offset + a] = ext * self.options.arm_swing * s;
            }
            if let Task::Point { target, .. } = &mut self.ik.tasks[self.base_task] {
                target.z = stance.stand - stance.depth * s;
            }
            let rep = self.ik.project(model, self.data, q, 60, 1e-13);
            if rep.max_residual > 1e-9 {
                return Err(fail(rep));
            }
        }
        if start {
            self.stand_q = Some(q.to_vec());
            return Ok(());
        }
        check_squat_limits(model, q, t)
    }
}

/// Errors if a joint of the squat's configuration at `t` is outside its limits.
fn check_squat_limits(model: &Model, q: &[f64], t: f64) -> Result<(), IdentError> {
    for i in 0..model.nbodies {
        let x = q[model.q_offset + i];
        if x < model.lower_limits[i] - 1e-9 || x > model.upper_limits[i] + 1e-9 {
            return Err(IdentError::new(format!(
                "the squat at t = {t:.3} s needs joint {} at {x:.3} rad, outside its limits: \
                 try a smaller squat depth",
                model.joint_names[i]
            ))
            .option("depth"));
        }
    }
    Ok(())
}

/// The squat of seed 004, Fig. 4, made with the truth model: double support with the
/// feet where the neutral stance puts them, the pelvis lowered by `depth` and raised
/// again along a cosine, the arms swinging forward, the CoM kept over the middle of
/// the feet; velocities and accelerations by central differences of the exact
/// inverse-kinematics solution, and the plate readings as the truth's inverse
/// dynamics demands them.
pub fn squat_motion(
    robot: &Description,
    model: &Model,
    options: &SquatOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<Motion, IdentError> {
    if !model.is_floating() {
        return Err(IdentError::new("the squat needs a floating-base model"));
    }
    if !(options.rate > 0.0 && options.duration > 0.0 && options.rest >= 0.0) {
        return Err(IdentError::new("rate, duration and rest must be positive").option("rate"));
    }
    let feet = options.feet.as_ref().map(|(l, r)| (l.as_str(), r.as_str()));
    let anatomy = Anatomy::detect(robot, model, feet)?;
    let mut data = Data::new(model);
    let stance = squat_stance(model, &anatomy, &mut data, options);
    let reference = squat_reference_posture(model, &anatomy);
    let swings = arm_swings(model, &anatomy, &mut data);
    let (ik, base_task) = squat_ik(model, &anatomy, &mut data, &stance)?;
    let total = options.rest * 2.0 + options.duration;
    let frames = (total * options.rate).round() as usize + 1;
    // Step of the central differences of the exact motion (1 ms).
    let h = 1e-3;
    let mut squat = SquatFrames {
        model,
        options,
        stance: &stance,
        reference: &reference,
        swings: &swings,
        ik,
        base_task,
        data: &mut data,
        stand_q: None,
    };
    let mut motion = Motion::default();
    let mut plate = Vec::with_capacity(frames);
    let mut truth_data = Data::new(model);
    let mut q = stance.q0.clone();
    squat.solve_at(0.0, &mut q)?; // the standing solution every frame starts from
    let (mut qm, mut qp) = (q.clone(), q.clone());
    let (mut v, mut a) = (vec![0.0; model.nv], vec![0.0; model.nv]);
    for k in 0..frames {
        let t = k as f64 / options.rate;
        squat.solve_at(t, &mut q)?;
        squat.solve_at(t - h, &mut qm)?;
        squat.solve_at(t + h, &mut qp)?;
        // v, a by central differences on the manifold (base twist in the base frame).
        central_state(model, &qm, &q, &qp, h, &mut v, &mut a);
        let need = Force::from_slice(&rnea(model, &mut truth_data, &q, &v, &a).as_slice()[0..6]);
        let base: Se3 = truth_data.base_placement;
        let w = base.act_force(&need);
        plate.push(PlateSample::from_wrench(&w.f, &w.n));
        motion.t.push(t);
        motion.q.push(q.clone());
        progress(k + 1, frames);
    }
    motion.plate = Some(plate);
    Ok(motion)
}

/// Velocity and acceleration at `q` from its neighbours `h` before and after.
fn central_state(
    model: &Model,
    qm: &[f64],
    q: &[f64],
    qp: &[f64],
    h: f64,
    v: &mut [f64],
    a: &mut [f64],
) {
    let (qo, vo) = (model.q_offset, model.v_offset);
    for i in 0..model.nbodies {
        v[vo + i] = (qp[qo + i] - qm[qo + i]) / (2.0 * h);
        a[vo + i] = (qp[qo + i] - 2.0 * q[qo + i] + qm[qo + i]) / (h * h);
    }
    if model.is_floating() {
        // Body-frame twist from X^-1 X(t +- h): log on SE(3) to second order is enough
        // at h = 1 ms; use the displacement in the base frame and the rotation vector.
        let x = |qq: &[f64]| {
            Se3::new(
                quaternion_xyzw_to_matrix(qq[3], qq[4], qq[5], qq[6]),
                Vector3::new(qq[0], qq[1], qq[2]),
            )
        };
        let (xm, x0, xp) = (x(qm), x(q), x(qp));
        let lin = |xx: &Se3| x0.rotation.tr_mul(&(xx.translation - x0.translation));
        // The rotation vector through the quaternions: a rotation matrix's angle is
        // acos((trace - 1) / 2), NaN when rounding puts the trace of a near-identity
        // rotation above 3 (seen at the squat's first and last moving frames).
        let quat = |qq: &[f64]| {
            nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                qq[6], qq[3], qq[4], qq[5],
            ))
        };
        let q0 = quat(q);
        let ang = |qq: &[f64]| (q0.inverse() * quat(qq)).scaled_axis();
        // Body velocity components: v(t) = R^T p'(t), w(t) from R^T R'.
        // Second-order: v0 = (d+ - d-)/(2h) and the derivative of v = R^T p' is
        // R^T p'' - [w]x R^T p' (the frame turns).
        let (dp, dm) = (lin(&xp), lin(&xm));
        let (rp, rm) = (ang(qp), ang(qm));
        let vl = (dp - dm) / (2.0 * h);
        let w = (rp - rm) / (2.0 * h);
        let pdd = (dp + dm) / (h * h); // R^T p''
        let wd = (rp + rm) / (h * h);
        let al = pdd - w.cross(&vl);
        v[0..3].copy_from_slice(vl.as_slice());
        v[3..6].copy_from_slice(w.as_slice());
        a[0..3].copy_from_slice(al.as_slice());
        a[3..6].copy_from_slice(wd.as_slice());
    }
}

/// Write a motion as CSV: `t`, the `q:` columns and the plate columns.
pub fn write_motion(path: &Path, model: &Model, motion: &Motion) -> Result<(), IdentError> {
    let mut cols = vec!["t".to_string()];
    cols.extend(Quantity::Q.column_names(&model.q_names()));
    if motion.plate.is_some() {
        cols.extend(PLATE_COLUMNS.iter().map(|c| c.to_string()));
    }
    let mut w = twinloop_io::CsvWriter::create(path, &cols)?;
    let mut row = Vec::with_capacity(cols.len());
    for k in 0..motion.t.len() {
        row.clear();
        row.push(motion.t[k]);
        row.extend_from_slice(&motion.q[k]);
        if let Some(p) = &motion.plate {
            let s = p[k];
            row.extend_from_slice(&s.force);
            row.extend_from_slice(&s.cop);
            row.push(s.free_moment);
        }
        w.write_row(&row)?;
    }
    w.finish()?;
    Ok(())
}

#[cfg(test)]
mod paired_tests {
    use super::*;

    /// Issue 29, class 3: a plate file is paired with the motion by its `t`, not by
    /// its row: in step it is taken, 0.5 s late or a row short it is refused.
    #[test]
    fn a_plate_out_of_step_with_the_motion_is_refused() {
        let motion = [0.0, 0.01, 0.02, 0.03];
        let plate = |dt: f64, n: usize| {
            let rows: String = motion[..n]
                .iter()
                .map(|t| format!("{},1\n", t + dt))
                .collect();
            Table::parse(&format!("t,grf.fz\n{rows}")).unwrap()
        };
        assert!(check_paired_times(&motion, &plate(0.0, 4)).is_ok());
        assert!(check_paired_times(&motion, &plate(1e-7, 4)).is_ok());
        let e = check_paired_times(&motion, &plate(0.5, 4))
            .unwrap_err()
            .to_string();
        assert!(e.contains("data row 1") && e.contains("out of step"), "{e}");
        let e = check_paired_times(&motion, &plate(0.0, 3))
            .unwrap_err()
            .to_string();
        assert!(e.contains("3 plate rows for 4"), "{e}");
        // Without `t` the rows pair by index (the counts are checked later).
        let no_t = Table::parse("grf.fz\n1\n2\n").unwrap();
        assert!(check_paired_times(&motion, &no_t).is_ok());
    }
}
