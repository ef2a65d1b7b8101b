//! The fit of the compact model's corrections to a recorded CoM (seed 002, section 4).
//!
//! Cost: the mean squared error of the compact model's CoM against the recorded one,
//! `MSE = sum_i [(x_i - x^_i)^2 + (z_i - z^_i)^2] / (2N)` (m^2), the model rolled out by
//! RK4 from the first recorded CoM at rest. Minimised over a chosen subset of the ten
//! parameters (by default the seed's eight, eta1 = eta2 fixed) by
//!
//! | method | file |
//! |---|---|
//! | Levenberg-Marquardt on the residuals, exact sensitivities (the default) | [`lm`] |
//! | CMA-ES, (mu/mu_w, lambda) with rank-one and rank-mu updates | [`cmaes`] |
//! | PoWER, as the seed (Kober and Peters) | [`power`] |
//!
//! and [`identifiability()`] reports what the data determine at the optimum.

pub mod cmaes;
pub mod dataset;
pub mod identifiability;
pub mod lm;
pub mod model_file;
pub mod power;
pub mod report;
pub mod sensitivity;
pub mod summary;
pub mod synthetic;

pub use dataset::Dataset;
pub use identifiability::{Identifiability, identifiability};
pub use model_file::{parse_model_file, read_model_file, read_plant};

use crate::error::{IdentError, err};
use twinloop_reduced::{CompactModel, Corrections, SagittalCompliance, SagittalReference};

/// The ten parameter names, in [`Corrections::to_array`] order.
pub const PARAMETER_NAMES: [&str; 10] = [
    "alpha1", "beta1", "gamma1", "epsilon1", "alpha2", "beta2", "gamma2", "epsilon2", "eta1",
    "eta2",
];

/// The seed's eight (Table 1): eta1, eta2 stay as given.
pub const SEED_PARAMETERS: [usize; 8] = [0, 1, 2, 3, 4, 5, 6, 7];

/// Indices of comma-separated parameter names ("all" = the ten).
pub fn parse_parameter_names(text: &str) -> Result<Vec<usize>, IdentError> {
    if text.trim() == "all" {
        return Ok((0..10).collect());
    }
    let mut out = Vec::new();
    for name in text.split(',').map(str::trim) {
        let Some(i) = PARAMETER_NAMES.iter().position(|n| *n == name) else {
            return err(format!(
                "unknown parameter `{name}` (choose from {} or `all`)",
                PARAMETER_NAMES.join(", ")
            ));
        };
        if out.contains(&i) {
            return err(format!("parameter `{name}` is listed twice"));
        }
        out.push(i);
    }
    Ok(out)
}

/// What is fitted: a plant, the data, the starting values of all ten parameters and
/// which of them are free.
#[derive(Debug, Clone)]
pub struct FitProblem<'a> {
    pub plant: SagittalCompliance,
    pub data: &'a Dataset,
    pub start: [f64; 10],
    pub free: Vec<usize>,
}

