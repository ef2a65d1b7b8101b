//! Datasheet defaults: what a servo's parameters are before identification.
//!
//! - `kt` = stall torque / stall current and `resistance` = voltage / stall current
//!   (e-manual ratings; at stall the back-EMF is zero, so the whole supply drives
//!   the stall current through the winding);
//! - `friction_base`: an assumption, 2.5 % of the stall torque (ROBOTIS publishes no
//!   friction; BAM identified 0.09 N m on an MX-64, 1.5 % of its 6 N m);
//! - `friction_viscous`: what makes the model's no-load speed the datasheet's
//!   (`kt/R (V - kt w0) = friction_base + friction_viscous w0`), never below 0;
//! - `armature`: BAM's identified MX-64 figure (0.012 kg m^2, ratio 200) scaled by
//!   the gear ratio squared: an assumption that the rotors are alike;
//! - Stribeck: as much again as the Coulomb friction, fading by 0.2 rad/s (BAM's
//!   starting values); `load_friction` 0.05 (BAM's starting value).

use crate::params::{ModelLevel, ServoParams, *};
use crate::servo_type::ServoType;

/// The datasheet parameters of `servo` on rung `level` (terms the rung lacks are 0).
pub fn defaults(servo: ServoType, level: ModelLevel) -> ServoParams {
    let r = servo.rating();
    let kt = r.stall_torque / r.stall_current;
    let resistance = r.voltage / r.stall_current;
    let friction_base = 0.025 * r.stall_torque;
    let no_load_torque = kt / resistance * (r.voltage - kt * r.no_load_speed);
    let viscous = ((no_load_torque - friction_base) / r.no_load_speed).max(0.0);
    let armature = 0.012 * (r.gear_ratio / 200.0).powi(2);
    let mut values = [0.0; N_PARAMS];
    values[KT] = kt;
    values[RESISTANCE] = resistance;
    values[ARMATURE] = armature;
    values[FRICTION_BASE] = friction_base;
    values[FRICTION_VISCOUS] = viscous;
    if level.has_stribeck() {
        values[FRICTION_STRIBECK] = friction_base;
        values[STRIBECK_VELOCITY] = 0.2;
    }
    if level.has_load_friction() {
        values[LOAD_FRICTION] = 0.05;
    }
    ServoParams {
        servo,
        level,
        voltage: r.voltage,
        values,
        uncertainty: None,
    }
}
