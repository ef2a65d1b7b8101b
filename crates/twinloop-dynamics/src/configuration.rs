//! Configuration-space helpers: integration and difference on the base's SE(3) and
//! the spherical joints' SO(3) (Pinocchio's `integrate`, `difference`), random states.

use crate::model::{JointType, Model};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use twinloop_random::SplitMix64;
use twinloop_spatial::{matrix_to_quaternion_xyzw, quaternion_xyzw_to_matrix};

/// `q (+) v dt`: 1-DoF joints add, a spherical joint turns by `exp(w dt)` in its
/// child frame, the base moves along the twist `v[0..6]` (base frame) held constant
/// for `dt` (the exponential map of SE(3)), as Pinocchio's `integrate`. Quaternions
/// come out normalised, so long integrations do not drift off the unit sphere.
pub fn integrate(model: &Model, q: &[f64], v: &[f64], dt: f64, out: &mut [f64]) {
    assert_eq!(q.len(), model.nq);
    assert_eq!(v.len(), model.nv);
    assert_eq!(out.len(), model.nq);
    for i in 0..model.nbodies {
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        if model.joint_types[i] == JointType::Spherical {
            let w = Vector3::new(v[iv], v[iv + 1], v[iv + 2]) * dt;
            let turned = quaternion(&q[iq..iq + 4]) * UnitQuaternion::from_scaled_axis(w);
            // Stay in q's hemisphere, as Pinocchio does, so q and -q never alternate.
            write_quaternion(&turned, &q[iq..iq + 4], &mut out[iq..iq + 4]);
        } else {
            out[iq] = q[iq] + v[iv] * dt;
        }
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

/// The unit quaternion of `(x, y, z, w)`, normalised.
fn quaternion(xyzw: &[f64]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(xyzw[3], xyzw[0], xyzw[1], xyzw[2]))
}

/// Write `r` as (x, y, z, w), the sign chosen to be in the hemisphere of `near`.
fn write_quaternion(r: &UnitQuaternion<f64>, near: &[f64], out: &mut [f64]) {
    let c = r.coords; // (x, y, z, w)
    let dot = c.x * near[0] + c.y * near[1] + c.z * near[2] + c.w * near[3];
    let sign = if dot < 0.0 { -1.0 } else { 1.0 };
    for k in 0..4 {
        out[k] = sign * c[k];
    }
}

/// `q1 (-) q0`: the velocity that [`integrate`] over unit time turns `q0` into `q1`
/// (Pinocchio's `difference`): 1-DoF joints subtract, a spherical joint gives
/// `log(R0^T R1)` (child frame), the base `log(M0^-1 M1)` of SE(3) (base frame).
pub fn difference(model: &Model, q0: &[f64], q1: &[f64], out: &mut [f64]) {
    assert_eq!(q0.len(), model.nq);
    assert_eq!(q1.len(), model.nq);
    assert_eq!(out.len(), model.nv);
    for i in 0..model.nbodies {
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        if model.joint_types[i] == JointType::Spherical {
            let r = quaternion(&q0[iq..iq + 4]).inverse() * quaternion(&q1[iq..iq + 4]);
            out[iv..iv + 3].copy_from_slice(r.scaled_axis().as_slice());
        } else {
            out[iv] = q1[iq] - q0[iq];
        }
    }
    if model.is_floating() {
        let r0 = quaternion(&q0[3..7]);
        let r1 = quaternion(&q1[3..7]);
        let dr = r0.inverse() * r1;
        let dp =
            r0.inverse() * (Vector3::new(q1[0], q1[1], q1[2]) - Vector3::new(q0[0], q0[1], q0[2]));
        let w = dr.scaled_axis();
        // Invert se3_exp's V(w): the linear part v with V(w) v = dp.
        let (_, vmat) = se3_exp_parts(&w);
        let lin = vmat.try_inverse().map_or(dp, |vi| vi * dp);
        out[0..3].copy_from_slice(lin.as_slice());
        out[3..6].copy_from_slice(w.as_slice());
    }
}

/// Exponential of a twist (linear `v`, angular `w`): rotation and translation.
fn se3_exp(v: &Vector3<f64>, w: &Vector3<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    let (rot, vmat) = se3_exp_parts(w);
    (rot, vmat * v)
}

/// The rotation `exp(w)` and the matrix `V(w)` with which SE(3)'s exponential moves
/// the origin by `V(w) v`.
fn se3_exp_parts(w: &Vector3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
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
    (rot, vmat)
}

/// Normalise the base's and the spherical joints' quaternions of `q` in place.
pub fn normalize(model: &Model, q: &mut [f64]) {
    if model.is_floating() {
        normalize4(&mut q[3..7]);
    }
    for i in 0..model.nbodies {
        if model.joint_types[i] == JointType::Spherical {
            let iq = model.idx_q[i];
            normalize4(&mut q[iq..iq + 4]);
        }
    }
}

fn normalize4(x: &mut [f64]) {
    let n = x.iter().map(|c| c * c).sum::<f64>().sqrt();
    for c in x {
        *c /= n;
    }
}

/// A uniformly random unit quaternion (x, y, z, w): a normalised Gaussian 4-vector.
fn random_quaternion(rng: &mut SplitMix64, out: &mut [f64]) {
    for c in out.iter_mut() {
        *c = rng.normal();
    }
    normalize4(out);
}

/// A random configuration: base position in [-1, 1]^3, uniformly random unit
/// quaternions for the base and the spherical joints, 1-DoF joints uniform within
/// their limits (or [-1.5, 1.5] where unlimited).
pub fn random_configuration(model: &Model, rng: &mut SplitMix64) -> Vec<f64> {
    let mut q = vec![0.0; model.nq];
    if model.is_floating() {
        for x in &mut q[0..3] {
            *x = rng.uniform(-1.0, 1.0);
        }
        random_quaternion(rng, &mut q[3..7]);
    }
    for i in 0..model.nbodies {
        if model.joint_types[i] == JointType::Spherical {
            let iq = model.idx_q[i];
            random_quaternion(rng, &mut q[iq..iq + 4]);
            continue;
        }
        let (lo, hi) = (model.lower_limits[i], model.upper_limits[i]);
        let (lo, hi) = if lo.is_finite() && hi.is_finite() && lo < hi {
            (lo, hi)
        } else {
            (-1.5, 1.5)
        };
        q[model.idx_q[i]] = rng.uniform(lo, hi);
    }
    q
}

/// A vector of nv standard-normal entries.
pub fn random_tangent(model: &Model, rng: &mut SplitMix64) -> Vec<f64> {
    (0..model.nv).map(|_| rng.normal()).collect()
}
