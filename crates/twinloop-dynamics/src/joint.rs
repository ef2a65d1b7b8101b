//! Joint transforms and motion subspaces of the 1-DoF joints.

use crate::model::{JointType, Model};
use nalgebra::{Matrix3, Vector3};
use twinloop_spatial::{Force, Motion, Se3, axis_angle_sc};

/// `liMi = jointPlacement * M_joint(q)`.
#[inline(always)]
pub(crate) fn joint_placement(model: &Model, i: usize, q: f64) -> Se3 {
    let p = &model.joint_placements[i];
    let r = &p.rotation;
    match model.joint_types[i] {
        JointType::RevoluteX => {
            let (s, c) = q.sin_cos();
            let c1 = r.column(1);
            let c2 = r.column(2);
            Se3::new(
                Matrix3::from_columns(&[r.column(0).into(), c1 * c + c2 * s, c2 * c - c1 * s]),
                p.translation,
            )
        }
        JointType::RevoluteY => {
            let (s, c) = q.sin_cos();
            let c0 = r.column(0);
            let c2 = r.column(2);
            Se3::new(
                Matrix3::from_columns(&[c0 * c - c2 * s, r.column(1).into(), c0 * s + c2 * c]),
                p.translation,
            )
        }
        JointType::RevoluteZ => {
            let (s, c) = q.sin_cos();
            let c0 = r.column(0);
            let c1 = r.column(1);
            Se3::new(
                Matrix3::from_columns(&[c0 * c + c1 * s, c1 * c - c0 * s, r.column(2).into()]),
                p.translation,
            )
        }
        JointType::Revolute => {
            let (s, c) = q.sin_cos();
            Se3::new(r * axis_angle_sc(&model.axes[i], s, c), p.translation)
        }
        JointType::Prismatic => Se3::new(*r, p.translation + r * (model.axes[i] * q)),
    }
}

/// The joint's motion subspace in its own frame, times `x`.
#[inline(always)]
pub(crate) fn subspace_times(model: &Model, i: usize, x: f64) -> Motion {
    match model.joint_types[i] {
        JointType::RevoluteX => Motion::new(Vector3::zeros(), Vector3::new(x, 0.0, 0.0)),
        JointType::RevoluteY => Motion::new(Vector3::zeros(), Vector3::new(0.0, x, 0.0)),
        JointType::RevoluteZ => Motion::new(Vector3::zeros(), Vector3::new(0.0, 0.0, x)),
        JointType::Revolute => Motion::new(Vector3::zeros(), model.axes[i] * x),
        JointType::Prismatic => Motion::new(model.axes[i] * x, Vector3::zeros()),
    }
}

/// `S^T f` in the joint's own frame.
#[inline(always)]
pub(crate) fn subspace_dot(model: &Model, i: usize, f: &Force) -> f64 {
    match model.joint_types[i] {
        JointType::RevoluteX => f.n.x,
        JointType::RevoluteY => f.n.y,
        JointType::RevoluteZ => f.n.z,
        JointType::Revolute => model.axes[i].dot(&f.n),
        JointType::Prismatic => model.axes[i].dot(&f.f),
    }
}

/// The joint's motion subspace expressed through the body placement `x` (e.g. in base
/// or world coordinates).
#[inline(always)]
pub(crate) fn subspace_in(model: &Model, i: usize, x: &Se3) -> Motion {
    match model.joint_types[i] {
        JointType::RevoluteX | JointType::RevoluteY | JointType::RevoluteZ => {
            let k = model.joint_types[i] as usize; // X=0, Y=1, Z=2
            let w: Vector3<f64> = x.rotation.column(k).into();
            Motion::new(x.translation.cross(&w), w)
        }
        JointType::Revolute => {
            let w = x.rotation * model.axes[i];
            Motion::new(x.translation.cross(&w), w)
        }
        JointType::Prismatic => Motion::new(x.rotation * model.axes[i], Vector3::zeros()),
    }
}
