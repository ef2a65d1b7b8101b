//! `twinloop identify arx|ss`: black-box identification of a recorded input/output
//! data set (seed 003): MIMO ARX, or a state-space model by subspace
//! identification, the prediction-error method, or the seed's ARX-reduce-PEM route.

use crate::common::{emit, num, read_table};
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
use std::time::Instant;
use twinloop_sysid::identify::Evaluation;
use twinloop_sysid::json::{ArxJson, DataJson, SsOrdersJson, StateSpaceJson};
use twinloop_sysid::pem::{OutputWeight, PemOptions};
use twinloop_sysid::report::{arx_report, seed_reference_fits, state_space_report};
use twinloop_sysid::{
    ArxOrders, EvaluationOptions, IoData, SsMethod, SsOptions, identify_arx, identify_state_space,
};

/// What the output means, shared by both commands' `--help`.
macro_rules! sysid_output_help {
    () => {
        "\
The JSON (--json FILE, - for stdout) holds the model and its evaluation, on the --val record when given, else on
the estimation record:
  A, B (arx)            lists of na matrices ny x ny and nb matrices ny x nu, nested row lists:
                        y(k) + A1 y(k-1) + .. = B1 u(k-nk) + .. + e(k)
  A, B, C, D, K (ss)    x(k+1) = A x + B u + K e, y = C x + D u + e
  noise_covariance      covariance of e
  fit_percent           simulation, prediction: FIT per output, 100 (1 - |y-yhat|/|y-mean y|)
                        as MATLAB's compare (100 perfect, 0 no better than the mean);
                        seed_eq10_simulation, seed_eq10_prediction: the seed's eq 10,
                        100 |y-yhat|/|y| (an error: lower is better); prediction_horizon
  estimation_fit_percent  the same on the estimation record
  prediction_cost       mean squared one-step prediction error
  stability             stable, spectral_radius, poles_outside_unit_circle, predictor_spectral_radius
  hankel_singular_values  of (A, B, C), largest first; null for an unstable model
  order_suggestion      order (largest HSV gap), gap_ratio, truncation_error_bound per order
  frequency_response    peak_gain_db, peak_frequency, dc_gain_db, bandwidth (3 dB below the
                        zero-frequency gain), frequency_unit, frequency[], sigma_db[][]
  residual_tests        pass, whiteness_pass, independence_pass, summary, band_99, and per test
                        (autocorrelation, cross_correlation, input_correlation): correlation
                        per lag, statistic, degrees_of_freedom, p_value, pass
  stages, pem (ss)      earlier models of the route with their FIT; iterations, costs, termination
  warnings              e.g. an unstable model
  timing_seconds        estimation, evaluation

Numbers in the JSON are full precision. The text printed on stdout is a summary: FIT per
output, Hankel singular values, peak gain and bandwidth, and the residual-test verdict.
Exit code 0 on success, 2 on unreadable data or impossible orders (the message names the
file, line, row or column at fault)."
    };
}

#[derive(Args, Debug)]
pub struct DataArgs {
    /// Estimation data: CSV with a header row (a `t` column gives the sample time).
    #[arg(long, value_name = "FILE.csv")]
    pub data: PathBuf,
    /// Validation data with the same columns: the evaluation uses it when given.
    #[arg(long, value_name = "FILE.csv")]
    pub val: Option<PathBuf>,
    /// Input columns, comma-separated; `prefix*` selects every column starting with prefix.
    #[arg(long, value_name = "NAMES", value_delimiter = ',', required = true)]
    pub inputs: Vec<String>,
    /// Output columns, comma-separated; `prefix*` as for --inputs.
    #[arg(long, value_name = "NAMES", value_delimiter = ',', required = true)]
    pub outputs: Vec<String>,
    /// Sample period in seconds (default: from a uniform `t` column; frequencies are
    /// then in rad/s, else in rad/sample).
    #[arg(long, value_name = "S", value_parser = crate::common::positive)]
    pub dt: Option<f64>,
    /// Keep the means. By default the estimation data's mean is subtracted from every
    /// input and output (the same offsets from the validation data; the JSON's
    /// data.offsets says what was removed).
    #[arg(long)]
    pub no_detrend: bool,
    /// Horizon of the `prediction` FIT (1 = one step ahead).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = crate::bounds::count)]
    pub kstep: usize,
    /// Largest lag of the residual tests.
    #[arg(long, value_name = "M", default_value_t = 25, value_parser = crate::bounds::count)]
    pub lags: usize,
    /// Write the model and its evaluation as JSON to FILE (-: to stdout, in place of
    /// the text).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write an HTML report with the seed's figures.
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
    /// Show seed 003's FIT figures beside the model's (outputs ordered left roll, pitch,
    /// yaw rate, then right roll, pitch, yaw rate).
    #[arg(long)]
    pub compare_seed: bool,
}

