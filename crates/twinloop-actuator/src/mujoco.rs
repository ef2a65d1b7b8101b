//! What of a servo model MuJoCo can express, for `model export --servo-params`.
//!
//! The model's torque is `kt/R (duty V - kt v) - friction`, with the duty clamped by
//! the firmware. In MuJoCo terms:
//! - the firmware's linear region is a `<position>` actuator of gain `kp` (N m/rad):
//!   full drive `kt V / R` reached at the slope's error (RX: compliance slope counts;
//!   MX/X: 885 / (P/128) counts; XL330 P/256), clamped by `forcerange` = +-`kt V / R` x torque
//!   limit, as the duty is;
//! - the back-EMF `kt^2/R` and viscous friction act outside that clamp: joint
//!   `damping`;
//! - Coulomb friction: joint `frictionloss`; the armature: joint `armature`.
//!
//! MuJoCo cannot express: the compliance margin and punch (a dead band and a
//! minimum drive), the encoder's counts, the I and D terms (D could be `kv`, but it
//! then sits inside the clamp), Stribeck and load-dependent friction (BAM patches
//! `frictionloss` every step for those), profile velocity and acceleration.

use crate::firmware::rx_slope_units;
use crate::params::{FRICTION_BASE, FRICTION_VISCOUS, ServoParams};
use crate::servo_type::LoopFamily;

/// The MuJoCo parameters of one servo on its factory (or given) loop registers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MujocoServo {
    /// Position actuator gain, N m/rad.
    pub kp: f64,
    /// Actuator force range (symmetric), N m.
    pub forcerange: f64,
    /// Joint damping, N m s/rad.
    pub damping: f64,
    /// Joint frictionloss, N m.
    pub frictionloss: f64,
    /// Joint armature, kg m^2.
    pub armature: f64,
}

/// `params` with the loop registers `registers` (see [`crate::Firmware`]).
pub fn mujoco_servo(params: &ServoParams, registers: [f64; 3], torque_limit: f64) -> MujocoServo {
    let servo = params.servo;
    let full = params.kt() / params.resistance() * params.voltage;
    let counts_to_full = match servo.family() {
        LoopFamily::Compliance => rx_slope_units(registers[0]),
        LoopFamily::Pid => servo.pwm_max() / (registers[0] / servo.p_gain_divisor()).max(1e-9),
    };
    MujocoServo {
        kp: full / (counts_to_full * servo.resolution()),
        forcerange: full * torque_limit,
        damping: params.kt() * params.kt() / params.resistance() + params.values[FRICTION_VISCOUS],
        frictionloss: params.values[FRICTION_BASE],
        armature: params.armature(),
    }
}

/// An MJCF fragment for `joints` driven by servos of parameters `m`: a default class
/// with the joint and actuator settings and one `<position>` actuator per joint, to
/// merge into a model (`<include>` or by hand).
pub fn mjcf_fragment(joints: &[String], servo: &str, m: &MujocoServo) -> String {
    let class = format!("servo-{}", servo.replace(['(', ')', '.'], ""));
    let mut s = format!(
        "<mujoco>\n  <!-- {servo} servo model (twinloop, docs/servo-models.md). Not expressed here: the \
compliance margin and punch, encoder counts, I/D terms, Stribeck and load-dependent friction, \
profile velocity. -->\n  <default>\n    <default class=\"{class}\">\n      \
<joint armature=\"{:?}\" damping=\"{:?}\" frictionloss=\"{:?}\"/>\n      \
<position kp=\"{:?}\" forcerange=\"{:?} {:?}\" forcelimited=\"true\"/>\n    </default>\n  </default>\n  <actuator>\n",
        m.armature, m.damping, m.frictionloss, m.kp, -m.forcerange, m.forcerange
    );
    for j in joints {
        s.push_str(&format!(
            "    <position name=\"{j}\" joint=\"{j}\" class=\"{class}\"/>\n"
        ));
    }
    s.push_str("  </actuator>\n</mujoco>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::datasheet::defaults;
    use crate::{ModelLevel, ServoType};

    #[test]
    fn rx28_factory_gain() {
        let p = defaults(ServoType::Rx28, ModelLevel::M1);
        let m = mujoco_servo(&p, ServoType::Rx28.factory_firmware(), 1.0);
        // Stall torque 3.7 N m over 32 counts of 0.293 deg.
        let want = 3.7 / (32.0 * (300.0f64 / 1024.0).to_radians());
        assert!((m.kp - want).abs() < 1e-9 * want && (m.forcerange - 3.7).abs() < 1e-12);
        // No-load: the damping stops the free motor at the datasheet speed, less friction.
        let w0 = 85.0 * std::f64::consts::TAU / 60.0;
        assert!((m.forcerange - m.damping * w0 - m.frictionloss).abs() < 1e-9);
    }
}
