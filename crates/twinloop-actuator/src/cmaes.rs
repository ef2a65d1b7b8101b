//! CMA-ES, the (mu/mu_w, lambda) evolution strategy with covariance matrix
//! adaptation (Hansen, "The CMA Evolution Strategy: A Tutorial", 2016: default
//! strategy parameters, positive weights, cumulative step-size adaptation, rank-one
//! and rank-mu updates), in a box: a sample outside it is scored at its projection
//! plus a quadratic penalty on the distance (Hansen's boundary handling, simplified).
//!
//! Why here and not a crate: the fit needs a few dozen generations in two to four
//! dimensions, seeded so a fit repeats; the crates on crates.io for it (`cmaes`)
//! bring plotting and threading the fit does not use. twinloop-ident has its own for
//! the compliant fit; this crate cannot depend on it (it is below it).

use nalgebra::{DMatrix, DVector};
use twinloop_random::SplitMix64;

#[derive(Debug, Clone, Copy)]
pub struct CmaOptions {
    /// Initial step size, in the units of x.
    pub sigma: f64,
    pub max_evaluations: usize,
    /// Stop when the step size falls below this (units of x).
    pub tolerance: f64,
    pub seed: u64,
}

#[derive(Debug, Clone)]
pub struct CmaResult {
    pub x: Vec<f64>,
    pub cost: f64,
    pub evaluations: usize,
    pub generations: usize,
}

