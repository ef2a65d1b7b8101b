//! The gearbox's friction as a budget (BAM's formulation): the friction torque is
//! whatever stops the output, limited to +-budget, plus a viscous term.

use crate::params::*;

/// The Coulomb budget at output speed `v` with motor torque `motor_torque` carried
/// by the gears:
/// `F = friction_base + load_friction |tau_m| + friction_stribeck exp(-(v / stribeck_velocity)^2)`.
/// Load and Stribeck terms only on the rungs that have them; the Stribeck shape's
/// exponent is fixed at 2, where BAM fits it.
pub fn budget(values: &[f64; N_PARAMS], v: f64, motor_torque: f64) -> f64 {
    let mut f = values[FRICTION_BASE] + values[LOAD_FRICTION] * motor_torque.abs();
    let vs = values[STRIBECK_VELOCITY];
    if values[FRICTION_STRIBECK] > 0.0 && vs > 0.0 {
        let x = v / vs;
        f += values[FRICTION_STRIBECK] * (-x * x).exp();
    }
    f
}
