//! Errors that name the place at fault: file, line, element, field.

use std::fmt;
use std::path::PathBuf;

/// Where in a description file a problem is.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Location {
    pub file: Option<PathBuf>,
    /// 1-based line and column, when the problem has a place in the text.
    pub line: Option<u32>,
    pub column: Option<u32>,
    /// The element at fault, e.g. `<joint name="l_knee">`.
    pub element: Option<String>,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut wrote = false;
        if let Some(p) = &self.file {
            write!(f, "{}", p.display())?;
            wrote = true;
        }
        if let Some(l) = self.line {
            if wrote {
                write!(f, ":")?;
            } else {
                write!(f, "line ")?;
            }
            write!(f, "{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
            wrote = true;
        }
        if let Some(e) = &self.element {
            if wrote {
                write!(f, ": ")?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

/// An error in a robot description.
#[derive(Debug, Clone, PartialEq)]
pub struct DescriptionError {
    pub location: Location,
    pub message: String,
}

impl DescriptionError {
    pub fn new(message: impl Into<String>) -> Self {
        DescriptionError {
            location: Location::default(),
            message: message.into(),
        }
    }

    pub fn at_element(mut self, element: impl Into<String>) -> Self {
        self.location.element = Some(element.into());
        self
    }

    pub fn at_line(mut self, line: u32, column: u32) -> Self {
        self.location.line = Some(line);
        self.location.column = Some(column);
        self
    }

    /// The file the error is in, unless it already names one (an element of a
    /// file that the reader's file includes).
    pub fn in_file(mut self, file: impl Into<PathBuf>) -> Self {
        if self.location.file.is_none() {
            self.location.file = Some(file.into());
        }
        self
    }
}

impl fmt::Display for DescriptionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let loc = self.location.to_string();
        if loc.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{loc}: {}", self.message)
        }
    }
}

impl std::error::Error for DescriptionError {}
