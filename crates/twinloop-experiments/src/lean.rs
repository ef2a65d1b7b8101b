//! The lean experiment of seed 001 (section F, Figs 8-11): from the standing pose, both
//! ankle pitches lean the robot centre -> forward -> backward -> centre, each lean
//! followed by a hold (the seed's "stabilizing section"), while the ankle and knee
//! angles and torques are recorded. It does not go to the fall: the amplitude is a
//! fraction of the model's static tipping angle ([`sagittal_tip_angles`]).
//!
//! On the simulator the torque is the servo's applied torque; over a Dynamixel bus it
//! is the servos' Present Load turned into N m by the datasheet stall torque
//! (`twinloop_link::DynamixelRobot` does that below the `Robot` trait). The seed
//! compared the two traces by eye (Figs 10-11); [`crate::lean_validation`] compares
//! them by RMS per joint.

use crate::error::{ExperimentError, err};
use nalgebra::Vector3;
use twinloop_description::Description;
use twinloop_dynamics::{Data, Model};
use twinloop_io::Table;
use twinloop_robot::{Robot, RobotError, RobotState};
use twinloop_sim::statics::{FlatFeet, lean_signs};
use twinloop_sim::{SimConfig, Simulator, servo_for_joint};

/// The joints the lean turns (ankle pitches) and records (ankle pitches and knees),
/// by name, left first.
#[derive(Debug, Clone, PartialEq)]
pub struct LeanJointNames {
    pub ankles: [String; 2],
    pub knees: [String; 2],
}

impl Default for LeanJointNames {
    /// km20's names (and those of the robots that follow its convention).
    fn default() -> Self {
        LeanJointNames {
            ankles: ["l_ank_pitch".into(), "r_ank_pitch".into()],
            knees: ["l_knee".into(), "r_knee".into()],
        }
    }
}

