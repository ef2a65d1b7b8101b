//! Inverse kinematics over the full configuration (floating base included) on weighted
//! tasks: points of frames reaching world targets (feet, virtual markers), frame
//! directions aligning (a flat sole), frame poses and orientations (a sole placed, the
//! pelvis upright), the CoM over a point, and a posture to stay near. The base moves on
//! SE(3) through [`twinloop_dynamics::configuration::integrate`]; [`Ik::free`] restricts
//! the coordinates that move.
//!
//! Two solvers share the tasks:
//!
//! - [`Ik::solve`]: Levenberg-Marquardt with adaptive damping; joint limits are respected
//!   by projection, with joints pressed against a limit held for the step (a bounded
//!   LM). For posing: static poses, marker fitting.
//! - [`Ik::least_squares`]: Gauss-Newton steps of least norm with a fixed damping,
//!   every step taken (Nakamura's damped least squares,
//!   `d = -J^T (J J^T + lambda^2 I)^-1 r`), optionally capped, ending on a tolerance or
//!   best-effort on the iteration cap. Nothing depends on accept/reject decisions, so
//!   the result is a smooth function of the start: what a motion differentiated
//!   afterwards ([`Ik::project`]) and a walking controller warm-started from the
//!   previous sample ([`crate::walking_ik`]) need.
//!
//! Everything is allocated in [`Ik::new`]: solving allocates nothing.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3, Vector6};
use twinloop_dynamics::configuration::integrate;
use twinloop_dynamics::{
    BASE, Data, Model, ReferenceFrame, compute_joint_jacobians, forward_kinematics, frame_jacobian,
};
use twinloop_spatial::{Se3, skew};

/// One weighted residual group.
#[derive(Debug, Clone)]
pub enum Task {
    /// `point` (in the frame) at world `target`; `weight` per world axis (0 ignores an axis).
    Point {
        frame: usize,
        point: Vector3<f64>,
        target: Vector3<f64>,
        weight: Vector3<f64>,
    },
    /// Direction `axis` (unit, in the frame) along world direction `target` (unit);
    /// `weight` per world component of the difference. Weight only the components
    /// that matter (2 for a direction, 1 for a heading): a third, redundant row would
    /// make the least-norm projection erratic.
    Axis {
        frame: usize,
        axis: Vector3<f64>,
        target: Vector3<f64>,
        weight: Vector3<f64>,
    },
    /// The frame's pose at `target`: position rows `w (p - p_des)` and orientation rows
    /// the rotation vector `-w log(R_des R^T)` (world axes; zero at the target); `weight`
    /// per row, three position then three rotation.
    Pose {
        frame: usize,
        target: Se3,
        weight: Vector6<f64>,
    },
    /// The frame's orientation at `target`: the rotation vector `-w log(R_des R^T)`
    /// (world axes); `weight` per world axis.
    Orientation {
        frame: usize,
        target: Matrix3<f64>,
        weight: Vector3<f64>,
    },
    /// Centre of mass at `target`; `weight` per world axis.
    Com {
        target: Vector3<f64>,
        weight: Vector3<f64>,
    },
    /// Joint coordinates near `reference` (one per joint, model order), weighted per joint.
    Posture {
        reference: Vec<f64>,
        weight: Vec<f64>,
    },
}

impl Task {
    fn dim(&self) -> usize {
        match self {
            Task::Point { .. }
            | Task::Axis { .. }
            | Task::Orientation { .. }
            | Task::Com { .. } => 3,
            Task::Pose { .. } => 6,
            Task::Posture { reference, .. } => reference.len(),
        }
    }
}

/// Solver settings.
#[derive(Debug, Clone)]
pub struct IkOptions {
    pub max_iterations: usize,
    /// Stop when the cost (half the squared residual norm) is below this.
    pub cost_tolerance: f64,
    /// Stop when a step is smaller than this (max norm).
    pub step_tolerance: f64,
    /// Stop when the gradient's max norm is below this.
    pub gradient_tolerance: f64,
    /// Keep configuration limits (joint lower/upper).
    pub respect_limits: bool,
}

