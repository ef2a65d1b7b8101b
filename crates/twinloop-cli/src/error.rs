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
        // One line, whatever the message carries; a TOML error's picture of the line
        // (`2 | k = [1,2` and its caret line) is left out: the place is named before it.
        let one_line: String = self
            .message
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !is_source_picture(l))
            .map(|l| match l.split_once("TOML parse error at ") {
                Some((before, at)) => format!("{before}{at}:"),
                None => l.to_string(),
            })
            .collect::<Vec<_>>()
            .join(" ");
        f.write_str(&plain_words(&one_line))
    }
}

/// A line of a parser's picture of the source: `|`, `2 | text`, `  |    ^`.
fn is_source_picture(line: &str) -> bool {
    let rest = line
        .trim_start_matches(|c: char| c.is_ascii_digit())
        .trim_start();
    rest.starts_with('|')
}

/// serde's "unknown field/variant `x`, expected one of `a`, `b`" as "unknown WHAT
/// \"x\" (known: a, b)", the position (" at line ...") kept.
fn unknown(what: &str, name: &str, rest: &str) -> String {
    let known = rest
        .strip_prefix(", expected one of ")
        .or_else(|| rest.strip_prefix(", expected "))
        .map(|k| {
            let end = k.find(" at line").unwrap_or(k.len());
            (k[..end].replace('`', ""), &k[end..])
        });
    match known {
        Some((k, tail)) => format!("unknown {what} \"{name}\" (known: {k}){tail}"),
        None => format!("unknown {what} \"{name}\"{rest}"),
    }
}

/// A message with the parsers' wording (serde's, Rust's I/O errors') put as people
/// say it: `missing field `forward`` is `field "forward" is missing`, `invalid
/// type: integer `5`, expected a string` is `5 (a number) where a string is
/// expected`, ` (os error 13)` is left out.
pub fn plain_words(text: &str) -> String {
    let mut s = twinloop_io::without_os_error(text);
    s = rewrite(&s, "missing field `", |name, rest| {
        format!("field \"{name}\" is missing{rest}")
    });
    s = rewrite(&s, "unknown field `", |name, rest| {
        unknown("field", name, rest)
    });
    s = rewrite(&s, "unknown variant `", |name, rest| {
        unknown("value", name, rest)
    });
    if let Some(k) = s.find("invalid type: ") {
        let body = &s[k + "invalid type: ".len()..];
        if let Some((found, expected)) = body.split_once(", expected ") {
            let found = found
                .replace("integer `", "the number `")
                .replace("floating point `", "the number `")
                .replace("sequence", "a list")
                .replace("map", "a table")
                .replace('`', "");
            let end = expected.find(" at line").unwrap_or(expected.len());
            let (expected, at) = expected.split_at(end);
            let expected = rust_type_in_words(expected);
            s = format!("{}{found} where {expected} is expected{at}", &s[..k]);
        }
    }
    quote_tokens(&s)
}

/// serde's name of what it expected (`i64`, `f64`, `struct Joint`, `a sequence`) as
/// people say it: a whole number, a number, a table, a list.
fn rust_type_in_words(expected: &str) -> String {
    let t = expected.trim();
    let whole = [
        "i8", "i16", "i32", "i64", "i128", "isize", "u8", "u16", "u32", "u64", "u128", "usize",
    ];
    if whole.contains(&t) {
        "a whole number".into()
    } else if t == "f32" || t == "f64" {
        "a number".into()
    } else if t.starts_with("struct ") || t == "a map" {
        "a table".into()
    } else if t == "a sequence" {
        "a list".into()
    } else {
        t.to_string()
    }
}

/// A parser's backquoted token (`]`, `robot`) in double quotes, as the messages here
/// quote names; a backquoted command (it has spaces) stays as it is.
fn quote_tokens(text: &str) -> String {
    let parts: Vec<&str> = text.split('`').collect();
    if parts.len() < 3 {
        return text.to_string();
    }
    let mut out = String::from(parts[0]);
    let mut k = 1;
    while k < parts.len() {
        let inner = parts[k];
        if k + 1 < parts.len() && !inner.is_empty() && !inner.contains(' ') {
            out.push_str(&format!("\"{inner}\"{}", parts[k + 1]));
            k += 2;
        } else if k + 1 < parts.len() {
            out.push_str(&format!("`{inner}`{}", parts[k + 1]));
            k += 2;
        } else {
            out.push('`');
            out.push_str(inner);
            k += 1;
        }
    }
    out
}

/// `text` with each `<start>NAME`REST` made `f(NAME, REST)` (REST: to the end).
fn rewrite(text: &str, start: &str, f: impl Fn(&str, &str) -> String) -> String {
    let Some(k) = text.find(start) else {
        return text.to_string();
    };
    let after = &text[k + start.len()..];
    let Some(end) = after.find('`') else {
        return text.to_string();
    };
    format!("{}{}", &text[..k], f(&after[..end], &after[end + 1..]))
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
    fn parser_words_are_put_as_people_say_them() {
        let e = |m: &str| CliError::new(m).to_string();
        assert_eq!(
            e("tip.json: missing field `forward` at line 1 column 31"),
            "tip.json: field \"forward\" is missing at line 1 column 31"
        );
        assert_eq!(
            e("tip.json: invalid type: integer `5`, expected a string at line 1 column 11"),
            "tip.json: the number 5 where a string is expected at line 1 column 11"
        );
        assert_eq!(
            e("m.toml:1:1: unknown field `foo`, expected one of `robot`, `roles`"),
            "m.toml:1:1: unknown field \"foo\" (known: robot, roles)"
        );
        assert_eq!(
            e(
                "p.toml: TOML parse error at line 2, column 9\n  |\n2 | k = [1,2\n  |         ^\nunclosed array"
            ),
            "p.toml: line 2, column 9: unclosed array"
        );
        assert_eq!(
            e("p.toml: unclosed array, expected `]`; see `twinloop model info`"),
            "p.toml: unclosed array, expected \"]\"; see `twinloop model info`"
        );
        assert_eq!(
            e("x.urdf: cannot create: Permission denied (os error 13)"),
            "x.urdf: cannot create: Permission denied"
        );
    }

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
