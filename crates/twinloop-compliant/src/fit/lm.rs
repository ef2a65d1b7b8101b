//! Levenberg-Marquardt on the residuals (compact-model CoM minus recorded CoM, x and z
//! at every sample), with the exact Jacobian of the RK4 rollout from forward
//! sensitivities ([`super::sensitivity`]).
//!
//! The step solves `(J^T J + lambda mu I) delta = -J^T r` (Levenberg's damping, mu the
//! mean of diag(J^T J)): the corrections are dimensionless factors near 1, so a step is
//! measured alike in every parameter. lambda follows the gain ratio rho = actual /
//! predicted reduction of r^T r (Nielsen 1999), and is raised until the step fits a
//! trust radius (0.1 at first, grown by good steps, halved by bad ones).
//!
//! Why not Marquardt's scaling D = diag(J^T J): on COMAN the damping corrections
//! (gamma, epsilon) barely move the CoM, so their scaled damping is tiny and the first
//! steps throw them to -90 or 1500; and why a trust radius: the x-z stiffness block is
//! nearly singular (det K is a small difference of large products), so the static sag
//! K^-1 m g is far from linear in alpha, beta, and an undamped Gauss-Newton step from all
//! ones lands in a spurious minimum (alpha2 near 0). Both were seen on the seed's gait.

use super::sensitivity::normal_equations;
use super::{FitOptions, FitProblem, FitResult, Method, Progress};
use nalgebra::{DMatrix, DVector};

/// Relative parameter step below which the fit has converged.
const X_TOL: f64 = 1e-12;
/// Relative reduction of the cost below which an accepted step counts as converged.
const F_TOL: f64 = 1e-15;
/// First trust radius on the parameter step: the corrections are factors near 1 and the
/// rollout's response to them is far from linear beyond about 10 %.
const INITIAL_RADIUS: f64 = 0.1;

/// J^T J and J^T r of the free parameters, and r^T r, at free parameters `p`.
fn linearise(problem: &FitProblem, p: &[f64]) -> (DMatrix<f64>, DVector<f64>, f64) {
    let ne = normal_equations(&problem.model(&problem.full(p)), problem.data);
    let n = problem.dim();
    let a = DMatrix::from_fn(n, n, |r, c| ne.jtj[problem.free[r]][problem.free[c]]);
    let g = DVector::from_fn(n, |r, _| ne.jtr[problem.free[r]]);
    (a, g, ne.sse)
}

/// Minimises the MSE over the free parameters from their starting values.
pub fn levenberg_marquardt(
    problem: &FitProblem,
    options: &FitOptions,
    on_progress: &mut dyn FnMut(&Progress),
) -> FitResult {
    let n = problem.dim();
    let residuals = (2 * problem.data.len()) as f64;
    let jacobian_cost = 1 + n;
    let mut p = DVector::from_vec(problem.initial());
    let (mut a, mut g, mut sse) = linearise(problem, p.as_slice());
    let mut evaluations = jacobian_cost;
    let mut jacobians = 1;
    let mut radius = INITIAL_RADIUS;
    let mut lambda = 1e-3;
    let mut nu = 2.0;
    let mut history = Vec::new();
    let mut iterations = 0;
    let stop;
    let mut record = |evaluations: usize, sse: f64, p: &DVector<f64>| {
        let point = Progress {
            evaluations,
            mse: sse / residuals,
            params: problem.full(p.as_slice()),
        };
        on_progress(&point);
        history.push(point);
    };
    record(evaluations, sse, &p);
    loop {
        if sse / residuals <= options.target_mse {
            stop = "reached the target MSE".to_string();
            break;
        }
        if evaluations + 1 > options.max_evaluations {
            stop = format!("evaluation budget {} spent", options.max_evaluations);
            break;
        }
        iterations += 1;
        // Levenberg's damping lambda * mean(diag A) * I: the corrections are
        // dimensionless factors near 1, so every parameter's step is measured alike.
        let mean = a.trace() / n as f64;
        // Raise lambda until the step fits the trust radius (cheap: n x n solves).
        let mut delta = DVector::zeros(n);
        let mut solved = false;
        for _ in 0..200 {
            let mut damped = a.clone();
            for i in 0..n {
                damped[(i, i)] += lambda * mean;
            }
            if let Some(chol) = damped.cholesky() {
                delta = chol.solve(&(-&g));
                if delta.norm() <= radius {
                    solved = true;
                    break;
                }
            }
            lambda *= 2.0;
        }
        if !solved {
            stop = "the damped normal equations have no solution".to_string();
            break;
        }
        let trial = &p + &delta;
        let trial_sse = problem.mse(trial.as_slice()) * residuals;
        evaluations += 1;
        // r^T r of the linearised model: sse + 2 delta.g + delta^T A delta.
        let predicted = -(2.0 * delta.dot(&g) + delta.dot(&(&a * &delta)));
        let rho = (sse - trial_sse) / predicted;
        let small_step = (0..n).all(|i| delta[i].abs() <= X_TOL * (p[i].abs() + X_TOL));
        if trial_sse.is_finite() && trial_sse < sse && predicted > 0.0 {
            let reduction = (sse - trial_sse) / sse;
            p = trial;
            if evaluations + jacobian_cost > options.max_evaluations {
                sse = trial_sse;
                record(evaluations, sse, &p);
                stop = format!("evaluation budget {} spent", options.max_evaluations);
                break;
            }
            (a, g, sse) = linearise(problem, p.as_slice());
            evaluations += jacobian_cost;
            jacobians += 1;
            record(evaluations, sse, &p);
            lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
            nu = 2.0;
            if rho > 0.75 {
                radius = radius.max(3.0 * delta.norm());
            } else if rho < 0.25 {
                radius = 0.5 * delta.norm();
            }
            if small_step || reduction < F_TOL {
                stop = "converged (step or cost reduction below tolerance)".to_string();
                break;
            }
        } else {
            if small_step {
                stop = "converged (no smaller cost within tolerance)".to_string();
                break;
            }
            radius = 0.5 * delta.norm();
            lambda *= nu;
            nu *= 2.0;
        }
    }
    FitResult {
        method: Method::Lm,
        params: crate::Corrections::from_slice(&problem.full(p.as_slice())),
        mse_before: f64::NAN,
        mse_after: sse / residuals,
        evaluations,
        iterations,
        jacobians,
        stop,
        history,
    }
}