#[derive(Args, Debug)]
pub struct ArxArgs {
    #[command(flatten)]
    pub data: DataArgs,
    /// Output lags (each A_i is ny x ny).
    #[arg(long, default_value_t = 2)]
    pub na: usize,
    /// Input lags (each B_j is ny x nu).
    #[arg(long, default_value_t = 2, value_parser = crate::bounds::count)]
    pub nb: usize,
    /// Input delay in samples.
    #[arg(long, default_value_t = 1)]
    pub nk: usize,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MethodArg {
    /// Subspace identification alone.
    N4sid,
    /// Subspace estimate refined by the prediction-error method (as MATLAB's ssest).
    Pem,
    /// Seed 003's route: ARX (--na --nb --nk), balanced truncation to --order, prediction error.
    ArxReducePem,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum WeightArg {
    /// Sum of squared prediction errors.
    Identity,
    /// Errors weighted by the inverse of the initial model's noise covariance.
    Noise,
}

#[derive(Args, Debug)]
pub struct SsArgs {
    #[command(flatten)]
    pub data: DataArgs,
    /// Number of states.
    #[arg(long, value_parser = crate::bounds::count)]
    pub order: usize,
    /// How to estimate the model.
    #[arg(long, value_enum, default_value = "pem")]
    pub method: MethodArg,
    /// ARX output lags for arx-reduce-pem.
    #[arg(long, default_value_t = 10)]
    pub na: usize,
    /// ARX input lags for arx-reduce-pem.
    #[arg(long, default_value_t = 10, value_parser = crate::bounds::count)]
    pub nb: usize,
    /// ARX input delay for arx-reduce-pem.
    #[arg(long, default_value_t = 1)]
    pub nk: usize,
    /// Estimate a direct feedthrough D (default: D = 0, as ssest and the seed's eq 9).
    #[arg(long)]
    pub feedthrough: bool,
    /// Estimate the initial state in the prediction-error search (default: zero).
    #[arg(long)]
    pub estimate_x0: bool,
    /// Iteration limit of the prediction-error search.
    #[arg(long, default_value_t = 100, value_parser = crate::bounds::count)]
    pub max_iter: usize,
    /// Output weighting of the prediction-error cost.
    #[arg(long, value_enum, default_value = "identity")]
    pub weight: WeightArg,
    /// Block rows of the subspace method (default: max(10, order/ny + 2), within what the data allow).
    #[arg(long, value_name = "I", value_parser = crate::bounds::count)]
    pub n4sid_horizon: Option<usize>,
    /// What the prediction-error search minimises: `prediction` (one-step errors, K
    /// estimated: the innovations form) or `simulation` (output error, K = 0, A kept
    /// stable; MATLAB's ssestOptions Focus = 'simulation'). Simulation suits models
    /// meant to be run open loop, as the seed's walking model.
    #[arg(long, value_enum, default_value = "prediction")]
    pub focus: FocusArg,
    /// Keep A stable in the search even with --focus prediction (MATLAB's EnforceStability).
    #[arg(long)]
    pub enforce_stability: bool,
    /// Largest pole radius the search may leave on A when it keeps A stable (below 1: a
    /// damping margin against undamped oscillators fitted to periodic data).
    #[arg(long, default_value_t = 1.0, value_name = "R", value_parser = crate::common::positive)]
    pub max_pole_radius: f64,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FocusArg {
    Prediction,
    Simulation,
}

fn load(path: &Path, a: &DataArgs) -> Result<IoData, CliError> {
    let table = read_table(path)?;
    let mut d = IoData::from_io_table(&table, &a.inputs, &a.outputs)?;
    if let Some(dt) = a.dt {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(CliError::new(format!(
                "--dt {dt}: the sample period must be a positive number of seconds"
            )));
        }
        // A t column spaced otherwise: the frequencies would be off by their ratio.
        if let Some(step) = d.sample_time
            && (step - dt).abs() > 1e-3 * step
        {
            return Err(CliError::new(format!(
                "--dt {} s: the t column of {} is spaced {} s; leave --dt out (it is read \
                 from t) or give the step the rows have",
                crate::common::num(dt),
                path.display(),
                crate::common::num(step)
            )));
        }
        d.sample_time = Some(dt);
    }
    Ok(d)
}

struct Records {
    est: IoData,
    val: Option<IoData>,
    offsets: Option<(Vec<f64>, Vec<f64>)>,
}

fn load_records(a: &DataArgs) -> Result<Records, CliError> {
    let mut est = load(&a.data, a)?;
    let mut val = a.val.as_ref().map(|p| load(p, a)).transpose()?;
    if let Some(v) = &val {
        est.check_same_channels(v).map_err(|e| {
            CliError::from(e).context(
                a.val
                    .as_ref()
                    .map_or(String::new(), |p| p.display().to_string()),
            )
        })?;
    }
    let offsets = if !a.no_detrend {
        let (u0, y0) = est.means();
        est.remove_offsets(&u0, &y0);
        if let Some(v) = &mut val {
            v.remove_offsets(&u0, &y0);
        }
        Some((u0, y0))
    } else {
        None
    };
    est.check_excitation()
        .map_err(|e| CliError::from(e).context(a.data.display()))?;
    Ok(Records { est, val, offsets })
}

fn data_json(a: &DataArgs, r: &Records) -> DataJson {
    DataJson::new(
        a.data.display().to_string(),
        a.val.as_ref().map(|p| p.display().to_string()),
        &r.est,
        r.val.as_ref(),
        r.offsets.as_ref(),
    )
}

pub fn command_line() -> String {
    std::env::args()
        .map(|a| if a.contains(' ') { format!("'{a}'") } else { a })
        .collect::<Vec<_>>()
        .join(" ")
}

fn summary(names: &[String], ev: &Evaluation, warnings: &[String]) -> String {
    use std::fmt::Write as _;
    let f = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.1}"));
    let mut s = String::new();
    let _ = writeln!(
        s,
        "FIT on the {} data ({} samples), percent (MATLAB compare; eq 10 = seed's error measure):",
        ev.data, ev.samples
    );
    let _ = writeln!(
        s,
        "  {:<20} {:>9} {:>9} {:>10} {:>10}",
        "output",
        "sim",
        format!("{}-step", ev.fit_percent.prediction_horizon),
        "eq10 sim",
        "eq10 pred"
    );
    for (i, n) in names.iter().enumerate() {
        let fp = &ev.fit_percent;
        let _ = writeln!(
            s,
            "  {:<20} {:>9} {:>9} {:>10} {:>10}",
            n,
            f(fp.simulation[i]),
            f(fp.prediction[i]),
            f(fp.seed_eq10_simulation[i]),
            f(fp.seed_eq10_prediction[i])
        );
    }
    let _ = writeln!(
        s,
        "prediction cost (mean squared one-step error): {}",
        num(ev.prediction_cost)
    );
    match &ev.hankel_singular_values {
        Some(h) => {
            let shown: Vec<String> = h.iter().take(12).map(|x| num(*x)).collect();
            let more = if h.len() > 12 {
                format!(" ... ({} in all)", h.len())
            } else {
                String::new()
            };
            let _ = writeln!(s, "Hankel singular values: {}{more}", shown.join(" "));
            if let Some(o) = &ev.order_suggestion {
                let _ = writeln!(
                    s,
                    "  largest gap after state {} (ratio {})",
                    o.order,
                    num(o.gap_ratio)
                );
            }
        }
        None => {
            let _ = writeln!(s, "Hankel singular values: none (the model is unstable)");
        }
    }
    let fr = &ev.frequency_response;
    let _ = writeln!(
        s,
        "frequency response: peak gain {:.2} dB at {} {}, bandwidth {}",
        fr.peak_gain_db,
        num(fr.peak_frequency),
        fr.frequency_unit,
        fr.bandwidth
            .map_or("not reached below Nyquist".to_string(), |b| format!(
                "{} {}",
                num(b),
                fr.frequency_unit
            ))
    );
    let _ = writeln!(s, "residual tests: {}", ev.residual_tests.summary);
    for w in warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    s
}

fn eval_options(a: &DataArgs) -> EvaluationOptions {
    EvaluationOptions {
        prediction_horizon: a.kstep.max(1),
        max_lag: a.lags.max(1),
        ..EvaluationOptions::default()
    }
}

pub fn arx(a: &ArxArgs) -> CliResult {
    let d = &a.data;
    let recs = load_records(d)?;
    let orders = ArxOrders {
        na: a.na,
        nb: a.nb,
        nk: a.nk,
    };
    let t0 = Instant::now();
    let id = identify_arx(&recs.est, recs.val.as_ref(), orders, &eval_options(d))
        .map_err(|e| CliError::from(e).context(d.data.display()))?;
    let elapsed = t0.elapsed().as_secs_f64();
    let json = ArxJson::new(&id, data_json(d, &recs), orders, elapsed);
    let ev_data = recs.val.as_ref().unwrap_or(&recs.est);
    if let Some(p) = &d.report {
        let refs = if d.compare_seed {
            seed_reference_fits()[..1].to_vec()
        } else {
            Vec::new()
        };
        arx_report(&id, ev_data, &command_line(), &refs).write(p)?;
    }
    let text = format!(
        "ARX na={} nb={} nk={}: {} inputs, {} outputs, {} parameters per output, estimated in {:.3} s\n{}",
        a.na,
        a.nb,
        a.nk,
        recs.est.nu(),
        recs.est.ny(),
        orders.parameters_per_output(recs.est.ny(), recs.est.nu()),
        id.estimation_seconds,
        summary(
            &recs.est.output_names,
            &id.evaluation,
            &id.evaluation.warnings
        )
    );
    emit(&text, d.json.as_ref(), &json)?;
    Ok(Outcome::Ok)
}

fn ss_options(a: &SsArgs) -> SsOptions {
    SsOptions {
        order: a.order,
        method: match a.method {
            MethodArg::N4sid => SsMethod::N4sid,
            MethodArg::Pem => SsMethod::Pem,
            MethodArg::ArxReducePem => SsMethod::ArxReducePem,
        },
        arx_orders: ArxOrders {
            na: a.na,
            nb: a.nb,
            nk: a.nk,
        },
        horizon: a.n4sid_horizon,
        pem: PemOptions {
            max_iterations: a.max_iter,
            feedthrough: a.feedthrough,
            estimate_x0: a.estimate_x0,
            weight: match a.weight {
                WeightArg::Identity => OutputWeight::Identity,
                WeightArg::Noise => OutputWeight::InverseNoise,
            },
            enforce_stability: a.enforce_stability,
            output_error: a.focus == FocusArg::Simulation,
            max_pole_radius: a.max_pole_radius,
            ..PemOptions::default()
        },
        evaluation: eval_options(&a.data),
    }
}

pub fn ss(a: &SsArgs) -> CliResult {
    let d = &a.data;
    let recs = load_records(d)?;
    let opts = ss_options(a);
    let method = opts.method;
    let bar = progress::steps(a.max_iter);
    bar.set_message("prediction-error search");
    let t0 = Instant::now();
    let id = identify_state_space(&recs.est, recs.val.as_ref(), &opts, &mut |p| {
        bar.set_position(p.iteration as u64);
        bar.set_message(format!("cost {}", num(p.cost)));
    })
    .map_err(|e| {
        // The library speaks of the horizon; here it is an option.
        let horizon = e.message.contains("horizon");
        let e = CliError::from(e).context(d.data.display());
        if horizon {
            e.context(format!(
                "--n4sid-horizon {}",
                a.n4sid_horizon
                    .map_or("(default max(10, order / outputs + 2))".into(), |i| i
                        .to_string())
            ))
        } else {
            e
        }
    });
    bar.finish_and_clear();
    let id = id?;
    let elapsed = t0.elapsed().as_secs_f64();
    let orders = SsOrdersJson {
        order: a.order,
        arx: (method == SsMethod::ArxReducePem).then_some(opts.arx_orders),
    };
    let focus = match a.focus {
        FocusArg::Prediction => "prediction",
        FocusArg::Simulation => "simulation",
    };
    let json = StateSpaceJson::new(&id, data_json(d, &recs), focus, orders, elapsed);
    let ev_data = recs.val.as_ref().unwrap_or(&recs.est);
    if let Some(p) = &d.report {
        let refs = if d.compare_seed {
            seed_reference_fits()
        } else {
            Vec::new()
        };
        state_space_report(&id, ev_data, &command_line(), &refs).write(p)?;
    }
    let m = &id.model;
    let mut head = format!(
        "state-space model, order {}, method {}: {} inputs, {} outputs, estimated in {:.3} s\n",
        m.n(),
        method.name(),
        m.nu(),
        m.ny(),
        id.estimation_seconds
    );
    if let Some(p) = &id.pem {
        head.push_str(&format!(
            "prediction-error search: {} iterations, {} free parameters, cost {} -> {} ({})\n",
            p.iterations,
            p.free_parameters,
            num(p.initial_cost),
            num(p.final_cost),
            p.termination
        ));
    }
    let text = head + &summary(&recs.est.output_names, &id.evaluation, &id.warnings);
    emit(&text, d.json.as_ref(), &json)?;
    Ok(Outcome::Ok)
}
