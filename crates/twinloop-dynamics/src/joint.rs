//! Joint transforms and motion subspaces: the 1-DoF joints and the spherical joint
//! (Pinocchio's JointModelSpherical: q a unit quaternion (x, y, z, w), v the angular
//! velocity in the child frame, motion subspace [0; I3]).

use crate::model::{JointType, Model};
use nalgebra::{Matrix3, Vector3};
use twinloop_spatial::{Force, Motion, Se3, axis_angle_sc, quaternion_xyzw_to_matrix, sin_cos};

/// `liMi = jointPlacement * M_joint(q)`; `q` is the whole configuration vector.
#[inline(always)]
pub(crate) fn joint_placement(model: &Model, i: usize, q: &[f64]) -> Se3 {
    let p = &model.joint_placements[i];
    let r = &p.rotation;
    let iq = model.idx_q[i];
    match model.joint_types[i] {
        JointType::RevoluteX => {
            let (s, c) = sin_cos(q[iq]);
            if model.keeps_axis[i] {
                // No placement rotation: the plane rotation itself.
                let r = Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c);
                return Se3::new(r, p.translation);
            }
            let c1 = r.column(1);
            let c2 = r.column(2);
            Se3::new(
                Matrix3::from_columns(&[r.column(0).into(), c1 * c + c2 * s, c2 * c - c1 * s]),
                p.translation,
            )
        }
        JointType::RevoluteY => {
            let (s, c) = sin_cos(q[iq]);
            if model.keeps_axis[i] {
                let r = Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c);
                return Se3::new(r, p.translation);
            }
            let c0 = r.column(0);
            let c2 = r.column(2);
            Se3::new(
                Matrix3::from_columns(&[c0 * c - c2 * s, r.column(1).into(), c0 * s + c2 * c]),
                p.translation,
            )
        }
        JointType::RevoluteZ => {
            let (s, c) = sin_cos(q[iq]);
            if model.keeps_axis[i] {
                let r = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
                return Se3::new(r, p.translation);
            }
            let c0 = r.column(0);
            let c1 = r.column(1);
            Se3::new(
                Matrix3::from_columns(&[c0 * c + c1 * s, c1 * c - c0 * s, r.column(2).into()]),
                p.translation,
            )
        }
        JointType::Revolute => {
            let (s, c) = sin_cos(q[iq]);
            Se3::new(r * axis_angle_sc(&model.axes[i], s, c), p.translation)
        }
        JointType::Prismatic => Se3::new(*r, p.translation + r * (model.axes[i] * q[iq])),
        JointType::Spherical => Se3::new(
            r * quaternion_xyzw_to_matrix(q[iq], q[iq + 1], q[iq + 2], q[iq + 3]),
            p.translation,
        ),
    }
}

/// `parent * li` with `li` body i's `liMi`. When the joint keeps an axis of its frame
/// (`Model::keeps_axis`), `li`'s rotation is a plane rotation: the product turns two of
/// the parent's columns (12 multiplications instead of 27) and leaves the third, with
/// the same sums as the full product (the skipped terms are exact zeros and ones).
#[inline(always)]
pub(crate) fn compose(model: &Model, i: usize, parent: &Se3, li: &Se3) -> Se3 {
    let p = &parent.rotation;
    let l = &li.rotation;
    let translation = p * li.translation + parent.translation;
    if !model.keeps_axis[i] {
        return Se3::new(p * l, translation);
    }
    // Column k of the product from the parent's columns a and b.
    let turn = |a: usize, b: usize, k: usize| -> Vector3<f64> {
        p.column(a) * l[(a, k)] + p.column(b) * l[(b, k)]
    };
    let kept = |a: usize| -> Vector3<f64> { p.column(a).into() };
    let rotation = match model.joint_types[i] {
        JointType::RevoluteX => Matrix3::from_columns(&[kept(0), turn(1, 2, 1), turn(1, 2, 2)]),
        JointType::RevoluteY => Matrix3::from_columns(&[turn(0, 2, 0), kept(1), turn(0, 2, 2)]),
        JointType::RevoluteZ => Matrix3::from_columns(&[turn(0, 1, 0), turn(0, 1, 1), kept(2)]),
        _ => p * l,
    };
    Se3::new(rotation, translation)
}

/// The joint velocity `S x` in the joint's own frame; `x` starts at the joint's
/// first velocity coordinate.
#[inline(always)]
pub(crate) fn subspace_times(model: &Model, i: usize, x: &[f64]) -> Motion {
    match model.joint_types[i] {
        JointType::RevoluteX => Motion::new(Vector3::zeros(), Vector3::new(x[0], 0.0, 0.0)),
        JointType::RevoluteY => Motion::new(Vector3::zeros(), Vector3::new(0.0, x[0], 0.0)),
        JointType::RevoluteZ => Motion::new(Vector3::zeros(), Vector3::new(0.0, 0.0, x[0])),
        JointType::Revolute => Motion::new(Vector3::zeros(), model.axes[i] * x[0]),
        JointType::Prismatic => Motion::new(model.axes[i] * x[0], Vector3::zeros()),
        JointType::Spherical => Motion::new(Vector3::zeros(), Vector3::new(x[0], x[1], x[2])),
    }
}

/// `S^T f` in the joint's own frame, written to `out[0..nv]`.
#[inline(always)]
pub(crate) fn subspace_dot(model: &Model, i: usize, f: &Force, out: &mut [f64]) {
    match model.joint_types[i] {
        JointType::RevoluteX => out[0] = f.n.x,
        JointType::RevoluteY => out[0] = f.n.y,
        JointType::RevoluteZ => out[0] = f.n.z,
        JointType::Revolute => out[0] = model.axes[i].dot(&f.n),
        JointType::Prismatic => out[0] = model.axes[i].dot(&f.f),
        JointType::Spherical => out[0..3].copy_from_slice(f.n.as_slice()),
    }
}

/// Column `k` of the joint's motion subspace expressed through the body placement
/// `x` (e.g. in base or world coordinates). A spherical joint's columns are unit
/// rotations about the body's own x, y and z axes.
#[inline(always)]
pub(crate) fn subspace_column(model: &Model, i: usize, k: usize, x: &Se3) -> Motion {
    let about_body_axis = |a: usize| {
        let w: Vector3<f64> = x.rotation.column(a).into();
        Motion::new(x.translation.cross(&w), w)
    };
    match model.joint_types[i] {
        JointType::RevoluteX => about_body_axis(0),
        JointType::RevoluteY => about_body_axis(1),
        JointType::RevoluteZ => about_body_axis(2),
        JointType::Spherical => about_body_axis(k),
        JointType::Revolute => {
            let w = x.rotation * model.axes[i];
            Motion::new(x.translation.cross(&w), w)
        }
        JointType::Prismatic => Motion::new(x.rotation * model.axes[i], Vector3::zeros()),
    }
}

/// Every column of the joint's subspace through `x`, into `out[0..nv]`.
#[inline(always)]
pub(crate) fn subspace_in(model: &Model, i: usize, x: &Se3, out: &mut [Motion]) {
    out[0] = subspace_column(model, i, 0, x);
    if model.joint_types[i] == JointType::Spherical {
        out[1] = subspace_column(model, i, 1, x);
        out[2] = subspace_column(model, i, 2, x);
    }
}
