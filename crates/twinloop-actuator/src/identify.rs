//! Identification of one servo's parameters from logs on a known load: the model's
//! positions (and currents, where the servo senses them) against the logged ones,
//! by Levenberg-Marquardt over the logarithms of the parameters (they are positive,
//! and their scales span five decades). Reports one standard deviation and the
//! correlations from the Jacobian at the optimum, the held-out error in mrad, and
//! what the data cannot determine (the Jacobian's weak directions).

use crate::error::ActuatorError;
use crate::lm::{LmOptions, LmResult, levenberg_marquardt_parallel};
use crate::load::Load;
use crate::log::ServoLog;
use crate::params::{
    BACKLASH, FRICTION_VISCOUS, KT, NONSMOOTH, PARAM_NAMES, RESISTANCE, ServoParams,
};
use crate::replay::replay;
use crate::segments::{Segment, mean_voltage, position_sum_squares, residual_blocks, split_logs};
use nalgebra::DMatrix;
use std::ops::Range;
use twinloop_optim::parallel::Scratch;
use twinloop_optim::{CmaOptions, StepTolerance};

/// Weight of a current residual: one standard deviation, A. Timing (when the servo
/// samples its current against when the model does) dominates the register's
/// quantisation (2.69-3.36 mA).
pub const CURRENT_SD: f64 = 0.02;

/// A parameter is reported as not determined when its standard deviation exceeds
/// this fraction of its value.
pub const UNDETERMINED_RELATIVE_SD: f64 = 0.25;

/// Held-out RMS position error, in encoder counts, above which the fit does not
/// reproduce the logs: good logs come back within one count (0.3-0.5 of a count for
/// RX, MX and X over ptys, docs/servo-models.md). Beyond it every parameter is not
/// determined (see [`distrust`]).
pub const HELDOUT_COUNTS: f64 = 2.0;

