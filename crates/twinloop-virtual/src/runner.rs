//! The simulator thread: apply the servos' registers, step, publish, and keep
//! simulated time on the wall clock.

use crate::drive::{DriveRegisters, servo_with_registers};
use crate::shared::{Shared, Snapshot, thermal_step};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};
use twinloop_sim::{Actuator, DynamixelServo, SimError, Simulator};

/// At most this many steps between two looks at the registers and two snapshots,
/// so a host's command takes effect within a few milliseconds even when the
/// simulator is catching up.
const MAX_BATCH: usize = 8;
/// Time constant of the IMU's analogue low-pass, s (about 16 Hz): a MEMS gyro and
/// accelerometer read through RC filters do not pass the contact's high-frequency
/// chatter, which sampled at the bus's rate would alias into jumps of a whole m/s^2.
/// The figure is ours, not from a board's datasheet.
pub const IMU_TIME_CONSTANT_S: f64 = 0.01;

/// Trunk tilt at which the virtual operator catches a falling robot, deg: well past
/// any tip (the host has seen the fall by then), before anything but the feet can
/// touch the floor.
pub const CATCH_DEG: f64 = 30.0;

/// Lagging more than this, the simulator stops chasing the wall clock (it runs as
/// fast as it can from there) and counts the time it dropped.
const MAX_LAG_S: f64 = 0.1;

/// How the simulation is doing.
#[derive(Debug, Clone, PartialEq)]
pub struct SimStatus {
    /// Simulated time, s.
    pub time: f64,
    pub steps: u64,
    /// Wall-clock time the simulation could not keep up with, s.
    pub behind_s: f64,
    pub error: Option<String>,
}

/// One servo of the bus tied to a joint of the simulator.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ServoJoint {
    /// Joint index in the simulator's model.
    pub joint: usize,
    /// servo angle = zero + direction * joint angle (the mapping's rule).
    pub zero: f64,
    pub direction: f64,
    /// The joint's servo from its datasheet (factory registers).
    pub base: DynamixelServo,
    /// Stall torque of the bus-side model over the simulated one: Present Load is
    /// torque over stall torque of the simulated servo, and the bus divides by its
    /// model's figure.
    pub torque_scale: f64,
    /// Supply voltage, V.
    pub voltage: f64,
}

pub(crate) struct Runner {
    pub sim: Simulator,
    pub servos: Vec<ServoJoint>,
    pub shared: Arc<Shared>,
    pub realtime_factor: f64,
    /// See [`crate::VirtualRobotOptions::catch_falls`].
    pub catch_falls: bool,
    /// See [`crate::VirtualRobotOptions::tether_s`].
    pub tether_s: Option<f64>,
    /// Times the operator caught the robot.
    pub pick_ups: u64,
    /// Joint pose the operator stands the robot in (sized once).
    pose: Vec<f64>,
    /// The IMU's gyro and accelerometer after its low-pass ([`IMU_TIME_CONSTANT_S`]),
    /// updated every step, and the state it is read into (sized once).
    imu_lp: Option<[f64; 6]>,
    /// Whether a board reads the IMU over the bus (only then is it filtered: the
    /// filter reads the sensors every step).
    pub imu_on_bus: bool,
    sensed: twinloop_robot::RobotState,
    regs: Vec<DriveRegisters>,
    /// Goal after the Moving Speed limit, servo angle.
    profile: Vec<f64>,
    temperature: Vec<f64>,
    snap: Snapshot,
    behind_s: f64,
}

