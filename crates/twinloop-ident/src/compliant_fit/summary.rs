//! What a compact-model fit reports as JSON: the fields of `twinloop identify
//! compliant --json` and of Python's `twinloop.fit_compliant`, written once so the
//! two cannot drift apart.

use super::{FitResult, Identifiability, Method, PARAMETER_NAMES, Validation};
use serde::Serialize;
use twinloop_reduced::{Corrections, SagittalCompliance};

/// The fit's summary; `T` is the CLI's `--timing-rounds` medians (Python: `()`,
/// always null).
#[derive(Serialize)]
pub struct FitSummary<'a, T: Serialize> {
    pub data: String,
    pub model: String,
    pub samples: usize,
    pub plant: SagittalCompliance,
    pub method: Method,
    pub free: Vec<&'static str>,
    pub start: Corrections,
    pub params: Corrections,
    pub mse_before: f64,
    pub mse_after: f64,
    pub rms_before: f64,
    pub rms_after: f64,
    pub evaluations: usize,
    pub iterations: usize,
    pub stop: &'a str,
    pub seconds: f64,
    pub identifiability: Option<&'a Identifiability>,
    pub identifiability_error: Option<String>,
    pub validation: &'a [Validation],
    pub timing: Option<T>,
}

/// Where the fit's numbers came from, beside its result.
pub struct FitInputs<'a> {
    pub data: String,
    pub model: String,
    pub samples: usize,
    pub plant: SagittalCompliance,
    pub free: &'a [usize],
    pub start: Corrections,
    pub seconds: f64,
}

impl<'a, T: Serialize> FitSummary<'a, T> {
    pub fn new(
        inputs: FitInputs<'_>,
        result: &'a FitResult,
        identifiability: Result<&'a Identifiability, String>,
        validation: &'a [Validation],
        timing: Option<T>,
    ) -> Self {
        let (identifiability, identifiability_error) = match identifiability {
            Ok(i) => (Some(i), None),
            Err(e) => (None, Some(e)),
        };
        FitSummary {
            data: inputs.data,
            model: inputs.model,
            samples: inputs.samples,
            plant: inputs.plant,
            method: result.method,
            free: inputs.free.iter().map(|&i| PARAMETER_NAMES[i]).collect(),
            start: inputs.start,
            params: result.params,
            mse_before: result.mse_before,
            mse_after: result.mse_after,
            rms_before: result.mse_before.sqrt(),
            rms_after: result.mse_after.sqrt(),
            evaluations: result.evaluations,
            iterations: result.iterations,
            stop: &result.stop,
            seconds: inputs.seconds,
            identifiability,
            identifiability_error,
            validation,
            timing,
        }
    }
}