impl Default for IkOptions {
    fn default() -> Self {
        IkOptions {
            max_iterations: 100,
            cost_tolerance: 1e-24,
            step_tolerance: 1e-12,
            gradient_tolerance: 1e-14,
            respect_limits: true,
        }
    }
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkReport {
    pub iterations: usize,
    /// Half the squared residual norm at the solution.
    pub cost: f64,
    /// Largest absolute entry of the residual at the solution.
    pub max_residual: f64,
    /// Euclidean norm of the residual at the solution (m and rad for unit weights).
    pub error: f64,
}

/// Which size of the residual [`Ik::least_squares`] compares with its tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResidualNorm {
    /// The largest absolute entry.
    Max,
    /// The Euclidean norm.
    Euclidean,
}

/// The damping `lambda^2` added to `J J^T` in [`Ik::least_squares`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Damping {
    /// `lambda^2 = factor trace(J J^T)`: scale-free, just enough to keep the Cholesky
    /// factorisation defined when tasks are redundant.
    RelativeToTrace(f64),
    /// A fixed `lambda` (its square is added): bounds the step near a singularity (a
    /// stretched knee) at the price of a least-squares compromise there.
    Fixed(f64),
}

/// Settings of [`Ik::least_squares`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeastSquaresOptions {
    pub max_iterations: usize,
    /// Converged when the residual's size (in `norm`) is at most this.
    pub tolerance: f64,
    pub norm: ResidualNorm,
    pub damping: Damping,
    /// Largest Euclidean norm of a step; longer steps are scaled down (a long Newton
    /// step from a warm start means a singular direction). `f64::INFINITY`: no cap.
    pub max_step: f64,
}

/// Why [`Ik::least_squares`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LeastSquaresEnd {
    /// The residual is within the tolerance.
    Converged,
    /// The iteration cap was reached: `q` is the last iterate.
    OutOfIterations,
    /// The residual stopped being finite.
    NotFinite,
    /// `J J^T + lambda^2 I` is not positive definite (no damping and a singular task).
    Singular,
}

/// A task set with its workspace.
#[derive(Debug, Clone)]
pub struct Ik {
    pub tasks: Vec<Task>,
    /// Velocity coordinates allowed to move (all by default).
    pub free: Vec<bool>,
    nres: usize,
    r: DVector<f64>,
    jac: DMatrix<f64>,
    jf: DMatrix<f64>,
    a: DMatrix<f64>,
    jtj: DMatrix<f64>,
    g: DVector<f64>,
    delta: DVector<f64>,
    q_trial: Vec<f64>,
    frozen: Vec<bool>,
    jjt: DMatrix<f64>,
    y: DVector<f64>,
}

/// World placement of a frame after forward kinematics.
pub fn frame_placement(model: &Model, data: &Data, frame: usize) -> Se3 {
    let f = &model.frames[frame];
    let parent = if f.body == BASE {
        data.base_placement
    } else {
        data.o_m_i[f.body]
    };
    parent * f.placement
}

/// Solve `a x = b` for symmetric positive definite `a` in place (Cholesky; `a` is
/// overwritten by its factor, `b` by the solution). False if `a` is not positive definite.
pub fn cholesky_solve_in_place(a: &mut DMatrix<f64>, b: &mut DVector<f64>) -> bool {
    let n = a.nrows();
    for j in 0..n {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= a[(j, k)] * a[(j, k)];
        }
        if d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        a[(j, j)] = d;
        for i in (j + 1)..n {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= a[(i, k)] * a[(j, k)];
            }
            a[(i, j)] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[(i, k)] * b[k];
        }
        b[i] = s / a[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in (i + 1)..n {
            s -= a[(k, i)] * b[k];
        }
        b[i] = s / a[(i, i)];
    }
    true
}

impl Ik {
    pub fn new(model: &Model, tasks: Vec<Task>) -> Ik {
        let nres: usize = tasks.iter().map(Task::dim).sum();
        let nv = model.nv;
        Ik {
            tasks,
            free: vec![true; nv],
            nres,
            r: DVector::zeros(nres),
            jac: DMatrix::zeros(nres, nv),
            jf: DMatrix::zeros(6, nv),
            a: DMatrix::zeros(nv, nv),
            jtj: DMatrix::zeros(nv, nv),
            g: DVector::zeros(nv),
            delta: DVector::zeros(nv),
            q_trial: vec![0.0; model.nq],
            frozen: vec![false; nv],
            jjt: DMatrix::zeros(nres, nres),
            y: DVector::zeros(nres),
        }
    }

