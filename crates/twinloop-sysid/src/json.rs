//! The JSON shape of an identification result, as `twinloop identify arx|ss|walk`
//! write it: serde structs with stable field names (scripts read them by name).
//!
//! Matrices are lists of rows. An ARX or state-space result is the model, the data
//! it came from and its [`EvaluationJson`] side by side in one object.

use crate::freq::SigmaResponse;
use crate::gramian::OrderSuggestion;
use crate::identify::{
    ArxIdentification, Evaluation, Fit, PemSummary, Stability, Stage, StateSpaceIdentification,
};
use crate::resid::ResidualTests;
use crate::{ArxOrders, IoData, StateSpace};
use nalgebra::DMatrix;
use serde::Serialize;

/// A matrix as a list of rows.
pub type Rows = Vec<Vec<f64>>;

/// The rows of `m`.
pub fn rows(m: &DMatrix<f64>) -> Rows {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}

/// The means removed from the inputs and outputs (detrending).
#[derive(Debug, Clone, Serialize)]
pub struct OffsetsJson {
    pub inputs: Vec<f64>,
    pub outputs: Vec<f64>,
}

impl OffsetsJson {
    pub fn new(offsets: Option<&(Vec<f64>, Vec<f64>)>) -> Option<OffsetsJson> {
        offsets.map(|(u, y)| OffsetsJson {
            inputs: u.clone(),
            outputs: y.clone(),
        })
    }
}

/// The records a model was estimated (and evaluated) on.
#[derive(Debug, Clone, Serialize)]
pub struct DataJson {
    /// The estimation file.
    pub estimation: String,
    /// The validation file, if any.
    pub validation: Option<String>,
    pub samples: usize,
    pub validation_samples: Option<usize>,
    /// Seconds; `None`: frequencies are in rad/sample.
    pub sample_time: Option<f64>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    pub offsets: Option<OffsetsJson>,
}

impl DataJson {
    pub fn new(
        estimation_file: String,
        validation_file: Option<String>,
        est: &IoData,
        val: Option<&IoData>,
        offsets: Option<&(Vec<f64>, Vec<f64>)>,
    ) -> DataJson {
        DataJson {
            estimation: estimation_file,
            validation: validation_file,
            samples: est.len(),
            validation_samples: val.map(IoData::len),
            sample_time: est.sample_time,
            inputs: est.input_names.clone(),
            outputs: est.output_names.clone(),
            offsets: OffsetsJson::new(offsets),
        }
    }
}

/// FIT per output, and which record (`estimation` or `validation`) it is on.
#[derive(Debug, Clone, Serialize)]
pub struct FitJson<'a> {
    #[serde(flatten)]
    pub fit: &'a Fit,
    pub data: &'a str,
}

/// How good a model is: FIT, prediction cost, stability, Hankel singular values,
/// frequency response, residual tests.
#[derive(Debug, Clone, Serialize)]
pub struct EvaluationJson<'a> {
    pub fit_percent: FitJson<'a>,
    pub estimation_fit_percent: &'a Fit,
    pub prediction_cost: f64,
    pub estimation_prediction_cost: f64,
    pub stability: &'a Stability,
    pub hankel_singular_values: &'a Option<Vec<f64>>,
    pub order_suggestion: &'a Option<OrderSuggestion>,
    pub frequency_response: &'a SigmaResponse,
    pub residual_tests: &'a ResidualTests,
}

impl<'a> EvaluationJson<'a> {
    pub fn new(ev: &'a Evaluation, estimation_fit: &'a Fit, estimation_cost: f64) -> Self {
        EvaluationJson {
            fit_percent: FitJson {
                fit: &ev.fit_percent,
                data: &ev.data,
            },
            estimation_fit_percent: estimation_fit,
            prediction_cost: ev.prediction_cost,
            estimation_prediction_cost: estimation_cost,
            stability: &ev.stability,
            hankel_singular_values: &ev.hankel_singular_values,
            order_suggestion: &ev.order_suggestion,
            frequency_response: &ev.frequency_response,
            residual_tests: &ev.residual_tests,
        }
    }
}

/// An ARX model: `A1 .. A_na`, `B1 .. B_nb`, the covariance of e.
#[derive(Debug, Clone, Serialize)]
#[allow(non_snake_case)]
pub struct ArxModelJson {
    pub A: Vec<Rows>,
    pub B: Vec<Rows>,
    pub noise_covariance: Rows,
}

