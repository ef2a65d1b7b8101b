//! What moves a virtual robot's servos. The virtual bus speaks the protocol and
//! keeps the control tables; a [`VirtualServoBackend`] decides where each servo
//! is. The physics simulator implements it in the `twinloop-virtual` crate (kept
//! out of here so the link needs no dynamics); [`TrackingServoModel`] is a
//! stand-in without physics for protocol-only work.

use crate::board::ImuSample;
use crate::register::Item;
use crate::servo_model::ServoSpec;

/// One servo's measurable state, SI units, in the servo's own angle (radians from
/// the middle of its range, counter-clockwise positive: what the Present Position
/// register converts to).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoMeasurement {
    pub position: f64,
    /// rad/s.
    pub velocity: f64,
    /// Output torque, N m (the bus turns it into Present Load or Present Current).
    pub torque: f64,
    /// Supply voltage, V.
    pub voltage: f64,
    /// Degrees Celsius.
    pub temperature: f64,
}

/// The servo side's view of whatever moves the servos. Servo indices are the bus's
/// servo order.
pub trait VirtualServoBackend: Send {
    /// Torque Enable was written.
    fn set_torque_enabled(&mut self, servo: usize, enabled: bool);
    /// Goal Position was written (already checked against the servo's limits).
    fn set_goal_position(&mut self, servo: usize, position: f64);
    /// The servo's state now.
    fn measure(&self, servo: usize) -> ServoMeasurement;
    /// Let `dt` seconds pass. A backend whose time runs on its own thread (the
    /// simulator) ignores it.
    fn step(&mut self, dt: f64);
    /// A register that shapes how the servo moves was set (compliance, gains,
    /// moving speed, torque limit, ...): its item and raw value. Called for every
    /// written register that has an [`Item`] other than Goal Position and Torque
    /// Enable, and for all of them at power-on, reboot and factory reset. The
    /// default ignores it (the stand-in model has no such behaviour).
    fn register_written(&mut self, servo: usize, item: Item, raw: i32) {
        let _ = (servo, item, raw);
    }
    /// What the inertial sensors of the board at bus index `board` (a
    /// sub-controller such as the CM-730, after the servos) measure now, SI units
    /// along the board's own axes; the bus turns it into the board's counts.
    /// `None` (the default) leaves the registers as they are: a board lying level
    /// and still.
    fn board_imu(&self, board: usize) -> Option<ImuSample> {
        let _ = board;
        None
    }
}

#[derive(Debug, Clone, Copy)]
struct TrackingState {
    position: f64,
    velocity: f64,
    goal: f64,
    enabled: bool,
    spec: ServoSpec,
    min: f64,
    max: f64,
}

/// A stand-in for the simulator, good enough to exercise the protocol: with torque
/// on, each servo's position approaches its goal as a first-order lag
/// (`time_constant`, 50 ms by default), never faster than the datasheet's no-load
/// speed, and stays within its position limits. Torque is a proportional estimate
/// (stall torque at `saturation` radians of error); voltage and temperature are
/// constant. It has no gravity, no inertia and no load: it is not a robot model.
#[derive(Debug, Clone)]
pub struct TrackingServoModel {
    servos: Vec<TrackingState>,
    /// Seconds.
    pub time_constant: f64,
    /// Position error (rad) at which the torque estimate reaches stall torque.
    pub saturation: f64,
    pub voltage: f64,
    pub temperature: f64,
}

impl TrackingServoModel {
    /// One servo per entry: its datasheet figures and the range it can reach (rad);
    /// each starts at rest at 0 (the middle of its range) or the nearest reachable
    /// angle.
    pub fn new(servos: &[(ServoSpec, f64, f64)]) -> TrackingServoModel {
        TrackingServoModel {
            servos: servos
                .iter()
                .map(|&(spec, min, max)| {
                    let start = 0.0f64.clamp(min, max);
                    TrackingState {
                        position: start,
                        velocity: 0.0,
                        goal: start,
                        enabled: false,
                        spec,
                        min,
                        max,
                    }
                })
                .collect(),
            time_constant: 0.05,
            saturation: 0.2,
            voltage: 12.0,
            temperature: 36.0,
        }
    }

    /// Put servo `servo` at `position` (rad), at rest: a test's starting pose.
    pub fn place(&mut self, servo: usize, position: f64) {
        let s = &mut self.servos[servo];
        s.position = position.clamp(s.min, s.max);
        s.velocity = 0.0;
        s.goal = s.position;
    }
}

impl VirtualServoBackend for TrackingServoModel {
    fn set_torque_enabled(&mut self, servo: usize, enabled: bool) {
        let s = &mut self.servos[servo];
        if enabled && !s.enabled {
            // Torque on holds the current position until a goal arrives.
            s.goal = s.position;
        }
        s.enabled = enabled;
    }

    fn set_goal_position(&mut self, servo: usize, position: f64) {
        let s = &mut self.servos[servo];
        s.goal = position.clamp(s.min, s.max);
    }

    fn measure(&self, servo: usize) -> ServoMeasurement {
        let s = &self.servos[servo];
        let torque = if s.enabled {
            s.spec.stall_torque * ((s.goal - s.position) / self.saturation).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        ServoMeasurement {
            position: s.position,
            velocity: s.velocity,
            torque,
            voltage: self.voltage,
            temperature: self.temperature,
        }
    }

    fn step(&mut self, dt: f64) {
        if dt <= 0.0 {
            return;
        }
        let decay = (-dt / self.time_constant).exp();
        for s in &mut self.servos {
            if !s.enabled {
                s.velocity = 0.0;
                continue;
            }
            let target = s.goal + (s.position - s.goal) * decay;
            let max_step = s.spec.no_load_speed * dt;
            let step = (target - s.position).clamp(-max_step, max_step);
            let next = (s.position + step).clamp(s.min, s.max);
            // The velocity at the end of the step, not its mean: a long step (a
            // served bus steps by the wall-clock time between packets) that
            // settles on the goal ends at rest. Speed-limited, it is the top speed.
            let settling = (s.goal - next) / self.time_constant;
            s.velocity = if next == s.min || next == s.max {
                0.0
            } else if step.abs() >= max_step {
                step.signum() * s.spec.no_load_speed
            } else {
                settling.clamp(-s.spec.no_load_speed, s.spec.no_load_speed)
            };
            s.position = next;
        }
    }
}
