//! Whether forward dynamics has a solution: the mass matrix is singular exactly when
//! some joint's articulated inertia about its own motion subspace,
//! `D = S^T IA S` (+ armature), is (RBDA section 7.3: ABA divides by it). That
//! happens when nothing with mass moves with the joint, when its mass lies on its
//! axis, or when a massless link sits between two joints with the same axis.

use crate::aba::aba;
use crate::data::Data;
use crate::model::{JointType, Model};
use nalgebra::{DVector, Matrix3};
use std::fmt;

/// A pivot at most this fraction of the joint's articulated-inertia scale is zero.
pub const SINGULAR_RELATIVE_TOLERANCE: f64 = 1e-12;

/// The joint at which the mass matrix is singular (`None`: the floating base, whose
/// locked-robot inertia is singular).
#[derive(Debug, Clone, PartialEq)]
pub struct SingularJoint {
    pub joint: Option<String>,
    /// The smallest pivot `D` found there (kg m^2 or kg).
    pub pivot: f64,
}

impl fmt::Display for SingularJoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.joint {
            Some(j) => write!(
                f,
                "the mass matrix is singular at joint \"{j}\": the inertia that moves with it \
                 about its axis is {:e} (nothing with mass moves with it, its mass lies on its \
                 axis, or a massless link joins it to a joint with the same axis), so forward \
                 dynamics has no solution; give the link a mass and inertia",
                self.pivot
            ),
            None => write!(
                f,
                "the mass matrix is singular at the floating base: the whole robot's spatial \
                 inertia is singular (no mass, or all mass on one line), so forward dynamics \
                 has no solution"
            ),
        }
    }
}

impl std::error::Error for SingularJoint {}

/// [`aba`], refusing a singular mass matrix with the joint at fault instead of
/// returning infinite or NaN accelerations.
pub fn try_aba<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
) -> Result<&'a DVector<f64>, SingularJoint> {
    aba(model, data, q, v, tau);
    singular_pivot(model, data)?;
    Ok(&data.ddq)
}

/// Whether the mass matrix at `q` is invertible (runs ABA's passes with v = 0).
pub fn check_mass_matrix(model: &Model, data: &mut Data, q: &[f64]) -> Result<(), SingularJoint> {
    let zero = vec![0.0; model.nv];
    try_aba(model, data, q, &zero, &zero).map(|_| ())
}

/// The first joint (leaves first, as ABA meets them) whose pivot is zero, after
/// [`aba`] has left each body's articulated inertia in `data.ia`.
fn singular_pivot(model: &Model, data: &Data) -> Result<(), SingularJoint> {
    for i in (0..model.nbodies).rev() {
        let ia = &data.ia[i];
        let scale = ia.a.abs().max().max(ia.b.abs().max()).max(ia.c.abs().max());
        let d = model.idx_v[i] - model.v_offset;
        let n = model.joint_types[i].nv();
        let mut dm = Matrix3::identity() * model.armature[i];
        for r in 0..n {
            for c in 0..n {
                dm[(r, c)] += data.s[d + r].dot(&ia.mul_motion(&data.s[d + c]));
            }
        }
        let pivot = if model.joint_types[i] == JointType::Spherical {
            dm.symmetric_eigenvalues().min()
        } else {
            dm[(0, 0)]
        };
        let floor = SINGULAR_RELATIVE_TOLERANCE * (scale + model.armature[i]);
        // NaN (a non-finite model) counts as singular too.
        if pivot.is_nan() || pivot <= floor {
            return Err(SingularJoint {
                joint: Some(model.joint_names[i].clone()),
                pivot,
            });
        }
    }
    if model.is_floating() && data.ddq.iter().take(6).any(|x| !x.is_finite()) {
        return Err(SingularJoint {
            joint: None,
            pivot: 0.0,
        });
    }
    Ok(())
}
