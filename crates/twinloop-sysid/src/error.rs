use std::fmt;

/// Why an identification could not be done. The message names the data row,
/// the channel or the order at fault; callers that read files prefix the file.
#[derive(Debug, Clone, PartialEq)]
pub struct SysidError {
    pub kind: ErrorKind,
    pub message: String,
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
        }
    }

    pub fn order(message: impl Into<String>) -> Self {
        SysidError {
            kind: ErrorKind::Order,
            message: message.into(),
        }
    }

    pub fn numerical(message: impl Into<String>) -> Self {
        SysidError {
            kind: ErrorKind::Numerical,
            message: message.into(),
        }
    }
}

impl fmt::Display for SysidError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for SysidError {}

pub type Result<T> = std::result::Result<T, SysidError>;