impl ArxModelJson {
    pub fn new(id: &ArxIdentification) -> ArxModelJson {
        ArxModelJson {
            A: id.model.a.iter().map(rows).collect(),
            B: id.model.b.iter().map(rows).collect(),
            noise_covariance: rows(&id.model.noise_covariance),
        }
    }
}

/// A state-space model in innovations form: A, B, C, D, K, the covariance of e.
#[derive(Debug, Clone, Serialize)]
#[allow(non_snake_case)]
pub struct StateSpaceModelJson {
    pub A: Rows,
    pub B: Rows,
    pub C: Rows,
    pub D: Rows,
    pub K: Rows,
    pub noise_covariance: Rows,
}

impl StateSpaceModelJson {
    pub fn new(m: &StateSpace) -> StateSpaceModelJson {
        StateSpaceModelJson {
            A: rows(&m.a),
            B: rows(&m.b),
            C: rows(&m.c),
            D: rows(&m.d),
            K: rows(&m.k),
            noise_covariance: rows(&m.noise_covariance),
        }
    }
}

/// Wall-clock seconds.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct TimingJson {
    pub estimation: f64,
    pub estimation_and_evaluation: f64,
}

/// `identify arx`: the whole result.
#[derive(Debug, Clone, Serialize)]
pub struct ArxJson<'a> {
    /// `"arx"`.
    pub kind: &'static str,
    /// `"arx"`.
    pub method: &'static str,
    pub data: DataJson,
    pub orders: ArxOrders,
    #[serde(flatten)]
    pub model: ArxModelJson,
    #[serde(flatten)]
    pub evaluation: EvaluationJson<'a>,
    pub warnings: &'a [String],
    pub timing_seconds: TimingJson,
}

impl<'a> ArxJson<'a> {
    /// `elapsed`: seconds for estimation and evaluation together.
    pub fn new(id: &'a ArxIdentification, data: DataJson, orders: ArxOrders, elapsed: f64) -> Self {
        ArxJson {
            kind: "arx",
            method: "arx",
            data,
            orders,
            model: ArxModelJson::new(id),
            evaluation: EvaluationJson::new(
                &id.evaluation,
                &id.estimation_fit,
                id.estimation_prediction_cost,
            ),
            warnings: &id.evaluation.warnings,
            timing_seconds: TimingJson {
                estimation: id.estimation_seconds,
                estimation_and_evaluation: elapsed,
            },
        }
    }
}

/// The order of a state-space model and, for the ARX-reduce-PEM route, the ARX orders.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SsOrdersJson {
    pub order: usize,
    pub arx: Option<ArxOrders>,
}

/// `identify ss`: the whole result.
#[derive(Debug, Clone, Serialize)]
pub struct StateSpaceJson<'a> {
    /// `"state-space"`.
    pub kind: &'static str,
    /// `n4sid`, `pem` or `arx-reduce-pem`.
    pub method: &'static str,
    /// What the prediction-error search minimised: `prediction` or `simulation`.
    pub focus: &'static str,
    pub data: DataJson,
    pub orders: SsOrdersJson,
    #[serde(flatten)]
    pub model: StateSpaceModelJson,
    pub x0: Vec<f64>,
    #[serde(flatten)]
    pub evaluation: EvaluationJson<'a>,
    pub stages: &'a [Stage],
    pub pem: &'a Option<PemSummary>,
    pub subspace_singular_values: &'a Option<Vec<f64>>,
    pub arx_hankel_singular_values: &'a Option<Vec<f64>>,
    pub warnings: &'a [String],
    pub timing_seconds: TimingJson,
}

impl<'a> StateSpaceJson<'a> {
    /// `elapsed`: seconds for estimation and evaluation together.
    pub fn new(
        id: &'a StateSpaceIdentification,
        data: DataJson,
        focus: &'static str,
        orders: SsOrdersJson,
        elapsed: f64,
    ) -> Self {
        StateSpaceJson {
            kind: "state-space",
            method: id.method.name(),
            focus,
            data,
            orders,
            model: StateSpaceModelJson::new(&id.model),
            x0: id.x0.iter().copied().collect(),
            evaluation: EvaluationJson::new(
                &id.evaluation,
                &id.estimation_fit,
                id.estimation_prediction_cost,
            ),
            stages: &id.stages,
            pem: &id.pem,
            subspace_singular_values: &id.subspace_singular_values,
            arx_hankel_singular_values: &id.arx_hankel_singular_values,
            warnings: &id.warnings,
            timing_seconds: TimingJson {
                estimation: id.estimation_seconds,
                estimation_and_evaluation: elapsed,
            },
        }
    }
}