impl<'a> FitProblem<'a> {
    /// Checks the plant, the starting values and the free set.
    pub fn new(
        plant: SagittalCompliance,
        data: &'a Dataset,
        start: Corrections,
        free: &[usize],
    ) -> Result<FitProblem<'a>, IdentError> {
        model_file::check_plant(&plant)?;
        data.reference.validate()?;
        let start = start.to_array();
        for (i, v) in start.iter().enumerate() {
            if !v.is_finite() {
                return err(format!(
                    "start value of {} is not finite",
                    PARAMETER_NAMES[i]
                ));
            }
        }
        if free.is_empty() {
            return err("no parameter to fit");
        }
        for (k, &i) in free.iter().enumerate() {
            if i >= 10 || free[..k].contains(&i) {
                return err(format!("bad free parameter index {i}"));
            }
        }
        for (i, name) in [(8, "eta1"), (9, "eta2")] {
            if start[i] == 0.0 {
                return err(format!(
                    "{name} must not be zero (it scales the double-support forces)"
                ));
            }
        }
        Ok(FitProblem {
            plant,
            data,
            start,
            free: free.to_vec(),
        })
    }

    pub fn dim(&self) -> usize {
        self.free.len()
    }

    /// The free parameters' starting values.
    pub fn initial(&self) -> Vec<f64> {
        self.free.iter().map(|&i| self.start[i]).collect()
    }

    /// All ten parameters with the free ones set to `p`.
    pub fn full(&self, p: &[f64]) -> [f64; 10] {
        let mut a = self.start;
        for (k, &i) in self.free.iter().enumerate() {
            a[i] = p[k];
        }
        a
    }

    pub fn model(&self, full: &[f64; 10]) -> CompactModel {
        CompactModel {
            plant: self.plant,
            corrections: Corrections::from_slice(full),
        }
    }

    /// The cost at free parameters `p` (infinite if the rollout diverges).
    pub fn mse(&self, p: &[f64]) -> f64 {
        mse(&self.model(&self.full(p)), self.data)
    }
}

/// The mean squared error of the model's CoM against the data (both x and z, m^2), the
/// model rolled out from the first recorded CoM at rest; infinite if it diverges.
/// Allocates nothing.
///
/// The model is linear with constant coefficients in each phase and the reference is
/// linear inside each sample interval, so one RK4 step is an affine map
/// `s+ = Phi s + Ga u_a + Gb u_b + c` of the state and the interval's end references
/// (u = [xr, zr]). With uniform sampling the map is formed once per phase and each step
/// costs a 4x4 and two 4x2 products instead of four derivative evaluations; a step of
/// another length falls back to [`CompactModel::rk4_step`].
pub fn mse(model: &CompactModel, data: &Dataset) -> f64 {
    let r = &data.reference;
    let h = r.t[1] - r.t[0];
    let maps = [
        AffineStep::new(model, false, h),
        AffineStep::new(model, true, h),
    ];
    let mut s = [data.x[0], data.z[0], 0.0, 0.0];
    let mut sse = 0.0;
    let uniform =
        r.t.windows(2)
            .all(|t| (t[1] - t[0] - h).abs() <= STEP_TOLERANCE * h);
    if uniform {
        // Run by run of one phase, the run's map copied into locals (registers), over
        // equal-length slices (no bounds checks): a tight loop.
        let n = data.len();
        let (xr, zr, ds) = (&r.xr[..n], &r.zr[..n], &r.double_support[..n]);
        let (xm, zm) = (&data.x[..n], &data.z[..n]);
        let mut i = 1;
        while i < n {
            let phase = ds[i - 1];
            let map = maps[usize::from(phase)];
            let mut j = i;
            while j < n && ds[j - 1] == phase {
                s = map.apply(&s, xr[j - 1], zr[j - 1], xr[j], zr[j]);
                let (dx, dz) = (s[0] - xm[j], s[1] - zm[j]);
                sse += dx * dx + dz * dz;
                j += 1;
            }
            i = j;
        }
    } else {
        for i in 1..data.len() {
            let hi = r.t[i] - r.t[i - 1];
            s = if (hi - h).abs() <= STEP_TOLERANCE * h {
                maps[usize::from(r.double_support[i - 1])].apply(
                    &s,
                    r.xr[i - 1],
                    r.zr[i - 1],
                    r.xr[i],
                    r.zr[i],
                )
            } else {
                model.rk4_step(&s, r, i)
            };
            let (dx, dz) = (s[0] - data.x[i], s[1] - data.z[i]);
            sse += dx * dx + dz * dz;
        }
    }
    let m = sse / (2 * data.len()) as f64;
    if m.is_finite() { m } else { f64::INFINITY }
}

/// Sample intervals within this relative difference count as equal for the affine map:
/// times written as i * dt differ from uniform by a few 1e-12 relative at 30 s, and 1e-9
/// of a millisecond (1 ps) changes nothing the data could show.
const STEP_TOLERANCE: f64 = 1e-9;

