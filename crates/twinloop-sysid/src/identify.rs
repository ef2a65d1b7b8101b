//! The whole identification of seed 003 in one call: estimate, then evaluate the
//! model the way the seed's section 8 does (FIT, Hankel singular values,
//! singular-value plot, residual tests), on validation data when given.

use crate::arx::{ArxModel, ArxOrders, estimate_arx};
use crate::data::IoData;
use crate::error::{Result, SysidError};
use crate::freq::{ArxResponse, SigmaResponse, StateSpaceResponse, TransferMatrix, sigma_response};
use crate::gramian::{
    OrderSuggestion, balanced_truncation, hankel_singular_values_of_stable, suggest_order,
};
use crate::metrics::{fit_percent, seed_eq10_percent};
use crate::pem::{PemOptions, PemProgress, pem};
use crate::resid::{ResidualTests, residual_tests};
use crate::ss::StateSpace;
use crate::subspace::{SubspaceOptions, n4sid};
use nalgebra::{DMatrix, DVector};

/// What the evaluation computes and how.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvaluationOptions {
    /// Horizon of the `prediction` FIT (1 = one step ahead).
    pub prediction_horizon: usize,
    /// Largest lag of the residual tests (MATLAB's `resid` uses 25).
    pub max_lag: usize,
    /// Frequencies of the singular-value plot.
    pub frequency_points: usize,
}

impl Default for EvaluationOptions {
    fn default() -> Self {
        EvaluationOptions {
            prediction_horizon: 1,
            max_lag: 25,
            frequency_points: 300,
        }
    }
}

/// FIT per output (MATLAB `compare`) and the seed's eq 10 beside it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Fit {
    /// `100 (1 - |y - ysim| / |y - mean y|)` of the simulated outputs (inputs only, zero initial state).
    pub simulation: Vec<Option<f64>>,
    /// Same for the `prediction_horizon`-step-ahead predictions.
    pub prediction: Vec<Option<f64>>,
    pub prediction_horizon: usize,
    /// Seed 003 eq 10, `100 |y - ysim| / |y|` (an error: lower is better).
    pub seed_eq10_simulation: Vec<Option<f64>>,
    pub seed_eq10_prediction: Vec<Option<f64>>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Stability {
    pub stable: bool,
    /// Largest pole magnitude (`None` when the poles could not be computed).
    pub spectral_radius: Option<f64>,
    pub poles_outside_unit_circle: usize,
    /// Largest eigenvalue magnitude of the one-step predictor `A - K C`.
    pub predictor_spectral_radius: Option<f64>,
}

/// A model judged on one record.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Evaluation {
    /// `"validation"` or `"estimation"`: which record the numbers are from.
    pub data: String,
    pub samples: usize,
    pub fit_percent: Fit,
    /// `(1/N) sum_k |e(k)|^2` of the one-step prediction errors.
    pub prediction_cost: f64,
    pub stability: Stability,
    /// Of the input-to-output part `(A, B, C)`, largest first; `None` if unstable.
    pub hankel_singular_values: Option<Vec<f64>>,
    pub order_suggestion: Option<OrderSuggestion>,
    pub frequency_response: SigmaResponse,
    pub residual_tests: ResidualTests,
    pub warnings: Vec<String>,
    /// Simulated and predicted outputs (`ny x N`), for plots.
    #[serde(skip)]
    pub simulated: DMatrix<f64>,
    #[serde(skip)]
    pub predicted: DMatrix<f64>,
}

/// Evaluate any model given through its state-space form (an ARX model through
/// [`ArxModel::to_state_space`], whose predictor and simulation are the same).
pub fn evaluate(
    model: &StateSpace,
    data: &IoData,
    which: &str,
    opts: &EvaluationOptions,
) -> Result<Evaluation> {
    let mut ev = StateSpaceResponse::new(model);
    evaluate_with_response(model, &mut ev, data, which, opts)
}