impl Runner {
    pub fn new(
        sim: Simulator,
        servos: Vec<ServoJoint>,
        shared: Arc<Shared>,
        realtime_factor: f64,
    ) -> Runner {
        let n = servos.len();
        let regs = shared
            .registers
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone();
        let mut r = Runner {
            regs,
            profile: vec![0.0; n],
            temperature: vec![crate::shared::AMBIENT_C; n],
            snap: Snapshot {
                servos: vec![
                    twinloop_link::servo::ServoMeasurement {
                        position: 0.0,
                        velocity: 0.0,
                        torque: 0.0,
                        voltage: 0.0,
                        temperature: 0.0,
                    };
                    n
                ],
                ..Snapshot::default()
            },
            sim,
            servos,
            shared,
            realtime_factor,
            catch_falls: false,
            tether_s: None,
            pick_ups: 0,
            pose: Vec::new(),
            imu_lp: None,
            imu_on_bus: false,
            sensed: twinloop_robot::RobotState::default(),
            behind_s: 0.0,
        };
        r.pose = vec![0.0; r.sim.model.nbodies];
        for k in 0..n {
            r.profile[k] = r.servo_angle(k);
        }
        r
    }

    fn servo_angle(&self, k: usize) -> f64 {
        let s = &self.servos[k];
        s.zero + s.direction * self.sim.q[self.sim.model.q_offset + s.joint]
    }

    /// Copy the registers the bus thread wrote.
    pub fn take_registers(&mut self) {
        let r = self
            .shared
            .registers
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        self.regs.copy_from_slice(&r);
    }

    /// One time step with the registers last taken.
    pub fn step(&mut self) -> Result<(), SimError> {
        let dt = self.sim.dt();
        for k in 0..self.servos.len() {
            let s = self.servos[k];
            let r = &self.regs[k];
            let now = self.servo_angle(k);
            if !r.torque_on {
                // Limp: the joint is free; the profile waits where the servo is.
                self.profile[k] = now;
                self.sim.actuators[s.joint] = Actuator::Passive;
                continue;
            }
            // Moving Speed: the servo heads for its goal no faster than that (a
            // full-model servo's firmware runs its own profile).
            self.profile[k] = if r.moving_speed > 0.0 && s.base.full.is_none() {
                let d = r.moving_speed * dt;
                self.profile[k] + (r.goal - self.profile[k]).clamp(-d, d)
            } else {
                r.goal
            };
            let ccw = self.profile[k] > now;
            self.sim.actuators[s.joint] =
                Actuator::Dynamixel(servo_with_registers(&s.base, r, ccw));
            self.sim.goals[s.joint] = s.direction * (self.profile[k] - s.zero);
        }
        self.sim.step()?;
        if self.imu_on_bus {
            self.filter_imu();
        }
        for (k, s) in self.servos.iter().enumerate() {
            let load = self.sim.applied[s.joint] / s.base.stall_torque;
            self.temperature[k] = thermal_step(self.temperature[k], load, dt);
        }
        Ok(())
    }

    /// One step of the IMU's low-pass.
    fn filter_imu(&mut self) {
        self.sim.read_sensors(&mut self.sensed);
        let Some(imu) = self.sensed.imu else {
            return;
        };
        let x = [
            imu.gyro[0],
            imu.gyro[1],
            imu.gyro[2],
            imu.accel[0],
            imu.accel[1],
            imu.accel[2],
        ];
        let a = self.sim.dt() / (IMU_TIME_CONSTANT_S + self.sim.dt());
        let y = self.imu_lp.get_or_insert(x);
        for i in 0..6 {
            y[i] += a * (x[i] - y[i]);
        }
    }

