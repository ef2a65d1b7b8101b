//! Whole-body inverse kinematics for walking: both sole poses, the CoM position and the
//! pelvis orientation, solved over the floating base and the twelve leg joints. A
//! configuration of the one IK of [`crate::ik`]: four tasks and the free coordinates,
//! solved by its damped least squares.
//!
//! # Formulation
//!
//! With the arms and waist held at their nominal angles, the unknowns are the base twist
//! (6) and the leg joint velocities (12): 18. The tasks are the two sole frames' poses
//! (6 + 6, [`Task::Pose`]), the CoM (3) and the pelvis orientation (3,
//! [`Task::Orientation`] of the base frame): 18 as well, so the task Jacobian `J` (sole
//! rows LocalWorldAligned, CoM rows `Jcom`, pelvis rows `[0 R_b 0]`) is square over the
//! free coordinates and, away from a stretched knee, invertible. Newton's method with a
//! damped least-squares step
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
use crate::ik::{Damping, Ik, IkReport, LeastSquaresEnd, LeastSquaresOptions, ResidualNorm, Task};
use nalgebra::{Matrix3, Vector3, Vector6};
use twinloop_dynamics::{BASE, Data, Model};
use twinloop_spatial::Se3;

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

/// Task order in the [`Ik`]: the soles' poses, the CoM, the pelvis orientation.
const LEFT_SOLE: usize = 0;
const RIGHT_SOLE: usize = 1;
const COM: usize = 2;
const PELVIS: usize = 3;

/// The walking configuration of the IK: tasks built once, targets set per solve.
pub struct WholeBodyIk {
    ik: Ik,
    /// Sole frames (left, right).
    soles: [usize; 2],
    /// Convergence tolerance on the task error norm (m and rad), and iteration cap.
    pub tolerance: f64,
    pub max_iterations: usize,
    /// Damping lambda of the least-squares step.
    pub damping: f64,
    /// Return the last iterate instead of an error when the iterations run out (a
    /// controller must command something; near a stretched knee the damped step is the
    /// least-squares compromise).
    pub best_effort: bool,
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
        let mut leg_columns = [0; 12];
        for (l, leg) in legs.iter().enumerate() {
            for (k, name) in leg.iter().enumerate() {
                let Some(i) = model.joint_index(name) else {
                    return err(format!("the model has no joint named {name}"));
                };
                leg_columns[6 * l + k] = model.v_offset + i;
            }
        }
        let mut soles = [0; 2];
        for (s, name) in soles.iter_mut().zip(sole_frames) {
            let Some(f) = model.frame_index(name) else {
                return err(format!("the model has no frame named {name}"));
            };
            *s = f;
        }
        // The pelvis is the base link's own frame: on the base, at its origin.
        let Some(pelvis) = model
            .frames
            .iter()
            .position(|f| f.body == BASE && f.placement == Se3::IDENTITY)
        else {
            return err("the model has no frame for its base link");
        };
        let sole = |frame| Task::Pose {
            frame,
            target: Se3::IDENTITY,
            weight: Vector6::repeat(1.0),
        };
        let tasks = vec![
            sole(soles[0]),
            sole(soles[1]),
            Task::Com {
                target: Vector3::zeros(),
                weight: Vector3::repeat(1.0),
            },
            Task::Orientation {
                frame: pelvis,
                target: Matrix3::identity(),
                weight: Vector3::repeat(1.0),
            },
        ];
        let mut ik = Ik::new(model, tasks);
        ik.set_free(|k| k < 6 || leg_columns.contains(&k));
        Ok(WholeBodyIk {
            ik,
            soles,
            tolerance: 1e-10,
            max_iterations: 20,
            damping: 1e-6,
            best_effort: false,
        })
    }

    /// World placement of a frame after kinematics.
    pub fn frame_placement(model: &Model, data: &Data, frame: usize) -> Se3 {
        crate::ik::frame_placement(model, data, frame)
    }

    /// The sole frames' indices (left, right).
    pub fn sole_frames(&self) -> [usize; 2] {
        self.soles
    }

    /// Solve in place from `q` (the warm start). Joints other than the legs keep their
    /// values. `error` in the report is the task error norm. Errors if the targets are
    /// out of reach (no convergence: a leg would have to stretch beyond its length) or
    /// the state stops being finite.
    pub fn solve(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &mut [f64],
        targets: &IkTargets,
    ) -> Result<IkReport, GaitError> {
        self.set_targets(targets);
        let opts = LeastSquaresOptions {
            max_iterations: self.max_iterations,
            tolerance: self.tolerance,
            norm: ResidualNorm::Euclidean,
            damping: Damping::Fixed(self.damping),
            max_step: 0.2,
        };
        let (report, end) = self.ik.least_squares(model, data, q, &opts);
        match end {
            LeastSquaresEnd::Converged => Ok(report),
            LeastSquaresEnd::OutOfIterations if self.best_effort => Ok(report),
            LeastSquaresEnd::NotFinite => {
                err("whole-body IK: the configuration is no longer finite")
            }
            LeastSquaresEnd::Singular => err("whole-body IK: the task Jacobian is singular"),
            LeastSquaresEnd::OutOfIterations => err(format!(
                "whole-body IK did not converge (task error {:.3e} after {} iterations): \
                 the feet and CoM targets are out of the legs' reach (a step too long, or \
                 the CoM too high for the legs)",
                report.error, self.max_iterations
            )),
        }
    }

    fn set_targets(&mut self, targets: &IkTargets) {
        for (task, sole) in [LEFT_SOLE, RIGHT_SOLE].into_iter().zip(targets.soles) {
            if let Task::Pose { target, .. } = &mut self.ik.tasks[task] {
                *target = sole;
            }
        }
        if let Task::Com { target, .. } = &mut self.ik.tasks[COM] {
            *target = targets.com;
        }
        if let Task::Orientation { target, .. } = &mut self.ik.tasks[PELVIS] {
            *target = targets.pelvis;
        }
    }
}
