//! One servo on the pendulum bench behind the bus: the servo models of
//! twinloop-actuator moved by the wall clock, what `twinloop serve --bench` runs.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use twinloop_actuator::replay::advance;
use twinloop_actuator::{Bench, LoopFamily, Pendulum, ServoParams, ServoType};
use twinloop_link::servo::ServoMeasurement;
use twinloop_link::{Item, ServoModel, VirtualServoBackend};

use crate::shared::thermal_step;

/// The bench as a bus backend (one servo, index 0).
pub struct BenchBackend {
    pub bench: Bench,
    model: ServoModel,
    /// Simulated seconds per wall-clock second.
    pub realtime_factor: f64,
    pub temperature: f64,
    /// The served servo's hardware condition bits
    /// ([`VirtualServo::condition`](twinloop_link::servo::VirtualServo)): past the
    /// factory Temperature Limit (80 C) the overheating bit (0x04) is set, as a real
    /// servo reports it in every status packet.
    pub condition: Option<Arc<AtomicU8>>,
}

/// The link's servo model for a model type, by name.
pub fn link_model(servo: ServoType) -> Option<ServoModel> {
    ServoModel::parse(servo.name())
}

/// The actuator crate's type of a link servo model, by name.
pub fn servo_type(model: ServoModel) -> Option<ServoType> {
    ServoType::parse(model.name())
}

impl BenchBackend {
    /// The servo with `params` swinging `load`, hanging at rest, torque off.
    pub fn new(params: ServoParams, load: Pendulum, realtime_factor: f64) -> Option<BenchBackend> {
        let model = link_model(params.servo)?;
        Some(BenchBackend {
            bench: Bench::new(params, load),
            model,
            realtime_factor,
            temperature: crate::shared::AMBIENT_C,
            condition: None,
        })
    }

    pub fn model(&self) -> ServoModel {
        self.model
    }
}

impl VirtualServoBackend for BenchBackend {
    fn set_torque_enabled(&mut self, _servo: usize, enabled: bool) {
        if enabled != self.bench.torque_on {
            self.bench.firmware.reset();
        }
        self.bench.torque_on = enabled;
    }

    fn set_goal_position(&mut self, _servo: usize, position: f64) {
        self.bench.send_goal(position);
    }

    /// Present Load is the RX's PWM (so the torque handed to the bus is the duty
    /// times the stall torque the bus divides by); Present Current is the motor's
    /// current (handed over as torque at the datasheet's torque per amp, which the
    /// bus divides by).
    fn measure(&self, _servo: usize) -> ServoMeasurement {
        let spec = self.model.spec();
        let torque = match (
            self.bench.params().servo.current_unit(),
            spec.torque_per_amp(),
        ) {
            (Some(_), Some(k)) => self.bench.current * k,
            _ => self.bench.duty * spec.stall_torque,
        };
        ServoMeasurement {
            position: self.bench.sensed_angle(),
            velocity: self.bench.v,
            torque,
            voltage: self.bench.params().voltage,
            temperature: self.temperature,
        }
    }

    /// Advance the wall clock's `dt` (times the realtime factor) in equal steps of at
    /// most `replay::MAX_STEP`, as the fit's replay does between two log rows.
    fn step(&mut self, dt: f64) {
        let span = dt * self.realtime_factor;
        if span <= 0.0 {
            return;
        }
        let stall = self.model.spec().stall_torque;
        // The winding heats with the torque it carried over the span.
        advance(&mut self.bench, span);
        self.temperature = thermal_step(self.temperature, self.bench.motor_torque / stall, span);
        if self.temperature > 80.0
            && let Some(c) = &self.condition
        {
            c.fetch_or(0x04, Ordering::Relaxed);
        }
    }

    /// Compliance (RX) or position gains (MX(2.0), X) and the torque limit.
    fn register_written(&mut self, _servo: usize, item: Item, raw: i32) {
        let family = self.bench.params().servo.family();
        let f = &mut self.bench.firmware;
        let raw_f = raw as f64;
        match (family, item) {
            (LoopFamily::Compliance, Item::CwComplianceSlope | Item::CcwComplianceSlope) => {
                f.registers[0] = raw_f
            }
            (LoopFamily::Compliance, Item::CwComplianceMargin | Item::CcwComplianceMargin) => {
                f.registers[1] = raw_f
            }
            (LoopFamily::Compliance, Item::Punch) => f.registers[2] = raw_f,
            (LoopFamily::Pid, Item::PositionPGain) => f.registers[0] = raw_f,
            (LoopFamily::Pid, Item::PositionIGain) => f.registers[1] = raw_f,
            (LoopFamily::Pid, Item::PositionDGain) => f.registers[2] = raw_f,
            (LoopFamily::Compliance, Item::TorqueLimit) => {
                f.torque_limit = (raw_f / 1023.0).clamp(0.0, 1.0)
            }
            (LoopFamily::Pid, Item::MaxTorque) => f.torque_limit = (raw_f / 885.0).clamp(0.0, 1.0),
            // Moving Speed (RX) or Profile Velocity (X, MX(2.0)), Profile Acceleration.
            (_, Item::MovingSpeed) => f.profile.set_velocity_register(f.servo, raw_f),
            (LoopFamily::Pid, Item::ProfileAcceleration) => {
                f.profile.set_acceleration_register(raw_f)
            }
            _ => {}
        }
    }
}
