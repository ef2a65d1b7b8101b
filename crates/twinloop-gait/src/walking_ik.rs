//! Whole-body inverse kinematics for walking: both sole poses, the CoM position and the
//! pelvis orientation, solved over the floating base and the twelve leg joints.
//!
//! # Formulation
//!
//! With the arms and waist held at their nominal angles, the unknowns are the base twist
//! (6) and the leg joint velocities (12): 18. The tasks are the two sole frames' poses
//! (6 + 6), the CoM (3) and the pelvis orientation (3): 18 as well, so the task
//! Jacobian `J` (18 x 18; sole rows LocalWorldAligned, CoM rows `Jcom`, pelvis rows
//! `[0 R_b 0]`) is square and, away from a stretched knee, invertible. Newton's method
//! with a damped least-squares step
//!
//! ```text
//! dx = J^T (J J^T + lambda^2 I)^-1 e,   q <- q (+) dx
//! ```
//!
//! (Nakamura's damped least squares; `e` stacks position errors and rotation vectors
//! `log(R_des R^T)` in the world) converges quadratically from the previous sample's
//! solution: a 1 kHz reference moves the solution by a few micro-radians per sample, so
//! one or two iterations reach 1e-10.

use crate::error::{GaitError, err};
use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};
use twinloop_dynamics::{
    BASE, Data, Model, ReferenceFrame, compute_joint_jacobians, frame_jacobian,
    jacobian_center_of_mass,
};
use twinloop_spatial::Se3;

/// Number of unknowns and of task rows.
const N: usize = 18;

/// Targets of one IK solve, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkTargets {
    /// Sole poses (left, right).
    pub soles: [Se3; 2],
    /// Whole-body CoM, m.
    pub com: Vector3<f64>,
    /// Pelvis (floating base) orientation.
    pub pelvis: Matrix3<f64>,
}

/// The solver: indices resolved once, buffers allocated once.
pub struct WholeBodyIk {
    /// Velocity columns of the unknowns: the base's six, then the leg joints.
    columns: [usize; N],
    /// Sole frames (left, right).
    soles: [usize; 2],
    jf: DMatrix<f64>,
    /// Convergence tolerance on the task error norm (m and rad), and iteration cap.
    pub tolerance: f64,
    pub max_iterations: usize,
    /// Damping lambda of the least-squares step.
    pub damping: f64,
    /// Return the last iterate instead of an error when the iterations run out (a
    /// controller must command something; near a stretched knee the damped step is the
    /// least-squares compromise).
    pub best_effort: bool,
    dq: Vec<f64>,
    q_next: Vec<f64>,
}

/// The result of a solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkReport {
    pub iterations: usize,
    /// Final task error norm.
    pub error: f64,
}

impl WholeBodyIk {
    /// A solver for a floating-base model with legs `[left, right]`, each six joint names
    /// hip to ankle, and the sole frame names.
    pub fn new(
        model: &Model,
        legs: [&[String; 6]; 2],
        sole_frames: [&str; 2],
    ) -> Result<WholeBodyIk, GaitError> {
        if !model.is_floating() {
            return err("whole-body IK needs a floating-base model");
        }
        let mut columns = [0; N];
        for (k, c) in columns.iter_mut().enumerate().take(6) {
            *c = k;
        }
        for (l, leg) in legs.iter().enumerate() {
            for (k, name) in leg.iter().enumerate() {
                let Some(i) = model.joint_index(name) else {
                    return err(format!("the model has no joint named {name}"));
                };
                columns[6 + 6 * l + k] = model.v_offset + i;
            }
        }
        let mut soles = [0; 2];
        for (s, name) in soles.iter_mut().zip(sole_frames) {
            let Some(f) = model.frame_index(name) else {
                return err(format!("the model has no frame named {name}"));
            };
            *s = f;
        }
        Ok(WholeBodyIk {
            columns,
            soles,
            jf: DMatrix::zeros(6, model.nv),
            tolerance: 1e-10,
            max_iterations: 20,
            damping: 1e-6,
            best_effort: false,
            dq: vec![0.0; model.nv],
            q_next: vec![0.0; model.nq],
        })
    }

    /// World placement of a frame after kinematics.
    pub fn frame_placement(model: &Model, data: &Data, frame: usize) -> Se3 {
        let f = &model.frames[frame];
        (if f.body == BASE {
            data.base_placement
        } else {
            data.o_m_i[f.body]
        }) * f.placement
    }