/// [`evaluate`] with the frequency response computed by `response` (an ARX model's
/// polynomials are cheaper than its large realisation).
pub fn evaluate_with_response(
    model: &StateSpace,
    response: &mut dyn TransferMatrix,
    data: &IoData,
    which: &str,
    opts: &EvaluationOptions,
) -> Result<Evaluation> {
    model.check_shapes(&data.u, Some(&data.y), None)?;
    let mut warnings = Vec::new();
    let stability = assess_stability(model, &mut warnings);
    let stable = stability.stable;
    let horizon = opts.prediction_horizon.max(1);
    let (fit, simulated, predicted) = simulate_and_fit(model, data, horizon)?;
    let e = model.residuals(data)?;
    let prediction_cost = e.norm_squared() / data.len().max(1) as f64;
    if fit.simulation.iter().any(|f| f.is_none()) && stable {
        warnings.push(
            "a simulation FIT is undefined (constant output or non-finite simulation)".to_string(),
        );
    }
    let hsv = if stable {
        match hankel_singular_values_of_stable(model) {
            Ok(h) => Some(h),
            Err(err) => {
                warnings.push(format!("Hankel singular values: {err}"));
                None
            }
        }
    } else {
        None
    };
    let order_suggestion = hsv.as_deref().and_then(suggest_order);
    let frequency_response = sigma_response(
        response,
        data.sample_time.or(model.sample_time),
        opts.frequency_points,
    );
    let residual_tests = finite_residual_tests(&e, data, opts.max_lag, &mut warnings);
    Ok(Evaluation {
        data: which.to_string(),
        samples: data.len(),
        fit_percent: fit,
        prediction_cost,
        stability,
        hankel_singular_values: hsv,
        order_suggestion,
        frequency_response,
        residual_tests,
        warnings,
        simulated,
        predicted,
    })
}

/// Poles and predictor eigenvalues, with a warning for each that is unstable.
fn assess_stability(model: &StateSpace, warnings: &mut Vec<String>) -> Stability {
    let poles = model.poles();
    let rho = poles
        .as_ref()
        .map(|p| p.iter().fold(0.0f64, |m, z| m.max(z.norm())));
    let poles = poles.unwrap_or_default();
    let outside = poles.iter().filter(|p| p.norm() >= 1.0).count();
    let stable = rho.is_some_and(|r| r < 1.0);
    let prho = model.predictor_spectral_radius();
    if !stable {
        warnings.push(match rho {
            Some(r) => format!(
                "the model is unstable: {outside} of its {} poles lie on or outside the unit circle \
                 (largest |pole| = {r:.6}); its simulation diverges, so simulation FIT is meaningless \
                 and it has no Hankel singular values",
                poles.len()
            ),
            None => "the model's poles could not be computed (non-finite entries?)".to_string(),
        });
    }
    if !prho.is_some_and(|r| r < 1.0) {
        warnings.push(format!(
            "the one-step predictor A - KC is unstable (largest |eigenvalue| = {}): predictions diverge",
            prho.map_or("unknown".to_string(), |r| format!("{r:.6}"))
        ));
    }
    Stability {
        stable,
        spectral_radius: rho,
        poles_outside_unit_circle: outside,
        predictor_spectral_radius: prho,
    }
}

/// FIT of the simulation and the `horizon`-step prediction, with both outputs
/// kept for the plots.
fn simulate_and_fit(
    model: &StateSpace,
    data: &IoData,
    horizon: usize,
) -> Result<(Fit, DMatrix<f64>, DMatrix<f64>)> {
    let simulated = model.simulate(&data.u, None)?;
    let predicted = model.predict(data, horizon)?;
    let fit = Fit {
        simulation: fit_percent(&data.y, &simulated),
        prediction: fit_percent(&data.y, &predicted),
        prediction_horizon: horizon,
        seed_eq10_simulation: seed_eq10_percent(&data.y, &simulated),
        seed_eq10_prediction: seed_eq10_percent(&data.y, &predicted),
    };
    Ok((fit, simulated, predicted))
}

/// Residual tests of `e`; on zeros when `e` is not finite, so that the report
/// keeps its shape, with a warning.
fn finite_residual_tests(
    e: &DMatrix<f64>,
    data: &IoData,
    max_lag: usize,
    warnings: &mut Vec<String>,
) -> ResidualTests {
    if e.iter().all(|x| x.is_finite()) {
        residual_tests(e, &data.u, &data.output_names, &data.input_names, max_lag)
    } else {
        warnings.push("residual tests skipped: the prediction errors are not finite".to_string());
        residual_tests(
            &DMatrix::zeros(e.nrows(), e.ncols()),
            &data.u,
            &data.output_names,
            &data.input_names,
            max_lag,
        )
    }
}

