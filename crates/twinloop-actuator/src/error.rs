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

impl ActuatorError {
    /// A TOML syntax error in `text` (the file `file`), placed at its line and
    /// column (1-based) as the parser's span gives them.
    pub fn toml(file: &str, text: &str, e: &toml::de::Error) -> Self {
        let place = match e.span() {
            Some(span) => {
                let before = &text[..span.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let column = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
                format!("line {line}, column {column}")
            }
            None => String::new(),
        };
        ActuatorError::new(file, place, e.message().trim())
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
