//! CMA-ES on the compliant model's MSE: the workspace's one implementation
//! ([`twinloop_optim::cmaes`], Hansen's tutorial defaults), unbounded, stopping at the
//! target MSE, the budget or a step size 1e-13 of the parameters.

use super::{FitOptions, Minimum};
use twinloop_optim::{CmaOptions, StepTolerance, Stop};

/// CMA-ES on any cost `f` from mean `x0` with step size `options.sigma`;
/// `on_generation(evaluations, best f, best x)` after every generation.
pub fn minimize(
    f: &mut dyn FnMut(&[f64]) -> f64,
    x0: &[f64],
    options: &FitOptions,
    on_generation: &mut dyn FnMut(usize, f64, &[f64]),
) -> Minimum {
    let r = twinloop_optim::minimize(
        f,
        x0,
        None,
        &CmaOptions {
            sigma: options.sigma,
            max_evaluations: options.max_evaluations,
            tolerance: StepTolerance::Relative(1e-13),
            target: options.target_mse,
            seed: options.seed,
        },
        on_generation,
    );
    Minimum {
        x: r.x,
        f: r.cost,
        evaluations: r.evaluations,
        iterations: r.generations,
        stop: match r.stop {
            Stop::Target => "reached the target MSE".to_string(),
            Stop::Budget => format!("evaluation budget {} spent", options.max_evaluations),
            Stop::Converged => "converged (step size below tolerance)".to_string(),
        },
    }
}
