//! Levenberg-Marquardt (Marquardt's scaling of the damping by diag(J^T J)) with a
//! central-difference Jacobian.
//!
//! Why finite differences and not automatic derivatives: the residuals are a time
//! simulation with clamps (PWM saturation, friction's stop-or-slide switch,
//! encoder counts), piecewise smooth in the parameters; dual numbers through the
//! switches give the derivative of one branch, the central difference over a step
//! of 1e-4 in log-parameter (0.01 %) averages over the branch changes the fit meets
//! and costs 2p simulations, well inside the time budget for p <= 8; those 2p are
//! independent, so [`levenberg_marquardt_parallel`] runs them on rayon's pool.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

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
/// One simulation at a time, for residuals that cannot be shared between threads;
/// [`levenberg_marquardt_parallel`] is the same fit.
pub fn levenberg_marquardt(
    x0: &[f64],
    m: usize,
    residuals: impl FnMut(&[f64], &mut [f64]),
    options: &LmOptions,
) -> LmResult {
    let mut serial = Serial {
        f: residuals,
        x: x0.to_vec(),
        plus: DVector::zeros(m),
        minus: DVector::zeros(m),
    };
    fit(x0, m, &mut serial, options)
}

/// [`levenberg_marquardt`] with the Jacobian's 2n residual evaluations run on the
/// current rayon pool (see [`crate::parallel::on_threads`]): each column from the
/// same perturbed point into its own buffer, so the result is the serial fit's bit
/// for bit on any number of threads. The damped steps stay one at a time (each
/// depends on the last).
pub fn levenberg_marquardt_parallel(
    x0: &[f64],
    m: usize,
    residuals: &(dyn Fn(&[f64], &mut [f64]) + Sync),
    options: &LmOptions,
) -> LmResult {
    let n = x0.len();
    let mut parallel = Parallel {
        f: residuals,
        points: vec![x0.to_vec(); 2 * n],
        columns: vec![DVector::zeros(m); 2 * n],
    };
    fit(x0, m, &mut parallel, options)
}

/// How the fit evaluates its residuals.
trait Residuals {
    fn at(&mut self, x: &[f64], out: &mut [f64]);
    /// The central-difference Jacobian at `x` into `j`.
    fn jacobian(&mut self, x: &[f64], step: f64, j: &mut DMatrix<f64>);
}

/// The difference step of coordinate `x0`.
fn step_of(x0: f64, step: f64) -> f64 {
    step * x0.abs().max(1.0)
}

/// Column `k` of the Jacobian from the residuals at `x_k + h` and `x_k - h`.
fn set_column(j: &mut DMatrix<f64>, k: usize, plus: &DVector<f64>, minus: &DVector<f64>, h: f64) {
    for i in 0..plus.len() {
        j[(i, k)] = (plus[i] - minus[i]) / (2.0 * h);
    }
}

struct Serial<F> {
    f: F,
    x: Vec<f64>,
    plus: DVector<f64>,
    minus: DVector<f64>,
}

impl<F: FnMut(&[f64], &mut [f64])> Residuals for Serial<F> {
    fn at(&mut self, x: &[f64], out: &mut [f64]) {
        (self.f)(x, out);
    }

    fn jacobian(&mut self, x: &[f64], step: f64, j: &mut DMatrix<f64>) {
        self.x.copy_from_slice(x);
        for (k, &xk) in x.iter().enumerate() {
            let h = step_of(xk, step);
            self.x[k] = xk + h;
            (self.f)(&self.x, self.plus.as_mut_slice());
            self.x[k] = xk - h;
            (self.f)(&self.x, self.minus.as_mut_slice());
            self.x[k] = xk;
            set_column(j, k, &self.plus, &self.minus, h);
        }
    }
}

struct Parallel<'a> {
    f: &'a (dyn Fn(&[f64], &mut [f64]) + Sync),
    /// The 2n perturbed points (x + h e_k, x - h e_k, ...) and their residuals.
    points: Vec<Vec<f64>>,
    columns: Vec<DVector<f64>>,
}

impl Residuals for Parallel<'_> {
    fn at(&mut self, x: &[f64], out: &mut [f64]) {
        (self.f)(x, out);
    }

    fn jacobian(&mut self, x: &[f64], step: f64, j: &mut DMatrix<f64>) {
        for (c, p) in self.points.iter_mut().enumerate() {
            let k = c / 2;
            let h = step_of(x[k], step);
            p.copy_from_slice(x);
            p[k] = if c % 2 == 0 { x[k] + h } else { x[k] - h };
        }
        let f = self.f;
        self.points
            .par_iter()
            .zip(self.columns.par_iter_mut())
            .with_max_len(1)
            .for_each(|(p, r)| f(p, r.as_mut_slice()));
        for (k, &xk) in x.iter().enumerate() {
            let h = step_of(xk, step);
            set_column(j, k, &self.columns[2 * k], &self.columns[2 * k + 1], h);
        }
    }
}

/// The fit behind [`levenberg_marquardt`] and [`levenberg_marquardt_parallel`].
fn fit(x0: &[f64], m: usize, residuals: &mut dyn Residuals, options: &LmOptions) -> LmResult {
    let n = x0.len();
    let mut x = x0.to_vec();
    let mut r = DVector::zeros(m);
    residuals.at(&x, r.as_mut_slice());
    let mut evaluations = 1;
    let mut cost = 0.5 * r.norm_squared();
    let mut j = DMatrix::zeros(m, n);
    let mut lambda = 1e-3;
    let mut iterations = 0;
    let mut trial = DVector::zeros(m);
    let mut fresh = false;
    let mut done = false;
    while !done && iterations < options.max_iterations {
        iterations += 1;
        if !fresh {
            residuals.jacobian(&x, options.step, &mut j);
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
            residuals.at(&xt, trial.as_mut_slice());
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
        residuals.jacobian(&x, options.step, &mut j);
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
