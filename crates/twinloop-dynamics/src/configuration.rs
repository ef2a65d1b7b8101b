//! Configuration-space helpers: integration on the base's SE(3), random states.

use crate::model::Model;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use twinloop_random::SplitMix64;
use twinloop_spatial::{matrix_to_quaternion_xyzw, quaternion_xyzw_to_matrix};

/// `q (+) v dt`: joints add, the base moves along the twist `v[0..6]` (base frame)
/// held constant for `dt` (the exponential map of SE(3), as Pinocchio's `integrate`).
pub fn integrate(model: &Model, q: &[f64], v: &[f64], dt: f64, out: &mut [f64]) {
    assert_eq!(q.len(), model.nq);
    assert_eq!(v.len(), model.nv);
    assert_eq!(out.len(), model.nq);
    let (qo, vo) = (model.q_offset, model.v_offset);
    for i in 0..model.nbodies {
        out[qo + i] = q[qo + i] + v[vo + i] * dt;
    }
    if model.is_floating() {
        let r = quaternion_xyzw_to_matrix(q[3], q[4], q[5], q[6]);
        let p = Vector3::new(q[0], q[1], q[2]);
        let lin = Vector3::new(v[0], v[1], v[2]) * dt;
        let ang = Vector3::new(v[3], v[4], v[5]) * dt;
        let (dr, dp) = se3_exp(&lin, &ang);
        let r2 = r * dr;
        let p2 = p + r * dp;
        // Re-orthonormalise through the quaternion so long integrations stay unit.
        let q2 = matrix_to_quaternion_xyzw(&r2);
        let n = (q2[0] * q2[0] + q2[1] * q2[1] + q2[2] * q2[2] + q2[3] * q2[3]).sqrt();
        out[0..3].copy_from_slice(p2.as_slice());
        for k in 0..4 {
            out[3 + k] = q2[k] / n;
        }
    }
}

/// Exponential of a twist (linear `v`, angular `w`): rotation and translation.
fn se3_exp(v: &Vector3<f64>, w: &Vector3<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    let theta = w.norm();
    let rot = UnitQuaternion::from_scaled_axis(*w)
        .to_rotation_matrix()
        .into_inner();
    let k = twinloop_spatial::skew(w);
    let vmat = if theta < 1e-8 {
        Matrix3::identity() + k * 0.5 + k * k / 6.0
    } else {
        let t2 = theta * theta;
        Matrix3::identity()
            + k * ((1.0 - theta.cos()) / t2)
            + k * k * ((theta - theta.sin()) / (t2 * theta))
    };
    (rot, vmat * v)
}

/// Normalise the base quaternion of `q` in place (no-op for a fixed base).
pub fn normalize(model: &Model, q: &mut [f64]) {
    if model.is_floating() {
        let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
        for x in &mut q[3..7] {
            *x /= n;
        }
    }
}

/// A random configuration: base position in [-1, 1]^3, a uniformly random unit
/// quaternion, joints uniform within their limits (or [-1.5, 1.5] where unlimited).
pub fn random_configuration(model: &Model, rng: &mut SplitMix64) -> Vec<f64> {
    let mut q = vec![0.0; model.nq];
    if model.is_floating() {
        for x in &mut q[0..3] {
            *x = rng.uniform(-1.0, 1.0);
        }
        // Normalised Gaussian 4-vector: uniform on the sphere.
        let g: [f64; 4] = [rng.normal(), rng.normal(), rng.normal(), rng.normal()];
        let n = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        for k in 0..4 {
            q[3 + k] = g[k] / n;
        }
    }
    for i in 0..model.nbodies {
        let (lo, hi) = (model.lower_limits[i], model.upper_limits[i]);
        let (lo, hi) = if lo.is_finite() && hi.is_finite() && lo < hi {
            (lo, hi)
        } else {
            (-1.5, 1.5)
        };
        q[model.q_offset + i] = rng.uniform(lo, hi);
    }
    q
}

/// A vector of nv standard-normal entries.
pub fn random_tangent(model: &Model, rng: &mut SplitMix64) -> Vec<f64> {
    (0..model.nv).map(|_| rng.normal()).collect()
}