    /// Only these velocity coordinates move (the others keep their value).
    pub fn set_free(&mut self, free: impl Fn(usize) -> bool) {
        for (k, f) in self.free.iter_mut().enumerate() {
            *f = free(k);
        }
    }

    /// The residual vector of the last evaluation.
    pub fn residual(&self) -> &DVector<f64> {
        &self.r
    }

    /// Residuals (and their Jacobian if `jacobian`) at `q`; returns the cost ½|r|².
    pub fn evaluate(&mut self, model: &Model, data: &mut Data, q: &[f64], jacobian: bool) -> f64 {
        debug_assert_eq!(self.r.len(), self.nres);
        self.kinematics(model, data, q, jacobian);
        let mut rows = Rows {
            r: &mut self.r,
            jac: &mut self.jac,
            jf: &mut self.jf,
            jacobian,
            row: 0,
        };
        for t in &self.tasks {
            match t {
                Task::Point {
                    frame,
                    point,
                    target,
                    weight,
                } => rows.point(model, data, *frame, point, target, weight),
                Task::Axis {
                    frame,
                    axis,
                    target,
                    weight,
                } => rows.axis(model, data, *frame, axis, target, weight),
                Task::Pose {
                    frame,
                    target,
                    weight,
                } => rows.pose(model, data, *frame, target, weight),
                Task::Orientation {
                    frame,
                    target,
                    weight,
                } => rows.orientation(model, data, *frame, target, weight),
                Task::Com { target, weight } => rows.com(model, data, target, weight),
                Task::Posture { reference, weight } => rows.posture(model, q, reference, weight),
            }
            rows.row += t.dim();
        }
        0.5 * self.r.norm_squared()
    }

    /// The kinematics the tasks read: forward kinematics, the CoM (and its Jacobian)
    /// if a task needs it, the joint Jacobians if `jacobian`.
    fn kinematics(&self, model: &Model, data: &mut Data, q: &[f64], jacobian: bool) {
        let has_com = self.tasks.iter().any(|t| matches!(t, Task::Com { .. }));
        if has_com {
            if jacobian {
                twinloop_dynamics::jacobian_center_of_mass(model, data, q);
            } else {
                twinloop_dynamics::center_of_mass(model, data, q);
            }
        }
        if jacobian {
            compute_joint_jacobians(model, data, q);
        } else if !has_com {
            forward_kinematics(model, data, q);
        }
    }

    /// Levenberg-Marquardt from `q` (updated in place). Steps are taken in the tangent
    /// space and mapped back with `integrate`; joints are clamped to their limits and
    /// a joint at a limit that the step would push further out is held for that step.
    pub fn solve(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &mut [f64],
        opts: &IkOptions,
    ) -> IkReport {
        let nv = model.nv;
        if opts.respect_limits {
            clamp_to_limits(model, q);
        }
        let mut cost = self.evaluate(model, data, q, true);
        self.normal_equations();
        let mut mu = -1.0;
        let mut nu = 2.0;
        let mut it = 0;
        while it < opts.max_iterations && cost > opts.cost_tolerance {
            it += 1;
            for k in 0..nv {
                let mut frozen = !self.free[k];
                if !frozen && opts.respect_limits && k >= model.v_offset {
                    let i = k - model.v_offset;
                    let x = q[model.q_offset + i];
                    let (lo, hi) = (model.lower_limits[i], model.upper_limits[i]);
                    // The descent direction is -g: at the lower limit a positive g pushes out.
                    frozen = (x <= lo + 1e-12 && self.g[k] > 0.0)
                        || (x >= hi - 1e-12 && self.g[k] < 0.0);
                }
                self.frozen[k] = frozen;
            }
            let gmax = (0..nv)
                .filter(|&k| !self.frozen[k])
                .map(|k| self.g[k].abs())
                .fold(0.0, f64::max);
            if gmax < opts.gradient_tolerance {
                break;
            }
            if mu < 0.0 {
                let dmax = (0..nv).map(|k| self.jtj[(k, k)]).fold(0.0, f64::max);
                mu = 1e-6 * dmax.max(1e-12);
            }
            if !self.damped_step(nv, mu) {
                mu *= nu;
                nu *= 2.0;
                continue;
            }
            let step_max = self.delta.amax();
            integrate(model, q, self.delta.as_slice(), 1.0, &mut self.q_trial);
            if opts.respect_limits {
                clamp_to_limits(model, &mut self.q_trial);
            }
            let q_trial = std::mem::take(&mut self.q_trial);
            let trial = self.evaluate(model, data, &q_trial, false);
            // Predicted reduction of the linear model: -g.d - 1/2 d^T J^T J d = 1/2 d^T (mu d - g).
            let mut pred = 0.0;
            for k in 0..nv {
                pred += 0.5 * self.delta[k] * (mu * self.delta[k] - self.g[k]);
            }
            let rho = if pred > 0.0 {
                (cost - trial) / pred
            } else {
                -1.0
            };
            if trial < cost && rho > 0.0 {
                q.copy_from_slice(&q_trial);
                cost = self.evaluate(model, data, q, true);
                self.normal_equations();
                mu *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
            } else {
                mu *= nu;
                nu *= 2.0;
            }
            self.q_trial = q_trial;
            if step_max < opts.step_tolerance || mu > 1e30 {
                break;
            }
        }
        // Leave r at the solution.
        let cost = self.evaluate(model, data, q, false);
        IkReport {
            iterations: it,
            cost,
            max_residual: self.r.amax(),
            error: self.r.norm(),
        }
    }

