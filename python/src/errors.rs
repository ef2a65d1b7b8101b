//! Rust errors as Python exceptions, with the CLI's messages.

use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use twinloop_description::DescriptionError;

pyo3::create_exception!(
    twinloop,
    ModelError,
    pyo3::exceptions::PyValueError,
    "A robot description that cannot be read or compiled (the message names the file, line and element)."
);

/// A description error: `OSError` when the file itself cannot be read, else `ModelError`.
pub fn description_error(e: DescriptionError) -> PyErr {
    if let Some(path) = &e.location.file
        && std::fs::read(path).is_err()
    {
        return PyOSError::new_err(e.to_string());
    }
    ModelError::new_err(e.to_string())
}

/// A `ValueError` with the given message.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}