/// An ARX model and its evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct ArxIdentification {
    pub model: ArxModel,
    /// Wall time of the least-squares estimation alone, seconds.
    pub estimation_seconds: f64,
    /// On the validation record when one was given, else on the estimation record.
    pub evaluation: Evaluation,
    /// FIT on the estimation record (equal to `evaluation.fit_percent` without validation data).
    pub estimation_fit: Fit,
    pub estimation_prediction_cost: f64,
}

fn check_records(est: &IoData, val: Option<&IoData>) -> Result<()> {
    est.check_excitation()?;
    if let Some(v) = val {
        est.check_same_channels(v)?;
    }
    Ok(())
}

/// Estimate a MIMO ARX model on `est` and evaluate it on `val` (or `est`).
pub fn identify_arx(
    est: &IoData,
    val: Option<&IoData>,
    orders: ArxOrders,
    opts: &EvaluationOptions,
) -> Result<ArxIdentification> {
    check_records(est, val)?;
    let t0 = std::time::Instant::now();
    let model = estimate_arx(est, orders)?;
    let estimation_seconds = t0.elapsed().as_secs_f64();
    let ss = model.to_state_space();
    let which = if val.is_some() {
        "validation"
    } else {
        "estimation"
    };
    let evaluation = evaluate_with_response(
        &ss,
        &mut ArxResponse(&model),
        val.unwrap_or(est),
        which,
        opts,
    )?;
    let (estimation_fit, estimation_prediction_cost) = match val {
        Some(_) => (
            evaluate_fit(&ss, est, opts.prediction_horizon)?,
            ss.prediction_cost(est)?,
        ),
        None => (evaluation.fit_percent.clone(), evaluation.prediction_cost),
    };
    Ok(ArxIdentification {
        model,
        estimation_seconds,
        estimation_fit,
        estimation_prediction_cost,
        evaluation,
    })
}

/// How to estimate the state-space model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SsMethod {
    /// Subspace identification alone.
    N4sid,
    /// Subspace initial estimate refined by the prediction-error method (MATLAB `ssest`).
    Pem,
    /// The seed's route: ARX, realised in state space, reduced by balanced
    /// truncation, refined by the prediction-error method.
    ArxReducePem,
}

