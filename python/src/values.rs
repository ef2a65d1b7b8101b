//! Values between Rust and Python through `json`: a report as dicts, lists and
//! floats (the CLI's JSON fields), and a tip-over dict back as the report it is.

use crate::errors::value_error;
use pyo3::prelude::*;
use serde::Serialize;

/// A serde value as Python objects (dicts, lists, floats), through `json`.
pub fn to_py<'py, T: Serialize + ?Sized>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| value_error(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// `tipover`: `tipover()`'s dict (or a JSON file's contents) as the report it is.
pub fn study_arg(
    py: Python<'_>,
    tipover: &Bound<'_, PyAny>,
) -> PyResult<twinloop_ident::tipover_study::StudyReport> {
    let text: String = py
        .import("json")?
        .call_method1("dumps", (tipover,))?
        .extract()?;
    serde_json::from_str(&text)
        .map_err(|e| value_error(format!("tipover: not a tip-over report ({e})")))
}
