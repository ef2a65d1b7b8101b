//! The crate's one error: where (file, field, row) and what.

use std::fmt;

/// A bad parameter file, load file or log, located.
#[derive(Debug, Clone, PartialEq)]
pub struct ActuatorError {
    /// The file (or "" when the input was not a file).
    pub file: String,
    /// Where in it: `[params] kt`, `line 12`, `data row 3, column "q"`.
    pub place: String,
    pub message: String,
}

impl ActuatorError {
    pub fn new(file: &str, place: impl Into<String>, message: impl Into<String>) -> Self {
        ActuatorError {
            file: file.to_string(),
            place: place.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for ActuatorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.file.is_empty(), self.place.is_empty()) {
            (true, true) => write!(f, "{}", self.message),
            (true, false) => write!(f, "{}: {}", self.place, self.message),
            (false, true) => write!(f, "{}: {}", self.file, self.message),
            (false, false) => write!(f, "{}: {}: {}", self.file, self.place, self.message),
        }
    }
}

impl std::error::Error for ActuatorError {}
