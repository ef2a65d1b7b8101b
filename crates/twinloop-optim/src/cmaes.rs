//! CMA-ES: the (mu/mu_w, lambda) evolution strategy with covariance matrix
//! adaptation, cumulative step-size adaptation, rank-one and rank-mu updates, with
//! the default strategy parameters of Hansen, "The CMA Evolution Strategy: A
//! Tutorial" (2016), positive recombination weights only. Seeded, so a run repeats
//! exactly. Optionally in a box: a sample outside it is scored at its projection
//! plus a penalty growing with its squared distance (Hansen's boundary handling,
//! simplified).
//!
//! Why ours and not a crate: the fits need a few dozen generations in one to ten
//! dimensions, seeded so a fit repeats, and a callback per generation for their
//! progress; the `cmaes` crate brings plotting and threads they do not use. Its
//! population is evaluated in parallel by [`minimize_parallel`] (rayon's pool).

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use twinloop_random::SplitMix64;

/// When the step size counts as converged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepTolerance {
    /// `sigma * max sqrt(eig C)` below this, in the units of x.
    Absolute(f64),
    /// Below this times the mean's largest coordinate (parameters of any size).
    Relative(f64),
}

#[derive(Debug, Clone, Copy)]
pub struct CmaOptions {
    /// Initial step size, in the units of x.
    pub sigma: f64,
    /// Budget in cost evaluations; a generation that would pass it is not started.
    pub max_evaluations: usize,
    pub tolerance: StepTolerance,
    /// Stop once the best cost is at or below this (`f64::NEG_INFINITY`: never).
    pub target: f64,
    pub seed: u64,
}

/// Why the search stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    Target,
    Budget,
    Converged,
}

#[derive(Debug, Clone)]
pub struct CmaResult {
    /// The best point evaluated (inside the box, when there is one).
    pub x: Vec<f64>,
    pub cost: f64,
    pub evaluations: usize,
    pub generations: usize,
    pub stop: Stop,
}

/// Minimise `f` from the mean `x0` with step size `o.sigma`, within `bounds`
/// (`(lower, upper)` per coordinate) when given; `on_generation(evaluations, best
/// cost, best x)` after every generation. One evaluation at a time, for an `f` that
/// cannot be shared between threads; [`minimize_parallel`] is the same search.
pub fn minimize(
    f: &mut dyn FnMut(&[f64]) -> f64,
    x0: &[f64],
    bounds: Option<(&[f64], &[f64])>,
    o: &CmaOptions,
    on_generation: &mut dyn FnMut(usize, f64, &[f64]),
) -> CmaResult {
    let mut evaluate = |xs: &[DVector<f64>], out: &mut [f64]| {
        for (x, fx) in xs.iter().zip(out.iter_mut()) {
            *fx = f(x.as_slice());
        }
    };
    search(&mut evaluate, x0, bounds, o, on_generation)
}

/// [`minimize`] with each generation's population evaluated on the current rayon
/// pool (see [`crate::parallel::on_threads`]): the same samples, the same costs in
/// the same slots, ranked on one thread, so the result is [`minimize`]'s bit for bit
/// on any number of threads.
pub fn minimize_parallel(
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    x0: &[f64],
    bounds: Option<(&[f64], &[f64])>,
    o: &CmaOptions,
    on_generation: &mut dyn FnMut(usize, f64, &[f64]),
) -> CmaResult {
    let mut evaluate = |xs: &[DVector<f64>], out: &mut [f64]| {
        xs.par_iter()
            .zip(out.par_iter_mut())
            .with_max_len(1)
            .for_each(|(x, fx)| *fx = f(x.as_slice()));
    };
    search(&mut evaluate, x0, bounds, o, on_generation)
}

/// Hansen's default strategy parameters for dimension `n` (the tutorial's table 1).
struct Strategy {
    lambda: usize,
    mu: usize,
    /// Recombination weights, positive, summing to 1.
    w: Vec<f64>,
    mu_eff: f64,
    c_sigma: f64,
    d_sigma: f64,
    c_c: f64,
    c_1: f64,
    c_mu: f64,
    /// E|N(0, I)|.
    chi_n: f64,
}

