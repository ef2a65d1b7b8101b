//! Errors that name what is at fault: the file, the data row, the field (a column or a
//! link), the option (a field of the options struct the caller filled in) and what is
//! wrong with it. The library knows nothing of command-line flags: a front end that
//! maps options to flags (the CLI: `total_mass` is `--total-mass`) renders `option`.

use std::fmt;
use std::path::PathBuf;

/// An identification input or computation error. `Display` gives
/// `<file>: data row <n>: field "<f>": <message>` with the parts that are known.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentError {
    pub file: Option<PathBuf>,
    /// 1-based data row (the header is not counted), where a row is at fault.
    pub row: Option<usize>,
    /// Column, link or parameter name at fault.
    pub field: Option<String>,
    /// The option at fault, as named in the options struct (`total_mass`).
    pub option: Option<String>,
    pub message: String,
}

impl IdentError {
    pub fn new(message: impl Into<String>) -> Self {
        IdentError {
            file: None,
            row: None,
            field: None,
            option: None,
            message: message.into(),
        }
    }

    pub fn in_file(mut self, file: impl Into<PathBuf>) -> Self {
        self.file = Some(file.into());
        self
    }

    /// `row` is 0-based here (index into the data rows); it is shown 1-based.
    pub fn at_row(mut self, row: usize) -> Self {
        self.row = Some(row + 1);
        self
    }

    pub fn field(mut self, field: impl Into<String>) -> Self {
        self.field = Some(field.into());
        self
    }

    pub fn option(mut self, option: impl Into<String>) -> Self {
        self.option = Some(option.into());
        self
    }
}

impl fmt::Display for IdentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.file {
            write!(f, "{}: ", p.display())?;
        }
        if let Some(r) = self.row {
            write!(f, "data row {r}: ")?;
        }
        if let Some(c) = &self.field {
            write!(f, "field \"{c}\": ")?;
        }
        if let Some(o) = &self.option {
            write!(f, "option {o}: ")?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for IdentError {}

/// A message that already names what is at fault (the internal steps of an estimator
/// that report in words).
impl From<String> for IdentError {
    fn from(message: String) -> Self {
        IdentError::new(message)
    }
}

/// An error whose message says what is at fault.
pub(crate) fn err<T>(message: impl Into<String>) -> Result<T, IdentError> {
    Err(IdentError::new(message))
}

impl From<twinloop_gait::GaitError> for IdentError {
    fn from(e: twinloop_gait::GaitError) -> Self {
        IdentError::new(e.0)
    }
}

impl From<twinloop_reduced::ReducedError> for IdentError {
    fn from(e: twinloop_reduced::ReducedError) -> Self {
        let field = (!e.field.is_empty()).then_some(e.field);
        IdentError {
            file: None,
            row: None,
            field,
            option: None,
            message: e.message,
        }
    }
}

impl From<twinloop_io::IoError> for IdentError {
    fn from(e: twinloop_io::IoError) -> Self {
        // Keep the reader's own line/column wording in the message.
        let file = e.file.clone();
        let mut inner = e;
        inner.file = None;
        IdentError {
            file,
            row: None,
            field: None,
            option: None,
            message: inner.to_string(),
        }
    }
}

impl From<twinloop_description::DescriptionError> for IdentError {
    fn from(e: twinloop_description::DescriptionError) -> Self {
        IdentError::new(e.to_string())
    }
}
