//! A servo model's identified parameters (`twinloop-actuator`'s file, docs/servo-models.md)
//! on a joint of the simulator: the full model of `crate::servo_model` (the firmware
//! on encoder counts with its punch or I and D terms and profile, the DC motor, BAM's
//! friction budget, the sensing and bus delays), the armature, the viscous friction
//! as the joint's damping, and the backlash.

use crate::actuator::{Actuator, DynamixelServo};
use crate::servo_model::{FullServo, ServoState};
use crate::simulator::Simulator;
use twinloop_actuator::ActuatorError;
use twinloop_actuator::params::{BACKLASH, FRICTION_BASE, FRICTION_VISCOUS};
pub use twinloop_actuator::params_set::{ServoParamsSet, ServoSlot};
use twinloop_actuator::{LoopFamily, ServoParams, ServoType};

/// The simulator's servo for `p`: the full model (`full`: the file's parameters and
/// the factory punch, I and D gains, no profile), the loop's slope at the factory
/// registers (RX: compliance slope 32 counts, margin 1 count; MX(2.0)/X: full PWM at
/// `885 x 128 / P` counts (XL330: 256), no margin), the backlash with the armature on its motor
/// side. The rating fields (full drive `kt V / R`, no-load speed `V / kt`) say the
/// same motor to code that reads them.
pub fn servo_from_params(p: &ServoParams) -> DynamixelServo {
    let count = p.servo.resolution();
    let regs = p.servo.factory_firmware();
    let rx = p.servo.family() == LoopFamily::Compliance;
    let (slope, margin) = match p.servo.family() {
        LoopFamily::Compliance => (
            twinloop_actuator::firmware::rx_slope_units(regs[0]) * count,
            regs[1] * count,
        ),
        LoopFamily::Pid => (
            p.servo.pwm_max() * p.servo.p_gain_divisor() / regs[0].max(1.0) * count,
            0.0,
        ),
    };
    DynamixelServo {
        stall_torque: p.kt() / p.resistance() * p.voltage,
        no_load_speed: p.voltage / p.kt(),
        torque_limit: 1.0,
        compliance_slope: slope,
        compliance_margin: margin,
        backlash: p.values[BACKLASH],
        motor_inertia: p.armature(),
        gear_friction: p.values[FRICTION_BASE],
        full: Some(FullServo {
            servo: p.servo,
            voltage: p.voltage,
            values: p.values,
            punch: if rx { regs[2] } else { 0.0 },
            i_gain: if rx { 0.0 } else { regs[1] },
            d_gain: if rx { 0.0 } else { regs[2] },
            profile_velocity: 0.0,
            profile_acceleration: 0.0,
        }),
    }
}

impl Simulator {
    /// Drive joint `i` by the servo of `p` ([`servo_from_params`]). The file's
    /// gearbox replaces the description's joint terms: the friction budget as its
    /// Coulomb friction (per step); without a backlash the armature as the joint's
    /// and the viscous friction as its damping, with one both on the motor side.
    /// The servo's delay rings are sized here for the simulator's time step.
    pub fn set_servo_params(&mut self, i: usize, p: &ServoParams) {
        let s = servo_from_params(p);
        self.actuators[i] = Actuator::Dynamixel(s);
        // The gearbox's Coulomb friction is the full model's budget (per step).
        self.joint_friction[i] = 0.0;
        if s.backlash <= 0.0 {
            self.model.armature[i] = p.armature();
            self.joint_damping[i] = p.values[FRICTION_VISCOUS];
        } else {
            // Behind a dead band the gearbox's viscous friction is on the motor side.
            self.joint_damping[i] = 0.0;
        }
        self.gears[i] = Default::default();
        if let Some(full) = &s.full {
            self.servo_states[i] = ServoState::new(full, self.config.dt);
        }
    }

    /// Give the joints of robot `robot_name` the servos of `set` (`option` names the
    /// flag in errors): a file for one joint by its name, or for every joint whose
    /// servo is of its type (the built-in robots' servo tables say which; on other
    /// robots every joint). Returns how many joints took one.
    pub fn apply_servo_params(
        &mut self,
        robot_name: &str,
        set: &ServoParamsSet,
        option: &str,
    ) -> Result<usize, ActuatorError> {
        let names = self.model.joint_names.clone();
        let mut slots = Vec::with_capacity(names.len());
        let mut n = 0;
        for (i, name) in names.iter().enumerate() {
            if self.model.joint_types[i].nv() != 1 {
                continue;
            }
            let slot = ServoSlot {
                id: None,
                joint: name,
                servo: twinloop_description::builtin::servo_of_joint(robot_name, name)
                    .and_then(|s| ServoType::parse(s.name)),
            };
            if let Some(p) = set.for_servo(slot, option)? {
                self.set_servo_params(i, p);
                n += 1;
            }
            slots.push(slot);
        }
        set.check_used(&slots, option)?;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use twinloop_actuator::datasheet::defaults;
    use twinloop_actuator::{ModelLevel, ServoType};

    #[test]
    fn datasheet_parameters_give_the_datasheet_servo() {
        // The datasheet file (kt = stall torque / stall current, R = V / stall
        // current) gives the rating back: stall torque exactly; no-load speed V/kt is
        // the motor's own (above the datasheet's, whose friction the file keeps apart).
        let p = defaults(ServoType::Rx28, ModelLevel::M1);
        let s = servo_from_params(&p);
        assert!((s.stall_torque - 3.7).abs() < 1e-12);
        assert!((s.no_load_speed - 18.5 / (3.7 / 1.9)).abs() < 1e-12);
        let rx = DynamixelServo::rx28();
        assert!((s.compliance_slope - rx.compliance_slope).abs() < 1e-12);
        assert!((s.compliance_margin - rx.compliance_margin).abs() < 1e-12);
        // XM430 at P 800: full PWM at 141.6 counts.
        let x = servo_from_params(&defaults(ServoType::Xm430W350, ModelLevel::M1));
        assert!((x.compliance_slope - 141.6 * std::f64::consts::TAU / 4096.0).abs() < 1e-9);
    }
}
