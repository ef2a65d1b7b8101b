use std::fmt;

/// Why an identification could not be done. The message names the data row,
/// the channel or the order at fault; data read from a file
/// ([`crate::IoData::from_io_table`]) also names the file and line.
#[derive(Debug, Clone, PartialEq)]
pub struct SysidError {
    pub kind: ErrorKind,
    pub message: String,
    /// The 1-based data row at fault, when one is.
    pub row: Option<usize>,
    /// `file:line` of that row, when the data came from a file.
    pub place: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The data cannot be used: not finite, constant, too short, mismatched shapes.
    Data,
    /// The requested orders or options make no sense for the data.
    Order,
    /// A numerical step failed (rank-deficient regressor, unstable model where a
    /// stable one is needed, a solver that did not converge).
    Numerical,
}

impl SysidError {
    pub fn data(message: impl Into<String>) -> Self {
        SysidError {
            kind: ErrorKind::Data,
            message: message.into(),
            row: None,
            place: None,
        }
    }

    pub fn order(message: impl Into<String>) -> Self {
        SysidError {
            kind: ErrorKind::Order,
            message: message.into(),
            row: None,
            place: None,
        }
    }

    pub fn numerical(message: impl Into<String>) -> Self {
        SysidError {
            kind: ErrorKind::Numerical,
            message: message.into(),
            row: None,
            place: None,
        }
    }
}

impl SysidError {
    /// The same error about data row `row` (1-based).
    pub fn at_row(mut self, row: usize) -> Self {
        self.row = Some(row);
        self
    }
}

impl fmt::Display for SysidError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.place {
            write!(f, "{p}: ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for SysidError {}

pub type Result<T> = std::result::Result<T, SysidError>;
