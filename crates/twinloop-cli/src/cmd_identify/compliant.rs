//! `twinloop identify compliant`: fit the compact compliant model's corrections to a
//! recorded CoM (seed 002, section 4).

use crate::common::{emit, num, print};
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use clap::{Args, ValueEnum};
use serde::Serialize;
use std::path::PathBuf;
use twinloop_ident::compliant_fit::read_plant as read_plant_any;
use twinloop_ident::compliant_fit::report::fit_report;
use twinloop_ident::compliant_fit::summary::{FitInputs, FitSummary};
use twinloop_ident::compliant_fit::{
    self as fit, Dataset, FitOptions, FitProblem, FitResult, Identifiability, Method,
    PARAMETER_NAMES, SEED_PARAMETERS, Validation,
};
use twinloop_reduced::{Corrections, SagittalCompliance};

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    Lm,
    Cmaes,
    Power,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::Lm => Method::Lm,
            MethodArg::Cmaes => Method::Cmaes,
            MethodArg::Power => Method::Power,
        }
    }
}

#[derive(Args, Debug)]
pub struct CompliantFitArgs {
    /// Recorded data: t, xr, zr, x, z, phase.
    #[arg(long, value_name = "FILE.csv")]
    pub data: PathBuf,
    /// m, g and the x-z stiffness/damping (PLANT.toml, or the JSON of `compliant stiffness`).
    #[arg(long, value_name = "PLANT.toml")]
    pub plant: PathBuf,
    /// Optimiser.
    #[arg(long, value_enum, default_value_t = MethodArg::Lm)]
    pub method: MethodArg,
    /// Parameters to fit, comma-separated names or `all` (default: the seed's eight).
    #[arg(long, value_name = "NAMES")]
    pub params: Option<String>,
    /// Starting values of all ten (alpha1,..,epsilon2,eta1,eta2); default all ones.
    #[arg(long, value_name = "P1,..,P10")]
    pub start: Option<String>,
    /// Budget of cost evaluations (default: lm 500, cmaes 25000, power 4000).
    #[arg(long, value_parser = crate::bounds::count)]
    pub max_evaluations: Option<usize>,
    /// Initial step size (CMA-ES sigma, PoWER exploration std).
    #[arg(long, default_value_t = 0.05, value_parser = crate::common::positive)]
    pub sigma: f64,
    /// Random seed (CMA-ES, PoWER).
    #[arg(long, default_value_t = 2012)]
    pub seed: u64,
    /// Noise standard deviation (m) for the Cramer-Rao bounds; default: estimated from
    /// the residuals.
    #[arg(long, value_name = "M", value_parser = crate::units::noise)]
    pub noise_std: Option<f64>,
    /// Validation data of other gaits (repeatable): MSE before and after on each.
    #[arg(long = "val", value_name = "FILE.csv")]
    pub val: Vec<PathBuf>,
    /// Also time the rollout, the sensitivity rollout and the whole fit over this many
    /// rounds each and report the medians (JSON `timing`; for BENCHMARKS.md).
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub timing_rounds: usize,
    /// Write the result as JSON to FILE (-: to stdout, in place of the text).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write an HTML report (seed 002 Fig. 4: x and z before and after against the data).
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
}

/// Medians over rounds, seconds.
#[derive(Serialize, Clone, Copy)]
struct Timing {
    rounds: usize,
    rollout: f64,
    rollout_per_1000_samples: f64,
    sensitivity_rollout: f64,
    fit: f64,
}

