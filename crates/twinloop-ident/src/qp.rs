//! A dense convex quadratic program by the primal active-set method (Nocedal &
//! Wright, *Numerical Optimization*, algorithm 16.3):
//!
//! ```text
//! minimise 1/2 z^T H z - f^T z   subject to   E z = e,   C z <= d
//! ```
//!
//! with `H` positive definite. The static identification has at most a few hundred
//! unknowns and few active bounds, so the equality-constrained subproblems are
//! solved through one Cholesky factor of `H` and a small Schur complement over the
//! working set.

use crate::IdentError;
use nalgebra::{Cholesky, DMatrix, DVector};

/// The problem; `eq` and `ineq` have one constraint per row.
pub struct Qp<'a> {
    pub h: &'a DMatrix<f64>,
    pub f: &'a DVector<f64>,
    pub eq: &'a DMatrix<f64>,
    pub eq_rhs: &'a DVector<f64>,
    pub ineq: &'a DMatrix<f64>,
    pub ineq_rhs: &'a DVector<f64>,
}

#[derive(Debug, Clone)]
pub struct QpSolution {
    pub z: DVector<f64>,
    /// Inequality rows active at the solution.
    pub active: Vec<usize>,
    /// Lagrange multipliers of the active inequalities (>= 0), same order.
    pub multipliers: Vec<f64>,
    pub iterations: usize,
}

/// A constraint row's size, for relative tolerances.
fn row_scale(row: nalgebra::DMatrixView<f64>) -> f64 {
    row.amax().max(1e-300)
}

