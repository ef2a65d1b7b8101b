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

/// The longest wall time an option may ask a command to spend or wait, s: an hour
/// (a benchmark's time per case, a silence window, a reply's allowance).
pub const MAX_WALL_S: f64 = 3600.0;

/// The most extra attempts after a lost reply: 100 (a dead servo with
/// `--retries 4000000000` would be asked for years).
pub const MAX_RETRIES: u32 = 100;

/// The slowest a simulated robot may run against the wall clock: a thousandth
/// (`--realtime-factor 1e-12` would make a 90 s tip-over last 3000 years).
pub const MIN_REALTIME_FACTOR: f64 = 1e-3;

/// A wall time in seconds, as a clap value parser: positive, at most [`MAX_WALL_S`].
pub fn wall_seconds(s: &str) -> Result<f64, String> {
    let x = crate::common::positive(s)?;
    wall(x, x, "s")
}

/// A wall time in milliseconds (`--timeout-ms`), as a clap value parser.
pub fn wall_millis(s: &str) -> Result<f64, String> {
    let x = crate::common::positive(s)?;
    wall(x * 1e-3, x, "ms")
}

fn wall(seconds: f64, x: f64, unit: &str) -> Result<f64, String> {
    if seconds <= MAX_WALL_S {
        Ok(x)
    } else {
        Err(format!(
            "{} {unit} is more than the hour of wall time ({MAX_WALL_S} s) one option may \
             ask a command to spend or wait",
            crate::common::num(x)
        ))
    }
}

/// `--max-time`, as a clap value parser: a positive number of seconds (any: the user
/// who asks for a day of work says so).
pub fn max_time(s: &str) -> Result<f64, String> {
    crate::common::positive(s)
}

/// Work estimated at `estimate` seconds before it starts: said on stderr when it is
/// long enough to wait for (over 10 s), refused when over `max_time` (the option
/// `--max-time`), naming the estimate, what it is made of, the bound, and `advice`.
pub fn within_time(
    what: &str,
    estimate: f64,
    made_of: &str,
    max_time: f64,
    advice: &str,
) -> Result<(), CliError> {
    if estimate > max_time {
        return Err(CliError::new(format!(
            "{what} would take about {} here ({made_of}), more than --max-time {} s; \
             {advice}, or raise --max-time",
            duration(estimate),
            crate::common::num(max_time)
        )));
    }
    if estimate > 10.0 {
        eprintln!("{what}: about {} here ({made_of})", duration(estimate));
    }
    Ok(())
}

/// Seconds as people say a duration: `40 s`, `12 min`, `3.4 h`.
pub fn duration(s: f64) -> String {
    if s < 120.0 {
        format!("{} s", crate::common::num((s * 10.0).round() / 10.0))
    } else if s < 7200.0 {
        format!("{} min", crate::common::num((s / 6.0).round() / 10.0))
    } else {
        format!("{} h", crate::common::num((s / 360.0).round() / 10.0))
    }
}

/// `--retries`, as a clap value parser: at most [`MAX_RETRIES`].
pub fn retries(s: &str) -> Result<u32, String> {
    let n: u32 = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a whole number"))?;
    if n <= MAX_RETRIES {
        Ok(n)
    } else {
        Err(format!(
            "{n} is more than the {MAX_RETRIES} extra attempts a lost reply is given"
        ))
    }
}

/// `--realtime-factor`, as a clap value parser: positive, at least
/// [`MIN_REALTIME_FACTOR`].
pub fn realtime_factor(s: &str) -> Result<f64, String> {
    let x = crate::common::positive(s)?;
    if x >= MIN_REALTIME_FACTOR {
        Ok(x)
    } else {
        Err(format!(
            "{} is slower than the {MIN_REALTIME_FACTOR} of the wall clock a simulated \
             robot may run at (a 90 s tip-over would take {} h)",
            crate::common::num(x),
            crate::common::num(90.0 / x / 3600.0)
        ))
    }
}

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

/// A count of 1 or more (cycles, steps, rounds, samples): 0 would do nothing and
/// say nothing.
pub fn count(s: &str) -> Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a whole number"))?;
    if (1..=MAX_COUNT).contains(&n) {
        Ok(n)
    } else if n == 0 {
        Err(format!("{n} is out of range: a count >= 1 is needed"))
    } else {
        Err(format!(
            "{n} is more than the {} of anything one command counts (a bound on its \
             work and memory; split the run)",
            MAX_COUNT
        ))
    }
}

/// Whole-number options that are not counts of work: a seed, a bit rate, a servo
/// id, a protocol or a time in microseconds, each checked by its own parser.
const NOT_COUNTS: &[&str] = &[
    "seed",
    "compare-seed",
    "baud",
    "id",
    "protocol",
    "return-delay-us",
    "spin-us",
];

/// The subcommand the user ran (the deepest one matched) with its matches: where the
/// command line's options are checked.
pub(crate) fn leaf<'a>(
    cli: &'a clap::Command,
    matches: &'a clap::ArgMatches,
) -> Option<(&'a clap::Command, &'a clap::ArgMatches)> {
    let (mut cmd, mut m) = (cli, matches);
    while let Some((name, sub)) = m.subcommand() {
        (cmd, m) = (cmd.find_subcommand(name)?, sub);
    }
    Some((cmd, m))
}

/// Every whole-number option of the command line that counts something (rounds,
/// restarts, samples to skip, validation runs) at most [`MAX_COUNT`], whichever
/// command it belongs to and whether or not its own parser says so: one place, so
/// that a new option cannot make a command allocate for a count of 4000000000.
pub fn check_counts(cli: &clap::Command, matches: &clap::ArgMatches) -> Result<(), CliError> {
    use std::any::TypeId;
    let whole = [
        TypeId::of::<usize>(),
        TypeId::of::<u64>(),
        TypeId::of::<u32>(),
        TypeId::of::<i64>(),
        TypeId::of::<i32>(),
    ];
    let Some((cmd, m)) = leaf(cli, matches) else {
        return Ok(());
    };
    for arg in cmd.get_arguments() {
        let Some(long) = arg.get_long() else {
            continue;
        };
        let kind = arg.get_value_parser().type_id();
        if NOT_COUNTS.contains(&long) || !whole.iter().any(|t| kind == *t) {
            continue;
        }
        let Ok(Some(values)) = m.try_get_raw(arg.get_id().as_str()) else {
            continue;
        };
        for v in values {
            let text = v.to_string_lossy();
            if let Ok(n) = text.trim().parse::<u128>()
                && n > MAX_COUNT as u128
            {
                return Err(CliError::new(format!(
                    "--{long} {n}: more than the {MAX_COUNT} of anything one command counts \
                     (a bound on its work and memory; split the run)"
                )));
            }
        }
    }
    Ok(())
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
