//! The `Data` workspace: every buffer the algorithms write, allocated once per model.

use crate::model::Model;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use twinloop_spatial::{Force, LinearInertia, Motion, Se3, Symmetric6};

/// Workspace and results. Create one per model (and per thread); algorithms reuse
/// it and allocate nothing.
#[derive(Debug, Clone)]
pub struct Data {
    /// World placement of the base (floating) or identity (fixed base).
    pub base_placement: Se3,
    /// Placement of each body's joint frame in its parent body frame at the current q
    /// (forward kinematics, RNEA, the Jacobians, the regressor; CRBA leaves it).
    pub li_m_i: Vec<Se3>,
    /// World placement of each body (forward kinematics).
    pub o_m_i: Vec<Se3>,
    /// Placement of each body in the base frame (the frame the world-style algorithms use).
    pub b_m_i: Vec<Se3>,
    /// World placement of every frame (`update_frame_placements`).
    pub o_m_f: Vec<Se3>,
    /// Joint motion subspace, one column per joint velocity coordinate (`v_offset + k`
    /// is column k; one per body unless a joint is spherical), in base coordinates.
    pub s: Vec<Motion>,
    /// Body velocities, accelerations and forces (RNEA: body frames; ABA: base coordinates).
    pub v: Vec<Motion>,
    pub a: Vec<Motion>,
    pub f: Vec<Force>,
    /// Velocity-product accelerations (ABA).
    pub c: Vec<Motion>,
    /// Articulated-body inertias and bias forces (ABA).
    pub ia: Vec<Symmetric6>,
    pub pa: Vec<Force>,
    /// ABA's `U = IA S`, `D^-1` (1-DoF joints) and `u = tau - S^T pA`, per joint
    /// velocity coordinate like `s`.
    pub u_col: Vec<Force>,
    pub d_inv: Vec<f64>,
    pub u: Vec<f64>,
    /// ABA's 3 x 3 `D^-1` of each spherical joint's body (unused for 1-DoF joints).
    pub(crate) d_inv_ball: Vec<Matrix3<f64>>,
    /// Composite rigid-body inertias (CRBA), linear form about the base origin.
    pub(crate) ycrb: Vec<LinearInertia>,
    /// Subtree masses and first moments (CoM, CoM Jacobian).
    pub subtree_mass: Vec<f64>,
    pub(crate) subtree_moment: Vec<Vector3<f64>>,
    /// Joint torques and base wrench (RNEA, gravity, nonlinear effects).
    pub tau: DVector<f64>,
    /// Accelerations (ABA).
    pub ddq: DVector<f64>,
    /// Joint-space inertia matrix (CRBA): upper triangle, like Pinocchio; call
    /// [`Data::symmetrize_mass_matrix`] for the full matrix.
    pub mass_matrix: DMatrix<f64>,
    /// World-frame joint Jacobians, one column per velocity coordinate.
    pub joint_jacobians: DMatrix<f64>,
    /// CoM and its Jacobian (world frame).
    pub com: Vector3<f64>,
    pub com_jacobian: DMatrix<f64>,
    /// Inertial-parameter regressor: nv x 10 (bodies incl. the floating base).
    pub regressor: DMatrix<f64>,
    /// Static CoM regressor: 3 x 4 per description link.
    pub static_regressor: DMatrix<f64>,
}

impl Data {
    pub fn new(model: &Model) -> Data {
        let nb = model.nbodies;
        let nparam_bodies = nb + usize::from(model.is_floating());
        let ndof = model.nv - model.v_offset;
        Data {
            base_placement: Se3::IDENTITY,
            li_m_i: vec![Se3::IDENTITY; nb],
            o_m_i: vec![Se3::IDENTITY; nb],
            b_m_i: vec![Se3::IDENTITY; nb],
            o_m_f: vec![Se3::IDENTITY; model.frames.len()],
            s: vec![Motion::ZERO; ndof],
            v: vec![Motion::ZERO; nb],
            a: vec![Motion::ZERO; nb],
            f: vec![Force::ZERO; nb],
            c: vec![Motion::ZERO; nb],
            ia: vec![Symmetric6::ZERO; nb],
            pa: vec![Force::ZERO; nb],
            u_col: vec![Force::ZERO; ndof],
            d_inv: vec![0.0; ndof],
            u: vec![0.0; ndof],
            d_inv_ball: vec![Matrix3::zeros(); nb],
            ycrb: vec![LinearInertia::ZERO; nb],
            subtree_mass: vec![0.0; nb],
            subtree_moment: vec![Vector3::zeros(); nb],
            tau: DVector::zeros(model.nv),
            ddq: DVector::zeros(model.nv),
            mass_matrix: DMatrix::zeros(model.nv, model.nv),
            joint_jacobians: DMatrix::zeros(6, model.nv),
            com: Vector3::zeros(),
            com_jacobian: DMatrix::zeros(3, model.nv),
            regressor: DMatrix::zeros(model.nv, 10 * nparam_bodies),
            static_regressor: DMatrix::zeros(3, 4 * model.links.len()),
        }
    }

    /// Copy the upper triangle of the mass matrix into the lower one.
    pub fn symmetrize_mass_matrix(&mut self) {
        let n = self.mass_matrix.nrows();
        for j in 0..n {
            for i in (j + 1)..n {
                self.mass_matrix[(i, j)] = self.mass_matrix[(j, i)];
            }
        }
    }
}