impl SsMethod {
    pub fn name(self) -> &'static str {
        match self {
            SsMethod::N4sid => "n4sid",
            SsMethod::Pem => "pem",
            SsMethod::ArxReducePem => "arx-reduce-pem",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SsOptions {
    pub order: usize,
    pub method: SsMethod,
    /// ARX orders of the `ArxReducePem` route.
    pub arx_orders: ArxOrders,
    /// Subspace horizon (block rows), `None` for the default.
    pub horizon: Option<usize>,
    pub pem: PemOptions,
    pub evaluation: EvaluationOptions,
}

impl Default for SsOptions {
    fn default() -> Self {
        SsOptions {
            order: 6,
            method: SsMethod::Pem,
            arx_orders: ArxOrders {
                na: 10,
                nb: 10,
                nk: 1,
            },
            horizon: None,
            pem: PemOptions::default(),
            evaluation: EvaluationOptions::default(),
        }
    }
}

/// A model on the way to the final one, with its FIT.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Stage {
    pub name: String,
    pub order: usize,
    /// Prediction cost on the estimation record.
    pub estimation_prediction_cost: f64,
    /// FIT on the evaluation record (validation when given).
    pub fit_percent: Fit,
}

/// The prediction-error search, summarised.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PemSummary {
    pub iterations: usize,
    pub free_parameters: usize,
    pub initial_cost: f64,
    pub final_cost: f64,
    pub termination: String,
    pub cost_history: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct StateSpaceIdentification {
    pub model: StateSpace,
    /// Wall time of the estimation (all stages of the route), seconds.
    pub estimation_seconds: f64,
    /// Initial state of the estimation record (zero unless estimated).
    pub x0: DVector<f64>,
    pub method: SsMethod,
    pub evaluation: Evaluation,
    pub estimation_fit: Fit,
    pub estimation_prediction_cost: f64,
    /// Earlier models of the route (subspace estimate, ARX, reduced ARX), in order.
    pub stages: Vec<Stage>,
    pub pem: Option<PemSummary>,
    /// Singular values of the subspace projection (order selection help).
    pub subspace_singular_values: Option<Vec<f64>>,
    /// Hankel singular values the ARX model was reduced from (arx-reduce-pem).
    pub arx_hankel_singular_values: Option<Vec<f64>>,
    pub warnings: Vec<String>,
}

/// Reduce a state-space model to `order` by balanced truncation, keeping the
/// noise model: of `(A, [B K], C)` when `A` is stable, else of the always
/// stable predictor `(A - KC, [B - KD, K], C)` of an ARX model, converted back.
pub fn reduce_with_noise_model(
    model: &StateSpace,
    order: usize,
) -> Result<(StateSpace, Vec<f64>, Vec<String>)> {
    let mut warnings = Vec::new();
    if model.spectral_radius().is_some_and(|r| r < 1.0) {
        let (red, hsv) = balanced_truncation(model, order, true)?;
        if red.predictor_spectral_radius().is_some_and(|r| r < 1.0) {
            return Ok((red, hsv, warnings));
        }
        warnings.push(
            "the truncated model's predictor was unstable; reduced the predictor instead"
                .to_string(),
        );
    } else {
        warnings.push(
            "the ARX model is unstable, so its realisation has no Gramians; reduced its (stable) \
             one-step predictor instead"
                .to_string(),
        );
    }
    let abar = &model.a - &model.k * &model.c;
    let bbar = &model.b - &model.k * &model.d;
    let pred = StateSpace {
        a: abar,
        b: bbar,
        c: model.c.clone(),
        d: model.d.clone(),
        k: model.k.clone(),
        noise_covariance: model.noise_covariance.clone(),
        sample_time: model.sample_time,
    };
    let (r, hsv) = balanced_truncation(&pred, order, true)?;
    let red = StateSpace {
        a: &r.a + &r.k * &r.c,
        b: &r.b + &r.k * &r.d,
        ..r
    };
    Ok((red, hsv, warnings))
}

/// Estimate a state-space model of order `opts.order` on `est` by `opts.method`
/// and evaluate it on `val` (or `est`). `progress` sees every PEM iteration.
pub fn identify_state_space(
    est: &IoData,
    val: Option<&IoData>,
    opts: &SsOptions,
    progress: &mut dyn FnMut(&PemProgress),
) -> Result<StateSpaceIdentification> {
    check_records(est, val)?;
    if opts.order == 0 {
        return Err(SysidError::order("the model order must be at least 1"));
    }
    let ev_data = val.unwrap_or(est);
    let which = if val.is_some() {
        "validation"
    } else {
        "estimation"
    };
    let eopts = &opts.evaluation;
    let stage = |name: &str, m: &StateSpace| -> Result<Stage> {
        Ok(Stage {
            name: name.to_string(),
            order: m.n(),
            estimation_prediction_cost: m.prediction_cost(est)?,
            fit_percent: evaluate_fit(m, ev_data, eopts.prediction_horizon)?,
        })
    };
    let mut stages = Vec::new();
    let mut warnings = Vec::new();
    let mut subspace_sv = None;
    let mut arx_hsv = None;
    let t0 = std::time::Instant::now();
    let initial = match opts.method {
        SsMethod::N4sid | SsMethod::Pem => {
            let (model, sv) = subspace_initial(est, opts, &mut warnings)?;
            subspace_sv = Some(sv);
            model
        }
        SsMethod::ArxReducePem => {
            let (model, hsv) = arx_reduced_initial(est, opts, &stage, &mut stages, &mut warnings)?;
            arx_hsv = Some(hsv);
            model
        }
    };
    let (model, x0, pem_summary) = if opts.method == SsMethod::N4sid {
        (initial, DVector::zeros(opts.order), None)
    } else {
        if opts.method == SsMethod::Pem {
            stages.push(stage("n4sid", &initial)?);
        }
        refine_by_pem(est, &initial, opts, progress)?
    };
    let estimation_seconds = t0.elapsed().as_secs_f64();
    let mut evaluation = evaluate(&model, ev_data, which, eopts)?;
    let (estimation_fit, estimation_prediction_cost) = match val {
        Some(_) => (
            evaluate_fit(&model, est, eopts.prediction_horizon)?,
            model.prediction_cost(est)?,
        ),
        None => (evaluation.fit_percent.clone(), evaluation.prediction_cost),
    };
    warnings.append(&mut evaluation.warnings);
    evaluation.warnings = warnings.clone();
    Ok(StateSpaceIdentification {
        model,
        estimation_seconds,
        x0,
        method: opts.method,
        estimation_fit,
        estimation_prediction_cost,
        evaluation,
        stages,
        pem: pem_summary,
        subspace_singular_values: subspace_sv,
        arx_hankel_singular_values: arx_hsv,
        warnings,
    })
}

/// The n4sid model of the `N4sid` and `Pem` routes, with the projection's
/// singular values.
fn subspace_initial(
    est: &IoData,
    opts: &SsOptions,
    warnings: &mut Vec<String>,
) -> Result<(StateSpace, Vec<f64>)> {
    let s = n4sid(
        est,
        &SubspaceOptions {
            order: Some(opts.order),
            horizon: opts.horizon,
            feedthrough: opts.pem.feedthrough,
        },
    )?;
    warnings.extend(s.warnings.iter().map(|w| format!("subspace: {w}")));
    Ok((s.model, s.singular_values))
}

/// The `ArxReducePem` route's start: a high-order ARX model reduced by balanced
/// truncation, each recorded as a stage; returns the Hankel singular values too.
fn arx_reduced_initial(
    est: &IoData,
    opts: &SsOptions,
    stage: &dyn Fn(&str, &StateSpace) -> Result<Stage>,
    stages: &mut Vec<Stage>,
    warnings: &mut Vec<String>,
) -> Result<(StateSpace, Vec<f64>)> {
    let arx = estimate_arx(est, opts.arx_orders)?;
    let full = arx.to_state_space();
    stages.push(stage(
        &format!(
            "arx (na={}, nb={}, nk={})",
            opts.arx_orders.na, opts.arx_orders.nb, opts.arx_orders.nk
        ),
        &full,
    )?);
    if opts.order > full.n() {
        return Err(SysidError::order(format!(
            "order {} is above the ARX realisation's {} states: raise na/nb or lower the order",
            opts.order,
            full.n()
        )));
    }
    let (mut red, hsv, w) = reduce_with_noise_model(&full, opts.order)?;
    warnings.extend(w);
    if !opts.pem.feedthrough {
        if red.d.amax() > 0.0 {
            warnings.push(format!(
                "the ARX model with nk = {} has a direct feedthrough; it is dropped because D is \
                 not estimated (ask for a feedthrough to keep it)",
                opts.arx_orders.nk
            ));
        }
        red.d.fill(0.0);
    }
    stages.push(stage(
        &format!("balanced truncation to order {}", opts.order),
        &red,
    )?);
    Ok((red, hsv))
}

/// The prediction-error search from `initial`: the model, its initial state and a
/// summary of the search.
fn refine_by_pem(
    est: &IoData,
    initial: &StateSpace,
    opts: &SsOptions,
    progress: &mut dyn FnMut(&PemProgress),
) -> Result<(StateSpace, DVector<f64>, Option<PemSummary>)> {
    let r = pem(est, initial, None, &opts.pem, progress)?;
    let summary = PemSummary {
        iterations: r.iterations,
        free_parameters: r.free_parameters,
        initial_cost: r.initial_cost,
        final_cost: r.final_cost,
        termination: r.termination.clone(),
        cost_history: r.cost_history.clone(),
    };
    Ok((r.model, r.x0, Some(summary)))
}

fn evaluate_fit(model: &StateSpace, data: &IoData, horizon: usize) -> Result<Fit> {
    let sim = model.simulate(&data.u, None)?;
    let pred = model.predict(data, horizon)?;
    Ok(Fit {
        simulation: fit_percent(&data.y, &sim),
        prediction: fit_percent(&data.y, &pred),
        prediction_horizon: horizon,
        seed_eq10_simulation: seed_eq10_percent(&data.y, &sim),
        seed_eq10_prediction: seed_eq10_percent(&data.y, &pred),
    })
}