impl LeanJointNames {
    /// The four recorded joints: left and right ankle pitch, left and right knee.
    pub fn recorded(&self) -> [&str; 4] {
        [
            &self.ankles[0],
            &self.ankles[1],
            &self.knees[0],
            &self.knees[1],
        ]
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct LeanConfig {
    /// Ankle pitch joints (left, right) in the robot's joint order.
    pub ankle_pitch: [usize; 2],
    /// The joints recorded, in the robot's joint order, with their names.
    pub recorded: Vec<usize>,
    pub recorded_names: Vec<String>,
    /// Sign of each ankle command that leans the robot forward (depends on the axes).
    pub forward_sign: [f64; 2],
    /// Lean amplitude, deg: the ankles go to +amplitude (forward) and -amplitude.
    pub amplitude_deg: f64,
    /// Ankle speed during the ramps, deg/s.
    pub ramp_deg_per_s: f64,
    /// Hold after each ramp, s (the seed's stabilizing sections).
    pub hold_s: f64,
    /// Standing still before the lean, s (not recorded).
    pub settle_s: f64,
    /// Control period, s.
    pub period_s: f64,
    /// Stop (an error) once the trunk's pitch has moved more than this from where the
    /// lean started, deg: the robot is falling. The model's static tip angle is a good
    /// bound: the trunk cannot lean that far and stay up. `None`: no check.
    pub max_tilt_deg: Option<f64>,
}

impl LeanConfig {
    pub fn new(ankle_pitch: [usize; 2], forward_sign: [f64; 2], amplitude_deg: f64) -> Self {
        LeanConfig {
            ankle_pitch,
            recorded: ankle_pitch.to_vec(),
            recorded_names: Vec::new(),
            forward_sign,
            amplitude_deg,
            ramp_deg_per_s: 2.0,
            hold_s: 1.0,
            settle_s: 1.0,
            period_s: 0.005,
            max_tilt_deg: None,
        }
    }

    /// Length of the lean from its start to the end of the last hold, s.
    pub fn duration_s(&self) -> f64 {
        4.0 * self.amplitude_deg / self.ramp_deg_per_s + 3.0 * self.hold_s
    }

    fn check(&self) -> Result<(), ExperimentError> {
        let ok = |x: f64| x.is_finite() && x > 0.0;
        if !ok(self.amplitude_deg) {
            return err(format!(
                "lean amplitude: must be > 0 deg, got {}",
                self.amplitude_deg
            ));
        }
        if !ok(self.ramp_deg_per_s) {
            return err(format!(
                "lean ramp: must be > 0 deg/s, got {}",
                self.ramp_deg_per_s
            ));
        }
        if !(self.hold_s.is_finite() && self.hold_s >= 0.0) {
            return err(format!("lean hold: must be >= 0 s, got {}", self.hold_s));
        }
        if !ok(self.period_s) {
            return err(format!("lean period: must be > 0 s, got {}", self.period_s));
        }
        if self.recorded.len() != self.recorded_names.len() {
            return err("lean: one name per recorded joint is needed");
        }
        Ok(())
    }
}

/// The commanded lean (rad, forward positive) `t` s after the start: ramp to
/// +amplitude, hold, ramp to -amplitude, hold, ramp back to 0, hold (seed 001: "center
/// to forward, forward to backward and backward to center"); `None` once it is over.
pub fn lean_command(cfg: &LeanConfig, t: f64) -> Option<f64> {
    let a = cfg.amplitude_deg.to_radians();
    let rate = cfg.ramp_deg_per_s.to_radians();
    let (r, h) = (a / rate, cfg.hold_s);
    // Segment ends: up, hold, down through zero, hold, back, hold.
    let ends = [r, r + h, 3.0 * r + h, 3.0 * r + 2.0 * h, 4.0 * r + 2.0 * h];
    Some(if t < 0.0 {
        0.0
    } else if t < ends[0] {
        rate * t
    } else if t < ends[1] {
        a
    } else if t < ends[2] {
        a - rate * (t - ends[1])
    } else if t < ends[3] {
        -a
    } else if t < ends[4] {
        -a + rate * (t - ends[3])
    } else if t <= ends[4] + h {
        0.0
    } else {
        return None;
    })
}

/// One row of a lean: time from the start of the lean (s), the trunk's pitch (rad,
/// forward positive, from the IMU; NaN without one) and, per recorded joint, the
/// commanded and measured angle (rad) and the torque (N m).
#[derive(Debug, Clone, Copy)]
pub struct LeanRow<'a> {
    pub t: f64,
    pub tilt: f64,
    pub goal: &'a [f64],
    pub q: &'a [f64],
    pub tau: &'a [f64],
}

/// A lean recorded: joint by joint series on a common time axis. `goal` and `q` (and
/// `tilt`) are empty when the table they were read from had no such columns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LeanRecord {
    pub joints: Vec<String>,
    pub t: Vec<f64>,
    pub tilt: Vec<f64>,
    pub goal: Vec<Vec<f64>>,
    pub q: Vec<Vec<f64>>,
    pub tau: Vec<Vec<f64>>,
}

impl LeanRecord {
    pub fn new(joints: Vec<String>) -> Self {
        let n = joints.len();
        LeanRecord {
            joints,
            t: Vec::new(),
            tilt: Vec::new(),
            goal: vec![Vec::new(); n],
            q: vec![Vec::new(); n],
            tau: vec![Vec::new(); n],
        }
    }

    pub fn push(&mut self, row: &LeanRow<'_>) {
        self.t.push(row.t);
        self.tilt.push(row.tilt);
        for k in 0..self.joints.len() {
            self.goal[k].push(row.goal[k]);
            self.q[k].push(row.q[k]);
            self.tau[k].push(row.tau[k]);
        }
    }

    /// The columns of the CSV: `t`, `tilt:pitch`, then `goal:<joint>`, `q:<joint>`,
    /// `tau:<joint>`.
    pub fn columns(joints: &[String]) -> Vec<String> {
        let mut cols = vec!["t".to_string(), "tilt:pitch".to_string()];
        for prefix in ["goal", "q", "tau"] {
            cols.extend(joints.iter().map(|j| format!("{prefix}:{j}")));
        }
        cols
    }

    /// One CSV row of `row` in the order of [`LeanRecord::columns`], into `out`.
    pub fn row_values(row: &LeanRow<'_>, out: &mut Vec<f64>) {
        out.clear();
        out.push(row.t);
        out.push(row.tilt);
        out.extend_from_slice(row.goal);
        out.extend_from_slice(row.q);
        out.extend_from_slice(row.tau);
    }

