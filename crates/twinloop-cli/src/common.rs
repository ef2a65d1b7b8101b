//! What every command group shares: loading a robot description (URDF, MJCF or
//! `builtin:NAME`) with errors that name the place at fault, writing JSON to a file
//! or stdout, and writing output without panicking on a closed pipe.

use crate::error::CliError;
use std::io::Write;
use std::path::{Path, PathBuf};
use twinloop_description::Description;
use twinloop_dynamics::{BaseKind, Model};

/// The help text of every `--robot` option.
pub const ROBOT_HELP: &str = "Robot description: a URDF or MJCF file, a robot profile (.toml: its \
     description, with its joint roles), or builtin:NAME (km20, lab17, op3, darwin_op)";

pub use twinloop_loop::profile::Format;

/// Load a robot description: `builtin:NAME`, a robot profile or a URDF or MJCF file
/// (`twinloop_loop::profile::load_description`).
pub fn load_description(spec: &str) -> Result<(Description, Format), CliError> {
    Ok(twinloop_loop::profile::load_description(spec)?)
}

/// [`load_description`] without the unit-scale refusal: for `model lint`, which
/// reports it among its findings.
pub fn read_description(spec: &str) -> Result<(Description, Format), CliError> {
    Ok(twinloop_loop::profile::read_description(spec)?)
}

/// A profile's description with its roles (`twinloop_loop::profile::profile_description`).
pub fn profile_description(
    mapping: &twinloop_link::RobotMapping,
) -> Result<Option<(Description, Format)>, CliError> {
    Ok(twinloop_loop::profile::profile_description(mapping)?)
}

/// Refuse a robot with a ball joint (`twinloop_loop::profile::hinges_only`).
pub fn hinges_only(robot: &Description, spec: &str, work: &str) -> Result<(), CliError> {
    Ok(twinloop_loop::profile::hinges_only(robot, spec, work)?)
}

/// Load a description and compile it for the dynamics, with a floating base (or
/// the root welded to the world).
pub fn load_model(spec: &str, base: BaseKind) -> Result<(Description, Model), CliError> {
    let (robot, _) = load_description(spec)?;
    let model = Model::from_description_with_base(&robot, base).map_err(|mut e| {
        if e.location.file.is_none() {
            e.location.file = Some(PathBuf::from(spec));
        }
        CliError::from(e)
    })?;
    Ok((robot, model))
}

/// Write to stdout; a closed pipe (`twinloop ... | head`) ends quietly instead of panicking.
pub fn print(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

/// The help text of every `--json` option.
pub const JSON_HELP: &str =
    "Write the machine-readable result as JSON to FILE (-: to stdout, in place of the text)";

/// Whether `--json` sends the JSON to stdout (`-`), in place of the text.
pub fn json_to_stdout(json: Option<&PathBuf>) -> bool {
    json.is_some_and(|p| p.as_os_str() == "-")
}

/// Write JSON (pretty, one trailing newline) to `target`: a file, or stdout for `-`.
pub fn write_json<T: serde::Serialize + ?Sized>(target: &Path, value: &T) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(value)? + "\n";
    if target.as_os_str() == "-" {
        print(&text);
        Ok(())
    } else {
        Ok(twinloop_io::output::write_atomic(target, text)
            .map_err(CliError::from)
            .map_err(|e| e.context("--json"))?)
    }
}

/// A command's two outputs: the text for people on stdout and, with `--json`, the
/// JSON for machines in its file; `--json -` puts the JSON on stdout instead of
/// the text.
pub fn emit<T: serde::Serialize + ?Sized>(
    text: &str,
    json: Option<&PathBuf>,
    value: &T,
) -> Result<(), CliError> {
    if let Some(target) = json {
        write_json(target, value)?;
    }
    if !json_to_stdout(json) {
        print(text);
    }
    Ok(())
}

/// Range checks of numeric options, as clap value parsers (`#[arg(value_parser =
/// crate::common::positive)]`): a value out of range is a usage error (exit 2)
/// naming the option and the range, before any work starts, so no option can make
/// a command hang (a zero step or ramp) or diverge (a negative one). Integer counts
/// use clap's own `value_parser!(u64).range(1..)`.
fn parse_number(s: &str, ok: impl Fn(f64) -> bool, range: &str) -> Result<f64, String> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a number"))?;
    if x.is_finite() && ok(x) {
        Ok(x)
    } else {
        Err(format!("{} is out of range: {range}", num(x)))
    }
}

/// A finite number > 0 (a step, a rate, a duration that must pass).
pub fn positive(s: &str) -> Result<f64, String> {
    parse_number(s, |x| x > 0.0, "a finite number > 0 is needed")
}

/// A finite number >= 0 (a duration, a noise level, a tolerance).
pub fn non_negative(s: &str) -> Result<f64, String> {
    parse_number(s, |x| x >= 0.0, "a finite number >= 0 is needed")
}