fn median_time(rounds: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..rounds)
        .map(|_| {
            let start = std::time::Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn timing(problem: &FitProblem, method: Method, options: &FitOptions, rounds: usize) -> Timing {
    let p = problem.initial();
    let model = problem.model(&problem.full(&p));
    let mut sink = 0.0;
    let rollout = median_time(rounds, || sink += fit::mse(&model, problem.data));
    let sensitivity_rollout = median_time(rounds, || {
        sink += fit::sensitivity::normal_equations(&model, problem.data).sse
    });
    let fit = median_time(rounds, || {
        if let Ok(r) = fit::fit(problem, method, options, &mut |_| {}) {
            sink += r.mse_after;
        }
    });
    // keep the work observable so it is not optimised away
    std::hint::black_box(sink);
    Timing {
        rounds,
        rollout,
        rollout_per_1000_samples: rollout * 1000.0 / problem.data.len() as f64,
        sensitivity_rollout,
        fit,
    }
}

fn parse_ten(text: &str, what: &str) -> Result<Corrections, CliError> {
    let values: Result<Vec<f64>, _> = text.split(',').map(|s| s.trim().parse::<f64>()).collect();
    match values {
        Ok(v) if v.len() == 10 && v.iter().all(|x| x.is_finite()) => {
            let mut a = [0.0; 10];
            a.copy_from_slice(&v);
            Ok(Corrections::from_slice(&a))
        }
        _ => Err(CliError::new(format!(
            "{what} {text}: expected 10 finite comma-separated numbers ({})",
            PARAMETER_NAMES.join(",")
        ))),
    }
}

/// What the fit is run on: the plant, the data, the validation data, which
/// parameters are free and where they start.
struct Inputs {
    plant: SagittalCompliance,
    data: Dataset,
    val: Vec<Dataset>,
    free: Vec<usize>,
    start: Corrections,
}

/// A dataset from its CSV, or from a log (an MCAP, a rosbag2 folder) read as the
/// table a CSV would give.
fn read_dataset(path: &std::path::Path) -> Result<Dataset, CliError> {
    if twinloop_logs::is_log(path) {
        let table = crate::common::read_table(path)?;
        return Ok(Dataset::from_table(&table, &path.display().to_string())?);
    }
    Ok(Dataset::read(path)?)
}

fn read_inputs(args: &CompliantFitArgs) -> Result<Inputs, CliError> {
    let plant = read_plant_any(&args.plant)?;
    let data = read_dataset(&args.data)?;
    let val = args
        .val
        .iter()
        .map(|p| read_dataset(p))
        .collect::<Result<Vec<_>, _>>()?;
    let free = match &args.params {
        Some(text) => {
            fit::parse_parameter_names(text).map_err(|e| CliError::from(e).context("--params"))?
        }
        None => SEED_PARAMETERS.to_vec(),
    };
    let start = match &args.start {
        Some(text) => parse_ten(text, "--start")?,
        None => Corrections::default(),
    };
    Ok(Inputs {
        plant,
        data,
        val,
        free,
        start,
    })
}

pub fn run(args: &CompliantFitArgs) -> CliResult {
    let Inputs {
        plant,
        data,
        val,
        free,
        start,
    } = read_inputs(args)?;
    let problem = FitProblem::new(plant, &data, start, &free)
        .map_err(|e| CliError::from(e).context(args.data.display()))?;
    let method: Method = args.method.into();
    let mut options = FitOptions::for_method(method);
    if let Some(n) = args.max_evaluations {
        options.max_evaluations = n;
    }
    options.sigma = args.sigma;
    options.seed = args.seed;
    let bar = progress::steps(options.max_evaluations);
    bar.set_message("evaluations");
    let started = std::time::Instant::now();
    let result = fit::fit(&problem, method, &options, &mut |p| {
        bar.set_position(p.evaluations as u64);
    });
    bar.finish_and_clear();
    let seconds = started.elapsed().as_secs_f64();
    let result = result.map_err(|e| CliError::from(e).context(args.data.display()))?;
    let fitted = result.params.to_array();
    let p_free: Vec<f64> = free.iter().map(|&i| fitted[i]).collect();
    let (ident, ident_error) = match fit::identifiability(&problem, &p_free, args.noise_std) {
        Ok(id) => (Some(id), None),
        Err(e) => (None, Some(e.to_string())),
    };
    let validation = fit::generalisation(&plant, &start, &result.params, &val);
    let timing =
        (args.timing_rounds > 0).then(|| timing(&problem, method, &options, args.timing_rounds));
    if let Some(t) = &timing {
        print(&format!(
            "timing (median of {}): rollout {} ms ({} us per 1000 samples), sensitivity rollout {} ms, whole fit {} ms\n",
            t.rounds,
            num(t.rollout * 1e3),
            num(t.rollout_per_1000_samples * 1e6),
            num(t.sensitivity_rollout * 1e3),
            num(t.fit * 1e3)
        ));
    }
    if let Some(path) = &args.report {
        let html = fit_report(
            &args.data.display().to_string(),
            &args.plant.display().to_string(),
            &plant,
            &start,
            &data,
            &result,
            ident.as_ref(),
            &validation,
        );
        html.write(path)?;
    }
    let report = FitSummary::new(
        FitInputs {
            data: args.data.display().to_string(),
            model: args.plant.display().to_string(),
            samples: data.len(),
            plant,
            free: &free,
            start,
            seconds,
        },
        &result,
        ident
            .as_ref()
            .ok_or_else(|| ident_error.clone().unwrap_or_default()),
        &validation,
        timing,
    );
    let text = summary(
        args,
        &data,
        &result,
        seconds,
        ident.as_ref(),
        ident_error.as_deref(),
        &validation,
    );
    emit(&text, args.json.as_ref(), &report)?;
    Ok(Outcome::Ok)
}

fn summary(
    args: &CompliantFitArgs,
    data: &Dataset,
    r: &FitResult,
    seconds: f64,
    ident: Option<&Identifiability>,
    ident_error: Option<&str>,
    validation: &[Validation],
) -> String {
    let mut s = format!(
        "{}: {} samples, method {:?}: {} evaluations, {} iterations, {} s ({})\n\
         MSE {} -> {} m^2 (RMS {} -> {} m)\n",
        args.data.display(),
        data.len(),
        r.method,
        r.evaluations,
        r.iterations,
        num(seconds),
        r.stop,
        num(r.mse_before),
        num(r.mse_after),
        num(r.mse_before.sqrt()),
        num(r.mse_after.sqrt()),
    );
    let p = r.params.to_array();
    match ident {
        Some(id) => {
            s += &format!(
                "parameter    value        Cramer-Rao std (noise {} m)  relative\n",
                num(id.noise_std)
            );
            for (k, name) in id.names.iter().enumerate() {
                let flag = if id.poorly_determined.contains(name) {
                    "  poorly determined"
                } else {
                    ""
                };
                s += &format!(
                    "{:<12} {:<12} {:<28} {:<10}{flag}\n",
                    name,
                    num(id.values[k]),
                    num(id.std[k]),
                    num(id.relative_std[k])
                );
            }
            for (a, b, c) in &id.correlated {
                s += &format!("correlated: {a} and {b} (r = {})\n", num(*c));
            }
        }
        None => {
            for (i, name) in PARAMETER_NAMES.iter().enumerate() {
                s += &format!("{name:<12} {}\n", num(p[i]));
            }
            if let Some(e) = ident_error {
                s += &format!("identifiability: {e}\n");
            }
        }
    }
    for v in validation {
        s += &format!(
            "validation {}: MSE {} -> {} m^2\n",
            v.source,
            num(v.mse_before),
            num(v.mse_after)
        );
    }
    s
}