    /// Gradient `g = J^T r` and Gauss-Newton matrix `J^T J` at the current point.
    fn normal_equations(&mut self) {
        self.g.gemv_tr(1.0, &self.jac, &self.r, 0.0);
        self.jtj.gemm_tr(1.0, &self.jac, &self.jac, 0.0);
    }

    /// Project `q` onto the zero set of the tasks by Gauss-Newton steps of least norm,
    /// `d = -J^T (J J^T + eps I)^-1 r` over the free coordinates, every step taken
    /// ([`Ik::least_squares`] with `eps = 1e-14 trace(J J^T)`, stopping when the largest
    /// residual is at most `tolerance`). Unlike the adaptive damping of
    /// [`solve`](Self::solve), nothing here depends on discrete accept/reject decisions,
    /// so the result is a smooth function of the start: what a motion differentiated
    /// afterwards needs. Joint limits are not enforced.
    pub fn project(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &mut [f64],
        max_iterations: usize,
        tolerance: f64,
    ) -> IkReport {
        let opts = LeastSquaresOptions {
            max_iterations,
            tolerance,
            norm: ResidualNorm::Max,
            damping: Damping::RelativeToTrace(1e-14),
            max_step: f64::INFINITY,
        };
        self.least_squares(model, data, q, &opts).0
    }

    /// Damped least squares from `q` (updated in place): while the residual exceeds the
    /// tolerance, `d = -J^T (J J^T + lambda^2 I)^-1 r` over the free coordinates (the
    /// other columns of `J` zeroed, so they get `d = 0`), capped to `max_step`, always
    /// taken. Joint limits are not enforced. Returns the report at the last iterate and
    /// why it stopped; on [`LeastSquaresEnd::OutOfIterations`] `q` is the best effort.
    pub fn least_squares(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &mut [f64],
        opts: &LeastSquaresOptions,
    ) -> (IkReport, LeastSquaresEnd) {
        let mut it = 0;
        let mut cost = self.evaluate(model, data, q, true);
        let end = loop {
            let size = match opts.norm {
                ResidualNorm::Max => self.r.amax(),
                ResidualNorm::Euclidean => self.r.norm(),
            };
            if !size.is_finite() {
                break LeastSquaresEnd::NotFinite;
            }
            if size <= opts.tolerance {
                break LeastSquaresEnd::Converged;
            }
            if it == opts.max_iterations {
                break LeastSquaresEnd::OutOfIterations;
            }
            it += 1;
            if !self.least_norm_step(model.nv, opts) {
                break LeastSquaresEnd::Singular;
            }
            integrate(model, q, self.delta.as_slice(), 1.0, &mut self.q_trial);
            q.copy_from_slice(&self.q_trial);
            cost = self.evaluate(model, data, q, true);
        };
        let report = IkReport {
            iterations: it,
            cost,
            max_residual: self.r.amax(),
            error: self.r.norm(),
        };
        (report, end)
    }

