//! `twinloop identify compliant`: fit the compact compliant model's corrections to a
//! recorded CoM (seed 002, section 4).

use crate::cmd_compliant::read_plant_any;
use crate::common::{emit, num, print};
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use clap::{Args, ValueEnum};
use serde::Serialize;
use std::path::PathBuf;
use twinloop_ident::compliant_fit::{
    self as fit, Dataset, FitOptions, FitProblem, FitResult, Identifiability, Method,
    PARAMETER_NAMES, SEED_PARAMETERS, Validation,
};
use twinloop_reduced::{CompactModel, Corrections, SagittalCompliance};
use twinloop_report::{Plot, Report, SeriesStyle};

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
    /// m, g and the x-z stiffness/damping (MODEL.toml, or the JSON of `compliant stiffness`).
    #[arg(long, value_name = "MODEL.toml")]
    pub model: PathBuf,
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
    #[arg(long)]
    pub max_evaluations: Option<usize>,
    /// Initial step size (CMA-ES sigma, PoWER exploration std).
    #[arg(long, default_value_t = 0.05)]
    pub sigma: f64,
    /// Random seed (CMA-ES, PoWER).
    #[arg(long, default_value_t = 2012)]
    pub seed: u64,
    /// Noise standard deviation (m) for the Cramer-Rao bounds; default: estimated from
    /// the residuals.
    #[arg(long, value_name = "M")]
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

#[derive(Serialize)]
struct FitReport<'a> {
    data: String,
    model: String,
    samples: usize,
    plant: SagittalCompliance,
    method: Method,
    free: Vec<&'static str>,
    start: Corrections,
    params: Corrections,
    mse_before: f64,
    mse_after: f64,
    rms_before: f64,
    rms_after: f64,
    evaluations: usize,
    iterations: usize,
    stop: &'a str,
    seconds: f64,
    identifiability: Option<&'a Identifiability>,
    identifiability_error: Option<String>,
    validation: &'a [Validation],
    timing: Option<Timing>,
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

fn read_inputs(args: &CompliantFitArgs) -> Result<Inputs, CliError> {
    let plant = read_plant_any(&args.model)?;
    let data = Dataset::read(&args.data)?;
    let val = args
        .val
        .iter()
        .map(|p| Dataset::read(p))
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
        let html = html_report(
            args,
            &plant,
            &start,
            &data,
            &result,
            ident.as_ref(),
            &validation,
        );
        html.write(path)?;
    }
    let report = FitReport {
        data: args.data.display().to_string(),
        model: args.model.display().to_string(),
        samples: data.len(),
        plant,
        method,
        free: free.iter().map(|&i| PARAMETER_NAMES[i]).collect(),
        start,
        params: result.params,
        mse_before: result.mse_before,
        mse_after: result.mse_after,
        rms_before: result.mse_before.sqrt(),
        rms_after: result.mse_after.sqrt(),
        evaluations: result.evaluations,
        iterations: result.iterations,
        stop: &result.stop,
        seconds,
        identifiability: ident.as_ref(),
        identifiability_error: ident_error.clone(),
        validation: &validation,
        timing,
    };
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

/// At most about 3000 points per curve: the SVG stays light.
fn decimate(v: &[f64]) -> Vec<f64> {
    let stride = v.len().div_ceil(3000).max(1);
    v.iter().step_by(stride).copied().collect()
}