/// Minimise `f` from `x0` within `[lower, upper]` (per coordinate).
pub fn cmaes(
    mut f: impl FnMut(&[f64]) -> f64,
    x0: &[f64],
    lower: &[f64],
    upper: &[f64],
    o: &CmaOptions,
) -> CmaResult {
    let n = x0.len();
    let nf = n as f64;
    let lambda = 4 + (3.0 * nf.ln()).floor() as usize;
    let mu = lambda / 2;
    let raw: Vec<f64> = (1..=mu)
        .map(|i| ((lambda as f64 + 1.0) / 2.0).ln() - (i as f64).ln())
        .collect();
    let total: f64 = raw.iter().sum();
    let w: Vec<f64> = raw.iter().map(|v| v / total).collect();
    let mu_eff = 1.0 / w.iter().map(|v| v * v).sum::<f64>();
    let c_sigma = (mu_eff + 2.0) / (nf + mu_eff + 5.0);
    let d_sigma = 1.0 + 2.0 * (((mu_eff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + c_sigma;
    let c_c = (4.0 + mu_eff / nf) / (nf + 4.0 + 2.0 * mu_eff / nf);
    let c_1 = 2.0 / ((nf + 1.3).powi(2) + mu_eff);
    let c_mu = (1.0 - c_1).min(2.0 * (mu_eff - 2.0 + 1.0 / mu_eff) / ((nf + 2.0).powi(2) + mu_eff));
    let chi_n = nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));

    let clip = |x: &DVector<f64>| -> (Vec<f64>, f64) {
        let mut pen = 0.0;
        let v = (0..n)
            .map(|k| {
                let c = x[k].clamp(lower[k], upper[k]);
                pen += (x[k] - c).powi(2);
                c
            })
            .collect();
        (v, pen)
    };
    let mut rng = SplitMix64(o.seed);
    let mut mean = DVector::from_column_slice(x0);
    let mut sigma = o.sigma;
    let mut cov = DMatrix::<f64>::identity(n, n);
    let mut b = DMatrix::<f64>::identity(n, n);
    let mut d = DVector::<f64>::from_element(n, 1.0);
    let (mut p_sigma, mut p_c) = (DVector::zeros(n), DVector::zeros(n));
    let (x, _) = clip(&mean);
    let mut best = (f(&x), x);
    let mut evaluations = 1;
    let mut generations = 0;
    let mut ys = vec![DVector::<f64>::zeros(n); lambda];
    let mut costs = vec![(0.0, 0usize); lambda];
    let mut z = DVector::<f64>::zeros(n);
    while evaluations + lambda <= o.max_evaluations && sigma * d.max() > o.tolerance {
        generations += 1;
        for k in 0..lambda {
            for zi in z.iter_mut() {
                *zi = rng.normal();
            }
            ys[k] = &b * d.component_mul(&z);
            let xk = &mean + sigma * &ys[k];
            let (xc, pen) = clip(&xk);
            let c = f(&xc);
            evaluations += 1;
            // Worse than any in-box cost by the penalty's size relative to the step.
            let scored = if pen > 0.0 {
                c * (1.0 + pen / (sigma * sigma).max(1e-300))
            } else {
                c
            };
            if pen == 0.0 && c < best.0 {
                best = (c, xc);
            }
            costs[k] = (scored, k);
        }
        costs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut y_w = DVector::zeros(n);
        for i in 0..mu {
            y_w += w[i] * &ys[costs[i].1];
        }
        mean += sigma * &y_w;
        // C^(-1/2) y_w = B D^-1 B^T y_w.
        let c_inv_half_y = &b * (b.transpose() * &y_w).component_div(&d);
        p_sigma =
            (1.0 - c_sigma) * &p_sigma + (c_sigma * (2.0 - c_sigma) * mu_eff).sqrt() * c_inv_half_y;
        let h_sigma = p_sigma.norm() / (1.0 - (1.0 - c_sigma).powi(2 * generations as i32)).sqrt()
            < (1.4 + 2.0 / (nf + 1.0)) * chi_n;
        let hs = if h_sigma { 1.0 } else { 0.0 };
        p_c = (1.0 - c_c) * &p_c + hs * (c_c * (2.0 - c_c) * mu_eff).sqrt() * &y_w;
        let mut rank_mu = DMatrix::zeros(n, n);
        for i in 0..mu {
            let y = &ys[costs[i].1];
            rank_mu += w[i] * y * y.transpose();
        }
        let delta = (1.0 - hs) * c_c * (2.0 - c_c);
        cov =
            (1.0 - c_1 - c_mu + c_1 * delta) * &cov + c_1 * &p_c * p_c.transpose() + c_mu * rank_mu;
        sigma *= ((c_sigma / d_sigma) * (p_sigma.norm() / chi_n - 1.0)).exp();
        let sym = 0.5 * (&cov + cov.transpose());
        let eig = sym.clone().symmetric_eigen();
        b = eig.eigenvectors;
        d = eig.eigenvalues.map(|e| e.max(1e-30).sqrt());
        cov = sym;
    }
    CmaResult {
        x: best.1,
        cost: best.0,
        evaluations,
        generations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_non_smooth_bowl_in_a_box() {
        // |x - 0.3| + 2 |y + 0.1| + a step: no gradient to follow.
        let f = |x: &[f64]| {
            (x[0] - 0.3).abs() + 2.0 * (x[1] + 0.1).abs() + (x[0] * 20.0).floor().abs() * 1e-3
        };
        let r = cmaes(
            f,
            &[1.0, 1.0],
            &[-2.0, -2.0],
            &[2.0, 2.0],
            &CmaOptions {
                sigma: 0.5,
                max_evaluations: 3000,
                tolerance: 1e-9,
                seed: 1,
            },
        );
        assert!(
            (r.x[0] - 0.3).abs() < 1e-4 && (r.x[1] + 0.1).abs() < 1e-4,
            "{r:?}"
        );
        // A minimum on the bound is reached from inside.
        let g = |x: &[f64]| (x[0] + 1.0).powi(2) + x[1].powi(2);
        let r = cmaes(
            g,
            &[0.5, 0.5],
            &[0.0, -1.0],
            &[1.0, 1.0],
            &CmaOptions {
                sigma: 0.3,
                max_evaluations: 3000,
                tolerance: 1e-10,
                seed: 2,
            },
        );
        assert!(r.x[0] < 1e-4 && r.x[1].abs() < 1e-4, "{r:?}");
    }
}