    /// The record as a table with the columns of [`LeanRecord::columns`]; a series the
    /// record lacks (read from a table without it) is NaN.
    pub fn to_table(&self) -> Table {
        let mut t = Table::new(Self::columns(&self.joints));
        for i in 0..self.t.len() {
            let mut row = vec![self.t[i], self.tilt.get(i).copied().unwrap_or(f64::NAN)];
            for series in [&self.goal, &self.q, &self.tau] {
                row.extend(series.iter().map(|c| c.get(i).copied().unwrap_or(f64::NAN)));
            }
            t.rows.push(row);
        }
        t
    }
}

/// Run the lean on `robot` from `standing` (joint positions): settle, then lean as
/// [`lean_command`] says, one row per control period handed to `on_row` as it comes
/// (so a recording survives an aborted run) and kept in the returned record.
///
/// The robot must report joint torques (`RobotState::efforts`): the simulator gives its
/// servos' applied torque, a Dynamixel robot its Present Load in N m.
pub fn run_lean<R: Robot + ?Sized>(
    robot: &mut R,
    standing: &[f64],
    cfg: &LeanConfig,
    on_row: &mut dyn FnMut(&LeanRow<'_>) -> Result<(), RobotError>,
) -> Result<LeanRecord, RobotError> {
    cfg.check().map_err(|e| RobotError::new(e.0))?;
    let n = robot.joint_names().len();
    if standing.len() != n {
        return Err(RobotError::new(format!(
            "the standing pose has {} joints, the robot {n}",
            standing.len()
        )));
    }
    if let Some(&j) = cfg
        .recorded
        .iter()
        .chain(&cfg.ankle_pitch)
        .find(|&&j| j >= n)
    {
        return Err(RobotError::new(format!(
            "lean joint index {j}: the robot has {n} joints"
        )));
    }
    let mut goals = standing.to_vec();
    robot.command_positions(&goals)?;
    robot.advance(cfg.settle_s)?;
    let t0 = robot.time();
    let shape = |cmd: f64, goals: &mut [f64]| {
        for k in 0..2 {
            let j = cfg.ankle_pitch[k];
            goals[j] = standing[j] + cfg.forward_sign[k] * cmd;
        }
    };
    command_loop(
        robot,
        cfg,
        t0,
        &mut goals,
        &mut |t, goals| lean_command(cfg, t).map(|cmd| shape(cmd, goals)).is_some(),
        on_row,
    )
}

/// The control loop shared by the profile and the replay: `set_goals(t, goals)` writes
/// the goals for time `t` from the start and says whether the lean goes on.
fn command_loop<R: Robot + ?Sized>(
    robot: &mut R,
    cfg: &LeanConfig,
    t0: f64,
    goals: &mut [f64],
    set_goals: &mut dyn FnMut(f64, &mut [f64]) -> bool,
    on_row: &mut dyn FnMut(&LeanRow<'_>) -> Result<(), RobotError>,
) -> Result<LeanRecord, RobotError> {
    let m = cfg.recorded.len();
    let mut record = LeanRecord::new(cfg.recorded_names.clone());
    let (mut g, mut q, mut tau) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    let mut st = RobotState::default();
    let mut tilt0 = None;
    loop {
        let t = robot.time() - t0;
        if !set_goals(t, goals) {
            return Ok(record);
        }
        robot.command_positions(goals)?;
        let before = robot.time();
        robot.advance(cfg.period_s)?;
        if robot.time() <= before {
            // A period shorter than the robot's step (a simulator rounds it to no step):
            // the lean would write rows at one time forever.
            return Err(RobotError::new(format!(
                "the robot's clock did not move over a control period of {} s (shorter than \
                 its time step?); give a longer period",
                cfg.period_s
            )));
        }
        robot.read(&mut st)?;
        let efforts = st.efforts.as_deref().ok_or_else(|| {
            RobotError::new("the lean experiment needs joint torques; the robot reports none")
        })?;
        for (k, &j) in cfg.recorded.iter().enumerate() {
            g[k] = goals[j];
            q[k] = st.positions[j];
            tau[k] = efforts[j];
        }
        let row = LeanRow {
            t: st.time - t0,
            tilt: st
                .imu
                .and_then(|i| i.orientation)
                .map_or(f64::NAN, |o| crate::tipover::tilt(o).0),
            goal: &g,
            q: &q,
            tau: &tau,
        };
        on_row(&row)?;
        record.push(&row);
        let start = *tilt0.get_or_insert(row.tilt);
        if let Some(max) = cfg.max_tilt_deg
            && (row.tilt - start).abs() > max.to_radians()
        {
            return Err(RobotError::new(format!(
                "the trunk leans {:.2} deg from where the lean started, beyond {max:.2} deg: the \
                 robot is falling (t = {:.2} s)",
                (row.tilt - start).abs().to_degrees(),
                row.t
            )));
        }
    }
}

/// Replay the commanded angles of a recorded lean (`goal:<joint>` columns of `record`,
/// linear between rows) on `robot`, every other joint held at `standing`; the joints
/// of `cfg.recorded` are recorded. This runs on a model exactly the lean a robot did,
/// whatever profile it followed.
pub fn replay_lean<R: Robot + ?Sized>(
    robot: &mut R,
    standing: &[f64],
    record: &LeanRecord,
    cfg: &LeanConfig,
) -> Result<LeanRecord, RobotError> {
    let names = robot.joint_names().to_vec();
    let mut driven = Vec::new();
    for (k, name) in record.joints.iter().enumerate() {
        if record.goal[k].is_empty() {
            continue;
        }
        let j = names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| RobotError::at_joint(name, "the robot has no such joint"))?;
        driven.push((j, k));
    }
    if driven.is_empty() || record.t.len() < 2 {
        return Err(RobotError::new(
            "the recorded lean has no goal:<joint> columns (or fewer than two rows) to replay",
        ));
    }
    let mut goals = standing.to_vec();
    for &(j, k) in &driven {
        goals[j] = record.goal[k][0];
    }
    robot.command_positions(&goals)?;
    robot.advance(cfg.settle_s)?;
    let t0 = robot.time();
    let end = record.t[record.t.len() - 1];
    let mut at = 0usize;
    command_loop(
        robot,
        cfg,
        t0,
        &mut goals,
        &mut |t, goals| {
            if t > end {
                return false;
            }
            while at + 2 < record.t.len() && record.t[at + 1] < t {
                at += 1;
            }
            let (ta, tb) = (record.t[at], record.t[at + 1]);
            let w = if tb > ta {
                ((t - ta) / (tb - ta)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            for &(j, k) in &driven {
                let c = &record.goal[k];
                goals[j] = (1.0 - w) * c[at] + w * c[at + 1];
            }
            true
        },
        &mut |_| Ok(()),
    )
}

/// The simulator the lean runs on: the robot on its servos (each joint's datasheet
/// servo, or one derived from its limits), standing on the ground at the zero pose
/// (clamped to the limits), as `twinloop serve` builds its virtual robot. With
/// `compliance_slope` (Dynamixel RX position units, 2 = stiffest) every servo's slope
/// is set to it and its margin to zero, as a host writing the Compliance Slope
/// registers would; `None` keeps the factory settings the virtual robot serves with.
/// Returns the simulator and the standing pose.
pub fn lean_simulator(
    robot: &Description,
    compliance_slope: Option<f64>,
) -> Result<(Simulator, Vec<f64>), ExperimentError> {
    let servo = |m: &Model, i: usize| {
        let mut servo = servo_for_joint(&robot.name, m, i);
        if let Some(slope) = compliance_slope {
            servo.compliance_slope = slope * twinloop_sim::actuator::RX_POSITION_UNIT;
            servo.compliance_margin = 0.0;
        }
        servo
    };
    let (sim, standing) = Simulator::standing_on_servos(robot, SimConfig::default(), &servo)
        .map_err(|e| ExperimentError(e.to_string()))?;
    Ok((sim, standing))
}

/// A lean configuration for `model` whose robot orders its joints as `joint_order`
/// (the simulator's model order, or a servo mapping's): the ankle pitch and knee
/// indices in that order and the forward signs from the model's axes.
pub fn lean_config(
    model: &Model,
    joint_order: &[String],
    names: &LeanJointNames,
    amplitude_deg: f64,
) -> Result<LeanConfig, ExperimentError> {
    let in_model = |n: &str| {
        model
            .joint_names
            .iter()
            .position(|j| j == n)
            .ok_or_else(|| {
                ExperimentError(format!(
                    "robot \"{}\": no joint \"{n}\" (the lean turns or records it)",
                    model.name
                ))
            })
    };
    let in_robot = |n: &str| {
        joint_order.iter().position(|j| j == n).ok_or_else(|| {
            ExperimentError(format!(
                "no joint \"{n}\" on the robot (the lean turns or records it)"
            ))
        })
    };
    let mut data = Data::new(model);
    let q0 = model.neutral_configuration();
    let pitch = [in_model(&names.ankles[0])?, in_model(&names.ankles[1])?];
    let signs = lean_signs(model, &mut data, &q0, pitch, Vector3::x());
    let ankles = [in_robot(&names.ankles[0])?, in_robot(&names.ankles[1])?];
    let mut cfg = LeanConfig::new(ankles, signs, amplitude_deg);
    let recorded = names.recorded();
    for n in recorded {
        in_model(n)?;
    }
    cfg.recorded = recorded
        .iter()
        .map(|n| in_robot(n))
        .collect::<Result<_, _>>()?;
    cfg.recorded_names = recorded.iter().map(|n| n.to_string()).collect();
    Ok(cfg)
}

/// The model's static forward and backward tipping angles of the ankle lean, rad: the
/// ankle pitches turned from `standing` with the feet flat until the CoM reaches the
/// front (back) edge of the soles (twinloop-sim's static analysis). The soles are the
/// lowest contact points of the standing simulator, one foot each side.
pub fn sagittal_tip_angles(
    sim: &mut Simulator,
    standing: &[f64],
    names: &LeanJointNames,
) -> Result<(f64, f64), ExperimentError> {
    let model = sim.model.clone();
    let order = model.joint_names.clone();
    let cfg = lean_config(&model, &order, names, 1.0)?;
    let feet = sole_links(sim)?;
    let foot_world = [
        sim.link_placement(&model.links[feet[0]].name),
        sim.link_placement(&model.links[feet[1]].name),
    ];
    let (Some(l), Some(r)) = (foot_world[0], foot_world[1]) else {
        return err("the feet's placements are unknown");
    };
    let points = sim.contact_points().to_vec();
    let flat = FlatFeet {
        model: &model,
        feet,
        points: &points,
        foot_world: [l, r],
        held: 0,
        tilt: 0.0,
    };
    let mut data = Data::new(&model);
    let [a, b] = cfg.ankle_pitch;
    let [sa, sb] = cfg.forward_sign;
    let hi = 60f64.to_radians();
    let forward = flat.tipping_angle(
        &mut data,
        standing,
        &[(a, sa), (b, sb)],
        Vector3::x(),
        0.0,
        hi,
    );
    let backward = flat.tipping_angle(
        &mut data,
        standing,
        &[(a, -sa), (b, -sb)],
        -Vector3::x(),
        0.0,
        hi,
    );
    match (forward, backward) {
        (Ok(f), Ok(b)) => Ok((f, b)),
        _ => err(format!(
            "robot \"{}\": no static tipping angle within 60 deg of ankle lean (is the CoM \
             over the feet standing?)",
            model.name
        )),
    }
}

/// The two links whose contact points are lowest in the standing simulator, left
/// (larger y) first: the feet.
fn sole_links(sim: &mut Simulator) -> Result<[usize; 2], ExperimentError> {
    let model = sim.model.clone();
    let mut data = Data::new(&model);
    twinloop_dynamics::forward_kinematics(&model, &mut data, &sim.q);
    let world: Vec<(usize, Vector3<f64>)> = sim
        .contact_points()
        .iter()
        .map(|p| {
            let x = if p.body == twinloop_dynamics::BASE {
                data.base_placement
            } else {
                data.o_m_i[p.body]
            }
            .act_point(&p.local);
            (p.link, x - Vector3::new(0.0, 0.0, p.radius))
        })
        .collect();
    let zmin = world.iter().map(|w| w.1.z).fold(f64::INFINITY, f64::min);
    // Links touching the ground, with the mean y of their touching points.
    let mut links: Vec<(usize, f64, usize)> = Vec::new();
    for (l, x) in world.iter().filter(|w| w.1.z < zmin + 1e-3) {
        match links.iter_mut().find(|e| e.0 == *l) {
            Some(e) => {
                e.1 += x.y;
                e.2 += 1;
            }
            None => links.push((*l, x.y, 1)),
        }
    }
    if links.len() != 2 {
        return err(format!(
            "robot \"{}\": {} links touch the ground standing; the lean needs two feet",
            model.name,
            links.len()
        ));
    }
    let y = |e: &(usize, f64, usize)| e.1 / e.2 as f64;
    Ok(if y(&links[0]) > y(&links[1]) {
        [links[0].0, links[1].0]
    } else {
        [links[1].0, links[0].0]
    })
}

/// The three holds of a lean (forward, backward, centre) in its time, s: from `settle`
/// s after each ramp ends to the end of the hold (the seed's stabilizing sections).
pub fn hold_windows(cfg: &LeanConfig, settle: f64) -> [(f64, f64); 3] {
    let r = cfg.amplitude_deg / cfg.ramp_deg_per_s;
    let starts = [r, 3.0 * r + cfg.hold_s, 4.0 * r + 2.0 * cfg.hold_s];
    starts.map(|s| ((s + settle).min(s + cfg.hold_s), s + cfg.hold_s))
}

/// One recorded joint over a lean: its mean angle and torque in each hold (forward,
/// backward, centre) and its torque's range.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LeanJointSummary {
    pub joint: String,
    /// Mean measured angle in the holds, rad.
    pub q_hold: [f64; 3],
    /// Mean torque in the holds, N m.
    pub tau_hold: [f64; 3],
    pub tau_min: f64,
    pub tau_max: f64,
}

/// Per joint, the holds' means (the second half of each hold, once the servos have
/// settled) and the torque range of `record`, a lean run with `cfg`.
pub fn summarize(record: &LeanRecord, cfg: &LeanConfig) -> Vec<LeanJointSummary> {
    let windows = hold_windows(cfg, 0.5 * cfg.hold_s);
    let mean = |y: &[f64], (a, b): (f64, f64)| {
        let v: Vec<f64> = (0..record.t.len())
            .filter(|&i| record.t[i] >= a && record.t[i] <= b)
            .map(|i| y[i])
            .collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    (0..record.joints.len())
        .map(|k| LeanJointSummary {
            joint: record.joints[k].clone(),
            q_hold: windows.map(|w| mean(&record.q[k], w)),
            tau_hold: windows.map(|w| mean(&record.tau[k], w)),
            tau_min: record.tau[k].iter().copied().fold(f64::INFINITY, f64::min),
            tau_max: record.tau[k]
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_profile_ramps_forward_back_through_zero_and_home_with_holds() {
        let mut cfg = LeanConfig::new([0, 1], [1.0, 1.0], 4.0);
        cfg.ramp_deg_per_s = 2.0;
        cfg.hold_s = 1.0;
        let deg = |t: f64| lean_command(&cfg, t).map(f64::to_degrees);
        assert!((cfg.duration_s() - 11.0).abs() < 1e-12);
        for (t, want) in [
            (0.0, 0.0),
            (1.0, 2.0),
            (2.5, 4.0),
            (4.0, 2.0),
            (5.0, 0.0),
            (7.0, -4.0),
            (8.5, -3.0),
            (10.0, 0.0),
            (10.9, 0.0),
        ] {
            let got = deg(t).unwrap();
            assert!((got - want).abs() < 1e-9, "t = {t}: {got} deg, want {want}");
        }
        assert_eq!(deg(11.1), None);
        let w = hold_windows(&cfg, 0.5);
        assert_eq!(w, [(2.5, 3.0), (7.5, 8.0), (10.5, 11.0)]);
    }
}