impl Qp<'_> {
    /// Solve from a feasible `z0` (the equalities and inequalities must hold there, to
    /// within `1e-9` relative).
    pub fn solve(&self, z0: DVector<f64>) -> Result<QpSolution, IdentError> {
        let n = self.h.nrows();
        let me = self.eq.nrows();
        let mi = self.ineq.nrows();
        let chol = Cholesky::new(self.h.clone()).ok_or_else(|| {
            IdentError::new("the quadratic program's Hessian is not positive definite")
        })?;
        let l = chol.l();
        let mut z = z0;
        self.check_start(&z)?;
        let mut active: Vec<usize> = Vec::new();
        let max_iter = 10 * (mi + n) + 50;
        let mut full_step = false;
        for it in 0..max_iter {
            let (p, mu) = self.working_set_step(&l, &z, &active)?;
            let zmax = z.amax().max(1.0);
            // After a full step the point minimises over the working set (p is then
            // only round-off).
            if full_step || p.amax() <= 1e-13 * zmax {
                // Stationary on the working set: optimal if no active inequality pulls inward.
                match most_negative_multiplier(&mu, me, active.len()) {
                    None => {
                        let multipliers = (0..active.len()).map(|k| mu[me + k].max(0.0)).collect();
                        return Ok(QpSolution {
                            z,
                            active,
                            multipliers,
                            iterations: it + 1,
                        });
                    }
                    Some(k) => {
                        active.remove(k);
                        full_step = false;
                        continue;
                    }
                }
            }
            let (alpha, blocking) = self.longest_feasible_step(&z, &p, &active);
            z += &p * alpha;
            full_step = blocking.is_none();
            if let Some(i) = blocking {
                active.push(i);
            }
        }
        Err(IdentError::new(format!(
            "the active-set method did not converge in {max_iter} iterations"
        )))
    }

    /// Errors unless `z` satisfies the equalities and inequalities (to `1e-9` relative).
    fn check_start(&self, z: &DVector<f64>) -> Result<(), IdentError> {
        for i in 0..self.eq.nrows() {
            let r = (self.eq.row(i) * z)[0] - self.eq_rhs[i];
            if r.abs() > 1e-9 * (1.0 + self.eq_rhs[i].abs()) {
                return Err(IdentError::new(format!(
                    "start point violates equality {i} by {r:e}"
                )));
            }
        }
        for i in 0..self.ineq.nrows() {
            let r = (self.ineq.row(i) * z)[0] - self.ineq_rhs[i];
            let tol = 1e-9 * (1.0 + self.ineq_rhs[i].abs()) * row_scale(self.ineq.row(i).as_view());
            if r > tol {
                return Err(IdentError::new(format!(
                    "start point violates inequality {i} by {r:e}"
                )));
            }
        }
        Ok(())
    }

    /// The step to the minimiser over the working set (the equalities, then the
    /// `active` inequalities) and its multipliers: `p` solves `H p + A_W^T mu = -g`,
    /// `A_W p = 0` with `g = H z - f`, through the Cholesky factor `l` of `H` and the
    /// Schur complement `K = Y^T Y`, `Y = L^-1 A_W^T`.
    fn working_set_step(
        &self,
        l: &DMatrix<f64>,
        z: &DVector<f64>,
        active: &[usize],
    ) -> Result<(DVector<f64>, DVector<f64>), IdentError> {
        let (n, me) = (self.h.nrows(), self.eq.nrows());
        let w = me + active.len();
        let mut aw = DMatrix::zeros(w, n);
        for i in 0..me {
            aw.row_mut(i).copy_from(&self.eq.row(i));
        }
        for (k, &i) in active.iter().enumerate() {
            aw.row_mut(me + k).copy_from(&self.ineq.row(i));
        }
        let g = self.h * z - self.f;
        let u = l
            .solve_lower_triangular(&g)
            .ok_or_else(|| IdentError::new("singular Cholesky factor"))?;
        let y = l
            .solve_lower_triangular(&aw.transpose())
            .ok_or_else(|| IdentError::new("singular Cholesky factor"))?;
        let k = y.transpose() * &y;
        let rhs = -(y.transpose() * &u);
        let mu = if w > 0 {
            let lu = k.clone().lu();
            let sol = lu.solve(&rhs).ok_or_else(|| {
                IdentError::new(
                    "the working set of constraints is linearly dependent (degenerate bounds)",
                )
            })?;
            if !sol.iter().all(|x| x.is_finite()) {
                return Err(IdentError::new(
                    "the working set of constraints is linearly dependent",
                ));
            }
            sol
        } else {
            DVector::zeros(0)
        };
        let t = &u + &y * &mu;
        let p = -l
            .tr_solve_lower_triangular(&t)
            .ok_or_else(|| IdentError::new("singular Cholesky factor"))?;
        Ok((p, mu))
    }

    /// The longest step `alpha <= 1` along `p` that keeps the inactive inequalities, and
    /// the one that blocks it (None for the full step).
    fn longest_feasible_step(
        &self,
        z: &DVector<f64>,
        p: &DVector<f64>,
        active: &[usize],
    ) -> (f64, Option<usize>) {
        let mut alpha = 1.0;
        let mut blocking = None;
        for i in 0..self.ineq.nrows() {
            if active.contains(&i) {
                continue;
            }
            let ap = (self.ineq.row(i) * p)[0];
            if ap > 1e-14 * row_scale(self.ineq.row(i).as_view()) * p.amax() {
                let slack = self.ineq_rhs[i] - (self.ineq.row(i) * z)[0];
                let a = (slack / ap).max(0.0);
                if a < alpha {
                    alpha = a;
                    blocking = Some(i);
                }
            }
        }
        (alpha, blocking)
    }
}

/// The active inequality (index into the active list) whose multiplier is the most
/// negative, beyond round-off: the constraint to release. None: the point is optimal.
fn most_negative_multiplier(mu: &DVector<f64>, me: usize, n_active: usize) -> Option<usize> {
    let mut worst: Option<(usize, f64)> = None;
    for k in 0..n_active {
        let m = mu[me + k];
        if m < -1e-12 * (1.0 + mu.amax()) && worst.is_none_or(|(_, wm)| m < wm) {
            worst = Some((k, m));
        }
    }
    worst.map(|(k, _)| k)
}
