//! The crate's one error: why a virtual robot could not be built or stepped, worded
//! for whoever called it (the mapping's file and line where it is at fault).

use std::fmt;

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VirtualError {
    message: String,
}

impl VirtualError {
    pub fn new(message: impl Into<String>) -> VirtualError {
        VirtualError {
            message: message.into(),
        }
    }

    /// The same error prefixed with what was being done (`what: message`).
    pub fn context(self, what: impl fmt::Display) -> VirtualError {
        VirtualError::new(format!("{what}: {}", self.message))
    }
}

impl fmt::Display for VirtualError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for VirtualError {}

/// The libraries below whose errors a virtual robot passes on as they are worded.
macro_rules! from_library_error {
    ($($t:ty),* $(,)?) => {
        $(impl From<$t> for VirtualError {
            fn from(e: $t) -> VirtualError {
                VirtualError::new(e.to_string())
            }
        })*
    };
}

from_library_error!(
    twinloop_sim::SimError,
    twinloop_description::DescriptionError,
    twinloop_actuator::ActuatorError,
);
