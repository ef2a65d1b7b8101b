//! The compliant compact model's fit (seed 002, section 4), as `twinloop identify
//! compliant --json` runs it: the same inputs, the same fields.

use crate::errors::value_error;
use crate::values::to_py;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use twinloop_ident::IdentError;
use twinloop_ident::compliant_fit::summary::{FitInputs, FitSummary};
use twinloop_ident::compliant_fit::{
    self as fit, Dataset, FitOptions, FitProblem, Method, PARAMETER_NAMES, SEED_PARAMETERS,
    read_plant,
};
use twinloop_reduced::Corrections;

/// A file that cannot be read is an OSError, a bad one a ValueError (the CLI's message).
fn input_error(path: &Path, e: IdentError) -> PyErr {
    let message = e.to_string();
    if path.is_file() {
        value_error(message)
    } else {
        PyOSError::new_err(message)
    }
}

fn method_arg(method: &str) -> PyResult<Method> {
    match method {
        "lm" => Ok(Method::Lm),
        "cmaes" => Ok(Method::Cmaes),
        "power" => Ok(Method::Power),
        _ => Err(value_error(format!(
            "method: {method:?} is not lm, cmaes or power"
        ))),
    }
}

/// Fit the compact compliant model's correction factors to a recorded CoM (seed 002,
/// section 4): `twinloop identify compliant --data DATA --plant PLANT --json`.
///
/// `data`: a CSV of t, xr, zr, x, z, phase (s, m, 0 single / 1 double support);
/// `plant`: PLANT.toml or the JSON of `twinloop compliant stiffness`; `method`: "lm"
/// (Levenberg-Marquardt, exact sensitivities), "cmaes" or "power" (the seed's);
/// `params`: the free parameters (names, a comma list or "all"; default the seed's
/// eight); `start`: the ten starting values (default all ones); `max_evaluations`
/// (default lm 500, cmaes 25000, power 4000); `sigma`: CMA-ES / PoWER step; `seed`:
/// their random draws; `noise_std` (m): for the Cramer-Rao bounds (default from the
/// residuals); `val`: CSVs of other gaits, MSE before and after on each.
///
/// Returns a dict with the CLI's JSON fields: data, model, samples, plant, method,
/// free, start, params, mse_before, mse_after (m^2), rms_before, rms_after (m),
/// evaluations, iterations, stop, seconds, identifiability, identifiability_error,
/// validation, timing (None).
#[pyfunction]
#[pyo3(signature = (data, plant, method = "lm", params = None, start = None,
    max_evaluations = None, sigma = 0.05, seed = 2012, noise_std = None, val = Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub fn fit_compliant<'py>(
    py: Python<'py>,
    data: PathBuf,
    plant: PathBuf,
    method: &str,
    params: Option<&Bound<'py, PyAny>>,
    start: Option<Vec<f64>>,
    max_evaluations: Option<usize>,
    sigma: f64,
    seed: u64,
    noise_std: Option<f64>,
    val: Vec<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let method = method_arg(method)?;
    if !(sigma > 0.0 && sigma.is_finite()) {
        return Err(value_error(format!("sigma: must be positive, got {sigma}")));
    }
    if let Some(s) = noise_std
        && !(s >= 0.0 && s.is_finite())
    {
        return Err(value_error(format!(
            "noise_std: must be zero or positive, got {s}"
        )));
    }
    if max_evaluations == Some(0) {
        return Err(value_error("max_evaluations: must be at least 1"));
    }
    let free = match params {
        None => SEED_PARAMETERS.to_vec(),
        Some(p) => {
            let text = match p.extract::<String>() {
                Ok(s) => s,
                Err(_) => p
                    .extract::<Vec<String>>()
                    .map_err(|_| value_error("params: a list of names or a comma-separated str"))?
                    .join(","),
            };
            fit::parse_parameter_names(&text).map_err(|e| value_error(format!("params: {e}")))?
        }
    };
    let start = match start {
        None => Corrections::default(),
        Some(v) if v.len() == 10 && v.iter().all(|x| x.is_finite()) => {
            let mut a = [0.0; 10];
            a.copy_from_slice(&v);
            Corrections::from_slice(&a)
        }
        Some(_) => {
            return Err(value_error(format!(
                "start: expected 10 finite numbers ({})",
                PARAMETER_NAMES.join(",")
            )));
        }
    };
    let plant_model = read_plant(&plant).map_err(|e| input_error(&plant, e))?;
    let dataset = Dataset::read(&data).map_err(|e| input_error(&data, e))?;
    let val_sets = val
        .iter()
        .map(|p| Dataset::read(p).map_err(|e| input_error(p, e)))
        .collect::<PyResult<Vec<_>>>()?;
    let problem = FitProblem::new(plant_model, &dataset, start, &free)
        .map_err(|e| value_error(format!("{}: {e}", data.display())))?;
    let mut options = FitOptions::for_method(method);
    if let Some(n) = max_evaluations {
        options.max_evaluations = n;
    }
    options.sigma = sigma;
    options.seed = seed;
    let started = std::time::Instant::now();
    let (result, ident, validation) = py
        .detach(|| {
            let result = fit::fit(&problem, method, &options, &mut |_| {})?;
            let fitted = result.params.to_array();
            let p_free: Vec<f64> = free.iter().map(|&i| fitted[i]).collect();
            let ident = fit::identifiability(&problem, &p_free, noise_std);
            let validation = fit::generalisation(&plant_model, &start, &result.params, &val_sets);
            Ok::<_, IdentError>((result, ident, validation))
        })
        .map_err(|e| value_error(format!("{}: {e}", data.display())))?;
    let seconds = started.elapsed().as_secs_f64();
    let ident = ident.map_err(|e| e.to_string());
    let report: FitSummary<'_, ()> = FitSummary::new(
        FitInputs {
            data: data.display().to_string(),
            model: plant.display().to_string(),
            samples: dataset.len(),
            plant: plant_model,
            free: &free,
            start,
            seconds,
        },
        &result,
        ident.as_ref().map_err(Clone::clone),
        &validation,
        None,
    );
    to_py(py, &report)
}
