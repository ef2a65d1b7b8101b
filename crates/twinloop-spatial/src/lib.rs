//! twinloop-spatial: 6-D spatial algebra on the stack (Featherstone's notation,
//! Pinocchio's conventions).
//!
//! - [`Se3`]: rigid placement `aMb` (rotation + translation of frame b in frame a).
//! - [`Motion`]: spatial velocity/acceleration, linear part first (`v`, `w`).
//! - [`Force`]: spatial force, linear part first (`f`, `n`).
//! - [`Inertia`]: rigid-body inertia in compact form (mass, CoM, rotational inertia about the CoM).
//! - [`LinearInertia`]: the same in the form linear in the parameters (m, m c, inertia about
//!   the origin), whose sums are plain sums.
//! - [`Symmetric6`]: a symmetric 6x6 operator (articulated-body inertia) kept as three 3x3 blocks.
//!
//! Everything is `Copy` and fixed-size: nothing here allocates.

mod force;
mod inertia;
mod linear_inertia;
mod motion;
mod se3;
mod symmetric6;
mod trig;

pub use force::Force;
pub use inertia::Inertia;
pub use linear_inertia::LinearInertia;
pub use motion::Motion;
pub use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
pub use se3::Se3;
pub use symmetric6::Symmetric6;
pub use trig::{sin_cos, sin_cos_lanes};

/// The skew-symmetric matrix `[v]x` with `[v]x u = v x u`.
#[inline(always)]
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Rotation about a unit axis by `angle` (Rodrigues).
#[inline]
pub fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    axis_angle_sc(axis, s, c)
}

/// Rotation about a unit axis given the sine and cosine of the angle.
#[inline(always)]
pub fn axis_angle_sc(a: &Vector3<f64>, s: f64, c: f64) -> Matrix3<f64> {
    let t = 1.0 - c;
    let (x, y, z) = (a.x, a.y, a.z);
    Matrix3::new(
        t * x * x + c,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        t * y * y + c,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        t * z * z + c,
    )
}

/// Rotation matrix of a quaternion given as (x, y, z, w), Pinocchio's storage order.
/// The quaternion must be of unit norm.
#[inline]
pub fn quaternion_xyzw_to_matrix(x: f64, y: f64, z: f64, w: f64) -> Matrix3<f64> {
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (xy, xz, yz) = (x * y, x * z, y * z);
    let (wx, wy, wz) = (w * x, w * y, w * z);
    Matrix3::new(
        1.0 - 2.0 * (yy + zz),
        2.0 * (xy - wz),
        2.0 * (xz + wy),
        2.0 * (xy + wz),
        1.0 - 2.0 * (xx + zz),
        2.0 * (yz - wx),
        2.0 * (xz - wy),
        2.0 * (yz + wx),
        1.0 - 2.0 * (xx + yy),
    )
}

/// Unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method: picks the
/// largest diagonal term so the square root never sees a small argument).
pub fn matrix_to_quaternion_xyzw(r: &Matrix3<f64>) -> [f64; 4] {
    let t = r[(0, 0)] + r[(1, 1)] + r[(2, 2)];
    let (x, y, z, w);
    if t > 0.0 {
        let s = (t + 1.0).sqrt() * 2.0;
        w = 0.25 * s;
        x = (r[(2, 1)] - r[(1, 2)]) / s;
        y = (r[(0, 2)] - r[(2, 0)]) / s;
        z = (r[(1, 0)] - r[(0, 1)]) / s;
    } else if r[(0, 0)] > r[(1, 1)] && r[(0, 0)] > r[(2, 2)] {
        let s = (1.0 + r[(0, 0)] - r[(1, 1)] - r[(2, 2)]).sqrt() * 2.0;
        w = (r[(2, 1)] - r[(1, 2)]) / s;
        x = 0.25 * s;
        y = (r[(0, 1)] + r[(1, 0)]) / s;
        z = (r[(0, 2)] + r[(2, 0)]) / s;
    } else if r[(1, 1)] > r[(2, 2)] {
        let s = (1.0 + r[(1, 1)] - r[(0, 0)] - r[(2, 2)]).sqrt() * 2.0;
        w = (r[(0, 2)] - r[(2, 0)]) / s;
        x = (r[(0, 1)] + r[(1, 0)]) / s;
        y = 0.25 * s;
        z = (r[(1, 2)] + r[(2, 1)]) / s;
    } else {
        let s = (1.0 + r[(2, 2)] - r[(0, 0)] - r[(1, 1)]).sqrt() * 2.0;
        w = (r[(1, 0)] - r[(0, 1)]) / s;
        x = (r[(0, 2)] + r[(2, 0)]) / s;
        y = (r[(1, 2)] + r[(2, 1)]) / s;
        z = 0.25 * s;
    }
    [x, y, z, w]
}

#[cfg(test)]
mod tests;
