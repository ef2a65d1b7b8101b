//! The experiments' error: one line that names what is at fault.

/// An experiment could not be set up or run; the message names the robot, joint,
/// link or option value at fault.
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentError(pub String);

impl std::fmt::Display for ExperimentError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ExperimentError {}

pub(crate) fn err<T>(message: impl Into<String>) -> Result<T, ExperimentError> {
    Err(ExperimentError(message.into()))
}

macro_rules! from_display {
    ($($t:ty),*) => {$(
        impl From<$t> for ExperimentError {
            fn from(e: $t) -> Self {
                ExperimentError(e.to_string())
            }
        }
    )*};
}

from_display!(
    twinloop_gait::GaitError,
    twinloop_reduced::ReducedError,
    twinloop_description::DescriptionError,
    twinloop_robot::RobotError
);
