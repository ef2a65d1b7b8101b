//! Seed 003 section 7's identification experiment, run on `lab17` in the simulator.
//!
//! The robot stands on the ground on seed 003's two-loop servos (a speed loop inside a
//! position loop, section 3 and Fig. 20; LD-2015 ratings, position gain
//! [`LD2015_KP_POSITION`], gear friction [`LD2015_GEAR_FRICTION`]), settles at its
//! trims, then walks the sequence of [`twinloop_gait::sequence`] (4 s cycles, 40 ms ticks) at
//! the seed's full offsets. [`DatasetOptions::skip_samples`] starts the record later in
//! the same walk, for a validation run that is a different stretch of it. Each tick,
//! as the seed's Arduino loop does, it first reads both gyroscopes, then sets the
//! servo goals of that tick:
//! - inputs: the ten offsets of eq 6, Delta theta = theta_C - theta_TRIM, servo
//!   degrees (`u:<joint>`);
//! - outputs: the roll, pitch and yaw rates of the left and right foot
//!   (`gyro:l_foot.roll` .. `gyro:r_foot.yaw`), deg/s, each from an MPU-6050 on the
//!   foot: quantised at 131 LSB per deg/s (eq 7) with white noise of the chip's
//!   datasheet level (0.05 deg/s rms). The left gyro is the simulator's IMU; the right
//!   one is read from the simulator state (`Simulator::link_angular_velocity`) and
//!   quantised and disturbed the same way.

use crate::error::ExperimentError;
use twinloop_description::Description;
use twinloop_description::builtin::servo::LD2015;
use twinloop_gait::sequence::{
    JointGoals, OFFSET_JOINTS, SequenceOptions, walking_sequence_samples,
};
use twinloop_random::SplitMix64;
use twinloop_robot::RobotState;
use twinloop_sim::sensors::MPU6050_GYRO_LSB_PER_DEG_S;
use twinloop_sim::{Actuator, SimConfig, Simulator, TwoLoopServo, quantize};

/// The feet carrying the gyroscopes: left (address 0x68) and right (0x69), seed 003.
pub const FEET: [&str; 2] = ["l_foot", "r_foot"];
/// Roll, pitch, yaw: the foot frame's x (forward), y (left), z (up) rates.
pub const AXES: [&str; 3] = ["roll", "pitch", "yaw"];

/// MPU-6050 datasheet (PS-MPU-6000A rev 3.4, gyroscope "total RMS noise", DLPF at
/// 100 Hz): 0.05 deg/s rms.
pub const MPU6050_GYRO_NOISE_DEG_S: f64 = 0.05;

/// How to record the walk.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DatasetOptions {
    pub sequence: SequenceOptions,
    /// Samples to record (seed 003: 1000).
    pub samples: usize,
    /// Gyro noise, deg/s rms (0 = none).
    pub gyro_noise_deg_s: f64,
    /// Seed of the noise.
    pub noise_seed: u64,
    /// Ticks walked before the first recorded sample (the walk goes on seamlessly):
    /// a validation record that is a genuinely different run of the same walk, e.g.
    /// cycles 11-20 instead of 1-10 (other slips, other heading, other noise).
    pub skip_samples: usize,
    /// Time standing at the trims before the first sample, s.
    pub settle: f64,
    /// Simulator step, s.
    pub dt: f64,
    /// Two-loop servo position gain, 1/s.
    pub kp_position: f64,
}

impl Default for DatasetOptions {
    fn default() -> Self {
        DatasetOptions {
            sequence: SequenceOptions::default(),
            samples: twinloop_gait::sequence::SEED_SAMPLES,
            gyro_noise_deg_s: MPU6050_GYRO_NOISE_DEG_S,
            noise_seed: 1,
            skip_samples: 0,
            settle: 1.0,
            dt: 1e-3,
            kp_position: LD2015_KP_POSITION,
        }
    }
}

/// Position-loop gain of the LD-2015, 1/s. A digital hobby servo drives its motor at
/// full duty beyond a few degrees of error; with the no-load speed of
/// [`LD2015`] (6.5 rad/s) a gain of 60 1/s reaches full speed at 6 degrees. A 60 degree
/// step then runs at full speed for ~130 ms and settles on a 17 ms time constant, about
/// 200 ms in all without overshoot: the seed's measured servo steps (section 4, Figs.
/// 25-30). The former 20 1/s (full speed only beyond 19 degrees) made every joint so
/// soft (5 N m/rad) that the stance leg sagged under the body and the 20 1/s tail alone
/// took 200 ms.
pub const LD2015_KP_POSITION: f64 = 60.0;

/// Coulomb friction of the LD-2015 gear train at the output, N m: 3 % of its stall
/// torque. A ~250:1 metal spur-gear train is barely back-drivable; this is an ASSUMED
/// round figure (no datasheet gives it). It is what keeps the body from rocking on in
/// the servos' dead time between weight shifts.
pub const LD2015_GEAR_FRICTION: f64 = 0.05;