/// One RK4 step of the compact model as an affine map (see [`mse`]).
#[derive(Debug, Clone, Copy)]
struct AffineStep {
    phi: [[f64; 4]; 4],
    ga: [[f64; 2]; 4],
    gb: [[f64; 2]; 4],
    c: [f64; 4],
}

impl AffineStep {
    /// Reads the map off the RK4 step itself: its value at zero input, then the change
    /// per unit state and reference (exact: the step is affine).
    fn new(model: &CompactModel, double_support: bool, h: f64) -> AffineStep {
        let mut r = SagittalReference {
            t: vec![0.0, h],
            xr: vec![0.0; 2],
            zr: vec![0.0; 2],
            double_support: vec![double_support; 2],
        };
        let c = model.rk4_step(&[0.0; 4], &r, 1);
        let mut phi = [[0.0; 4]; 4];
        for j in 0..4 {
            let mut e = [0.0; 4];
            e[j] = 1.0;
            let col = model.rk4_step(&e, &r, 1);
            for k in 0..4 {
                phi[k][j] = col[k] - c[k];
            }
        }
        let (mut ga, mut gb) = ([[0.0; 2]; 4], [[0.0; 2]; 4]);
        for (at, g) in [(0, &mut ga), (1, &mut gb)] {
            // unit xr, then unit zr, at the interval's start (at = 0) or end (at = 1)
            for (j, (ux, uz)) in [(1.0, 0.0), (0.0, 1.0)].into_iter().enumerate() {
                r.xr = vec![0.0; 2];
                r.zr = vec![0.0; 2];
                r.xr[at] = ux;
                r.zr[at] = uz;
                let col = model.rk4_step(&[0.0; 4], &r, 1);
                for (row, (v, c0)) in g.iter_mut().zip(col.iter().zip(&c)) {
                    row[j] = v - c0;
                }
            }
        }
        AffineStep { phi, ga, gb, c }
    }

    #[inline(always)]
    fn apply(&self, s: &[f64; 4], xa: f64, za: f64, xb: f64, zb: f64) -> [f64; 4] {
        // The input part does not depend on s: off the step-to-step dependency chain.
        let input = |k: usize| {
            self.c[k]
                + (self.ga[k][0] * xa + self.ga[k][1] * za)
                + (self.gb[k][0] * xb + self.gb[k][1] * zb)
        };
        let row = |k: usize| {
            let p = &self.phi[k];
            (p[0] * s[0] + p[1] * s[1]) + (p[2] * s[2] + p[3] * s[3])
        };
        [
            input(0) + row(0),
            input(1) + row(1),
            input(2) + row(2),
            input(3) + row(3),
        ]
    }
}

/// The fit methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    Lm,
    Cmaes,
    Power,
}

/// Options shared by the methods.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Budget in cost evaluations (an LM Jacobian counts as 1 + free parameters, what
    /// forward differences would cost).
    pub max_evaluations: usize,
    /// Stop when the MSE is below this (m^2).
    pub target_mse: f64,
    /// Seed of the random numbers (CMA-ES, PoWER).
    pub seed: u64,
    /// Initial step size (CMA-ES sigma, PoWER exploration standard deviation).
    pub sigma: f64,
}

impl FitOptions {
    /// Budgets that let each method converge on the seed's problem.
    pub fn for_method(method: Method) -> FitOptions {
        FitOptions {
            max_evaluations: match method {
                Method::Lm => 500,
                Method::Cmaes => 25_000,
                Method::Power => 4000,
            },
            target_mse: 0.0,
            seed: 2012,
            sigma: 0.05,
        }
    }
}

/// The outcome of a generic minimiser ([`cmaes::minimize`], [`power::minimize`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Minimum {
    pub x: Vec<f64>,
    pub f: f64,
    pub evaluations: usize,
    pub iterations: usize,
    pub stop: String,
}

