//! What every command group shares: loading a description with errors printed the
//! same way, exit codes, and writing output without panicking on a closed pipe.

use std::io::Write;
use std::path::Path;
use std::process::ExitCode;
use twinloop_description::{Description, DescriptionError};

/// The command ran and found nothing wrong.
pub const EXIT_OK: u8 = 0;
/// The command ran and its check failed (e.g. `model lint` found an error).
pub const EXIT_FINDINGS: u8 = 1;
/// The input could not be read or parsed (clap also uses 2 for bad usage).
pub const EXIT_BAD_INPUT: u8 = 2;

/// Description file formats, told apart by the root element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Urdf,
    Mjcf,
    Unknown,
}

impl Format {
    pub fn as_str(self) -> &'static str {
        match self {
            Format::Urdf => "URDF",
            Format::Mjcf => "MJCF",
            Format::Unknown => "unknown",
        }
    }
}

/// The format of a description from its root element (`<robot>`: URDF,
/// `<mujoco>`: MJCF) without parsing the whole file.
pub fn sniff_format(text: &str) -> Format {
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("<?") {
            let Some(end) = r.find("?>") else {
                return Format::Unknown;
            };
            rest = &r[end + 2..];
        } else if let Some(r) = rest.strip_prefix("<!--") {
            let Some(end) = r.find("-->") else {
                return Format::Unknown;
            };
            rest = &r[end + 3..];
        } else if let Some(r) = rest.strip_prefix("<!") {
            let Some(end) = r.find('>') else {
                return Format::Unknown;
            };
            rest = &r[end + 1..];
        } else if let Some(r) = rest.strip_prefix('<') {
            let name: String = r
                .chars()
                .take_while(|c| !c.is_whitespace() && *c != '>' && *c != '/')
                .collect();
            return match name.as_str() {
                "robot" => Format::Urdf,
                "mujoco" => Format::Mjcf,
                _ => Format::Unknown,
            };
        } else {
            return Format::Unknown;
        }
    }
}

/// Load a URDF or MJCF file. On failure prints `error: <file>:<line>:<col>: <element>: <message>`
/// to stderr and returns the exit code to end with.
pub fn load_robot(path: &Path) -> Result<(Description, Format), ExitCode> {
    let format = std::fs::read_to_string(path)
        .map(|t| sniff_format(&t))
        .unwrap_or(Format::Unknown);
    // A reader bug must not turn into a panic trace for the user: report it as
    // unreadable input, naming the file.
    let previous_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let loaded = std::panic::catch_unwind(|| twinloop_description::load(path));
    std::panic::set_hook(previous_hook);
    let result = match loaded {
        Ok(r) => r,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown cause".to_string());
            Err(DescriptionError::new(format!(
                "the reader failed unexpectedly ({what}); please report this file"
            )))
        }
    };
    match result {
        Ok(robot) => Ok((robot, format)),
        Err(mut e) => {
            if e.location.file.is_none() {
                e.location.file = Some(path.to_path_buf());
            }
            eprintln!("error: {e}");
            Err(ExitCode::from(EXIT_BAD_INPUT))
        }
    }
}

/// Write to stdout; a closed pipe (`twinloop ... | head`) ends quietly instead of panicking.
pub fn print(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

/// JSON for machines: pretty, one trailing newline. False (after printing the
/// error) if the value could not be serialised.
pub fn print_json<T: serde::Serialize>(value: &T) -> bool {
    match serde_json::to_string_pretty(value) {
        Ok(s) => {
            print(&s);
            print("\n");
            true
        }
        Err(e) => {
            eprintln!("error: could not write JSON: {e}");
            false
        }
    }
}

/// A number for people: 6 significant digits, no float noise (3.1474699999999998 -> 3.14747).
pub fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    if (1e-4..1e7).contains(&rounded.abs()) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_from_root_element() {
        assert_eq!(
            sniff_format("<?xml version=\"1.0\"?>\n<!-- c -->\n<robot name=\"x\">"),
            Format::Urdf
        );
        assert_eq!(sniff_format("\u{feff}<mujoco model=\"op3\">"), Format::Mjcf);
        assert_eq!(sniff_format("<!DOCTYPE x><robot/>"), Format::Urdf);
        assert_eq!(sniff_format("<sdf>"), Format::Unknown);
        assert_eq!(sniff_format("not xml"), Format::Unknown);
        assert_eq!(sniff_format("<!-- unterminated"), Format::Unknown);
    }

    #[test]
    fn numbers_for_people() {
        assert_eq!(num(3.1474699999999998), "3.14747");
        assert_eq!(num(1e-9), "1e-9");
        assert_eq!(num(0.0), "0");
    }
}

/// The model's coordinate names that a quantity's columns are named after.
pub fn coordinate_names(
    model: &twinloop_dynamics::Model,
    quantity: twinloop_io::Quantity,
) -> Vec<String> {
    use twinloop_io::Quantity;
    match quantity {
        Quantity::Q => model.q_names(),
        Quantity::V | Quantity::A => model.v_names(),
        Quantity::Tau => model.tau_names(),
    }
}

/// The columns of `table` that hold `quantity` for `model`, in model order.
pub fn state_columns(
    table: &twinloop_io::Table,
    model: &twinloop_dynamics::Model,
    quantity: twinloop_io::Quantity,
) -> Result<twinloop_io::StateColumns, twinloop_io::IoError> {
    twinloop_io::StateColumns::find(table, quantity, &coordinate_names(model, quantity))
}