    /// Measure and hand the snapshot to the bus.
    pub fn publish(&mut self) {
        self.sim.read_sensors(&mut self.snap.state);
        if let (Some(imu), Some(y)) = (self.snap.state.imu.as_mut(), self.imu_lp) {
            imu.gyro = [y[0], y[1], y[2]];
            imu.accel = [y[3], y[4], y[5]];
        }
        let vo = self.sim.model.v_offset;
        for (k, s) in self.servos.iter().enumerate() {
            let m = &mut self.snap.servos[k];
            // The angle the servo senses: its sensing delay ago for a full model.
            m.position = s.zero + s.direction * self.sim.sensed_joint_angle(s.joint);
            m.velocity = s.direction * self.sim.v[vo + s.joint];
            m.torque = s.direction * self.sim.applied[s.joint] * s.torque_scale;
            m.voltage = s.voltage;
            m.temperature = self.temperature[k];
        }
        self.snap.time = self.sim.time;
        self.snap.q.clone_from(&self.sim.q);
        self.snap.base_height = if self.sim.model.is_floating() {
            self.sim.q[2]
        } else {
            0.0
        };
        self.snap.behind_s = self.behind_s;
        let mut out = self
            .shared
            .snapshot
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        out.copy_from(&self.snap);
    }

    /// The virtual operator (see [`crate::VirtualRobotOptions::catch_falls`]): if
    /// the trunk tilts beyond [`CATCH_DEG`], stand the robot up. The pose is the
    /// servos' commanded one, so the robot lands in the posture its host holds and
    /// does not jump when the servos take over.
    pub(crate) fn operator(&mut self) -> Result<(), SimError> {
        if !self.catch_falls || !self.sim.model.is_floating() {
            return Ok(());
        }
        // The trunk's up axis against the world's: z of the base's z axis.
        let (x, y) = (self.sim.q[3], self.sim.q[4]);
        if 1.0 - 2.0 * (x * x + y * y) > CATCH_DEG.to_radians().cos() {
            return Ok(());
        }
        for i in 0..self.pose.len() {
            let m = &self.sim.model;
            self.pose[i] = self.sim.goals[i].clamp(m.lower_limits[i], m.upper_limits[i]);
        }
        let pose = std::mem::take(&mut self.pose);
        let placed = self.sim.place_on_ground(&pose);
        self.pose = pose;
        placed?;
        for k in 0..self.servos.len() {
            self.profile[k] = self.servo_angle(k);
        }
        self.pick_ups += 1;
        // Held still in the operator's hands: the IMU settles.
        self.imu_lp = None;
        Ok(())
    }

    fn fail(&mut self, e: SimError) {
        self.snap.error = Some(e.to_string());
        self.publish();
    }

    /// Run until told to stop, simulated time following the wall clock (times
    /// `realtime_factor`).
    pub fn run(mut self) -> Simulator {
        let dt = self.sim.dt();
        let factor = self.realtime_factor.max(1e-6);
        let start = Instant::now();
        let t0 = self.sim.time;
        // Wall-clock seconds given up after falling too far behind.
        let mut dropped = 0.0;
        while !self.shared.stop.load(Ordering::Relaxed) {
            if self.snap.error.is_some() {
                std::thread::sleep(Duration::from_millis(10));
                continue;
            }
            if let Some(t) = self.tether_s
                && self.shared.silence_s() > t
            {
                // Held: the wall clock runs on without the robot.
                let pause = Instant::now();
                std::thread::sleep(Duration::from_millis(1));
                dropped += pause.elapsed().as_secs_f64();
                continue;
            }
            self.take_registers();
            let wall = start.elapsed().as_secs_f64() - dropped;
            let target = t0 + wall * factor;
            let mut n = 0;
            while self.sim.time + 0.5 * dt < target && n < MAX_BATCH {
                if let Err(e) = self.step() {
                    self.fail(e);
                    break;
                }
                self.snap.steps += 1;
                n += 1;
            }
            if n > 0
                && let Err(e) = self.operator()
            {
                self.fail(e);
            }
            let lag = target - self.sim.time;
            if lag > MAX_LAG_S {
                dropped += lag / factor;
                self.behind_s += lag;
            }
            if n > 0 {
                self.publish();
            }
            let due = (self.sim.time + dt - t0) / factor + dropped;
            let left = due - start.elapsed().as_secs_f64();
            if left > 0.0 {
                std::thread::sleep(Duration::from_secs_f64(left));
            }
        }
        self.sim
    }
}
