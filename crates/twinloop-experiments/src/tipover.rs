//! The tip-over experiment (seed 000 section V.A, Table IV; seed 001): from a standing
//! pose, ramp both ankles (pitch forward, then backward, then roll left and right) until
//! the robot tips over, and record the commanded and measured ankle angle at the
//! moment it started to tip, and the time from the start of the ramp.
//!
//! Sideways, the hip rolls turn with the ankle rolls (`TipoverConfig::hip_roll`): the
//! legs move as a parallelogram, both feet stay flat and the pelvis level. Turning the
//! ankle rolls alone cannot lean a robot whose hips hold: two flat feet, two legs, the
//! pelvis and the ground form a closed chain (the rigid upper body cannot turn about
//! two parallel ankle axes at once), and the robot rocks onto its sole edges instead of
//! tipping. A real robot's compliant hips let the legs shear into the parallelogram;
//! commanding it makes the motion the one the CoM methods model.
//!
//! Tipping is seen in the trunk's tilt: while the feet stay flat, the trunk is where
//! the measured joint angles put it; once the centre of mass passes the edge of the
//! foot, the whole robot rotates about that edge and the IMU tilts beyond that. The
//! prediction comes from the caller (`predict`: forward kinematics of the robot's model
//! with the feet flat), because every joint deflects under the changing load, not only
//! the ankles; without a model the ankle angle alone is the prediction. The onset is the
//! last moment before the fall at which the excess tilt grew slower than the ankles
//! turned (times `onset_ratio`): before the tip it only creeps (the ground and the soles
//! give a little as the load moves to the edge), after it the robot falls away
//! exponentially. Comparing with the ankle's own rate makes the test independent of the
//! ramp speed and the robot's size. The excess at the onset (the feet rolled onto their
//! edges, which the exact CoM method and the static reference take into account) and
//! the trunk's lean are recorded beside the ankle angle: a real robot is not rigid.

use serde::Serialize;
use twinloop_robot::{Robot, RobotError, RobotState};

/// Longest step of the ramp's clock per control cycle, s (see [`run_direction`]).
const MAX_RAMP_STEP_S: f64 = 0.05;

/// A ramp direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    Forward,
    Backward,
    Left,
    Right,
}

impl Direction {
    pub const ALL: [Direction; 4] = [
        Direction::Forward,
        Direction::Backward,
        Direction::Left,
        Direction::Right,
    ];

    pub fn is_pitch(self) -> bool {
        matches!(self, Direction::Forward | Direction::Backward)
    }

