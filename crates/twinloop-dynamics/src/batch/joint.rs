//! The joint formulas of `crate::joint` and the base placement of
//! `crate::kinematics` on lanes, operation for operation.

use super::lanes::{LANES, M3, Mo, V3, W, X};
use crate::model::{JointType, Model};
use twinloop_spatial::sin_cos_lanes;

/// Sine and cosine of a lane of angles (`twinloop_spatial::sin_cos` per lane).
#[inline(always)]
fn sc(x: W) -> (W, W) {
    let (s, c) = sin_cos_lanes::<LANES>(&x.0);
    (W(s), W(c))
}

/// Rotation of a unit quaternion (x, y, z, w), as `quaternion_xyzw_to_matrix`.
#[inline(always)]
pub(crate) fn quaternion_matrix(x: W, y: W, z: W, w: W) -> M3 {
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (xy, xz, yz) = (x * y, x * z, y * z);
    let (wx, wy, wz) = (w * x, w * y, w * z);
    M3 {
        m: [
            [1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy)],
            [2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx)],
            [2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy)],
        ],
    }
}

/// World placement of the base (`kinematics::base_placement`).
#[inline(always)]
pub(crate) fn base_placement(model: &Model, q: &[W]) -> X {
    if model.is_floating() {
        X {
            r: quaternion_matrix(q[3], q[4], q[5], q[6]),
            t: V3::new(q[0], q[1], q[2]),
        }
    } else {
        X::splat(&twinloop_spatial::Se3::IDENTITY)
    }
}

/// A rotation about a unit axis from (sin, cos), as `axis_angle_sc`.
#[inline(always)]
fn axis_angle(a: &V3, s: W, c: W) -> M3 {
    let t = 1.0 - c;
    let (x, y, z) = (a.x, a.y, a.z);
    M3 {
        m: [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ],
    }
}

/// `liMi` of body `i` (`joint::joint_placement`); 1-DoF joints only.
#[inline(always)]
pub(crate) fn joint_placement(model: &Model, i: usize, q: &[W]) -> X {
    let p = &model.joint_placements[i];
    let r = M3::splat(&p.rotation);
    let t = V3::splat(&p.translation);
    let x = q[model.idx_q[i]];
    let (one, zero) = (W::splat(1.0), W::ZERO);
    // Columns `a`, `b` of the placement turned by the angle: a c + b s, b c - a s.
    let turn = |a: usize, b: usize, s: W, c: W| {
        let (ca, cb) = (r.column(a), r.column(b));
        (ca.scale(c) + cb.scale(s), cb.scale(c) - ca.scale(s))
    };
    let rot = match model.joint_types[i] {
        JointType::RevoluteX => {
            let (s, c) = sc(x);
            if model.keeps_axis[i] {
                M3 {
                    m: [[one, zero, zero], [zero, c, -s], [zero, s, c]],
                }
            } else {
                let (c1, c2) = turn(1, 2, s, c);
                M3::from_columns(&[r.column(0), c1, c2])
            }
        }
        JointType::RevoluteY => {
            let (s, c) = sc(x);
            if model.keeps_axis[i] {
                M3 {
                    m: [[c, zero, s], [zero, one, zero], [-s, zero, c]],
                }
            } else {
                // c0 c - c2 s and c0 s + c2 c: the turn from column 2 to 0.
                let (c2, c0) = turn(2, 0, s, c);
                M3::from_columns(&[c0, r.column(1), c2])
            }
        }
        JointType::RevoluteZ => {
            let (s, c) = sc(x);
            if model.keeps_axis[i] {
                M3 {
                    m: [[c, -s, zero], [s, c, zero], [zero, zero, one]],
                }
            } else {
                let (c0, c1) = turn(0, 1, s, c);
                M3::from_columns(&[c0, c1, r.column(2)])
            }
        }
        JointType::Revolute => {
            let (s, c) = sc(x);
            r.mul_m(&axis_angle(&V3::splat(&model.axes[i]), s, c))
        }
        JointType::Prismatic => {
            let d = V3::splat(&model.axes[i]).scale(x);
            return X {
                r,
                t: t + r.mul_v(&d),
            };
        }
        JointType::Spherical => unreachable!("the lanes take 1-DoF joints only"),
    };
    X { r: rot, t }
}

/// `parent * li` (`joint::compose`): two turned columns when the joint keeps an axis.
#[inline(always)]
pub(crate) fn compose(model: &Model, i: usize, parent: &X, li: &X) -> X {
    let p = &parent.r;
    let l = &li.r;
    let t = p.mul_v(&li.t) + parent.t;
    if !model.keeps_axis[i] {
        return X { r: p.mul_m(l), t };
    }
    let turn =
        |a: usize, b: usize, k: usize| p.column(a).scale(l.m[a][k]) + p.column(b).scale(l.m[b][k]);
    let r = match model.joint_types[i] {
        JointType::RevoluteX => M3::from_columns(&[p.column(0), turn(1, 2, 1), turn(1, 2, 2)]),
        JointType::RevoluteY => M3::from_columns(&[turn(0, 2, 0), p.column(1), turn(0, 2, 2)]),
        JointType::RevoluteZ => M3::from_columns(&[turn(0, 1, 0), turn(0, 1, 1), p.column(2)]),
        _ => p.mul_m(l),
    };
    X { r, t }
}

/// The joint velocity `S x` in the joint frame (`joint::subspace_times`).
#[inline(always)]
pub(crate) fn subspace_times(model: &Model, i: usize, x: W) -> Mo {
    let z = W::ZERO;
    let w = match model.joint_types[i] {
        JointType::RevoluteX => V3::new(x, z, z),
        JointType::RevoluteY => V3::new(z, x, z),
        JointType::RevoluteZ => V3::new(z, z, x),
        JointType::Revolute => V3::splat(&model.axes[i]).scale(x),
        JointType::Prismatic => {
            return Mo {
                v: V3::splat(&model.axes[i]).scale(x),
                w: V3::ZERO,
            };
        }
        JointType::Spherical => unreachable!("the lanes take 1-DoF joints only"),
    };
    Mo { v: V3::ZERO, w }
}

/// `S^T f` in the joint frame (`joint::subspace_dot`).
#[inline(always)]
pub(crate) fn subspace_dot(model: &Model, i: usize, f: &super::lanes::Fo) -> W {
    match model.joint_types[i] {
        JointType::RevoluteX => f.n.x,
        JointType::RevoluteY => f.n.y,
        JointType::RevoluteZ => f.n.z,
        JointType::Revolute => V3::splat(&model.axes[i]).dot(&f.n),
        JointType::Prismatic => V3::splat(&model.axes[i]).dot(&f.f),
        JointType::Spherical => unreachable!("the lanes take 1-DoF joints only"),
    }
}

/// The joint's subspace column through `x` (`joint::subspace_column`).
#[inline(always)]
pub(crate) fn subspace_column(model: &Model, i: usize, x: &X) -> Mo {
    let about = |w: V3| Mo {
        v: x.t.cross(&w),
        w,
    };
    match model.joint_types[i] {
        JointType::RevoluteX => about(x.r.column(0)),
        JointType::RevoluteY => about(x.r.column(1)),
        JointType::RevoluteZ => about(x.r.column(2)),
        JointType::Revolute => about(x.r.mul_v(&V3::splat(&model.axes[i]))),
        JointType::Prismatic => Mo {
            v: x.r.mul_v(&V3::splat(&model.axes[i])),
            w: V3::ZERO,
        },
        JointType::Spherical => unreachable!("the lanes take 1-DoF joints only"),
    }
}
