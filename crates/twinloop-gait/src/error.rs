//! The gait layer's error.

/// Errors of the gait layer; each message names the offending field.
#[derive(Debug, Clone, PartialEq)]
pub struct GaitError(pub String);

impl std::fmt::Display for GaitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for GaitError {}

pub(crate) fn err<T>(message: impl Into<String>) -> Result<T, GaitError> {
    Err(GaitError(message.into()))
}