    pub fn name(self) -> &'static str {
        match self {
            Direction::Forward => "forward",
            Direction::Backward => "backward",
            Direction::Left => "left",
            Direction::Right => "right",
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct TipoverConfig {
    /// Ankle joints: left and right pitch, left and right roll (indices in the robot's
    /// joint order).
    pub ankle_pitch: [usize; 2],
    pub ankle_roll: [usize; 2],
    /// Sign of the ankle command that leans the robot forward (pitch) and left (roll),
    /// per ankle joint; depends on the robot's joint axes.
    pub forward_sign: [f64; 2],
    pub left_sign: [f64; 2],
    /// Hip roll joints (left, right) turned with the ankle rolls in the sideways lean,
    /// and the sign of each hip command that leans its leg to the left, so the legs move
    /// as a parallelogram: both feet stay flat and the pelvis stays level while it moves
    /// sideways. `None` turns the ankle rolls alone (then, with the hips held, the two
    /// legs, the pelvis and the ground form a closed chain that cannot lean: two
    /// parallel ankle axes at different places cannot both be the axis the rigid upper
    /// body turns about, and the robot rocks onto its sole edges instead).
    pub hip_roll: Option<[usize; 2]>,
    pub hip_left_sign: [f64; 2],
    /// Ramp speed of the ankle command, deg/s (seed 000's falls took 5-15 s over 7-24 deg).
    pub ramp_deg_per_s: f64,
    /// Slow final approach: beyond this ankle command (deg) the ramp continues at
    /// `slow_ramp_deg_per_s`. A tip is seen only once the robot has started to fall
    /// away, about 1.6 fall time constants (`sqrt(I/(m g r))`, 0.15-0.2 s on a
    /// kid-size robot) after the CoM passed the edge, and the ankle keeps turning
    /// meanwhile: 0.15 deg at 0.5 deg/s, enough to move the exact method's CoM by a
    /// millimetre. A second run that comes up to just before the first run's tip and
    /// then creeps makes that lag ten times smaller.
    pub slow_from_deg: Option<f64>,
    pub slow_ramp_deg_per_s: f64,
    /// Time to stand still before the ramp, s.
    pub settle_s: f64,
    /// Control period, s.
    pub period_s: f64,
    /// Excess tilt that confirms a fall, deg.
    pub fall_deg: f64,
    /// The robot is tipping once its excess tilt grows faster than `onset_ratio` times
    /// the measured ankle rate, both over `onset_window_s`.
    pub onset_ratio: f64,
    pub onset_window_s: f64,
    /// Read the tip as the mean over this long up to the onset, s (0: the onset's
    /// sample alone). Over a bus the ankles read whole counts and flip between two
    /// as the robot rocks on its sole edges, and the onset falls on the cycle either
    /// side of the count step that starts the fall: one sample reads a count early or
    /// late from run to run. The mean over a rocking period or so reads between the
    /// counts and moves little when the onset moves by a cycle. With a slow final
    /// approach the window starts no earlier than the creep.
    pub onset_average_s: f64,
    /// Give up beyond this ankle command, deg.
    pub max_deg: f64,
}

impl TipoverConfig {
    pub fn new(
        ankle_pitch: [usize; 2],
        ankle_roll: [usize; 2],
        forward_sign: [f64; 2],
        left_sign: [f64; 2],
    ) -> Self {
        TipoverConfig {
            ankle_pitch,
            ankle_roll,
            forward_sign,
            left_sign,
            hip_roll: None,
            hip_left_sign: [0.0; 2],
            ramp_deg_per_s: 1.5,
            slow_from_deg: None,
            slow_ramp_deg_per_s: 0.05,
            settle_s: 1.0,
            period_s: 0.005,
            fall_deg: 5.0,
            onset_ratio: 1.5,
            onset_window_s: 0.1,
            onset_average_s: 0.0,
            max_deg: 45.0,
        }
    }
}

/// What one direction gave.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TipoverResult {
    pub direction: Direction,
    /// Ankle command (offset from the standing pose) at the onset of tipping, deg.
    pub commanded_deg: f64,
    /// Measured ankle angle (offset from the standing pose, mean of both ankles), deg.
    pub measured_deg: f64,
    /// Time from the start of the ramp to the onset, s.
    pub time_s: f64,
    /// Time from the start of the ramp until the fall was confirmed, s.
    pub fall_confirmed_s: f64,
    /// How far the robot leaned beyond what its joints explain at the onset, deg: the
    /// feet rolled onto their edges (servo deflection; the IMU tilt minus the tilt the
    /// joints give with the feet flat).
    pub excess_deg: f64,
    /// The trunk's lean from the standing pose at the onset (IMU), deg, in the lean
    /// direction: the ankle angle plus the give of the feet and of every other joint.
    pub lean_deg: f64,
    /// Every joint's measured position at the onset (rad), for analysis.
    #[serde(skip)]
    pub positions_at_onset: Vec<f64>,
}

/// Trunk pitch and roll (rad) from an IMU orientation (x, y, z, w).
pub fn tilt(q: [f64; 4]) -> (f64, f64) {
    let [x, y, z, w] = q;
    // Third column of the rotation matrix: where the trunk's up axis points.
    let r02 = 2.0 * (x * z + w * y);
    let r12 = 2.0 * (y * z - w * x);
    let r22 = 1.0 - 2.0 * (x * x + y * y);
    (r02.atan2(r22), (-r12).atan2(r22))
}

/// Trunk tilt from the vertical in any direction (rad) past which a run counts the
/// robot as fallen whatever its joints say. The lean-direction tilt of [`tilt`] is
/// meaningless there: a robot that fell while the host was held up (a stalled bus,
/// a busy machine) lies past 90 deg, where pitch and roll flip sign, and its next
/// reading would otherwise enter the run's history as a huge negative excess.
pub const FALLEN_TILT_DEG: f64 = 60.0;

/// How far the trunk's up axis is from the vertical, rad (0 to pi), from an IMU
/// orientation (x, y, z, w).
pub fn tilt_from_vertical(q: [f64; 4]) -> f64 {
    let [x, y, ..] = q;
    let norm2: f64 = q.iter().map(|c| c * c).sum();
    (1.0 - 2.0 * (x * x + y * y) / norm2)
        .clamp(-1.0, 1.0)
        .acos()
}

/// Run one direction from `standing` (joint positions). The robot must be standing
/// still in that pose when called.
/// One sample of a run: ankle command, measured ankle angle (rad), time (s), the
/// trunk's tilt beyond what the joints explain and its tilt, both in the lean
/// direction (rad).
type Sample = (f64, f64, f64, f64, f64);

/// The ankle joints `direction` turns, the sign of each that leans the robot forward or
/// left, and the direction's sign (forward and left +1).
fn ankles_of(direction: Direction, cfg: &TipoverConfig) -> ([usize; 2], [f64; 2], f64) {
    match direction {
        Direction::Forward => (cfg.ankle_pitch, cfg.forward_sign, 1.0),
        Direction::Backward => (cfg.ankle_pitch, cfg.forward_sign, -1.0),
        Direction::Left => (cfg.ankle_roll, cfg.left_sign, 1.0),
        Direction::Right => (cfg.ankle_roll, cfg.left_sign, -1.0),
    }
}

/// The ankle command at `t` s into the ramp, rad: `rate t`, slowed to the creep rate
/// past `slow_from_deg` (see [`TipoverConfig::slow_from_deg`]).
fn ramp_command(cfg: &TipoverConfig, rate: f64, t: f64) -> f64 {
    match cfg.slow_from_deg.map(f64::to_radians) {
        Some(a) if rate * t > a => a + cfg.slow_ramp_deg_per_s.to_radians() * (t - a / rate),
        _ => rate * t,
    }
}

/// The goals that lean the robot by `cmd` rad in `direction`: both ankles, and
/// sideways the hip rolls too when the configuration turns them.
fn lean_goals(
    goals: &mut [f64],
    standing: &[f64],
    direction: Direction,
    cfg: &TipoverConfig,
    cmd: f64,
) {
    let (joints, signs, dir_sign) = ankles_of(direction, cfg);
    for k in 0..2 {
        goals[joints[k]] = standing[joints[k]] + signs[k] * dir_sign * cmd;
    }
    if let (false, Some(hips)) = (direction.is_pitch(), cfg.hip_roll) {
        for k in 0..2 {
            goals[hips[k]] = standing[hips[k]] + cfg.hip_left_sign[k] * dir_sign * cmd;
        }
    }
}

/// The onset of the fall in a run's history: the last sample at which, over the onset
/// window, the excess tilt grew by no more than `onset_ratio` times the ankle angle
/// (0 if none). The window is in time, not samples: over a bus a cycle takes what
/// the bus takes, not `period_s`.
fn find_onset(history: &[Sample], cfg: &TipoverConfig) -> usize {
    let window = cfg.onset_window_s.max(cfg.period_s);
    (1..history.len())
        .rev()
        .find(|&k| {
            // The latest sample a whole window before k (the tolerance keeps the
            // simulator's evenly spaced samples exactly `window / period_s` apart).
            let before = history[..k].partition_point(|s| s.2 <= history[k].2 - window + 1e-9);
            if before == 0 {
                return false;
            }
            let j = before - 1;
            let excess_rate = history[k].3 - history[j].3;
            let ankle_rate = history[k].1.abs() - history[j].1.abs();
            excess_rate <= cfg.onset_ratio * ankle_rate.max(0.0)
        })
        .unwrap_or(0)
}

/// The first sample of the reading window that ends at `onset`: `onset_average_s` of
/// the robot's time (`onset` itself for 0), and no earlier than the slow final
/// approach when the run has one (`slow_from_deg`; `onset` if the robot tipped before
/// it), where the ankles move a hundredth of what they do on the approach.
fn reading_window_start(history: &[Sample], onset: usize, cfg: &TipoverConfig) -> usize {
    if cfg.onset_average_s <= 0.0 {
        return onset;
    }
    let t_onset = history[onset].2;
    let window = history[..onset].partition_point(|s| s.2 < t_onset - cfg.onset_average_s);
    let creep = match cfg.slow_from_deg.map(f64::to_radians) {
        Some(a) => history[..onset].partition_point(|s| s.0 <= a),
        None => 0,
    };
    window.max(creep)
}

/// The mean measured ankle angle, excess and lean of `window`'s samples.
fn mean_reading(window: &[Sample]) -> (f64, f64, f64) {
    let k = window.len() as f64;
    let (m, e, l) = window
        .iter()
        .fold((0.0, 0.0, 0.0), |(m, e, l), s| (m + s.1, e + s.3, l + s.4));
    (m / k, e / k, l / k)
}

/// The mean posture of `flat`'s rows of `n` joint positions.
fn mean_posture(flat: &[f64], n: usize) -> Vec<f64> {
    let rows = (flat.len() / n) as f64;
    let mut mean = vec![0.0; n];
    for row in flat.chunks_exact(n) {
        for (m, q) in mean.iter_mut().zip(row) {
            *m += q / rows;
        }
    }
    mean
}

/// Trunk pitch and roll (rad; forward and left positive) predicted from joint positions
/// with the feet flat on the ground.
pub type TiltPredictor<'a> = &'a mut dyn FnMut(&[f64]) -> [f64; 2];

/// One tip-over run (seeds 000/001): from `standing`, ramp the ankles (and sideways the
/// hip rolls) in `direction` until the trunk tilts beyond what the joints explain by
/// `fall_deg`, then report the ankle angle at the onset of that excess.
pub fn run_direction<R: Robot + ?Sized>(
    robot: &mut R,
    standing: &[f64],
    direction: Direction,
    cfg: &TipoverConfig,
    mut predict: Option<TiltPredictor<'_>>,
) -> Result<TipoverResult, RobotError> {
    check_pose(standing, robot.joint_names().len())?;
    let mut st = RobotState::default();
    let mut goals = standing.to_vec();
    robot.command_positions(&goals)?;
    robot.advance(cfg.settle_s)?;
    robot.read(&mut st)?;
    let (joints, signs, dir_sign) = ankles_of(direction, cfg);
    let ankle_now = |st: &RobotState| {
        0.5 * ((st.positions[joints[0]] - standing[joints[0]]) * signs[0]
            + (st.positions[joints[1]] - standing[joints[1]]) * signs[1])
            * dir_sign
    };
    // Tilt from the IMU orientation if the robot gives one, else the integrated gyro.
    let mut gyro_tilt = 0.0;
    let tilt_now = |st: &RobotState, gyro_tilt: f64| -> Result<f64, RobotError> {
        let imu = st
            .imu
            .ok_or_else(|| RobotError::new("the tip-over experiment needs a trunk IMU"))?;
        Ok(match imu.orientation {
            Some(q) => {
                let (p, r) = tilt(q);
                if direction.is_pitch() { p } else { -r }
            }
            None => gyro_tilt,
        })
    };
    let a0 = ankle_now(&st);
    let t0_tilt = tilt_now(&st, 0.0)?;
    let lean_sign = match direction {
        Direction::Forward | Direction::Left => 1.0,
        Direction::Backward | Direction::Right => -1.0,
    };
    let mut predicted = |st: &RobotState, ankle: f64| -> f64 {
        match predict.as_mut() {
            Some(p) => {
                let t = p(&st.positions);
                if direction.is_pitch() { t[0] } else { t[1] }
            }
            None => ankle * lean_sign,
        }
    };
    let p0 = predicted(&st, 0.0);
    let t_start = robot.time();
    // History of (command, measured, time, excess) to find the onset afterwards, and
    // the joint positions of the recent past.
    let mut history: Vec<Sample> = Vec::new();
    // Joint positions of every sample, flat (one row of `n` per sample).
    let n = standing.len();
    let mut positions: Vec<f64> = Vec::with_capacity(n * 4096);
    let rate = cfg.ramp_deg_per_s.to_radians();
    // Time along the ramp: the robot's, but a cycle that took long (a host held up,
    // a bus retry) moves the command on by at most `MAX_RAMP_STEP_S`, so the servos
    // never get a jump that jolts the robot.
    let mut ramp_t = 0.0;
    let mut last = robot.time();
    loop {
        let now = robot.time();
        ramp_t += (now - last).clamp(0.0, MAX_RAMP_STEP_S);
        last = now;
        let cmd = ramp_command(cfg, rate, ramp_t);
        if cmd > cfg.max_deg.to_radians() {
            return Err(RobotError::new(format!(
                "no fall {} within {} deg of ankle command",
                direction.name(),
                cfg.max_deg
            )));
        }
        lean_goals(&mut goals, standing, direction, cfg, cmd);
        robot.command_positions(&goals)?;
        robot.advance(cfg.period_s)?;
        robot.read(&mut st)?;
        if st.imu.is_some_and(|i| i.orientation.is_none()) {
            let g = st.imu.map(|i| i.gyro).unwrap_or_default();
            gyro_tilt += cfg.period_s * if direction.is_pitch() { g[1] } else { -g[0] };
        }
        let ankle = ankle_now(&st) - a0;
        // A robot found lying down fell between two readings: the history so far
        // holds the onset; this reading's lean-direction tilt means nothing.
        let fallen = lying_down(&st);
        let mut excess = f64::INFINITY;
        if !fallen {
            // Tilt beyond what the joints explain, in the lean direction.
            let body = tilt_now(&st, gyro_tilt)? - t0_tilt;
            let expect = predicted(&st, ankle) - p0;
            excess = (body - expect) * lean_sign;
            history.push((cmd, ankle, robot.time() - t_start, excess, body * lean_sign));
            positions.extend_from_slice(&st.positions[..n]);
        }
        if excess > cfg.fall_deg.to_radians() {
            let fall_confirmed_s = robot.time() - t_start;
            return result_at_onset(&history, &positions, n, direction, cfg, fall_confirmed_s);
        }
    }
}

fn check_pose(standing: &[f64], joints: usize) -> Result<(), RobotError> {
    if standing.len() != joints {
        return Err(RobotError::new(format!(
            "the standing pose has {} joints, the robot {joints}",
            standing.len(),
        )));
    }
    Ok(())
}

/// The trunk more than [`FALLEN_TILT_DEG`] from the vertical.
fn lying_down(st: &RobotState) -> bool {
    st.imu
        .and_then(|i| i.orientation)
        .is_some_and(|q| tilt_from_vertical(q) > FALLEN_TILT_DEG.to_radians())
}

/// The run's result once the fall is confirmed: the onset found in `history`, the
/// readings averaged over the window before it (`positions`: `n` joints per sample).
fn result_at_onset(
    history: &[Sample],
    positions: &[f64],
    n: usize,
    direction: Direction,
    cfg: &TipoverConfig,
    fall_confirmed_s: f64,
) -> Result<TipoverResult, RobotError> {
    if history.is_empty() {
        return Err(RobotError::new(format!(
            "{} run: the robot was lying down (trunk over {FALLEN_TILT_DEG} deg from \
             the vertical) at its first reading",
            direction.name()
        )));
    }
    let onset = find_onset(history, cfg);
    let (c, _, t, _, _) = history[onset];
    let from = reading_window_start(history, onset, cfg);
    let (m, e, lean) = mean_reading(&history[from..=onset]);
    let measured_deg = m.abs().to_degrees();
    // The command never exceeds max_deg: an ankle reading far beyond it is a
    // robot (or a simulation) gone unstable, not a tip angle to estimate from.
    if measured_deg.is_nan() || measured_deg > cfg.max_deg {
        return Err(RobotError::new(format!(
            "{} run: the ankles read {measured_deg:.1} deg at the onset of the fall, \
             beyond the {} deg the ramp may command: the robot (or the simulation) \
             went unstable",
            direction.name(),
            cfg.max_deg
        )));
    }
    Ok(TipoverResult {
        direction,
        commanded_deg: c.to_degrees(),
        measured_deg,
        time_s: t,
        excess_deg: e.to_degrees(),
        lean_deg: lean.to_degrees(),
        fall_confirmed_s,
        positions_at_onset: mean_posture(&positions[from * n..(onset + 1) * n], n),
    })
}

/// Run the four directions; `reset` puts the robot back standing in `standing` before
/// each (the simulator re-places itself; a real robot waits for a person).
pub fn run_tipover<R: Robot + ?Sized>(
    robot: &mut R,
    standing: &[f64],
    cfg: &TipoverConfig,
    reset: &mut dyn FnMut(&mut R) -> Result<(), RobotError>,
    mut predict: Option<TiltPredictor<'_>>,
) -> Result<Vec<TipoverResult>, RobotError> {
    let mut out = Vec::with_capacity(4);
    for d in Direction::ALL {
        reset(robot)?;
        let p: Option<TiltPredictor<'_>> = match predict.as_mut() {
            Some(p) => Some(&mut **p),
            None => None,
        };
        out.push(run_direction(robot, standing, d, cfg, p)?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use twinloop_robot::Imu;

    /// Four ankle joints that follow their goals, until `blow_up_s`, when the readings
    /// jump to 1000 rad and the trunk pitches 0.2 rad: a simulation gone unstable.
    struct BlowsUp {
        names: Vec<String>,
        goals: Vec<f64>,
        time: f64,
        blow_up_s: f64,
    }

    impl Robot for BlowsUp {
        fn joint_names(&self) -> &[String] {
            &self.names
        }
        fn time(&self) -> f64 {
            self.time
        }
        fn read(&mut self, st: &mut RobotState) -> Result<(), RobotError> {
            let broken = self.time >= self.blow_up_s;
            st.time = self.time;
            st.positions = if broken {
                vec![1e3; 4]
            } else {
                self.goals.clone()
            };
            let pitch: f64 = if broken { 0.2 } else { 0.0 };
            st.imu = Some(Imu {
                orientation: Some([0.0, (pitch / 2.0).sin(), 0.0, (pitch / 2.0).cos()]),
                ..Default::default()
            });
            Ok(())
        }
        fn command_positions(&mut self, goals: &[f64]) -> Result<(), RobotError> {
            self.goals.copy_from_slice(goals);
            Ok(())
        }
        fn advance(&mut self, dt: f64) -> Result<(), RobotError> {
            self.time += dt;
            Ok(())
        }
    }

    #[test]
    fn an_unstable_robot_is_an_error_not_a_tip_angle() {
        let mut robot = BlowsUp {
            names: ["lp", "rp", "lr", "rr"].map(String::from).to_vec(),
            goals: vec![0.0; 4],
            time: 0.0,
            blow_up_s: 2.0,
        };
        let cfg = TipoverConfig::new([0, 1], [2, 3], [1.0, 1.0], [1.0, 1.0]);
        let mut flat = |_: &[f64]| [0.0, 0.0];
        let e = run_direction(
            &mut robot,
            &[0.0; 4],
            Direction::Forward,
            &cfg,
            Some(&mut flat),
        )
        .unwrap_err();
        assert!(
            e.message
                .starts_with("forward run: the ankles read 57295.8 deg"),
            "{e}"
        );
        assert!(e.message.contains("went unstable"), "{e}");
        // Without the blow-up, a trunk that leaves the model's prediction once the
        // ankles pass 0.02 rad tips there: an ordinary angle, not an error.
        robot.blow_up_s = f64::INFINITY;
        robot.time = 0.0;
        let mut tips = |q: &[f64]| [if q[0] > 0.02 { -0.2 } else { 0.0 }, 0.0];
        let r = run_direction(
            &mut robot,
            &[0.0; 4],
            Direction::Forward,
            &cfg,
            Some(&mut tips),
        )
        .unwrap();
        assert!(
            (r.measured_deg - 0.02f64.to_degrees()).abs() < 0.05,
            "{r:?}"
        );
    }

    /// Ankles that follow their goals and a trunk that leans with them, until the
    /// ankles pass `fall_at` rad: from then the trunk lies 115 deg from the vertical
    /// (a fall the host did not see, held up between two readings).
    struct FallsUnseen {
        names: Vec<String>,
        goals: Vec<f64>,
        time: f64,
        fall_at: f64,
        pitch_lying: f64,
    }

    impl Robot for FallsUnseen {
        fn joint_names(&self) -> &[String] {
            &self.names
        }
        fn time(&self) -> f64 {
            self.time
        }
        fn read(&mut self, st: &mut RobotState) -> Result<(), RobotError> {
            st.time = self.time;
            st.positions = self.goals.clone();
            let pitch = if self.goals[0] > self.fall_at {
                self.pitch_lying
            } else {
                self.goals[0]
            };
            st.imu = Some(Imu {
                orientation: Some([0.0, (pitch / 2.0).sin(), 0.0, (pitch / 2.0).cos()]),
                ..Default::default()
            });
            Ok(())
        }
        fn command_positions(&mut self, goals: &[f64]) -> Result<(), RobotError> {
            self.goals.copy_from_slice(goals);
            Ok(())
        }
        fn advance(&mut self, dt: f64) -> Result<(), RobotError> {
            self.time += dt;
            Ok(())
        }
    }

    /// A robot first seen lying down fell between two readings: the run ends there
    /// with the onset from the readings before, whichever way the lying trunk's
    /// pitch reads (past 90 deg it flips sign, which once entered the history as a
    /// -61 deg feet roll and a run that never saw its fall).
    #[test]
    fn a_fall_between_two_readings_ends_the_run_at_the_readings_before() {
        let cfg = TipoverConfig::new([0, 1], [2, 3], [1.0, 1.0], [1.0, 1.0]);
        for pitch_lying in [2.0, -2.0, std::f64::consts::PI] {
            let mut robot = FallsUnseen {
                names: ["lp", "rp", "lr", "rr"].map(String::from).to_vec(),
                goals: vec![0.0; 4],
                time: 0.0,
                fall_at: 0.1,
                pitch_lying,
            };
            let mut leans_with_the_ankles = |q: &[f64]| [q[0], 0.0];
            let r = run_direction(
                &mut robot,
                &[0.0; 4],
                Direction::Forward,
                &cfg,
                Some(&mut leans_with_the_ankles),
            )
            .unwrap();
            assert!(
                (r.measured_deg - 0.1f64.to_degrees()).abs() < 0.1,
                "{pitch_lying}: {r:?}"
            );
            assert!(r.excess_deg.abs() < 1e-9, "{pitch_lying}: {r:?}");
        }
        assert!((tilt_from_vertical([0.0, 0.0, 0.0, 1.0])).abs() < 1e-12);
        let q = |a: f64| {
            [
                (a / 2.0).sin() * 0.6,
                (a / 2.0).sin() * 0.8,
                0.0,
                (a / 2.0).cos(),
            ]
        };
        for a in [0.3, 1.2, 2.5] {
            assert!((tilt_from_vertical(q(a)) - a).abs() < 1e-12);
        }
    }

    /// A reading that flips between two whole counts as the robot rocks: the onset's
    /// sample reads whichever count it lands on; the window's mean reads the value
    /// the flips dither around (here a known 0.4 of the way between the counts).
    #[test]
    fn the_windowed_reading_sees_between_the_counts() {
        let count = 0.29_f64.to_radians();
        let truth = 40.4 * count;
        let period = 0.029;
        // 2 s of samples; each reads the count below or above the truth, above with
        // probability 0.4, spread evenly (a deterministic low-discrepancy sequence).
        let history: Vec<Sample> = (0..69)
            .map(|k| {
                let up = ((k as f64 * 0.618_034).fract()) < 0.4;
                let m = if up { 41.0 * count } else { 40.0 * count };
                (k as f64 * 0.01, m, k as f64 * period, 0.0, 0.0)
            })
            .collect();
        let onset = history.len() - 1;
        let mut cfg = TipoverConfig::new([0, 1], [2, 3], [1.0, 1.0], [1.0, 1.0]);
        let one = reading_window_start(&history, onset, &cfg);
        assert_eq!(one, onset);
        cfg.onset_average_s = 1.0;
        let from = reading_window_start(&history, onset, &cfg);
        // 1 s of robot time at 29 ms a cycle: 35 samples up to and with the onset.
        assert_eq!(onset - from + 1, 35);
        let (m, _, _) = mean_reading(&history[from..=onset]);
        assert!(
            (m - truth).abs() < 0.05 * count,
            "mean {:.3} counts, truth 40.4",
            m / count
        );
        // With a slow final approach past the 60th sample's command, the window keeps
        // to the creep (the fast approach before it would drag the mean back).
        cfg.slow_from_deg = Some(history[59].0.to_degrees());
        assert_eq!(reading_window_start(&history, onset, &cfg), 60);
        // A creep that began before the window leaves the window as it was.
        cfg.slow_from_deg = Some(history[10].0.to_degrees());
        assert_eq!(reading_window_start(&history, onset, &cfg), from);
        cfg.slow_from_deg = None;
        assert_eq!(reading_window_start(&history, onset, &cfg), from);
        // The posture is averaged over the same samples.
        let flat: Vec<f64> = history[from..=onset]
            .iter()
            .flat_map(|s| [s.1, 2.0 * s.1])
            .collect();
        let q = mean_posture(&flat, 2);
        assert!((q[0] - m).abs() < 1e-12 && (q[1] - 2.0 * m).abs() < 1e-12);
        assert!((q[0] - truth).abs() < 0.05 * count && (q[1] - 2.0 * truth).abs() < 0.1 * count);
    }
}
