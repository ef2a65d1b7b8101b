//! Errors that name the input field at fault.

use std::fmt;

/// Bad input to a reduced model or estimator: which field, and what is wrong with it.
#[derive(Debug, Clone, PartialEq)]
pub struct ReducedError {
    /// The argument or field at fault, e.g. `length`, `angles.forward`, `hip joint`.
    pub field: String,
    pub message: String,
}

impl ReducedError {
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        ReducedError {
            field: field.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for ReducedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.field, self.message)
        }
    }
}

impl std::error::Error for ReducedError {}

/// An error whose message already says what is at fault (no separate field).
pub(crate) fn err<T>(message: impl Into<String>) -> Result<T, ReducedError> {
    Err(ReducedError::new("", message))
}

/// `value` must be finite and > 0.
pub fn positive(field: &str, value: f64) -> Result<f64, ReducedError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ReducedError::new(
            field,
            format!("must be a finite number > 0, got {value}"),
        ))
    }
}

/// `value` must be finite.
pub fn finite(field: &str, value: f64) -> Result<f64, ReducedError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ReducedError::new(
            field,
            format!("must be a finite number, got {value}"),
        ))
    }
}

/// `value` must be finite and >= 0.
pub fn non_negative(field: &str, value: f64) -> Result<f64, ReducedError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ReducedError::new(
            field,
            format!("must be a finite number >= 0, got {value}"),
        ))
    }
}
