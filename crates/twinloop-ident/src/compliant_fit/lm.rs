//! Levenberg-Marquardt on the residuals (compact-model CoM minus recorded CoM, x and z
//! at every sample), with the exact Jacobian of the RK4 rollout from forward
//! sensitivities ([`super::sensitivity`]).
//!
//! A trust-region Levenberg-Marquardt: each iteration takes the Gauss-Newton step if it
//! is within the trust radius, else the Levenberg step `(J^T J + lambda mu I) delta =
//! -J^T r` (mu the mean of diag(J^T J)) with lambda just large enough to bring it inside.
//! The radius is measured in the parameters themselves: the corrections are
//! dimensionless factors near 1, so a step counts alike in every one. It starts at 0.1,
//! triples after a step whose gain ratio rho (actual / predicted reduction of r^T r) is
//! above 0.75, and halves after one below 0.25 or a rejected one (Moré 1978, Nocedal and
//! Wright ch. 4, in the unscaled metric).
//!
//! Why not Marquardt's scaling D = diag(J^T J) (MINPACK's choice): on COMAN the damping
//! corrections (gamma, epsilon) barely move the CoM, so their scaled step is barely
//! limited and the first steps throw them to -90 or 1500 (with the pelvis held MINPACK
//! needs 400-700 evaluations, this 100-150); and why a trust radius at all: the x-z stiffness block is
//! nearly singular (det K is a small difference of large products), so the static sag
//! K^-1 m g is far from linear in alpha, beta, and an undamped Gauss-Newton step from all
//! ones lands in a spurious minimum (alpha2 near 0). Both were seen on the seed's gait.

use super::sensitivity::normal_equations;
use super::{FitOptions, FitProblem, FitResult, Method, Progress};
use nalgebra::{DMatrix, DVector};

/// Relative parameter step below which the fit has converged.
const X_TOL: f64 = 1e-12;
/// Relative reduction of the cost below which an accepted step counts as converged.
const F_TOL: f64 = 1e-12;
/// Stop when the Gauss-Newton step could gain less than this fraction of the noise
/// variance in r^T r, or when `INSIGNIFICANT_STEPS` accepted steps in a row each gained
/// less (a flat valley at the noise floor, walked at the trust radius).
const NOISE_FRACTION: f64 = 0.01;
const INSIGNIFICANT_STEPS: usize = 3;
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
    let mut history = Vec::new();
    let mut iterations = 0;
    // Accepted steps in a row that each gained less than NOISE_FRACTION of the noise
    // variance: progress nobody could see in the data.
    let mut insignificant = 0;
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
        if let Some(why) = stop_before_step(&a, &g, sse, residuals, evaluations, options) {
            stop = why;
            break;
        }
        iterations += 1;
        let Some(delta) = step_within(&a, &g, radius) else {
            stop = "the damped normal equations have no solution".to_string();
            break;
        };
        let trial = &p + &delta;
        let trial_sse = problem.mse(trial.as_slice()) * residuals;
        evaluations += 1;
        // r^T r of the linearised model: sse + 2 delta.g + delta^T A delta.
        let predicted = -(2.0 * delta.dot(&g) + delta.dot(&(&a * &delta)));
        let rho = (sse - trial_sse) / predicted;
        let small_step = (0..n).all(|i| delta[i].abs() <= X_TOL * (p[i].abs() + X_TOL));
        if trial_sse.is_finite() && trial_sse < sse && predicted > 0.0 {
            let reduction = (sse - trial_sse) / sse;
            let noise_variance = sse / (residuals - n as f64).max(1.0);
            if sse - trial_sse < NOISE_FRACTION * noise_variance {
                insignificant += 1;
            } else {
                insignificant = 0;
            }
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
            radius = updated_radius(radius, rho, delta.norm());
            if small_step || reduction < F_TOL {
                stop = "converged (step or cost reduction below tolerance)".to_string();
                break;
            }
            if insignificant >= INSIGNIFICANT_STEPS {
                stop = format!(
                    "converged ({INSIGNIFICANT_STEPS} steps in a row gained less than 1 % of the noise variance)"
                );
                break;
            }
        } else {
            if small_step {
                stop = "converged (no smaller cost within tolerance)".to_string();
                break;
            }
            radius = 0.5 * delta.norm();
        }
    }
    FitResult {
        method: Method::Lm,
        params: twinloop_reduced::Corrections::from_slice(&problem.full(p.as_slice())),
        mse_before: f64::NAN,
        mse_after: sse / residuals,
        evaluations,
        iterations,
        jacobians,
        stop,
        history,
    }
}

