//! What one command may do (issue 29: no work that never ends or eats the machine):
//! at most [`MAX_STEPS`] time steps or rows, at most [`MAX_COUNT`] of anything
//! counted by an option. Checked before the work starts; the error names the options
//! and the bound (exit 2). docs/architecture.md, "Errors and exit codes", says them.

use crate::error::CliError;

/// Time steps (or rows) one command computes: 10 million, 2.8 h of simulated time at
/// 1 ms, minutes of work; a run longer than that is split into several.
pub const MAX_STEPS: f64 = 1e7;

/// Any count an option gives (samples, poses, cycles, epochs): one million.
pub const MAX_COUNT: usize = 1_000_000;

/// The steps of `duration` seconds at `dt`: refused (naming `what`, e.g. "--duration
/// 1e12 s at --dt 0.001 s") when more than [`MAX_STEPS`].
pub fn steps(duration: f64, dt: f64, what: &str) -> Result<usize, CliError> {
    let n = (duration / dt).round();
    if n.is_finite() && n <= MAX_STEPS {
        return Ok(n as usize);
    }
    Err(CliError::new(format!(
        "{what} is {n:.3e} time steps (rows), more than the {MAX_STEPS:.0e} one command \
         computes ({:.1} h at 1 ms); shorten it, or split the run",
        MAX_STEPS * 1e-3 / 3600.0
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_run_is_refused_by_its_steps_and_a_normal_one_is_taken() {
        assert_eq!(steps(2.0, 0.001, "x").unwrap(), 2000);
        let e = steps(1e12, 0.001, "--duration 1e12 s at --dt 0.001 s").unwrap_err();
        assert!(
            e.message.starts_with("--duration 1e12 s") && e.message.contains("1e7"),
            "{e}"
        );
        assert!(steps(2.0, 1e-300, "--dt").is_err());
    }
}
