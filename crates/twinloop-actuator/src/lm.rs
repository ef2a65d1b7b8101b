//! Levenberg-Marquardt (Marquardt's scaling of the damping by diag(J^T J)) with a
//! central-difference Jacobian.
//!
//! Why finite differences and not automatic derivatives: the residuals are a time
//! simulation with clamps (PWM saturation, friction's stop-or-slide switch,
//! encoder counts), piecewise smooth in the parameters; dual numbers through the
//! switches give the derivative of one branch, the central difference over a step
//! of 1e-4 in log-parameter (0.01 %) averages over the branch changes the fit meets
//! and costs 2p simulations, well inside the time budget for p <= 8.

use nalgebra::{DMatrix, DVector};

#[derive(Debug, Clone, Copy)]
pub struct LmOptions {
    pub max_iterations: usize,
    /// Stop when the cost falls by less than this fraction.
    pub tolerance: f64,
    /// Relative step of the central differences.
    pub step: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iterations: 60,
            tolerance: 1e-9,
            step: 1e-2,
        }
    }
}

#[derive(Debug, Clone)]
pub struct LmResult {
    pub x: Vec<f64>,
    /// Half the sum of squared residuals.
    pub cost: f64,
    pub jacobian: DMatrix<f64>,
    pub residuals: DVector<f64>,
    pub iterations: usize,
    /// Residual evaluations (each a full simulation).
    pub evaluations: usize,
}

/// Minimise `|r(x)|^2 / 2` from `x0`; `residuals(x, out)` fills `out` (length `m`).
pub fn levenberg_marquardt(
    x0: &[f64],
    m: usize,
    mut residuals: impl FnMut(&[f64], &mut [f64]),
    options: &LmOptions,
) -> LmResult {
    let n = x0.len();
    let mut x = x0.to_vec();
    let mut r = DVector::zeros(m);
    residuals(&x, r.as_mut_slice());
    let mut evaluations = 1;
    let mut cost = 0.5 * r.norm_squared();
    let mut j = DMatrix::zeros(m, n);
    let mut lambda = 1e-3;
    let mut iterations = 0;
    let (mut plus, mut minus) = (DVector::zeros(m), DVector::zeros(m));
    let mut trial = DVector::zeros(m);
    let mut fresh = false;
    let mut done = false;
    while !done && iterations < options.max_iterations {
        iterations += 1;
        if !fresh {
            jacobian(
                &mut x,
                &mut residuals,
                options.step,
                &mut plus,
                &mut minus,
                &mut j,
            );
            evaluations += 2 * n;
            fresh = true;
        }
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &r;
        let mut improved = false;
        for _ in 0..12 {
            let mut a = jtj.clone();
            for k in 0..n {
                a[(k, k)] += lambda * jtj[(k, k)].max(1e-12);
            }
            let Some(delta) = a.cholesky().map(|c| c.solve(&(-&g))) else {
                lambda *= 10.0;
                continue;
            };
            let xt: Vec<f64> = x.iter().zip(delta.iter()).map(|(a, b)| a + b).collect();
            residuals(&xt, trial.as_mut_slice());
            evaluations += 1;
            let c = 0.5 * trial.norm_squared();
            if c.is_finite() && c < cost {
                let drop = (cost - c) / cost.max(1e-300);
                x = xt;
                std::mem::swap(&mut r, &mut trial);
                cost = c;
                lambda = (lambda / 3.0).max(1e-12);
                improved = true;
                fresh = false;
                done = drop < options.tolerance;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    if !fresh {
        jacobian(
            &mut x,
            &mut residuals,
            options.step,
            &mut plus,
            &mut minus,
            &mut j,
        );
        evaluations += 2 * n;
    }
    LmResult {
        x,
        cost,
        jacobian: j,
        residuals: r,
        iterations,
        evaluations,
    }
}

fn jacobian(
    x: &mut [f64],
    residuals: &mut impl FnMut(&[f64], &mut [f64]),
    step: f64,
    plus: &mut DVector<f64>,
    minus: &mut DVector<f64>,
    j: &mut DMatrix<f64>,
) {
    for k in 0..x.len() {
        let x0 = x[k];
        let h = step * x0.abs().max(1.0);
        x[k] = x0 + h;
        residuals(x, plus.as_mut_slice());
        x[k] = x0 - h;
        residuals(x, minus.as_mut_slice());
        x[k] = x0;
        for i in 0..plus.len() {
            j[(i, k)] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_an_exponential() {
        // y = a exp(-b t) from exact data: recovers a, b.
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let (a, b) = (2.5, 0.7);
        let y: Vec<f64> = t.iter().map(|t| a * (-b * t).exp()).collect();
        let r = levenberg_marquardt(
            &[1.0, 0.1],
            t.len(),
            |x, out| {
                for i in 0..t.len() {
                    out[i] = x[0] * (-x[1] * t[i]).exp() - y[i];
                }
            },
            &LmOptions::default(),
        );
        assert!(
            (r.x[0] - a).abs() < 1e-6 && (r.x[1] - b).abs() < 1e-6,
            "{:?}",
            r.x
        );
    }
}