/// The two-loop servo of seed 003 (section 3, Fig. 20) with LD-2015 ratings: the
/// speed loop's gain is the motor's own stall torque over no-load speed (the slope of
/// its torque-speed line, so full speed error is full torque), the position gain
/// `kp_position` ([`LD2015_KP_POSITION`] by default).
pub fn ld2015_two_loop(kp_position: f64) -> TwoLoopServo {
    TwoLoopServo {
        kp_position,
        kv: LD2015.stall_torque / LD2015.no_load_speed,
        max_speed: LD2015.no_load_speed,
        max_torque: LD2015.stall_torque,
    }
}

/// A recorded walk.
#[derive(Debug, Clone, PartialEq)]
pub struct WalkDataset {
    /// `t`, `u:<joint>` (10), `gyro:<foot>.<axis>` (6).
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
    /// Largest trunk tilt from upright over the record, degrees.
    pub max_tilt_deg: f64,
    /// Time (s from the start of the walk, skipped ticks included) the trunk first
    /// tilted past 45 degrees.
    pub fell_at: Option<f64>,
    /// Forward (x, the heading the robot starts the walk with) and sideways (y) travel
    /// of the trunk over the record, m.
    pub travel: [f64; 2],
    /// Trunk yaw change over the record, degrees.
    pub yaw_deg: f64,
}

fn trunk_pose(sim: &mut Simulator) -> Result<([f64; 3], f64, f64), ExperimentError> {
    let base = sim.model.base_link.clone();
    let x = sim
        .link_placement(&base)
        .ok_or_else(|| ExperimentError(format!("robot: no base link \"{base}\"")))?;
    let r = x.rotation;
    let tilt = r[(2, 2)].clamp(-1.0, 1.0).acos().to_degrees();
    let yaw = r[(1, 0)].atan2(r[(0, 0)]).to_degrees();
    Ok((
        [x.translation.x, x.translation.y, x.translation.z],
        tilt,
        yaw,
    ))
}

/// The option checks of [`record_walk`]; the error names the option.
fn check_options(o: &DatasetOptions) -> Result<(), ExperimentError> {
    if o.samples == 0 {
        return Err(ExperimentError("samples must be at least 1".into()));
    }
    if !(o.gyro_noise_deg_s.is_finite() && o.gyro_noise_deg_s >= 0.0) {
        return Err(ExperimentError(format!(
            "gyro_noise must be a non-negative number of deg/s, got {}",
            o.gyro_noise_deg_s
        )));
    }
    if !(o.settle.is_finite() && o.settle >= 0.0) {
        return Err(ExperimentError(format!(
            "settle must be a non-negative number of seconds, got {}",
            o.settle
        )));
    }
    if !(o.dt.is_finite() && o.dt > 0.0 && o.dt <= o.sequence.sample_time) {
        return Err(ExperimentError(format!(
            "dt must be positive and at most the sample time {} s, got {}",
            o.sequence.sample_time, o.dt
        )));
    }
    if !(o.kp_position.is_finite() && o.kp_position > 0.0) {
        return Err(ExperimentError(format!(
            "kp_position must be positive, got {}",
            o.kp_position
        )));
    }
    Ok(())
}

fn sim_err(e: twinloop_sim::SimError) -> ExperimentError {
    ExperimentError(format!("simulator: {e}"))
}

/// The simulator's joint index of each of the sequence's joints; errors if the robot
/// lacks one or a foot link for a gyroscope.
fn sequence_joints(
    robot: &Description,
    sim: &Simulator,
    goals: &JointGoals,
) -> Result<Vec<usize>, ExperimentError> {
    let mut map = Vec::with_capacity(goals.joints.len());
    for j in &goals.joints {
        map.push(sim.joint_index(j).ok_or_else(|| {
            ExperimentError(format!(
                "robot: \"{}\" has no joint \"{j}\"; the walking sequence of seed 003 is defined \
                 for builtin:lab17",
                robot.name
            ))
        })?);
    }
    for f in FEET {
        if !sim.model.links.iter().any(|l| l.name == f) {
            return Err(ExperimentError(format!(
                "robot: \"{}\" has no link \"{f}\" to carry a foot gyroscope",
                robot.name
            )));
        }
    }
    Ok(map)
}

/// Every joint an LD-2015 two-loop servo with its gear train's friction; the robot on
/// the ground at the sequence's first goals; the left foot's gyro the simulator's IMU
/// (quantised, with the noise).
fn prepare_lab17(
    sim: &mut Simulator,
    o: &DatasetOptions,
    goals: &JointGoals,
    map: &[usize],
) -> Result<(), ExperimentError> {
    let servo = ld2015_two_loop(o.kp_position);
    for a in sim.actuators.iter_mut() {
        *a = Actuator::TwoLoop(servo);
    }
    for f in sim.joint_friction.iter_mut() {
        *f = LD2015_GEAR_FRICTION;
    }
    let n = sim.model.nbodies;
    let mut q0 = vec![0.0; n];
    for (k, &i) in map.iter().enumerate() {
        q0[i] = goals.goals[0][k];
    }
    sim.place_on_ground(&q0).map_err(sim_err)?;
    let left = sim
        .model
        .links
        .iter()
        .position(|l| l.name == FEET[0])
        .expect("checked");
    let s = sim.sensors_mut();
    s.imu_link = left;
    s.imu_quantize = true;
    s.gyro_noise = o.gyro_noise_deg_s.to_radians();
    s.set_noise_seed(o.noise_seed ^ 0x0068);
    Ok(())
}