    /// `delta = -J^T (J J^T + lambda^2 I)^-1 r` with the frozen columns of `J` zeroed,
    /// scaled down to `max_step`. False if the damped `J J^T` is not positive definite.
    fn least_norm_step(&mut self, nv: usize, opts: &LeastSquaresOptions) -> bool {
        for c in 0..nv {
            if !self.free[c] {
                self.jac.column_mut(c).fill(0.0);
            }
        }
        self.jjt.gemm(1.0, &self.jac, &self.jac.transpose(), 0.0);
        let lambda2 = match opts.damping {
            Damping::RelativeToTrace(factor) => {
                let tr = (0..self.nres).map(|i| self.jjt[(i, i)]).sum::<f64>();
                factor * tr.max(1e-300)
            }
            Damping::Fixed(lambda) => lambda * lambda,
        };
        for i in 0..self.nres {
            self.jjt[(i, i)] += lambda2;
        }
        self.y.copy_from(&self.r);
        if !cholesky_solve_in_place(&mut self.jjt, &mut self.y) {
            return false;
        }
        self.delta.gemv_tr(-1.0, &self.jac, &self.y, 0.0);
        let norm = self.delta.norm();
        if norm > opts.max_step {
            self.delta *= opts.max_step / norm;
        }
        true
    }

    /// `(J^T J + mu I) d = -g` over the coordinates not frozen (frozen ones get d = 0).
    fn damped_step(&mut self, nv: usize, mu: f64) -> bool {
        for i in 0..nv {
            for j in 0..nv {
                self.a[(i, j)] = if self.frozen[i] || self.frozen[j] {
                    if i == j { 1.0 } else { 0.0 }
                } else {
                    self.jtj[(i, j)]
                };
            }
            if !self.frozen[i] {
                self.a[(i, i)] += mu;
            }
            self.delta[i] = if self.frozen[i] { 0.0 } else { -self.g[i] };
        }
        cholesky_solve_in_place(&mut self.a, &mut self.delta)
    }
}

/// Where the tasks write: the residual, the task Jacobian (if `jacobian`), the frame
/// Jacobian scratch, and the first row of the task being written.
struct Rows<'a> {
    r: &'a mut DVector<f64>,
    jac: &'a mut DMatrix<f64>,
    jf: &'a mut DMatrix<f64>,
    jacobian: bool,
    row: usize,
}

