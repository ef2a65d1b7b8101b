//! The full servo model of a parameter file on a joint: the equations of
//! `twinloop-actuator`'s bench (docs/servo-models.md), through the same code where
//! they are per servo: the bus delay and the sensing delay ([`Samples`]), the
//! firmware's cycle on encoder counts with its punch, I and D terms and motion
//! profile ([`Firmware::cycle`]), the DC motor ([`motor_torque`]) and BAM's friction
//! budget ([`budget`]: Coulomb, Stribeck and load-dependent). What differs is only
//! how the step moves the joint: the bench's one pendulum takes the friction that
//! stops it exactly; a joint of a robot holds by the simulator's stick spring
//! (`Simulator::joint_drive`) with the budget as its limit.
//!
//! The loop's torque is explicit in the step, as the firmware's is (it acts on the
//! last sensed counts for a whole cycle); the back-EMF and viscous damping are
//! implicit. The armature on the joint keeps that stable at a 1 ms step: the
//! stiffest RX loop (slope 2 counts, 3.7 N m over 10 mrad) on an RX-28's 0.011
//! kg m^2 gives `k dt^2 / J` = 0.03, far below the explicit limit of 4.

use crate::actuator::DynamixelServo;
pub use crate::actuator::FullServo;
use twinloop_actuator::Firmware;
use twinloop_actuator::delay::Samples;
use twinloop_actuator::params::{BUS_DELAY, SENSING_DELAY};

/// A full-model servo's state on its joint: the firmware's, the goals on the bus,
/// the angles the sensing delay still needs. The rings are sized when the servo is
/// set, so a step allocates nothing.
#[derive(Debug, Clone, Default)]
pub struct ServoState {
    pub firmware: Option<Firmware>,
    /// The goal last written by the caller, and the one in force (NaN: none yet).
    written: f64,
    pub goal: f64,
    /// Goals written but not in force: (time they take effect, goal).
    pending: Samples,
    /// (time, joint angle) of the last `sensing_delay`.
    history: Samples,
    /// The last step's duty and motor torque (N m).
    pub duty: f64,
    pub motor_torque: f64,
    /// When the firmware last ran (NaN: never).
    last_cycle: f64,
}

impl ServoState {
    pub fn new(full: &FullServo, dt: f64) -> ServoState {
        let mut firmware = Firmware::new(full.servo);
        firmware.profile.velocity = full.profile_velocity;
        firmware.profile.acceleration = full.profile_acceleration;
        ServoState {
            firmware: Some(firmware),
            written: f64::NAN,
            goal: f64::NAN,
            pending: Samples::for_delay(full.values[BUS_DELAY], dt),
            history: Samples::for_delay(full.values[SENSING_DELAY], dt),
            duty: 0.0,
            motor_torque: 0.0,
            last_cycle: f64::NAN,
        }
    }

    /// Forget the goals, the history and the loop's memory (the robot was placed, or
    /// the torque was off).
    pub fn reset(&mut self) {
        self.last_cycle = f64::NAN;
        self.written = f64::NAN;
        self.goal = f64::NAN;
        self.pending.clear();
        self.history.clear();
        if let Some(f) = &mut self.firmware {
            f.reset();
        }
    }

    /// The joint angle the servo senses at time `t` with the joint at `q`: the angle
    /// `sensing_delay` ago, linear between steps (before the first step, the
    /// oldest known), rad.
    pub fn sensed(&self, full: &FullServo, t: f64, q: f64) -> f64 {
        let delay = full.values[SENSING_DELAY];
        if delay <= 0.0 {
            q
        } else {
            self.history.value_at(t - delay, (t, q))
        }
    }

    /// One firmware cycle at time `t` with the joint at `q` and `written` the goal
    /// the caller has set: a new goal goes on the bus (in force `bus_delay` later),
    /// the loop runs on the sensed counts. Returns the duty.
    pub fn cycle(
        &mut self,
        s: &DynamixelServo,
        full: &FullServo,
        written: f64,
        t: f64,
        q: f64,
        dt: f64,
    ) -> f64 {
        // Skipped cycles: the torque was off (the virtual robot's servo was limp).
        // The firmware starts afresh where the joint is.
        let ran_last_step = t - self.last_cycle < 1.5 * dt; // false while NaN
        if !ran_last_step {
            self.reset();
        }
        self.last_cycle = t;
        let bus = full.values[BUS_DELAY];
        if written != self.written {
            self.written = written;
            if bus > 0.0 && self.goal.is_finite() {
                self.pending.push_back(t + bus, written);
            } else {
                self.pending.clear();
                self.goal = written;
            }
        }
        while let Some((at, g)) = self.pending.front() {
            if at > t + 1e-9 {
                break;
            }
            self.goal = g;
            self.pending.pop_front();
        }
        let sensed = self.sensed(full, t, q);
        let delay = full.values[SENSING_DELAY];
        if delay > 0.0 {
            self.history.push_back(t, q);
            self.history.forget_before(t - delay - 2.0 * dt);
        }
        let Some(f) = &mut self.firmware else {
            return 0.0;
        };
        f.registers = full.registers(s);
        f.torque_limit = s.torque_limit;
        f.profile.velocity = full.profile_velocity;
        f.profile.acceleration = full.profile_acceleration;
        self.duty = f.cycle(self.goal, sensed, dt);
        self.duty
    }
}