fn html_report(
    args: &CompliantFitArgs,
    plant: &SagittalCompliance,
    start: &Corrections,
    data: &Dataset,
    r: &FitResult,
    ident: Option<&Identifiability>,
    validation: &[Validation],
) -> Report {
    let mut rep = Report::new("Compact compliant model fit (seed 002)");
    rep.paragraph(format!(
        "Data {} ({} samples), model {}, method {:?}: {} evaluations ({}). MSE {} m^2 before, {} m^2 after.",
        args.data.display(),
        data.len(),
        args.model.display(),
        r.method,
        r.evaluations,
        r.stop,
        num(r.mse_before),
        num(r.mse_after)
    ));
    let roll = |c: &Corrections| {
        let m = CompactModel {
            plant: *plant,
            corrections: *c,
        };
        let (mut x, mut z) = (Vec::new(), Vec::new());
        m.rollout_unchecked(&data.reference, data.x[0], data.z[0], &mut x, &mut z);
        (x, z)
    };
    let (xb, zb) = roll(start);
    let (xa, za) = roll(&r.params);
    let t = decimate(&data.reference.t);
    rep.heading("Seed 002 Fig. 4: the model before and after the fit");
    for (axis, meas, before, after) in [("x", &data.x, &xb, &xa), ("z", &data.z, &zb, &za)] {
        rep.plot(
            &Plot::new(format!("CoM {axis}"), "t [s]", format!("{axis} [m]"))
                .series("measured", &t, &decimate(meas), SeriesStyle::Line)
                .series("before", &t, &decimate(before), SeriesStyle::DashedLine)
                .series("after", &t, &decimate(after), SeriesStyle::Line),
        );
    }
    rep.paragraph(
        "At walking scale the curves overlap; the model's error against the measurement shows the difference:",
    );
    for (axis, meas, before, after) in [("x", &data.x, &xb, &xa), ("z", &data.z, &zb, &za)] {
        let err = |m: &[f64]| -> Vec<f64> {
            decimate(
                &m.iter()
                    .zip(meas.iter())
                    .map(|(a, b)| a - b)
                    .collect::<Vec<_>>(),
            )
        };
        rep.plot(
            &Plot::new(
                format!("CoM {axis}: model minus measurement"),
                "t [s]",
                format!("error in {axis} [m]"),
            )
            .series("before", &t, &err(before), SeriesStyle::DashedLine)
            .series("after", &t, &err(after), SeriesStyle::Line),
        );
    }
    rep.heading("Parameters");
    let p = r.params.to_array();
    let s = start.to_array();
    let rows = (0..10)
        .map(|i| {
            let name = PARAMETER_NAMES[i];
            let (std, flag) = match ident.and_then(|id| id.names.iter().position(|n| n == name)) {
                Some(k) => {
                    let id = ident.expect("position came from it");
                    let flag = if id.poorly_determined.iter().any(|n| n == name) {
                        "poorly determined"
                    } else {
                        ""
                    };
                    (num(id.std[k]), flag.to_string())
                }
                None => ("fixed".to_string(), String::new()),
            };
            vec![name.to_string(), num(s[i]), num(p[i]), std, flag]
        })
        .collect();
    rep.table(
        vec![
            "parameter".into(),
            "start".into(),
            "fitted".into(),
            "Cramer-Rao std".into(),
            "".into(),
        ],
        rows,
    );
    if let Some(id) = ident {
        rep.paragraph(format!(
            "Noise standard deviation estimated from the residuals: {} m (variance {} m^2, \
             Cramer-Rao std of that variance {} m^2; the bounds use {} m). \
             Condition of the scaled Fisher information: {}. Least determined direction \
             (relative changes): {}.",
            num(id.noise_std_estimated),
            num(id.noise_std_estimated.powi(2)),
            num(id.noise_variance_std),
            num(id.noise_std),
            num(id.condition),
            id.names
                .iter()
                .zip(&id.weakest_direction)
                .map(|(n, v)| format!("{n} {}", num(*v)))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        let mut header = vec![String::new()];
        header.extend(id.names.iter().cloned());
        let rows = id
            .names
            .iter()
            .zip(&id.correlation)
            .map(|(n, row)| {
                let mut r = vec![n.clone()];
                r.extend(row.iter().map(|v| format!("{v:.3}")));
                r
            })
            .collect();
        rep.subheading("Parameter correlation (Cramer-Rao covariance)");
        rep.table(header, rows);
    }
    if !validation.is_empty() {
        rep.heading("Generalisation: other gaits");
        rep.table(
            vec![
                "data".into(),
                "samples".into(),
                "MSE before [m^2]".into(),
                "MSE after [m^2]".into(),
            ],
            validation
                .iter()
                .map(|v| {
                    vec![
                        v.source.clone(),
                        v.samples.to_string(),
                        num(v.mse_before),
                        num(v.mse_after),
                    ]
                })
                .collect(),
        );
    }
    rep
}