impl Rows<'_> {
    /// The frame's Jacobian, world-aligned at its origin, into the scratch.
    fn frame_jacobian(&mut self, model: &Model, data: &Data, frame: usize) {
        frame_jacobian(
            model,
            data,
            frame,
            ReferenceFrame::LocalWorldAligned,
            self.jf,
        );
    }

    /// Rows `w_k J_f[first + k]` (three weights) straight from the frame Jacobian (a frame's
    /// origin velocity from `first = 0`, its angular velocity from `first = 3`), at
    /// task row `at`.
    fn copy_frame_rows(&mut self, first: usize, weight: &[f64], at: usize) {
        for c in 0..self.jf.ncols() {
            for (k, w) in weight.iter().enumerate() {
                self.jac[(at + k, c)] = w * self.jf[(first + k, c)];
            }
        }
    }

    fn point(
        &mut self,
        model: &Model,
        data: &Data,
        frame: usize,
        point: &Vector3<f64>,
        target: &Vector3<f64>,
        weight: &Vector3<f64>,
    ) {
        let x = frame_placement(model, data, frame);
        let rp = x.rotation * point;
        let p = x.translation + rp;
        for k in 0..3 {
            self.r[self.row + k] = weight[k] * (p[k] - target[k]);
        }
        if self.jacobian {
            self.frame_jacobian(model, data, frame);
            let s = skew(&rp);
            point_rows(self.jf, &s, weight, self.jac, self.row);
        }
    }

    fn axis(
        &mut self,
        model: &Model,
        data: &Data,
        frame: usize,
        axis: &Vector3<f64>,
        target: &Vector3<f64>,
        weight: &Vector3<f64>,
    ) {
        let x = frame_placement(model, data, frame);
        let a = x.rotation * axis;
        for k in 0..3 {
            self.r[self.row + k] = weight[k] * (a[k] - target[k]);
        }
        if self.jacobian {
            self.frame_jacobian(model, data, frame);
            // d(R a) = w x (R a) = -[R a]x w.
            let s = -skew(&a);
            for c in 0..self.jf.ncols() {
                let w = Vector3::new(self.jf[(3, c)], self.jf[(4, c)], self.jf[(5, c)]);
                let d = s * w;
                for k in 0..3 {
                    self.jac[(self.row + k, c)] = weight[k] * d[k];
                }
            }
        }
    }

    /// Position rows `w (p - p_des)` with the frame's origin velocity as Jacobian, then
    /// orientation rows (see [`Rows::orientation`]).
    fn pose(
        &mut self,
        model: &Model,
        data: &Data,
        frame: usize,
        target: &Se3,
        weight: &Vector6<f64>,
    ) {
        let x = frame_placement(model, data, frame);
        for k in 0..3 {
            self.r[self.row + k] = weight[k] * (x.translation[k] - target.translation[k]);
        }
        let rotation = orientation_residual(&x.rotation, &target.rotation);
        for k in 0..3 {
            self.r[self.row + 3 + k] = weight[3 + k] * rotation[k];
        }
        if self.jacobian {
            self.frame_jacobian(model, data, frame);
            let row = self.row;
            self.copy_frame_rows(0, &weight.as_slice()[..3], row);
            self.copy_frame_rows(3, &weight.as_slice()[3..], row + 3);
        }
    }

    /// Rows `-w log(R_des R^T)`; their Jacobian is taken as the frame's angular velocity
    /// rows, exact at the target (where `d log = w dt`) and a Newton method converges
    /// to it quadratically all the same.
    fn orientation(
        &mut self,
        model: &Model,
        data: &Data,
        frame: usize,
        target: &Matrix3<f64>,
        weight: &Vector3<f64>,
    ) {
        let x = frame_placement(model, data, frame);
        let rotation = orientation_residual(&x.rotation, target);
        for k in 0..3 {
            self.r[self.row + k] = weight[k] * rotation[k];
        }
        if self.jacobian {
            self.frame_jacobian(model, data, frame);
            let row = self.row;
            self.copy_frame_rows(3, weight.as_slice(), row);
        }
    }

    fn com(&mut self, model: &Model, data: &Data, target: &Vector3<f64>, weight: &Vector3<f64>) {
        let c = data.com;
        for k in 0..3 {
            self.r[self.row + k] = weight[k] * (c[k] - target[k]);
        }
        if self.jacobian {
            for col in 0..model.nv {
                for k in 0..3 {
                    self.jac[(self.row + k, col)] = weight[k] * data.com_jacobian[(k, col)];
                }
            }
        }
    }

    fn posture(&mut self, model: &Model, q: &[f64], reference: &[f64], weight: &[f64]) {
        let (qo, vo) = (model.q_offset, model.v_offset);
        for i in 0..reference.len() {
            self.r[self.row + i] = weight[i] * (q[qo + i] - reference[i]);
            if self.jacobian {
                for col in 0..model.nv {
                    self.jac[(self.row + i, col)] = 0.0;
                }
                self.jac[(self.row + i, vo + i)] = weight[i];
            }
        }
    }
}

/// The orientation error of `rotation` from `target` as a residual: `-log(R_des R^T)`,
/// the rotation vector (world axes) that would take `target` back to `rotation`.
fn orientation_residual(rotation: &Matrix3<f64>, target: &Matrix3<f64>) -> Vector3<f64> {
    -rotation_log(&(target * rotation.transpose()))
}

/// Rotation vector of a rotation matrix (the SO(3) logarithm), robust near identity
/// (angle from atan2 of the skew part's norm and the trace; valid below pi).
pub fn rotation_log(r: &Matrix3<f64>) -> Vector3<f64> {
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

/// Rows of a point task: `w_k (J_v - [R p]x J_w)_k` for each world axis k.
fn point_rows(
    jf: &DMatrix<f64>,
    s: &Matrix3<f64>,
    weight: &Vector3<f64>,
    out: &mut DMatrix<f64>,
    row: usize,
) {
    for c in 0..jf.ncols() {
        let v = Vector3::new(jf[(0, c)], jf[(1, c)], jf[(2, c)]);
        let w = Vector3::new(jf[(3, c)], jf[(4, c)], jf[(5, c)]);
        let d = v - s * w;
        for k in 0..3 {
            out[(row + k, c)] = weight[k] * d[k];
        }
    }
}

/// Clamp joint coordinates into their limits.
pub fn clamp_to_limits(model: &Model, q: &mut [f64]) {
    for i in 0..model.nbodies {
        let x = &mut q[model.q_offset + i];
        let (lo, hi) = (model.lower_limits[i], model.upper_limits[i]);
        if lo <= hi {
            *x = x.clamp(lo, hi);
        }
    }
}
