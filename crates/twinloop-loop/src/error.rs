//! The crate's one error: what went wrong in a plan, worded for whoever called it. An
//! estimator's own error (`IdentError`) is kept as it is, so that the CLI names its
//! flags and Python its keywords; `setting` names the plan's field at fault.

use std::fmt;
use twinloop_ident::IdentError;

/// Whether the fault is the caller's input or the outside world (a port, a file).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    Input,
    Io,
}

#[derive(Debug, Clone)]
pub struct LoopError {
    pub kind: ErrorKind,
    /// The plan's field at fault (`map`, `record`, `realtime_factor`, `soft_servos`),
    /// when one is: Python words it as its keyword; the CLI's messages already name
    /// the file.
    pub setting: Option<&'static str>,
    /// The estimator's error, as it came (its `option` is named by the caller).
    pub ident: Option<Box<IdentError>>,
    message: String,
    /// What was being done, innermost first.
    context: Vec<String>,
}

impl LoopError {
    pub fn new(message: impl Into<String>) -> LoopError {
        LoopError {
            kind: ErrorKind::Input,
            setting: None,
            ident: None,
            message: message.into(),
            context: Vec::new(),
        }
    }

    /// A port or a file that failed.
    pub fn io(message: impl Into<String>) -> LoopError {
        LoopError {
            kind: ErrorKind::Io,
            ..LoopError::new(message)
        }
    }

    /// The same error, said to be about the plan's `setting`.
    pub fn at(mut self, setting: &'static str) -> LoopError {
        self.setting = Some(setting);
        self
    }

    /// The same error prefixed with what was being done (`what: message`).
    pub fn context(mut self, what: impl fmt::Display) -> LoopError {
        self.context.push(what.to_string());
        self
    }

    /// The message without its context, the estimator's worded by `ident`.
    pub fn core(&self, ident: &dyn Fn(&IdentError) -> String) -> String {
        match &self.ident {
            Some(e) => ident(e),
            None => self.message.clone(),
        }
    }

    /// The whole message, the estimator's error worded by `ident`, each context
    /// before it.
    pub fn worded(&self, ident: &dyn Fn(&IdentError) -> String) -> String {
        self.context
            .iter()
            .fold(self.core(ident), |m, c| format!("{c}: {m}"))
    }
}

impl fmt::Display for LoopError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.worded(&|e| e.to_string()))
    }
}

impl std::error::Error for LoopError {}

impl From<IdentError> for LoopError {
    fn from(e: IdentError) -> LoopError {
        LoopError {
            ident: Some(Box::new(e)),
            ..LoopError::new(String::new())
        }
    }
}

impl From<String> for LoopError {
    fn from(message: String) -> LoopError {
        LoopError::new(message)
    }
}

macro_rules! from_library_error {
    ($($t:ty),* $(,)?) => {
        $(impl From<$t> for LoopError {
            fn from(e: $t) -> LoopError {
                LoopError::new(e.to_string())
            }
        })*
    };
}

from_library_error!(
    twinloop_description::DescriptionError,
    twinloop_io::IoError,
    twinloop_experiments::ExperimentError,
    twinloop_robot::RobotError,
    twinloop_link::LinkError,
    twinloop_link::MappingError,
    twinloop_actuator::ActuatorError,
    twinloop_virtual::VirtualError,
);