/// `t`, the ten offsets `u:<joint>`, the six rates `gyro:<foot>.<axis>`.
fn dataset_columns() -> Vec<String> {
    let mut columns = vec!["t".to_string()];
    columns.extend(OFFSET_JOINTS.iter().map(|j| format!("u:{j}")));
    for f in FEET {
        columns.extend(AXES.iter().map(|a| format!("gyro:{f}.{a}")));
    }
    columns
}

/// An angle difference brought into (-180, 180] degrees.
fn wrap_degrees(mut d: f64) -> f64 {
    if d > 180.0 {
        d -= 360.0;
    } else if d < -180.0 {
        d += 360.0;
    }
    d
}

/// The right foot's MPU-6050, read from the simulator state: the foot's angular
/// velocity with white noise, quantised at its LSB (seed 003 eq 7).
struct RightGyro {
    noise: SplitMix64,
    noise_rad: f64,
    lsb: f64,
}

impl RightGyro {
    fn new(o: &DatasetOptions) -> RightGyro {
        RightGyro {
            noise: SplitMix64(o.noise_seed ^ 0x0069_0000_0000_0069),
            noise_rad: o.gyro_noise_deg_s.to_radians(),
            lsb: (1.0 / MPU6050_GYRO_LSB_PER_DEG_S).to_radians(),
        }
    }

    /// Appends the roll, pitch and yaw rates, deg/s.
    fn read(&mut self, sim: &mut Simulator, row: &mut Vec<f64>) {
        let wr = sim.link_angular_velocity(FEET[1]).expect("checked");
        for a in 0..3 {
            let w = wr[a] + self.noise_rad * self.noise.normal();
            row.push(quantize(w, self.lsb).to_degrees());
        }
    }
}

/// Seed 003 section 7: walk `robot` (lab17) through the sequence in the simulator and
/// record the identification data.
pub fn record_walk(
    robot: &Description,
    o: &DatasetOptions,
) -> Result<WalkDataset, ExperimentError> {
    check_options(o)?;
    let total = o.samples.checked_add(o.skip_samples).ok_or_else(|| {
        ExperimentError(format!(
            "skip_samples {} plus samples {} overflow",
            o.skip_samples, o.samples
        ))
    })?;
    let goals: JointGoals = walking_sequence_samples(&o.sequence, total)?;
    let mut sim = Simulator::new(
        robot,
        SimConfig {
            dt: o.dt,
            ..Default::default()
        },
    )
    .map_err(sim_err)?;
    let map = sequence_joints(robot, &sim, &goals)?;
    prepare_lab17(&mut sim, o, &goals, &map)?;
    let mut right_gyro = RightGyro::new(o);
    sim.run(o.settle).map_err(sim_err)?;

    let columns = dataset_columns();
    let steps = (o.sequence.sample_time / o.dt).round().max(1.0) as usize;
    let (mut p0, _, mut yaw0) = trunk_pose(&mut sim)?;
    let mut max_tilt: f64 = 0.0;
    let mut fell_at = None;
    let mut state = RobotState::default();
    let mut rows = Vec::with_capacity(o.samples);
    for k in 0..total {
        let record = k >= o.skip_samples;
        if k == o.skip_samples {
            (p0, _, yaw0) = trunk_pose(&mut sim)?;
        }
        if record {
            // Read both gyros (the state after the previous tick's goals) ...
            sim.read_sensors(&mut state);
            let gl = state.imu.as_ref().expect("the simulator has an IMU").gyro;
            let mut row = Vec::with_capacity(columns.len());
            row.push(goals.times[k]);
            row.extend_from_slice(&goals.offsets_deg[k]);
            row.extend(gl.iter().map(|w| w.to_degrees()));
            right_gyro.read(&mut sim, &mut row);
            rows.push(row);
        }
        // ... then command this tick's goals and let the servos work for one tick.
        for (j, &i) in map.iter().enumerate() {
            sim.goals[i] = goals.goals[k][j];
        }
        for _ in 0..steps {
            sim.step().map_err(sim_err)?;
        }
        let (_, tilt, _) = trunk_pose(&mut sim)?;
        if record {
            max_tilt = max_tilt.max(tilt);
        }
        if tilt > 45.0 && fell_at.is_none() {
            fell_at = Some(goals.times[k]);
        }
    }
    let (p1, _, yaw1) = trunk_pose(&mut sim)?;
    Ok(WalkDataset {
        columns,
        rows,
        max_tilt_deg: max_tilt,
        fell_at,
        travel: [p1[0] - p0[0], p1[1] - p0[1]],
        yaw_deg: wrap_degrees(yaw1 - yaw0),
    })
}