impl Strategy {
    fn new(n: usize) -> Strategy {
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
        let c_1 = 2.0 / ((nf + 1.3).powi(2) + mu_eff);
        Strategy {
            lambda,
            mu,
            d_sigma: 1.0 + 2.0 * (((mu_eff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + c_sigma,
            c_c: (4.0 + mu_eff / nf) / (nf + 4.0 + 2.0 * mu_eff / nf),
            c_1,
            c_mu: (1.0 - c_1)
                .min(2.0 * (mu_eff - 2.0 + 1.0 / mu_eff) / ((nf + 2.0).powi(2) + mu_eff)),
            chi_n: nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf)),
            w,
            mu_eff,
            c_sigma,
        }
    }
}

/// The search's state between generations.
struct State {
    mean: DVector<f64>,
    sigma: f64,
    cov: DMatrix<f64>,
    /// Eigenvectors and square roots of the eigenvalues of `cov`.
    b: DMatrix<f64>,
    d: DVector<f64>,
    p_sigma: DVector<f64>,
    p_c: DVector<f64>,
    generations: usize,
}

/// The point evaluated for a sample (its projection into the box) and the squared
/// distance it was moved.
fn project(x: &mut DVector<f64>, bounds: Option<(&[f64], &[f64])>) -> f64 {
    let Some((lower, upper)) = bounds else {
        return 0.0;
    };
    let mut moved = 0.0;
    for k in 0..x.len() {
        let c = x[k].clamp(lower[k], upper[k]);
        moved += (x[k] - c).powi(2);
        x[k] = c;
    }
    moved
}

/// Fills one cost per point: how a population is evaluated.
type Evaluate<'a> = dyn FnMut(&[DVector<f64>], &mut [f64]) + 'a;

/// The search behind [`minimize`] and [`minimize_parallel`]: `evaluate(points,
/// costs)` fills one cost per point; everything else runs here, in order.
fn search(
    evaluate: &mut Evaluate<'_>,
    x0: &[f64],
    bounds: Option<(&[f64], &[f64])>,
    o: &CmaOptions,
    on_generation: &mut dyn FnMut(usize, f64, &[f64]),
) -> CmaResult {
    let n = x0.len();
    let s = Strategy::new(n);
    let lambda = s.lambda;
    let mut rng = SplitMix64(o.seed);
    let mut st = State {
        mean: DVector::from_column_slice(x0),
        sigma: o.sigma,
        cov: DMatrix::<f64>::identity(n, n),
        b: DMatrix::<f64>::identity(n, n),
        d: DVector::<f64>::from_element(n, 1.0),
        p_sigma: DVector::<f64>::zeros(n),
        p_c: DVector::<f64>::zeros(n),
        generations: 0,
    };
    // Preallocated population: sampled steps y = B D z, the points evaluated (inside
    // the box), how far each was moved into it, their costs and scores.
    let mut xs = vec![st.mean.clone(); lambda];
    project(&mut xs[0], bounds);
    let mut fxs = vec![0.0; lambda];
    evaluate(&xs[..1], &mut fxs[..1]);
    let mut best = (fxs[0], xs[0].clone());
    let mut evaluations = 1;
    let mut ys = vec![DVector::<f64>::zeros(n); lambda];
    let mut moved = vec![0.0; lambda];
    let mut scores = vec![(0.0, 0usize); lambda];
    let stop = loop {
        if best.0 <= o.target {
            break Stop::Target;
        }
        if evaluations + lambda > o.max_evaluations {
            break Stop::Budget;
        }
        let tolerance = match o.tolerance {
            StepTolerance::Absolute(t) => t,
            StepTolerance::Relative(t) => t * st.mean.amax().max(1e-300),
        };
        if st.sigma * st.d.max() <= tolerance {
            break Stop::Converged;
        }
        st.generations += 1;
        for k in 0..lambda {
            let z = DVector::from_fn(n, |_, _| rng.normal());
            ys[k] = &st.b * st.d.component_mul(&z);
            xs[k].copy_from(&st.mean);
            xs[k].axpy(st.sigma, &ys[k], 1.0);
            moved[k] = project(&mut xs[k], bounds);
        }
        evaluate(&xs, &mut fxs);
        for k in 0..lambda {
            // Outside the box: worse than the projection by the distance relative to
            // the step, so the mean is drawn back inside.
            scores[k] = if moved[k] > 0.0 {
                (
                    fxs[k] * (1.0 + moved[k] / (st.sigma * st.sigma).max(1e-300)),
                    k,
                )
            } else {
                (fxs[k], k)
            };
            if moved[k] == 0.0 && fxs[k] < best.0 {
                best = (fxs[k], xs[k].clone());
            }
        }
        evaluations += lambda;
        scores.sort_by(|a, b| a.0.total_cmp(&b.0));
        update(&s, &mut st, &ys, &scores);
        on_generation(evaluations, best.0, best.1.as_slice());
    };
    CmaResult {
        x: best.1.as_slice().to_vec(),
        cost: best.0,
        evaluations,
        generations: st.generations,
        stop,
    }
}

/// One generation's update of the mean, the paths, the covariance and the step size
/// from the steps `ys` ranked by `scores`.
fn update(s: &Strategy, st: &mut State, ys: &[DVector<f64>], scores: &[(f64, usize)]) {
    let n = st.mean.len();
    let nf = n as f64;
    let mut y_w = DVector::<f64>::zeros(n);
    for i in 0..s.mu {
        y_w.axpy(s.w[i], &ys[scores[i].1], 1.0);
    }
    st.mean.axpy(st.sigma, &y_w, 1.0);
    // C^-1/2 y_w = B D^-1 B^T y_w
    let c_inv_sqrt_yw = &st.b * (st.b.transpose() * &y_w).component_div(&st.d);
    st.p_sigma = (1.0 - s.c_sigma) * &st.p_sigma
        + (s.c_sigma * (2.0 - s.c_sigma) * s.mu_eff).sqrt() * c_inv_sqrt_yw;
    let ps_norm = st.p_sigma.norm();
    let h_sigma = ps_norm / (1.0 - (1.0 - s.c_sigma).powi(2 * st.generations as i32)).sqrt()
        < (1.4 + 2.0 / (nf + 1.0)) * s.chi_n;
    let h = if h_sigma { 1.0 } else { 0.0 };
    st.p_c = (1.0 - s.c_c) * &st.p_c + h * (s.c_c * (2.0 - s.c_c) * s.mu_eff).sqrt() * &y_w;
    let delta_h = (1.0 - h) * s.c_c * (2.0 - s.c_c);
    let mut rank_mu = DMatrix::<f64>::zeros(n, n);
    for i in 0..s.mu {
        let y = &ys[scores[i].1];
        rank_mu.ger(s.w[i], y, y, 1.0);
    }
    st.cov = (1.0 + s.c_1 * delta_h - s.c_1 - s.c_mu) * &st.cov
        + s.c_1 * &st.p_c * st.p_c.transpose()
        + s.c_mu * rank_mu;
    st.cov = 0.5 * (&st.cov + st.cov.transpose());
    st.sigma *= ((s.c_sigma / s.d_sigma) * (ps_norm / s.chi_n - 1.0)).exp();
    let eig = st.cov.clone().symmetric_eigen();
    st.b = eig.eigenvectors;
    st.d = eig.eigenvalues.map(|v| v.max(1e-300).sqrt());
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(sigma: f64, budget: usize, seed: u64) -> CmaOptions {
        CmaOptions {
            sigma,
            max_evaluations: budget,
            tolerance: StepTolerance::Relative(1e-13),
            target: 1e-10,
            seed,
        }
    }

    /// Hansen's tutorial reports about 5000-7000 evaluations for the 8-10 dimensional
    /// Rosenbrock function with the default population; a broken update (wrong
    /// weights, no rank-mu or a mis-scaled path) needs many more or never gets there.
    #[test]
    fn solves_rosenbrock_and_a_1e6_ellipsoid_in_textbook_budgets() {
        let mut rosen = |x: &[f64]| {
            (0..x.len() - 1)
                .map(|i| 100.0 * (x[i + 1] - x[i] * x[i]).powi(2) + (1.0 - x[i]).powi(2))
                .sum::<f64>()
        };
        for seed in 1..=3 {
            let m = minimize(
                &mut rosen,
                &[0.0; 8],
                None,
                &options(0.5, 20_000, seed),
                &mut |_, _, _| {},
            );
            assert!(
                m.cost <= 1e-10 && m.stop == Stop::Target,
                "seed {seed}: f {} after {}",
                m.cost,
                m.evaluations
            );
            assert!(
                m.evaluations < 12_000,
                "seed {seed}: {} evaluations",
                m.evaluations
            );
            assert!(m.x.iter().all(|v| (v - 1.0).abs() < 1e-4), "{:?}", m.x);
        }
        let mut ellipsoid = |x: &[f64]| {
            let n = x.len() as f64;
            x.iter()
                .enumerate()
                .map(|(i, v)| 10f64.powf(6.0 * i as f64 / (n - 1.0)) * v * v)
                .sum::<f64>()
        };
        let m = minimize(
            &mut ellipsoid,
            &[1.0; 8],
            None,
            &options(0.5, 20_000, 7),
            &mut |_, _, _| {},
        );
        assert!(
            m.cost <= 1e-10 && m.evaluations < 8000,
            "f {} after {}",
            m.cost,
            m.evaluations
        );
    }

    #[test]
    fn finds_the_minimum_of_a_non_smooth_bowl_in_a_box() {
        // |x - 0.3| + 2 |y + 0.1| + a step: no gradient to follow.
        let mut f = |x: &[f64]| {
            (x[0] - 0.3).abs() + 2.0 * (x[1] + 0.1).abs() + (x[0] * 20.0).floor().abs() * 1e-3
        };
        let o = |sigma, tolerance, seed| CmaOptions {
            sigma,
            max_evaluations: 3000,
            tolerance: StepTolerance::Absolute(tolerance),
            target: f64::NEG_INFINITY,
            seed,
        };
        let r = minimize(
            &mut f,
            &[1.0, 1.0],
            Some((&[-2.0, -2.0], &[2.0, 2.0])),
            &o(0.5, 1e-9, 1),
            &mut |_, _, _| {},
        );
        assert!(
            (r.x[0] - 0.3).abs() < 1e-4 && (r.x[1] + 0.1).abs() < 1e-4,
            "{r:?}"
        );
        // A minimum on the bound is reached from inside, and nothing outside the box
        // is ever evaluated.
        let mut g = |x: &[f64]| {
            assert!((0.0..=1.0).contains(&x[0]) && (-1.0..=1.0).contains(&x[1]));
            (x[0] + 1.0).powi(2) + x[1].powi(2)
        };
        let r = minimize(
            &mut g,
            &[0.5, 0.5],
            Some((&[0.0, -1.0], &[1.0, 1.0])),
            &o(0.3, 1e-10, 2),
            &mut |_, _, _| {},
        );
        assert!(r.x[0] < 1e-4 && r.x[1].abs() < 1e-4, "{r:?}");
        assert_eq!(r.stop, Stop::Converged);
    }
}
