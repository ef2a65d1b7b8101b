//! What the servo's output turns: a rigid body about a fixed axis, of constant
//! inertia and with gravity's torque `A sin q + B cos q + C` at output angle `q`.
//!
//! This form is exact for any rigid body turning about a fixed axis under uniform
//! gravity: its centre of mass moves on a circle about the axis, so gravity's torque
//! about the axis is `m g` crossed with a lever that rotates with `q`, a sum of
//! `sin q` and `cos q` (C = 0); its inertia about the axis does not change. A
//! pendulum bench is one case (`A = -m g l`, hanging down at 0); a limb of a robot
//! held with its base fixed and its other joints stiff is another (the subtree
//! beyond the joint is one rigid body). `C` is kept for a constant torque (a spring
//! preload, a cable); gravity alone leaves it 0.

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Load {
    /// Inertia about the axis, without the servo's armature, kg m^2.
    pub inertia: f64,
    /// Gravity's torque `gravity_sin sin q + gravity_cos cos q + gravity_const`, N m,
    /// `q` the output's angle as the servo reports it (rad).
    pub gravity_sin: f64,
    pub gravity_cos: f64,
    pub gravity_const: f64,
}

impl Load {
    /// Gravity's torque at output angle `q`, N m.
    #[inline]
    pub fn gravity_torque(&self, q: f64) -> f64 {
        if self.gravity_cos.to_bits() == 0 && self.gravity_const.to_bits() == 0 {
            // A pendulum: no cosine to take. `+ 0.0` gives the sum's bits (a zero
            // sine term's sum is +0 whatever its sign).
            return self.gravity_sin * q.sin() + 0.0;
        }
        let (s, c) = q.sin_cos();
        self.gravity_sin * s + self.gravity_cos * c + self.gravity_const
    }

    /// The largest gravity torque over every angle, N m.
    pub fn max_gravity_torque(&self) -> f64 {
        self.gravity_sin.hypot(self.gravity_cos) + self.gravity_const.abs()
    }

    /// The load whose gravity torque is closest (least squares) to `torques[k]` at
    /// `angles[k]` (at least three angles, not all alike modulo 2 pi), and the RMS
    /// of what is left, N m: 0 to rounding for a rigid body about a fixed axis.
    pub fn fit_gravity(inertia: f64, angles: &[f64], torques: &[f64]) -> Option<(Load, f64)> {
        // Normal equations of [sin q, cos q, 1] x = tau.
        let mut a = nalgebra::Matrix3::<f64>::zeros();
        let mut b = nalgebra::Vector3::<f64>::zeros();
        for (&q, &tau) in angles.iter().zip(torques) {
            let row = nalgebra::Vector3::new(q.sin(), q.cos(), 1.0);
            a += row * row.transpose();
            b += row * tau;
        }
        let x = a.cholesky()?.solve(&b);
        let load = Load {
            inertia,
            gravity_sin: x[0],
            gravity_cos: x[1],
            gravity_const: x[2],
        };
        let n = angles.len().max(1) as f64;
        let rms = (angles
            .iter()
            .zip(torques)
            .map(|(&q, &t)| (load.gravity_torque(q) - t).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        Some((load, rms))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gravity_fit_recovers_a_shifted_sine() {
        // tau = -m g r sin(q - phi): A = -mgr cos phi, B = mgr sin phi.
        let (mgr, phi) = (0.8, 0.4);
        let angles: Vec<f64> = (0..8).map(|k| -1.0 + 0.3 * k as f64).collect();
        let torques: Vec<f64> = angles.iter().map(|q| -mgr * (q - phi).sin()).collect();
        let (l, rms) = Load::fit_gravity(0.01, &angles, &torques).unwrap();
        assert!(rms < 1e-12, "{rms}");
        assert!((l.gravity_sin + mgr * phi.cos()).abs() < 1e-12);
        assert!((l.gravity_cos - mgr * phi.sin()).abs() < 1e-12);
        assert!(l.gravity_const.abs() < 1e-12);
        assert!((l.max_gravity_torque() - mgr).abs() < 1e-12);
    }
}