/// Why to stop before another step, if so: the target MSE reached, the evaluation
/// budget spent, or nothing left to gain. The most the linearised model can still gain
/// is g^T A^-1 g (the full Gauss-Newton step); below 1 % of the noise variance that is
/// statistically insignificant (a shift of about 0.1 Cramer-Rao sigma along the
/// flattest direction): stop instead of crawling along a flat valley at the noise floor.
fn stop_before_step(
    a: &DMatrix<f64>,
    g: &DVector<f64>,
    sse: f64,
    residuals: f64,
    evaluations: usize,
    options: &FitOptions,
) -> Option<String> {
    if sse / residuals <= options.target_mse {
        return Some("reached the target MSE".to_string());
    }
    if evaluations + 1 > options.max_evaluations {
        return Some(format!(
            "evaluation budget {} spent",
            options.max_evaluations
        ));
    }
    let gain = gauss_newton_gain(a, g);
    let noise_variance = sse / (residuals - a.nrows() as f64).max(1.0);
    if gain < NOISE_FRACTION * noise_variance {
        return Some(
            "converged (what is left to gain is below 1 % of the noise variance)".to_string(),
        );
    }
    None
}

/// The trust radius after an accepted step of length `step` with gain ratio `rho`:
/// at least three times the step above 0.75, half the step below 0.25, else as it was.
fn updated_radius(radius: f64, rho: f64, step: f64) -> f64 {
    if rho > 0.75 {
        radius.max(3.0 * step)
    } else if rho < 0.25 {
        0.5 * step
    } else {
        radius
    }
}

/// g^T A^+ g, the decrease of r^T r the full Gauss-Newton step promises, computed on A
/// scaled to unit diagonal (A's own condition can pass 1e20 here) and ignoring
/// directions the data do not determine at all.
fn gauss_newton_gain(a: &DMatrix<f64>, g: &DVector<f64>) -> f64 {
    let n = a.nrows();
    let d: Vec<f64> = (0..n).map(|i| a[(i, i)].sqrt().max(1e-300)).collect();
    let scaled = DMatrix::from_fn(n, n, |r, c| a[(r, c)] / (d[r] * d[c]));
    let gs = DVector::from_fn(n, |r, _| g[r] / d[r]);
    let eig = scaled.symmetric_eigen();
    let top = eig.eigenvalues.amax();
    (0..n)
        .filter(|&k| eig.eigenvalues[k] > 1e-14 * top)
        .map(|k| eig.eigenvectors.column(k).dot(&gs).powi(2) / eig.eigenvalues[k])
        .sum()
}

/// The Gauss-Newton step if it fits the trust radius, else the Levenberg step
/// `(A + lambda mu I) delta = -g` (mu = mean of diag A) with the smallest lambda of a
/// doubling sequence that makes |delta| <= radius. n x n solves: cheap.
fn step_within(a: &DMatrix<f64>, g: &DVector<f64>, radius: f64) -> Option<DVector<f64>> {
    let n = a.nrows();
    let mean = a.trace() / n as f64;
    let mut lambda = 0.0;
    for _ in 0..300 {
        let mut damped = a.clone();
        for i in 0..n {
            damped[(i, i)] += lambda * mean;
        }
        if let Some(chol) = damped.cholesky() {
            let delta = chol.solve(&(-g));
            if delta.norm() <= radius {
                return Some(delta);
            }
        }
        lambda = if lambda == 0.0 { 1e-12 } else { 2.0 * lambda };
    }
    None
}
