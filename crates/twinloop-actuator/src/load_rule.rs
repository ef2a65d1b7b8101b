//! Which pendulum a servo type needs for its friction and armature to show in the
//! logs: the rule of docs/servo-models.md ("Which load"), from known-truth fits
//! (`tests/load_rule.rs`, the pty runs there).
//!
//! Why a heavy load: friction and armature show against the load through how the
//! servo's error under gravity moves. A servo that senses no current (RX) is seen
//! only through its position: with the pendulum's weight at 14-20 % of the stall
//! torque, friction_base came back off by up to 8 % (RX-28) and 12 % (RX-64);
//! at 53-56 % within 2.6 % in every draw. Present Current (MX(2.0), X) separates
//! the motor from the load: 12-18 % was enough (within 2.5 % over the pty).

use crate::bench::{GRAVITY, Pendulum};
use crate::servo_type::ServoType;

/// Least gravity torque (`m g l`, at the horizontal) over the stall torque for a
/// servo that senses no current.
pub const MIN_RATIO_POSITION_ONLY: f64 = 0.4;
/// The same for a servo that senses its current.
pub const MIN_RATIO_WITH_CURRENT: f64 = 0.1;
/// Most: above it the loop saturates holding the excitation's 0.8 rad steps
/// (`experiment servo` refuses it).
pub const MAX_RATIO: f64 = 0.6;

/// The pendulum's gravity torque at the horizontal over `servo`'s stall torque.
pub fn load_ratio(servo: ServoType, load: &Pendulum) -> f64 {
    load.mass * GRAVITY * load.length / servo.rating().stall_torque
}

/// The least ratio `servo` needs.
pub fn min_ratio(servo: ServoType) -> f64 {
    if servo.current_unit().is_some() {
        MIN_RATIO_WITH_CURRENT
    } else {
        MIN_RATIO_POSITION_ONLY
    }
}

/// A warning where `load` is too light for the logs of `servo` to determine its
/// friction and armature: the ratio, the least, and a mass that would do at the
/// load's length.
pub fn too_light(servo: ServoType, load: &Pendulum) -> Option<String> {
    let ratio = load_ratio(servo, load);
    let min = min_ratio(servo);
    if ratio >= min || load.length <= 0.0 {
        return None;
    }
    let stall = servo.rating().stall_torque;
    let target = 0.5 * (min + MAX_RATIO);
    let mass = target * stall / (GRAVITY * load.length);
    Some(format!(
        "the pendulum's weight takes {:.2} N m at the horizontal, {:.0} % of the {servo}'s {stall} N m stall torque; {}friction and armature are poorly determined below {:.0} % (docs/servo-models.md, \"Which load\"): about {mass:.2} kg at {} m",
        ratio * stall,
        100.0 * ratio,
        if servo.current_unit().is_none() {
            "it senses no current, so "
        } else {
            ""
        },
        100.0 * min,
        load.length
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_light_pendulum_is_too_light_for_an_rx64_and_the_heavy_one_is_not() {
        let light = Pendulum {
            mass: 0.5,
            length: 0.15,
            arm_inertia: 0.002,
        };
        let heavy = Pendulum {
            mass: 1.5,
            length: 0.2,
            arm_inertia: 0.002,
        };
        let w = too_light(ServoType::Rx64, &light).unwrap();
        assert!(w.contains("14 % of the RX-64's 5.3 N m"), "{w}");
        assert!(too_light(ServoType::Rx64, &heavy).is_none());
        // 0.5 kg at 15 cm is 18 % of an XM430's 4.1 N m: enough with its current.
        assert!(too_light(ServoType::Xm430W350, &light).is_none());
        // The suggested mass lands inside the range.
        let r = load_ratio(
            ServoType::Rx64,
            &Pendulum {
                mass: 0.5 * (MIN_RATIO_POSITION_ONLY + MAX_RATIO) * 5.3 / (GRAVITY * 0.15),
                ..light
            },
        );
        assert!((MIN_RATIO_POSITION_ONLY..MAX_RATIO).contains(&r), "{r}");
    }
}