#[derive(Debug, Clone)]
pub struct Identification {
    /// The fitted parameters with their standard deviations in `uncertainty`.
    pub params: ServoParams,
    /// Indices (into [`PARAM_NAMES`]) of the fitted parameters, in the order of
    /// `correlation`.
    pub fitted: Vec<usize>,
    pub correlation: Vec<Vec<f64>>,
    /// RMS of the fitted position residuals, mrad.
    pub fit_rms_mrad: f64,
    /// Held-out RMS and mean absolute position error, mrad, and its rows.
    pub heldout_rms_mrad: f64,
    pub heldout_mae_mrad: f64,
    pub heldout_rows: usize,
    /// The held-out RMS error in encoder counts of the servo. Above
    /// [`HELDOUT_COUNTS`] the model does not reproduce the logs: every parameter is
    /// then in `undetermined` and the combinations' deviations are widened.
    pub heldout_counts: f64,
    /// Singular values of the Jacobian with respect to the log-parameters, largest
    /// first, and their ratio (condition number).
    pub singular_values: Vec<f64>,
    pub condition: f64,
    /// Parameters whose relative standard deviation exceeds
    /// [`UNDETERMINED_RELATIVE_SD`].
    pub undetermined: Vec<&'static str>,
    /// The weakest direction in log-parameter space, as (name, weight) pairs.
    pub weakest_direction: Vec<(&'static str, f64)>,
    /// What the data determines where single parameters are not: (name, value,
    /// standard deviation). Position logs of a servo that senses no current (RX)
    /// determine the motor only through `kt/resistance` (N m/V: drive per volt) and
    /// `kt^2/resistance + friction_viscous` (N m s/rad: all damping), so
    /// `friction_viscous` is held at 0 (the back-EMF takes all the damping) and both
    /// combinations are reported here.
    pub combinations: Vec<(&'static str, f64, f64)>,
    /// Each parameter in `undetermined` with the interval the data allow, (name,
    /// low, high): for a servo without current, `kt`, `resistance` and
    /// `friction_viscous` from the two combinations (see [`motor_intervals`]); for any
    /// other, its value +- 3 standard deviations of the parameter itself (not of its
    /// logarithm, whose deviation grows without bound as a parameter runs to 0).
    pub intervals: Vec<(&'static str, f64, f64)>,
    /// LM iterations and simulations, over every LM run of the fit.
    pub iterations: usize,
    pub evaluations: usize,
    /// Parameters fitted by CMA-ES (the backlash, when asked), not in `correlation`.
    pub nonsmooth: Vec<usize>,
    /// Simulations CMA-ES ran for them.
    pub nonsmooth_evaluations: usize,
}

/// What [`identify_with`] fits beyond the rung's smooth parameters.
#[derive(Debug, Clone)]
pub struct IdentifyOptions {
    /// Non-smooth parameters to fit by CMA-ES (of [`NONSMOOTH`]); the others keep
    /// the start's values.
    pub nonsmooth: Vec<usize>,
    /// CMA-ES / LM alternations.
    pub rounds: usize,
    /// Simulations per CMA-ES round.
    pub cma_evaluations: usize,
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        IdentifyOptions {
            nonsmooth: Vec::new(),
            rounds: 2,
            cma_evaluations: 120,
        }
    }
}

/// The typical size of a non-smooth parameter (CMA-ES works in units of it).
fn nonsmooth_scale(i: usize) -> f64 {
    match i {
        BACKLASH => 0.01,
        _ => 0.002,
    }
}

/// The largest value the fit looks at.
fn nonsmooth_bound(i: usize) -> f64 {
    match i {
        BACKLASH => 0.06,
        _ => 0.02,
    }
}

/// Fit `start`'s rung to the first `1 - holdout_fraction` of each of `logs` (all of
/// them if `holdout` is not empty), held-out error on the rest and on `holdout`.
/// Backlash and delays keep the start's values.
pub fn identify(
    logs: &[ServoLog],
    holdout: &[ServoLog],
    load: &Load,
    start: &ServoParams,
    holdout_fraction: f64,
) -> Result<Identification, ActuatorError> {
    identify_with(
        logs,
        holdout,
        load,
        start,
        holdout_fraction,
        &IdentifyOptions::default(),
    )
}

/// [`identify`], also fitting `options.nonsmooth` (of backlash and the delays): the
/// backlash by CMA-ES, alternating with LM on the rest; the delays by LM with the
/// rung's parameters (they move the response continuously).
pub fn identify_with(
    logs: &[ServoLog],
    holdout: &[ServoLog],
    load: &Load,
    start: &ServoParams,
    holdout_fraction: f64,
    options: &IdentifyOptions,
) -> Result<Identification, ActuatorError> {
    check_request(logs, holdout, start, options)?;
    let (fit_segments, held_rows) = split_logs(logs, !holdout.is_empty(), holdout_fraction, |l| {
        l.current.is_some()
    });
    let held: Vec<(&ServoLog, Range<usize>)> = held_rows
        .into_iter()
        .map(|(k, rows)| (&logs[k], rows))
        .chain(holdout.iter().map(|l| (l, 0..l.len())))
        .collect();
    let senses_current = logs.iter().all(|l| l.current.is_some());
    let (mut params, fitted, nonsmooth) = starting_point(logs, start, options, senses_current);
    let sd_q = start.servo.resolution() / 12f64.sqrt();
    let m: usize = fit_segments.iter().map(Segment::residual_rows).sum();
    let longest = logs
        .iter()
        .chain(holdout)
        .map(ServoLog::len)
        .max()
        .unwrap_or(0);
    // One set of simulation buffers per worker of the pool (the fit runs its
    // simulations in parallel: twinloop_optim::parallel).
    let bufs = Scratch::new(move || Buffers {
        q: vec![0.0; longest],
        c: vec![0.0; longest],
        out: vec![0.0; m],
    });
    let mut fit = Fit {
        logs,
        load,
        segments: &fit_segments,
        sd_q,
        iterations: 0,
        evaluations: 0,
    };
    let mut result = fit.lm(&mut params, &fitted, &bufs);
    let mut nonsmooth_evaluations = 0;
    let mut nonsmooth_sd = vec![0.0; nonsmooth.len()];
    if !nonsmooth.is_empty() {
        nonsmooth_evaluations = alternate(
            &mut fit,
            &mut params,
            &fitted,
            &nonsmooth,
            options,
            &bufs,
            &mut result,
        );
        nonsmooth_sd =
            nonsmooth_deviations(&fit, &params, &nonsmooth, &result, fitted.len(), &bufs);
    }
    let (sq, count) = position_sum_squares(result.residuals.as_slice(), &fit_segments);
    let fit_rms_mrad = 1e3 * sd_q * (sq / count.max(1) as f64).sqrt();
    let heldout = bufs.with(|b| heldout_error(&params, load, &held, &mut b.q, &mut b.c));
    let mut block = Vec::new();
    residual_blocks(logs, &fit_segments, &mut block);
    let nonsmooth_pairs: Vec<(usize, f64)> = nonsmooth.iter().copied().zip(nonsmooth_sd).collect();
    let report = assess(
        &mut params,
        start,
        &fitted,
        &result,
        &block,
        senses_current,
        &nonsmooth_pairs,
    );
    let outcome = Outcome {
        fit_rms_mrad,
        heldout,
        iterations: fit.iterations,
        evaluations: fit.evaluations,
        nonsmooth_evaluations,
    };
    Ok(conclude(params, start, fitted, nonsmooth, report, outcome))
}

/// Refuses what [`identify_with`] cannot fit: an unknown non-smooth parameter, no
/// log, a log of another servo type.
fn check_request(
    logs: &[ServoLog],
    holdout: &[ServoLog],
    start: &ServoParams,
    options: &IdentifyOptions,
) -> Result<(), ActuatorError> {
    if let Some(&i) = options.nonsmooth.iter().find(|i| !NONSMOOTH.contains(i)) {
        return Err(ActuatorError::new(
            "",
            PARAM_NAMES.get(i).copied().unwrap_or("?"),
            "not a non-smooth parameter (backlash, sensing_delay, bus_delay)",
        ));
    }
    if logs.is_empty() {
        return Err(ActuatorError::new("", "--data", "no log to fit"));
    }
    for l in logs.iter().chain(holdout) {
        if l.servo != Some(start.servo) {
            return Err(ActuatorError::new(
                &l.file,
                "line 1",
                format!(
                    "a log of {:?}, but the model is of {}",
                    l.servo.map(|s| s.name()),
                    start.servo
                ),
            ));
        }
    }
    Ok(())
}

/// The fit's start (the logs' mean voltage as the supply), the smooth parameters LM
/// fits and the non-smooth ones CMA-ES fits.
fn starting_point(
    logs: &[ServoLog],
    start: &ServoParams,
    options: &IdentifyOptions,
    senses_current: bool,
) -> (ServoParams, Vec<usize>, Vec<usize>) {
    let mut params = start.clone();
    params.uncertainty = None;
    params.voltage = mean_voltage(logs);
    let mut fitted = params.level.parameters();
    if !senses_current {
        // Viscous friction and back-EMF damping are one term to the position: the
        // back-EMF (kt^2/R) takes it all, which any damping >= 0 allows.
        fitted.retain(|&i| i != FRICTION_VISCOUS);
        params.values[FRICTION_VISCOUS] = 0.0;
    }
    // The delays move the response continuously (the sensed angle is interpolated, a
    // goal comes into force inside a step): LM fits them, from 1 ms where the start
    // has none. The backlash's dead band and impacts are not smooth: CMA-ES.
    let nonsmooth: Vec<usize> = options
        .nonsmooth
        .iter()
        .copied()
        .filter(|&i| i == BACKLASH)
        .collect();
    for &i in &options.nonsmooth {
        if i != BACKLASH {
            fitted.push(i);
            if params.values[i] <= 0.0 {
                params.values[i] = 1e-3;
            }
        }
    }
    (params, fitted, nonsmooth)
}

/// Alternates CMA-ES on the non-smooth parameters (the smooth ones held) with LM on
/// the smooth ones (the non-smooth held), `result` becoming the last LM's; CMA-ES's
/// simulations.
fn alternate(
    fit: &mut Fit,
    params: &mut ServoParams,
    fitted: &[usize],
    nonsmooth: &[usize],
    options: &IdentifyOptions,
    bufs: &Scratch<Buffers>,
    result: &mut LmResult,
) -> usize {
    let scale: Vec<f64> = nonsmooth.iter().map(|&i| nonsmooth_scale(i)).collect();
    let upper: Vec<f64> = nonsmooth
        .iter()
        .zip(&scale)
        .map(|(&i, s)| nonsmooth_bound(i) / s)
        .collect();
    let lower = vec![0.0; nonsmooth.len()];
    let mut evaluations = 0;
    for round in 0..options.rounds.max(1) {
        let x0: Vec<f64> = nonsmooth
            .iter()
            .zip(&scale)
            .map(|(&i, s)| params.values[i] / s)
            .collect();
        let held = &*params;
        let fit_ref = &*fit;
        let r = twinloop_optim::minimize_parallel(
            &|x| {
                let mut trial = held.clone();
                for (k, &i) in nonsmooth.iter().enumerate() {
                    trial.values[i] = x[k] * scale[k];
                }
                fit_ref.cost(&trial, bufs)
            },
            &x0,
            Some((&lower, &upper)),
            &CmaOptions {
                sigma: 0.3,
                max_evaluations: options.cma_evaluations,
                tolerance: StepTolerance::Absolute(1e-3),
                target: f64::NEG_INFINITY,
                seed: 1 + round as u64,
            },
            &mut |_, _, _| {},
        );
        evaluations += r.evaluations;
        for (k, &i) in nonsmooth.iter().enumerate() {
            params.values[i] = r.x[k] * scale[k];
        }
        *result = fit.lm(params, fitted, bufs);
    }
    evaluations
}

/// One standard deviation of each non-smooth parameter from the cost's curvature
/// along it (the Gauss-Newton J^T J of a smooth model is the curvature of half the
/// squared residuals); infinite where the cost is flat or the parameter sits at 0.
fn nonsmooth_deviations(
    fit: &Fit,
    params: &ServoParams,
    nonsmooth: &[usize],
    result: &LmResult,
    n_fitted: usize,
    bufs: &Scratch<Buffers>,
) -> Vec<f64> {
    let m = result.residuals.len();
    let s2 = result.residuals.norm_squared() / m.saturating_sub(n_fitted).max(1) as f64;
    let c0 = fit.cost(params, bufs);
    nonsmooth
        .iter()
        .map(|&i| {
            let h = (0.1 * params.values[i]).max(0.02 * nonsmooth_scale(i));
            let mut t = params.clone();
            t.values[i] = params.values[i] + h;
            let up = fit.cost(&t, bufs);
            t.values[i] = (params.values[i] - h).max(0.0);
            let hd = params.values[i] - t.values[i];
            let down = fit.cost(&t, bufs);
            // Second difference on a possibly uneven stencil.
            let curvature = 2.0 * ((up - c0) / h + (down - c0) / hd.max(1e-300)) / (h + hd);
            if curvature > 0.0 && hd > 0.0 {
                (s2 / curvature).sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect()
}

/// The fit's errors and counts of work, as [`Identification`] reports them.
struct Outcome {
    /// RMS of the fitted position residuals, mrad.
    fit_rms_mrad: f64,
    /// Held-out RMS and MAE, mrad, and the rows compared.
    heldout: (f64, f64, usize),
    iterations: usize,
    evaluations: usize,
    nonsmooth_evaluations: usize,
}

/// The [`Identification`] from the fitted `params` and `report`: every parameter
/// distrusted when the held-out error is over [`HELDOUT_COUNTS`].
fn conclude(
    mut params: ServoParams,
    start: &ServoParams,
    fitted: Vec<usize>,
    nonsmooth: Vec<usize>,
    report: Report,
    outcome: Outcome,
) -> Identification {
    let (heldout_rms_mrad, heldout_mae_mrad, heldout_rows) = outcome.heldout;
    let stats = report.stats;
    let (mut undetermined, mut intervals, mut combinations) =
        (report.undetermined, report.intervals, report.combinations);
    let heldout_counts = 1e-3 * heldout_rms_mrad / start.servo.resolution();
    if heldout_counts > HELDOUT_COUNTS {
        let reported: Vec<usize> = fitted.iter().chain(&nonsmooth).copied().collect();
        distrust(
            &mut params,
            &reported,
            heldout_counts,
            &mut undetermined,
            &mut intervals,
            &mut combinations,
        );
    }
    let weakest_direction = fitted
        .iter()
        .zip(&stats.weakest)
        .filter(|(_, w)| w.abs() > 0.1)
        .map(|(&i, &w)| (PARAM_NAMES[i], w))
        .collect();
    let smallest = stats.singular_values.last().copied().unwrap_or(0.0);
    Identification {
        combinations,
        intervals,
        params,
        fitted,
        correlation: stats.correlation,
        fit_rms_mrad: outcome.fit_rms_mrad,
        heldout_rms_mrad,
        heldout_mae_mrad,
        heldout_rows,
        heldout_counts,
        condition: stats.singular_values[0] / smallest.max(1e-300),
        singular_values: stats.singular_values,
        undetermined,
        weakest_direction,
        iterations: outcome.iterations,
        evaluations: outcome.evaluations,
        nonsmooth_evaluations: outcome.nonsmooth_evaluations,
        nonsmooth,
    }
}

/// Half a step of Present Voltage (0.1 V, EM-RX28 / EM-XM430 control tables): the
/// logged voltage, which the fit takes as the supply, is this far off at most.
pub const VOLTAGE_HALF_STEP: f64 = 0.05;

/// Standard deviations an interval of a parameter not determined spans each side.
pub const INTERVAL_SIGMAS: f64 = 3.0;

/// A fitted parameter that fell below this fraction of its start ran to its bound
/// (0): it is not determined (the data do not need it), however small its deviation.
pub const AT_BOUND: f64 = 1e-3;

/// What [`assess`] reports.
struct Report {
    stats: Stats,
    undetermined: Vec<&'static str>,
    intervals: Vec<(&'static str, f64, f64)>,
    combinations: Vec<(&'static str, f64, f64)>,
}

/// The deviations, what is not determined and the intervals the data allow, after
/// the fit; sets `params.uncertainty`.
///
/// Why the block sandwich: the Jacobian's `s^2 (J^T J)^-1` takes the residuals as
/// independent, but the encoder's rounding and the sampling's timing errors persist
/// over a step, so it came out 5-60 times too small against known truths (issue 30
/// item 9: friction_base off by 18 of its deviations). The robust covariance
/// (`group.rs`, 1 s blocks as clusters) sees that correlation; the larger of the
/// two is kept per parameter. The register's 0.1 V voltage steps add a systematic
/// error the residuals cannot show: it is added to what the voltage scales.
fn assess(
    params: &mut ServoParams,
    start: &ServoParams,
    fitted: &[usize],
    result: &LmResult,
    block: &[usize],
    senses_current: bool,
    nonsmooth: &[(usize, f64)],
) -> Report {
    let mut stats = uncertainty(&result.jacobian, &result.residuals, &result.x, fitted.len());
    let robust =
        crate::robust_covariance::robust_covariance(&result.jacobian, &result.residuals, block);
    let n = fitted.len();
    let mut cov = robust.clone();
    for a in 0..n {
        for b in 0..n {
            // Scale the robust matrix up to the independent variances where those are
            // larger, keeping its correlations.
            let ra = (stats.covariance[(a, a)] / robust[(a, a)]).max(1.0).sqrt();
            let rb = (stats.covariance[(b, b)] / robust[(b, b)]).max(1.0).sqrt();
            cov[(a, b)] = robust[(a, b)] * ra * rb;
        }
    }
    // Relative deviation of the supply voltage from the register's rounding (uniform).
    let volt = VOLTAGE_HALF_STEP / 3f64.sqrt() / params.voltage;
    let scaled_by_voltage = |i: usize| senses_current && matches!(i, KT | RESISTANCE);
    // The back-EMF damping kt^2/R moves with kt and R, and friction_viscous takes up
    // what it misses of the damping the positions show.
    let back_emf = params.values[KT].powi(2) / params.values[RESISTANCE];
    for (a, &i) in fitted.iter().enumerate() {
        if scaled_by_voltage(i) {
            cov[(a, a)] += volt * volt;
        } else if senses_current && i == FRICTION_VISCOUS {
            cov[(a, a)] += (back_emf / params.values[i].max(1e-12) * volt).powi(2);
        }
    }
    stats.sd_log = (0..n).map(|a| cov[(a, a)].max(0.0).sqrt()).collect();
    stats.correlation = correlation(&cov, &stats.sd_log);
    stats.covariance = cov;
    let mut sd = [0.0; crate::params::N_PARAMS];
    let mut undetermined = Vec::new();
    let mut intervals = Vec::new();
    let mut combinations = motor_combinations(params, fitted, &stats.covariance);
    // kt/R carries the voltage's error whatever the servo senses (the drive is kt V/R).
    combinations[0].2 = combinations[0].2.hypot(volt * combinations[0].1);
    for c in &mut combinations {
        if c.2.is_nan() || c.2 <= 0.0 {
            c.2 = f64::INFINITY;
        }
    }
    if !senses_current {
        undetermined.extend(["kt", "resistance", "friction_viscous"]);
        intervals.extend(motor_intervals(&combinations));
    }
    for (k, &i) in fitted.iter().enumerate() {
        // d p = p d(ln p).
        let (p, s) = (params.values[i], params.values[i] * stats.sd_log[k]);
        sd[i] = s;
        let at_bound = p < AT_BOUND * start.values[i];
        // A zero or NaN deviation is a degenerate Jacobian, not certainty.
        let degenerate = s.is_nan() || s <= 0.0;
        if (stats.sd_log[k] > UNDETERMINED_RELATIVE_SD || at_bound || degenerate)
            && !undetermined.contains(&PARAM_NAMES[i])
        {
            undetermined.push(PARAM_NAMES[i]);
            // At the bound the linearised deviation is about 0 too (the residuals
            // barely move there): nothing bounds it above that the fit measured.
            let interval = if at_bound || degenerate {
                (PARAM_NAMES[i], 0.0, f64::INFINITY)
            } else {
                absolute_interval(PARAM_NAMES[i], p, s)
            };
            intervals.push(interval);
        }
    }
    for &(i, s) in nonsmooth {
        sd[i] = s;
        // An infinite or NaN deviation (a flat cost) counts as not determined.
        if s.is_nan() || s >= UNDETERMINED_RELATIVE_SD * params.values[i] {
            undetermined.push(PARAM_NAMES[i]);
            intervals.push(absolute_interval(PARAM_NAMES[i], params.values[i], s));
        }
    }
    // No finite deviation describes a parameter the data do not determine: its
    // interval does (a file written from this says `inf`).
    for (i, name) in PARAM_NAMES.iter().enumerate() {
        if undetermined.contains(name) {
            sd[i] = f64::INFINITY;
        }
    }
    params.uncertainty = Some(sd);
    Report {
        stats,
        undetermined,
        intervals,
        combinations,
    }
}

/// Relative error of a parameter allowed per encoder count of held-out error, in a
/// fit the held-out check flags. Measured, not derived: late samples bias a fit by
/// more than its deviations say (armature 8.5 % off at 5.7 counts, where 3 of its
/// deviations times the counts span 7.9 %, in `tests/honest_sweep.rs`; friction_base
/// 28 % at 10 counts over ptys, docs/servo-models.md); 5 % a count covers every case
/// seen.
pub const HELDOUT_RELATIVE_PER_COUNT: f64 = 0.05;

/// A fit whose held-out error is `counts` encoder counts (over [`HELDOUT_COUNTS`])
/// does not reproduce the logs: its deviations describe how well it fits these
/// logs, not how far the servo is (over ptys on an overloaded machine, late samples
/// gave held-out errors of 10-14 counts and errors of 4.3-4.9 deviations). Every
/// `reported` parameter is then not determined, its interval `value +- w` with `w`
/// the larger of `INTERVAL_SIGMAS sd counts` (the deviations scaled by the counts
/// the model is off by) and `HELDOUT_RELATIVE_PER_COUNT counts value`; an interval
/// it already had is widened as much about the value. The combinations' deviations
/// grow likewise (`w` is three of them).
fn distrust(
    params: &mut ServoParams,
    reported: &[usize],
    counts: f64,
    undetermined: &mut Vec<&'static str>,
    intervals: &mut Vec<(&'static str, f64, f64)>,
    combinations: &mut [(&'static str, f64, f64)],
) {
    let floor = |v: f64| HELDOUT_RELATIVE_PER_COUNT * counts * v.abs();
    for c in combinations.iter_mut() {
        c.2 = (c.2 * counts).max(floor(c.1) / INTERVAL_SIGMAS);
    }
    for (name, lo, hi) in intervals.iter_mut() {
        let i = PARAM_NAMES.iter().position(|n| n == name).unwrap_or(0);
        let v = params.values[i];
        *lo = (v - (counts * (v - *lo)).max(floor(v))).max(0.0);
        *hi = v + (counts * (*hi - v)).max(floor(v));
    }
    let Some(sd) = params.uncertainty.as_mut() else {
        return;
    };
    for &i in reported {
        let name = PARAM_NAMES[i];
        if undetermined.contains(&name) {
            continue;
        }
        let v = params.values[i];
        let w = (INTERVAL_SIGMAS * sd[i] * counts).max(floor(v));
        undetermined.push(name);
        intervals.push(absolute_interval(name, v, w / INTERVAL_SIGMAS));
        sd[i] = f64::INFINITY;
    }
}

/// `value +- INTERVAL_SIGMAS sd`, not below 0 (every parameter is >= 0).
fn absolute_interval(name: &'static str, value: f64, sd: f64) -> (&'static str, f64, f64) {
    let w = INTERVAL_SIGMAS * sd;
    if w.is_nan() {
        return (name, 0.0, f64::INFINITY);
    }
    (name, (value - w).max(0.0), value + w)
}

/// What position logs allow of `kt`, `resistance` and `friction_viscous` given the
/// drive `d = kt/R` and the damping `c = kt^2/R + friction_viscous` (`combinations`,
/// with their deviations): `friction_viscous = c - kt d >= 0`, so `kt` in `(0, c/d]`,
/// `resistance = kt/d` in `(0, c/d^2]`, `friction_viscous` in `[0, c]`; each upper
/// end taken with `c` and `d` [`INTERVAL_SIGMAS`] deviations towards it.
pub(crate) fn motor_intervals(
    combinations: &[(&'static str, f64, f64)],
) -> [(&'static str, f64, f64); 3] {
    let (d, sd_d) = (combinations[0].1, combinations[0].2);
    let (c, sd_c) = (combinations[1].1, combinations[1].2);
    let c_hi = c + INTERVAL_SIGMAS * sd_c;
    let d_lo = (d - INTERVAL_SIGMAS * sd_d).max(1e-3 * d);
    [
        ("kt", 0.0, c_hi / d_lo),
        ("resistance", 0.0, c_hi / (d_lo * d_lo)),
        ("friction_viscous", 0.0, c_hi),
    ]
}

/// Correlations of a covariance with deviations `sd` (NaN where a deviation is 0
/// or infinite).
fn correlation(cov: &DMatrix<f64>, sd: &[f64]) -> Vec<Vec<f64>> {
    let n = sd.len();
    (0..n)
        .map(|a| {
            (0..n)
                .map(|b| {
                    let c = cov[(a, b)] / (sd[a] * sd[b]);
                    if c.is_finite() { c } else { f64::NAN }
                })
                .collect()
        })
        .collect()
}

/// One simulation's buffers: positions and currents of the longest log, and the
/// residuals.
pub(crate) struct Buffers {
    q: Vec<f64>,
    c: Vec<f64>,
    out: Vec<f64>,
}

/// The fit's data: what the residuals compare.
pub(crate) struct Fit<'a> {
    pub(crate) logs: &'a [ServoLog],
    pub(crate) load: &'a Load,
    pub(crate) segments: &'a [Segment],
    pub(crate) sd_q: f64,
    /// LM iterations and simulations over every LM run.
    pub(crate) iterations: usize,
    pub(crate) evaluations: usize,
}

impl Fit<'_> {
    /// The weighted residuals of `trial` into `out`: positions over the encoder's
    /// quantisation deviation, currents over [`CURRENT_SD`].
    pub(crate) fn residuals(
        &self,
        trial: &ServoParams,
        qb: &mut [f64],
        cb: &mut [f64],
        out: &mut [f64],
    ) {
        let mut o = 0;
        for s in self.segments {
            let l = &self.logs[s.log];
            let n = s.rows.len();
            replay(
                trial,
                self.load,
                l,
                s.rows.clone(),
                &mut qb[..n],
                &mut cb[..n],
            );
            for (j, r) in s.rows.clone().enumerate() {
                out[o] = (qb[j] - l.q[r]) / self.sd_q;
                o += 1;
            }
            if let (true, Some(c)) = (s.current, &l.current) {
                for (j, r) in s.rows.clone().enumerate() {
                    // The first row has no model current yet.
                    out[o] = if j == 0 {
                        0.0
                    } else {
                        (cb[j] - c[r]) / CURRENT_SD
                    };
                    o += 1;
                }
            }
        }
    }

    /// Half the sum of squared residuals.
    fn cost(&self, trial: &ServoParams, bufs: &Scratch<Buffers>) -> f64 {
        bufs.with(|b| {
            self.residuals(trial, &mut b.q, &mut b.c, &mut b.out);
            0.5 * b.out.iter().map(|r| r * r).sum::<f64>()
        })
    }

    /// LM over the logarithms of `fitted` from `params`' values, which it updates;
    /// the Jacobian's simulations on the current rayon pool.
    fn lm(
        &mut self,
        params: &mut ServoParams,
        fitted: &[usize],
        bufs: &Scratch<Buffers>,
    ) -> LmResult {
        let m: usize = self
            .segments
            .iter()
            .map(|s| s.rows.len() * if s.current { 2 } else { 1 })
            .sum();
        let x0: Vec<f64> = fitted
            .iter()
            .map(|&i| params.values[i].max(1e-6).ln())
            .collect();
        let this = &*self;
        let result = levenberg_marquardt_parallel(
            &x0,
            m,
            &|x, out| {
                let mut trial = params.clone();
                for (k, &i) in fitted.iter().enumerate() {
                    trial.values[i] = x[k].exp();
                }
                bufs.with(|b| this.residuals(&trial, &mut b.q, &mut b.c, out));
            },
            &LmOptions::default(),
        );
        for (k, &i) in fitted.iter().enumerate() {
            params.values[i] = result.x[k].exp();
        }
        self.iterations += result.iterations;
        self.evaluations += result.evaluations;
        result
    }
}

/// Held-out RMS and MAE of the position, mrad, and the rows compared.
pub(crate) fn heldout_error(
    params: &ServoParams,
    load: &Load,
    held: &[(&ServoLog, Range<usize>)],
    qb: &mut [f64],
    cb: &mut [f64],
) -> (f64, f64, usize) {
    let (mut sq, mut abs, mut n) = (0.0, 0.0, 0usize);
    for (l, rows) in held {
        let len = rows.len();
        replay(
            params,
            load,
            l,
            rows.clone(),
            &mut qb[..len],
            &mut cb[..len],
        );
        for (j, r) in rows.clone().enumerate().skip(1) {
            let e = qb[j] - l.q[r];
            sq += e * e;
            abs += e.abs();
            n += 1;
        }
    }
    if n == 0 {
        return (f64::NAN, f64::NAN, 0);
    }
    (1e3 * (sq / n as f64).sqrt(), 1e3 * abs / n as f64, n)
}

/// `kt/resistance` and `kt^2/resistance + friction_viscous` with their standard
/// deviations (first-order propagation of the log-parameter covariance).
pub(crate) fn motor_combinations(
    p: &ServoParams,
    fitted: &[usize],
    cov: &DMatrix<f64>,
) -> Vec<(&'static str, f64, f64)> {
    let (kt, r, b) = (
        p.values[KT],
        p.values[RESISTANCE],
        p.values[FRICTION_VISCOUS],
    );
    let drive = kt / r;
    let damping = kt * kt / r + b;
    // Derivatives with respect to ln(parameter).
    let grad = |d_kt: f64, d_r: f64, d_b: f64| -> Vec<f64> {
        fitted
            .iter()
            .map(|&i| match i {
                KT => d_kt,
                RESISTANCE => d_r,
                FRICTION_VISCOUS => d_b,
                _ => 0.0,
            })
            .collect()
    };
    let sd = |g: Vec<f64>| {
        let mut v = 0.0;
        for a in 0..g.len() {
            for c in 0..g.len() {
                if g[a] != 0.0 && g[c] != 0.0 {
                    v += g[a] * cov[(a, c)] * g[c];
                }
            }
        }
        v.max(0.0).sqrt()
    };
    vec![
        ("kt/resistance", drive, sd(grad(drive, -drive, 0.0))),
        (
            "kt^2/resistance + friction_viscous",
            damping,
            sd(grad(2.0 * kt * kt / r, -kt * kt / r, b)),
        ),
    ]
}

pub(crate) struct Stats {
    pub(crate) covariance: DMatrix<f64>,
    pub(crate) sd_log: Vec<f64>,
    pub(crate) correlation: Vec<Vec<f64>>,
    pub(crate) singular_values: Vec<f64>,
    pub(crate) weakest: Vec<f64>,
}

/// Covariance of the log-parameters `s^2 (J^T J)^-1` (s^2 the residual variance),
/// through the SVD of J so a rank-deficient J gives infinite deviations along its
/// null directions instead of a failed inverse.
pub(crate) fn uncertainty(
    j: &DMatrix<f64>,
    r: &nalgebra::DVector<f64>,
    _x: &[f64],
    n: usize,
) -> Stats {
    let m = j.nrows();
    let s2 = r.norm_squared() / (m.saturating_sub(n)).max(1) as f64;
    let svd = j.clone().svd(false, true);
    let vt = svd.v_t.expect("asked for V^T");
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let singular_values: Vec<f64> = order.iter().map(|&k| svd.singular_values[k]).collect();
    let smax = singular_values[0].max(1e-300);
    let mut cov = DMatrix::zeros(n, n);
    for k in 0..n {
        let s = svd.singular_values[k];
        let inv = if s > 1e-10 * smax {
            1.0 / (s * s)
        } else {
            f64::INFINITY
        };
        for a in 0..n {
            for b in 0..n {
                let w = vt[(k, a)] * vt[(k, b)];
                if w != 0.0 {
                    cov[(a, b)] += w * inv;
                }
            }
        }
    }
    cov *= s2;
    let sd_log: Vec<f64> = (0..n).map(|a| cov[(a, a)].max(0.0).sqrt()).collect();
    let correlation = correlation(&cov, &sd_log);
    let weakest_k = *order.last().expect("n >= 1");
    let weakest = (0..n).map(|a| vt[(weakest_k, a)]).collect();
    Stats {
        covariance: cov,
        sd_log,
        correlation,
        singular_values,
        weakest,
    }
}