    /// The sole frames' indices (left, right).
    pub fn sole_frames(&self) -> [usize; 2] {
        self.soles
    }

    /// Solve in place from `q` (the warm start). Joints other than the legs keep their
    /// values. Errors if the targets are out of reach (no convergence: a leg would have to
    /// stretch beyond its length) or the state stops being finite.
    pub fn solve(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &mut [f64],
        targets: &IkTargets,
    ) -> Result<IkReport, GaitError> {
        let mut jac = SMatrix::<f64, N, N>::zeros();
        let mut e = SVector::<f64, N>::zeros();
        let mut error = f64::INFINITY;
        for it in 0..=self.max_iterations {
            // CoM rows (this also runs forward kinematics).
            let jc = jacobian_center_of_mass(model, data, q);
            for (c, &col) in self.columns.iter().enumerate() {
                for r in 0..3 {
                    jac[(12 + r, c)] = jc[(r, col)];
                }
            }
            let com = data.com;
            compute_joint_jacobians(model, data, q);
            for s in 0..2 {
                frame_jacobian(
                    model,
                    data,
                    self.soles[s],
                    ReferenceFrame::LocalWorldAligned,
                    &mut self.jf,
                );
                for (c, &col) in self.columns.iter().enumerate() {
                    for r in 0..6 {
                        jac[(6 * s + r, c)] = self.jf[(r, col)];
                    }
                }
                let m = Self::frame_placement(model, data, self.soles[s]);
                let target = &targets.soles[s];
                let dp = target.translation - m.translation;
                let dr = rotation_log(&(target.rotation * m.rotation.transpose()));
                for r in 0..3 {
                    e[6 * s + r] = dp[r];
                    e[6 * s + 3 + r] = dr[r];
                }
            }
            let dc = targets.com - com;
            let rb = data.base_placement.rotation;
            let dr = rotation_log(&(targets.pelvis * rb.transpose()));
            for r in 0..3 {
                e[12 + r] = dc[r];
                e[15 + r] = dr[r];
                // pelvis angular velocity in the world = R_b w_b
                for c in 0..N {
                    jac[(15 + r, c)] = if (3..6).contains(&c) {
                        rb[(r, c - 3)]
                    } else {
                        0.0
                    };
                }
            }
            error = e.norm();
            if !error.is_finite() {
                return err("whole-body IK: the configuration is no longer finite");
            }
            if error < self.tolerance {
                return Ok(IkReport {
                    iterations: it,
                    error,
                });
            }
            if it == self.max_iterations {
                if self.best_effort {
                    return Ok(IkReport {
                        iterations: it,
                        error,
                    });
                }
                break;
            }
            let a = jac * jac.transpose()
                + SMatrix::<f64, N, N>::identity() * (self.damping * self.damping);
            let Some(y) = a.cholesky().map(|c| c.solve(&e)) else {
                return err("whole-body IK: the task Jacobian is singular");
            };
            let mut dx = jac.transpose() * y;
            // Newton steps far from the warm start mean a singular direction: cap them.
            let norm = dx.norm();
            if norm > 0.2 {
                dx *= 0.2 / norm;
            }
            self.dq.iter_mut().for_each(|x| *x = 0.0);
            for (c, &col) in self.columns.iter().enumerate() {
                self.dq[col] = dx[c];
            }
            // The base columns of the world Jacobian are the base-frame unit twists, the
            // same coordinates `integrate` takes.
            twinloop_dynamics::configuration::integrate(model, q, &self.dq, 1.0, &mut self.q_next);
            q.copy_from_slice(&self.q_next);
        }
        err(format!(
            "whole-body IK did not converge (task error {error:.3e} after {} iterations): \
             the feet and CoM targets are out of the legs' reach (a step too long, or the \
             CoM too high for the legs)",
            self.max_iterations
        ))
    }
}

/// Rotation vector of a rotation matrix (the SO(3) logarithm), robust near identity
/// (angle from atan2 of the skew part's norm and the trace; valid below pi).
fn rotation_log(r: &Matrix3<f64>) -> Vector3<f64> {
    let w = 0.5
        * Vector3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        );
    let s = w.norm();
    let c = 0.5 * (r.trace() - 1.0);
    let angle = s.atan2(c);
    if s < 1e-12 {
        return w;
    }
    w * (angle / s)
}