/// Any finite number (an offset, an angle).
pub fn finite(s: &str) -> Result<f64, String> {
    parse_number(s, |_| true, "a finite number is needed (not NaN or inf)")
}

/// A servo id, as a clap value parser: 0 to 253 (e-manual, "ID": 254 is the broadcast
/// id, which every servo obeys and none answers as its own; 255 is not an id).
pub fn servo_id(s: &str) -> Result<u8, String> {
    s.trim()
        .parse::<u8>()
        .ok()
        .filter(|&id| id <= 253)
        .ok_or_else(|| {
            format!(
                "\"{s}\" is not a servo id: a whole number 0 to 253 (254 is the broadcast \
                 id, which no servo answers as its own)"
            )
        })
}

/// A servo model's name (`RX-28`, `XM430-W350`), as a clap value parser: the name
/// given, once it is one twinloop knows; the error lists the known ones.
pub fn servo_model_name(s: &str) -> Result<String, String> {
    match twinloop_link::ServoModel::parse(s) {
        Some(_) => Ok(s.to_string()),
        None => Err(format!(
            "\"{s}\" is not a servo model twinloop knows; known: {}",
            twinloop_link::ServoModel::known_names()
        )),
    }
}

/// A bus bit rate a Dynamixel servo can run at ([`twinloop_link::servo_model::BAUD_RANGE`]):
/// 0 would plan a cycle of infinite length or serve a bus that never answers.
pub fn baud(s: &str) -> Result<u32, String> {
    let range = twinloop_link::servo_model::BAUD_RANGE;
    let n: u32 = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a whole number of bit/s"))?;
    if range.contains(&n) {
        Ok(n)
    } else {
        Err(format!(
            "{n} is out of range: a Dynamixel bit rate, {} to {} bit/s (1000000 is the \
             factory setting of most)",
            range.start(),
            range.end()
        ))
    }
}

/// Read a CSV table; the error names the file (and line).
///
/// An `.mcap` file, a `.db3` or a rosbag2 folder is read as a log (twinloop-logs):
/// the topics of `--topic` (else every topic twinloop can use), resampled onto
/// `--resample` seconds when given.
pub fn read_table(path: &Path) -> Result<twinloop_io::Table, CliError> {
    if twinloop_logs::is_log(path) {
        let options = LOG_OPTIONS.get().cloned().unwrap_or_default();
        return Ok(twinloop_logs::read_log(path, &options)?);
    }
    Ok(twinloop_io::Table::read(path)?)
}

/// The global `--topic` and `--resample`, set once by `main` from the command line:
/// they apply to every log any command reads, so no command threads them through.
static LOG_OPTIONS: std::sync::OnceLock<twinloop_logs::ReadOptions> = std::sync::OnceLock::new();

/// Set the log options of [`read_table`] (once, at start-up).
pub fn set_log_options(topics: &[String], resample: Option<f64>) -> Result<(), CliError> {
    let topics = topics
        .iter()
        .map(|t| t.parse())
        .collect::<Result<Vec<twinloop_logs::TopicSpec>, _>>()
        .map_err(CliError::from)?;
    let _ = LOG_OPTIONS.set(twinloop_logs::ReadOptions {
        topics,
        dt: resample,
    });
    Ok(())
}

/// Whether an output is written as MCAP: its name ends in `.mcap` (any case), or
/// it is a folder (`run/`, or an existing folder): a rosbag2 bag of one MCAP file.
pub fn is_mcap(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
        || twinloop_io::sink::is_folder_output(path)
}

/// Rows written to a CSV, or to an MCAP of ROS 2 messages when the path ends in
/// `.mcap` (with the robot's URDF on `/robot_description`): what `simulate --out`
/// and `link record --out` write through.
pub enum RowWriter {
    Csv(twinloop_io::CsvWriter),
    Mcap(Box<twinloop_logs::McapLog>),
    /// One recording written to several files (`link record --out X.csv --out
    /// X.mcap`): every row goes to each, so they hold the same rows.
    Many(Vec<RowWriter>),
}

impl RowWriter {
    /// `recording`: a CSV kept row by row even if the run fails
    /// ([`twinloop_io::CsvWriter::recording`]); an MCAP is whole once finished.
    pub fn create(
        path: &Path,
        columns: &[String],
        robot: Option<&twinloop_description::Description>,
        recording: bool,
    ) -> Result<RowWriter, CliError> {
        if is_mcap(path) {
            let urdf = robot.map(twinloop_description::urdf::to_string);
            let root = robot
                .and_then(|r| r.root_links().first().map(|s| s.to_string()))
                .unwrap_or_else(|| "base_link".into());
            let mut log = twinloop_logs::McapLog::create(path, columns, urdf.as_deref(), &root)?;
            if recording {
                log = log.recording();
            }
            return Ok(RowWriter::Mcap(Box::new(log)));
        }
        Ok(RowWriter::Csv(if recording {
            twinloop_io::CsvWriter::recording(path, columns)?
        } else {
            twinloop_io::CsvWriter::create(path, columns)?
        }))
    }