/// One point of a method's progress: the best so far.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Progress {
    pub evaluations: usize,
    pub mse: f64,
    pub params: [f64; 10],
}

/// The outcome of a fit.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FitResult {
    pub method: Method,
    pub params: Corrections,
    pub mse_before: f64,
    pub mse_after: f64,
    pub evaluations: usize,
    pub iterations: usize,
    /// Sensitivity rollouts (LM's Jacobians), each counted as 1 + free parameters in
    /// `evaluations`.
    pub jacobians: usize,
    /// Why it stopped.
    pub stop: String,
    /// Best-so-far after each iteration.
    #[serde(skip)]
    pub history: Vec<Progress>,
}

/// Fits by `method`; `on_progress` sees the best-so-far after every iteration.
pub fn fit(
    problem: &FitProblem,
    method: Method,
    options: &FitOptions,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<FitResult, IdentError> {
    if options.max_evaluations == 0 {
        return err("the evaluation budget must be positive");
    }
    if !(options.sigma.is_finite() && options.sigma > 0.0) {
        return err(format!(
            "the step size sigma must be positive, got {}",
            options.sigma
        ));
    }
    let mse_before = problem.mse(&problem.initial());
    if !mse_before.is_finite() {
        return err(
            "the model diverges at the starting parameters: check the stiffness and damping entries",
        );
    }
    let mut result = match method {
        Method::Lm => lm::levenberg_marquardt(problem, options, on_progress),
        Method::Cmaes => with_minimizer(problem, method, cmaes::minimize, options, on_progress),
        Method::Power => with_minimizer(problem, method, power::minimize, options, on_progress),
    };
    result.mse_before = mse_before;
    Ok(result)
}

/// A derivative-free minimiser: cost, start, options, progress (evaluations, best cost,
/// best or mean point).
type Minimizer = fn(
    &mut dyn FnMut(&[f64]) -> f64,
    &[f64],
    &FitOptions,
    &mut dyn FnMut(usize, f64, &[f64]),
) -> Minimum;

/// A generic minimiser ([`cmaes::minimize`], [`power::minimize`]) over the free
/// parameters' MSE, from their start values, with its progress as [`Progress`].
fn with_minimizer(
    problem: &FitProblem,
    method: Method,
    minimize: Minimizer,
    options: &FitOptions,
    on_progress: &mut dyn FnMut(&Progress),
) -> FitResult {
    let mut history = Vec::new();
    let m = minimize(
        &mut |p| problem.mse(p),
        &problem.initial(),
        options,
        &mut |evaluations, mse, p| {
            let point = Progress {
                evaluations,
                mse,
                params: problem.full(p),
            };
            on_progress(&point);
            history.push(point);
        },
    );
    FitResult {
        method,
        params: twinloop_reduced::Corrections::from_slice(&problem.full(&m.x)),
        mse_before: f64::NAN,
        mse_after: m.f,
        evaluations: m.evaluations,
        iterations: m.iterations,
        jacobians: 0,
        stop: m.stop,
        history,
    }
}

/// MSE of the all-start and the fitted parameters on another dataset (seed 002: "the set
/// of parameters found has been also used to perform walking with different gaits").
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Validation {
    pub source: String,
    pub samples: usize,
    pub mse_before: f64,
    pub mse_after: f64,
}

/// Evaluates `before` and `after` corrections on each dataset.
pub fn generalisation(
    plant: &SagittalCompliance,
    before: &Corrections,
    after: &Corrections,
    datasets: &[Dataset],
) -> Vec<Validation> {
    datasets
        .iter()
        .map(|d| {
            let m = |c: &Corrections| {
                mse(
                    &CompactModel {
                        plant: *plant,
                        corrections: *c,
                    },
                    d,
                )
            };
            Validation {
                source: d.source.clone(),
                samples: d.len(),
                mse_before: m(before),
                mse_after: m(after),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests;
