//! PoWER, Policy learning by Weighting Exploration with the Returns (Kober and Peters,
//! NIPS 2008 / Machine Learning 2011), episodic with Gaussian parameter exploration, as
//! seed 002 (section 4) used it to fit the compact model.
//!
//! Every iteration runs one rollout (episode) with the parameters
//! theta_k = theta + eps_k, eps_k ~ N(0, sigma^2 I) (the first without exploration), and
//! scores it with the return R_k = exp(-MSE_k / MSE_0), MSE_0 the starting parameters'
//! error (the seed only says the cost is "a form of reward function"; this one is
//! positive, 1/e at the start and 1 at a perfect fit). Importance sampling reuses the
//! best rollouts of all so far: with the `BEST` highest returns,
//!
//! ```text
//! theta <- theta + sum_k R_k (theta_k - theta) / sum_k R_k
//! ```
//!
//! PoWER has no learning rate and a fixed exploration, as in Kober's reference code.

use super::{FitOptions, Minimum};
use twinloop_random::SplitMix64;

/// Rollouts reused by importance sampling (Kober's reference code uses 10).
pub const BEST: usize = 10;

/// PoWER on any cost `f` (return exp(-f / f(x0))) from `x0`;
/// `on_iteration(evaluations, best rollout's f, policy mean)` after every rollout.
pub fn minimize(
    f: &mut dyn FnMut(&[f64]) -> f64,
    x0: &[f64],
    options: &FitOptions,
    on_iteration: &mut dyn FnMut(usize, f64, &[f64]),
) -> Minimum {
    let n = x0.len();
    let mut rng = SplitMix64(options.seed);
    let mut theta = x0.to_vec();
    let mse0 = f(&theta);
    let scale = if mse0 > 0.0 { 1.0 / mse0 } else { 1.0 };
    // The best rollouts so far, highest return first: (return, mse, parameters).
    let mut best: Vec<(f64, f64, Vec<f64>)> = Vec::with_capacity(BEST + 1);
    let mut evaluations = 0;
    let mut candidate = vec![0.0; n];
    let mut step = vec![0.0; n];
    let stop = loop {
        // one evaluation is kept for the final policy mean
        if evaluations + 1 >= options.max_evaluations {
            break format!("evaluation budget {} spent", options.max_evaluations);
        }
        if best.first().is_some_and(|b| b.1 <= options.target_mse) {
            break "reached the target MSE".to_string();
        }
        for i in 0..n {
            let eps = if evaluations == 0 {
                0.0
            } else {
                options.sigma * rng.normal()
            };
            candidate[i] = theta[i] + eps;
        }
        let mse = if evaluations == 0 {
            mse0
        } else {
            f(&candidate)
        };
        evaluations += 1;
        let ret = (-scale * mse).exp();
        let at = best.partition_point(|b| b.0 >= ret);
        if at < BEST {
            best.insert(at, (ret, mse, candidate.clone()));
            best.truncate(BEST);
        }
        // Importance-sampled update from the best rollouts.
        let total: f64 = best.iter().map(|b| b.0).sum();
        step.fill(0.0);
        for (r, _, p) in &best {
            for i in 0..n {
                step[i] += r * (p[i] - theta[i]);
            }
        }
        for i in 0..n {
            theta[i] += step[i] / (total + 1e-300);
        }
        on_iteration(evaluations, best[0].1, &theta);
    };
    // The answer is the policy mean theta, unless a rollout did better.
    let f_theta = f(&theta);
    evaluations += 1;
    let (x, fx) = match best.first() {
        Some((_, m, p)) if *m < f_theta => (p.clone(), *m),
        _ => (theta, f_theta),
    };
    Minimum {
        x,
        f: fx,
        evaluations,
        iterations: evaluations - 1,
        stop,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_to_the_optimum_of_a_sphere_and_repeats_with_its_seed() {
        let c = [0.3, -0.2, 0.1, 0.25];
        let mut sphere = |x: &[f64]| x.iter().zip(&c).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        let o = FitOptions {
            max_evaluations: 2000,
            target_mse: 0.0,
            seed: 5,
            sigma: 0.05,
        };
        let m = minimize(&mut sphere, &[0.0; 4], &o, &mut |_, _, _| {});
        // Start: f = 0.2025; the reward-weighted mean of the best rollouts walks to c.
        assert!(m.f < 1e-3, "f {} at {:?}", m.f, m.x);
        assert_eq!(m.evaluations, 2000);
        let again = minimize(&mut sphere, &[0.0; 4], &o, &mut |_, _, _| {});
        assert_eq!(again.x, m.x);
    }
}
