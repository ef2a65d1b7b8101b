//! The one error path of the program: every command returns
//! `Result<Outcome, CliError>`, and `main` alone prints `error: ...` and picks the
//! exit code.
//!
//! Exit codes: 0 ok, 1 a check found problems, 2 bad input or a dead link (clap
//! also uses 2 for bad usage).

use std::fmt;
use std::path::Path;
use std::process::ExitCode;

/// How a command that ran to its end came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Nothing wrong: exit 0.
    Ok,
    /// The command did its work and its check found problems (e.g. `model lint`
    /// found an error): exit 1, the findings already printed.
    Problems,
}

impl Outcome {
    pub fn exit_code(self) -> ExitCode {
        match self {
            Outcome::Ok => ExitCode::SUCCESS,
            Outcome::Problems => ExitCode::from(1),
        }
    }
}

/// Which exit code an error ends the program with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExitKind {
    /// 1: the work ran, and what it checks failed (e.g. the simulated robot fell).
    Problems,
    /// 2: the input could not be read or used, or the link to the robot died.
    BadInput,
}

/// A one-line message naming the file, line, row, field or servo id at fault,
/// printed by `main` as `error: <message>`.
#[derive(Debug, Clone, PartialEq)]
pub struct CliError {
    pub message: String,
    pub exit: ExitKind,
}

/// What every command function returns.
pub type CliResult = Result<Outcome, CliError>;

impl CliError {
    /// Bad input or a dead link (exit 2).
    pub fn new(message: impl Into<String>) -> CliError {
        CliError {
            message: message.into(),
            exit: ExitKind::BadInput,
        }
    }

    /// The work ran and its check failed (exit 1).
    pub fn problems(message: impl Into<String>) -> CliError {
        CliError {
            message: message.into(),
            exit: ExitKind::Problems,
        }
    }

    /// An I/O error on `path`: `<path>: <what went wrong>`.
    pub fn io(path: &Path, e: std::io::Error) -> CliError {
        CliError::new(format!("{}: {e}", path.display()))
    }

    /// The same error with `what: ` in front (an option or a file the library
    /// message does not name).
    pub fn context(mut self, what: impl fmt::Display) -> CliError {
        self.message = format!("{what}: {}", self.message);
        self
    }

    pub fn exit_code(&self) -> ExitCode {
        match self.exit {
            ExitKind::Problems => ExitCode::from(1),
            ExitKind::BadInput => ExitCode::from(2),
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // One line, whatever the message carries.
        let one_line: String = self
            .message
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join(" ");
        f.write_str(&one_line)
    }
}

impl From<String> for CliError {
    fn from(message: String) -> CliError {
        CliError::new(message)
    }
}

impl From<&str> for CliError {
    fn from(message: &str) -> CliError {
        CliError::new(message)
    }
}

/// Library errors: their `Display` is already one line naming the place at fault;
/// they are printed as the library says them.
macro_rules! from_library_error {
    ($($t:ty),* $(,)?) => {
        $(impl From<$t> for CliError {
            fn from(e: $t) -> CliError {
                CliError::new(e.to_string())
            }
        })*
    };
}

from_library_error!(
    twinloop_description::DescriptionError,
    twinloop_io::IoError,
    twinloop_logs::LogError,
    twinloop_sysid::SysidError,
    twinloop_gait::GaitError,
    twinloop_reduced::ReducedError,
    twinloop_experiments::ExperimentError,
    twinloop_sim::SimError,
    twinloop_robot::RobotError,
    twinloop_link::LinkError,
    twinloop_link::MappingError,
    twinloop_link::control_cycle::CycleError,
    serde_json::Error,
    twinloop_actuator::ActuatorError,
    twinloop_virtual::VirtualError,
);

/// The identification library names an option by its field in the options struct
/// (`total_mass`); every such option is the flag of the same name (`--total-mass`),
/// so the message names the flag the user typed.
impl From<twinloop_ident::IdentError> for CliError {
    fn from(mut e: twinloop_ident::IdentError) -> CliError {
        match e.option.take() {
            // Either spelling reaches here: `total_mass` or `--plate`.
            Some(option) => CliError::new(format!(
                "--{}: {e}",
                option.trim_start_matches("--").replace('_', "-")
            )),
            None => CliError::new(e.to_string()),
        }
    }
}

impl From<twinloop_loop::LoopError> for CliError {
    /// The estimator's error worded with the CLI's flags, as from `IdentError`.
    fn from(e: twinloop_loop::LoopError) -> CliError {
        CliError::new(e.worded(&|i| CliError::from(i.clone()).message))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_print_on_one_line() {
        let e = CliError::new("first\n  second\n");
        assert_eq!(e.to_string(), "first second");
        assert_eq!(e.exit, ExitKind::BadInput);
        assert_eq!(
            CliError::new("x").context("--out a.csv").to_string(),
            "--out a.csv: x"
        );
    }
}