    /// Refuse a path given twice: two writers would race for one file.
    pub fn distinct_paths(paths: &[PathBuf]) -> Result<(), CliError> {
        match paths
            .iter()
            .enumerate()
            .find(|(k, p)| paths[..*k].contains(p))
        {
            Some((k, p)) => Err(CliError::new(format!(
                "--out {}: given twice (output {} repeats an earlier one)",
                p.display(),
                k + 1
            ))),
            None => Ok(()),
        }
    }

    /// [`RowWriter::create`] for each of `paths` (one: that file's writer).
    pub fn create_each(
        paths: &[PathBuf],
        columns: &[String],
        robot: Option<&twinloop_description::Description>,
        recording: bool,
    ) -> Result<RowWriter, CliError> {
        Self::distinct_paths(paths)?;
        let mut writers = paths
            .iter()
            .map(|p| RowWriter::create(p, columns, robot, recording))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(if writers.len() == 1 {
            writers.remove(0)
        } else {
            RowWriter::Many(writers)
        })
    }

    pub fn write_row(&mut self, row: &[f64]) -> Result<(), CliError> {
        match self {
            RowWriter::Csv(w) => Ok(w.write_row(row)?),
            RowWriter::Mcap(w) => Ok(w.write_row(row)?),
            RowWriter::Many(ws) => ws.iter_mut().try_for_each(|w| w.write_row(row)),
        }
    }

    /// Close every file; the first error, after all have been tried (one failed
    /// output does not lose the others).
    pub fn finish(self) -> Result<(), CliError> {
        match self {
            RowWriter::Csv(w) => Ok(w.finish()?),
            RowWriter::Mcap(w) => Ok(w.finish()?),
            RowWriter::Many(ws) => {
                let mut first = Ok(());
                for w in ws {
                    let r = w.finish();
                    if first.is_ok() {
                        first = r;
                    }
                }
                first
            }
        }
    }

    /// Give up the file: nothing is written, an older file of the name stays.
    pub fn discard(self) {
        match self {
            RowWriter::Csv(w) => w.discard(),
            RowWriter::Mcap(w) => w.discard(),
            RowWriter::Many(ws) => ws.into_iter().for_each(RowWriter::discard),
        }
    }
}

/// A number for people: 6 significant digits, no float noise (3.1474699999999998 -> 3.14747).
pub use twinloop_report::number as num;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounds::count;

    #[test]
    fn numeric_options_are_range_checked() {
        assert_eq!(positive("0.5"), Ok(0.5));
        for bad in ["0", "-1", "NaN", "inf", "x"] {
            assert!(positive(bad).is_err(), "{bad}");
        }
        assert_eq!(non_negative("0"), Ok(0.0));
        assert!(non_negative("-1e-9").is_err());
        assert_eq!(finite("-3"), Ok(-3.0));
        assert!(finite("nan").is_err() && finite("-inf").is_err());
        assert_eq!(baud("1000000"), Ok(1_000_000));
        assert_eq!(baud("57600"), Ok(57_600));
        for bad in ["0", "-1", "7999", "10500001", "1e6", "nan"] {
            assert!(baud(bad).is_err(), "{bad}");
        }
        assert_eq!(count("3"), Ok(3));
        assert!(count("0").is_err() && count("-1").is_err() && count("1.5").is_err());
    }

    proptest::proptest! {
        /// Every finite number is taken by `finite` as itself and by `positive` and
        /// `non_negative` exactly when it is in their range, written any way Rust writes
        /// it; any text that is not a number is refused with a message, never a panic.
        #[test]
        fn numeric_options_take_exactly_their_range(x in proptest::num::f64::ANY, junk in "\\PC{0,12}") {
            for text in [format!("{x}"), format!("{x:e}"), format!(" {x:?} ")] {
                let ok = x.is_finite();
                proptest::prop_assert_eq!(finite(&text).is_ok(), ok);
                proptest::prop_assert_eq!(positive(&text).is_ok(), ok && x > 0.0);
                proptest::prop_assert_eq!(non_negative(&text).is_ok(), ok && x >= 0.0);
                if ok {
                    proptest::prop_assert_eq!(finite(&text).unwrap().to_bits(), x.to_bits());
                }
            }
            let parsed = junk.trim().parse::<f64>();
            let r = positive(&junk);
            proptest::prop_assert_eq!(
                r.is_ok(),
                matches!(parsed, Ok(v) if v.is_finite() && v > 0.0)
            );
            if let Err(e) = r {
                proptest::prop_assert!(!e.is_empty());
            }
            let c = count(&junk);
            proptest::prop_assert_eq!(
                c.is_ok(),
                matches!(junk.trim().parse::<usize>(), Ok(n) if n >= 1)
            );
        }
    }

    #[test]
    fn numbers_for_people() {
        assert_eq!(num(3.1474699999999998), "3.14747");
        assert_eq!(num(1e-9), "1e-9");
        assert_eq!(num(0.0), "0");
    }
}
