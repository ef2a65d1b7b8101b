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

impl Qp<'_> {
    /// Solve from a feasible `z0` (the equalities and inequalities must hold there, to
    /// within `1e-9` relative).
    pub fn solve(&self, z0: DVector<f64>) -> Result<QpSolution, String> {
        let n = self.h.nrows();
        let me = self.eq.nrows();
        let mi = self.ineq.nrows();
        let chol = Cholesky::new(self.h.clone())
            .ok_or("the quadratic program's Hessian is not positive definite")?;
        let l = chol.l();
        let mut z = z0;
        let scale = |row: nalgebra::DMatrixView<f64>| row.amax().max(1e-300);
        // Feasibility check of the start.
        for i in 0..me {
            let r = (self.eq.row(i) * &z)[0] - self.eq_rhs[i];
            if r.abs() > 1e-9 * (1.0 + self.eq_rhs[i].abs()) {
                return Err(format!("start point violates equality {i} by {r:e}"));
            }
        }
        let mut active: Vec<usize> = Vec::new();
        for i in 0..mi {
            let r = (self.ineq.row(i) * &z)[0] - self.ineq_rhs[i];
            let tol = 1e-9 * (1.0 + self.ineq_rhs[i].abs()) * scale(self.ineq.row(i).as_view());
            if r > tol {
                return Err(format!("start point violates inequality {i} by {r:e}"));
            }
        }
        let max_iter = 10 * (mi + n) + 50;
        let mut full_step = false;
        for it in 0..max_iter {
            // Working-set rows: equalities, then active inequalities.
            let w = me + active.len();
            let mut aw = DMatrix::zeros(w, n);
            for i in 0..me {
                aw.row_mut(i).copy_from(&self.eq.row(i));
            }
            for (k, &i) in active.iter().enumerate() {
                aw.row_mut(me + k).copy_from(&self.ineq.row(i));
            }
            // g = H z - f; the step p solves H p + A_W^T mu = -g, A_W p = 0.
            let g = self.h * &z - self.f;
            let u = l
                .solve_lower_triangular(&g)
                .ok_or("singular Cholesky factor")?;
            let y = l
                .solve_lower_triangular(&aw.transpose())
                .ok_or("singular Cholesky factor")?;
            let k = y.transpose() * &y;
            let rhs = -(y.transpose() * &u);
            let mu = if w > 0 {
                let lu = k.clone().lu();
                let sol = lu.solve(&rhs).ok_or(
                    "the working set of constraints is linearly dependent (degenerate bounds)",
                )?;
                if !sol.iter().all(|x| x.is_finite()) {
                    return Err("the working set of constraints is linearly dependent".into());
                }
                sol
            } else {
                DVector::zeros(0)
            };
            let t = &u + &y * &mu;
            let p = -l
                .tr_solve_lower_triangular(&t)
                .ok_or("singular Cholesky factor")?;
            let zmax = z.amax().max(1.0);
            // After a full step the point minimises over the working set (p is then
            // only round-off).
            if full_step || p.amax() <= 1e-13 * zmax {
                // Stationary on the working set: optimal if no active inequality pulls inward.
                let mut worst: Option<(usize, f64)> = None;
                for (k, _) in active.iter().enumerate() {
                    let m = mu[me + k];
                    if m < -1e-12 * (1.0 + mu.amax()) && worst.is_none_or(|(_, wm)| m < wm) {
                        worst = Some((k, m));
                    }
                }
                match worst {
                    None => {
                        let multipliers = (0..active.len()).map(|k| mu[me + k].max(0.0)).collect();
                        return Ok(QpSolution {
                            z,
                            active,
                            multipliers,
                            iterations: it + 1,
                        });
                    }
                    Some((k, _)) => {
                        active.remove(k);
                        full_step = false;
                        continue;
                    }
                }
            }
            // Longest feasible step along p.
            let mut alpha = 1.0;
            let mut blocking = None;
            for i in 0..mi {
                if active.contains(&i) {
                    continue;
                }
                let ap = (self.ineq.row(i) * &p)[0];
                if ap > 1e-14 * scale(self.ineq.row(i).as_view()) * p.amax() {
                    let slack = self.ineq_rhs[i] - (self.ineq.row(i) * &z)[0];
                    let a = (slack / ap).max(0.0);
                    if a < alpha {
                        alpha = a;
                        blocking = Some(i);
                    }
                }
            }
            z += &p * alpha;
            full_step = blocking.is_none();
            if let Some(i) = blocking {
                active.push(i);
            }
        }
        Err(format!(
            "the active-set method did not converge in {max_iter} iterations"
        ))
    }
}
