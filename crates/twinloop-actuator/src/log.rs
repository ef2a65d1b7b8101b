//! An `experiment servo` log: CSV with a first comment line naming the servo
//! (`# twinloop experiment servo: RX-28 id 1`), then the columns
//!
//! | column | meaning |
//! |---|---|
//! | `t` | s since the start, when the row's read was sent |
//! | `goal` | Goal Position, rad, written at `t_goal` |
//! | `t_goal` | s, when the row's goal (and registers) were sent: after the previous row's read |
//! | `q`, `v` | Present Position (rad) and Present Speed/Velocity (rad/s) |
//! | `load` | Present Load as a fraction of full (RX), NaN where the servo has none |
//! | `current` | Present Current, A (MX(2.0), X), NaN where the servo has none |
//! | `voltage`, `temperature` | Present Voltage (V) and Temperature (C) |
//! | three firmware registers | `compliance_slope`, `compliance_margin`, `punch` (RX) or `p_gain`, `i_gain`, `d_gain` (MX(2.0), X), raw |

use crate::error::ActuatorError;
use crate::servo_type::ServoType;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;
use twinloop_io::Table;

/// The comment the first line of a log starts with.
pub const LOG_PREFIX: &str = "# twinloop experiment servo:";

/// The note (MCAP metadata record) in which a log that is not a CSV keeps the
/// comment lines a CSV log starts with (its `text`).
pub const SERVO_LOG_NOTE: &str = "twinloop.servo_log";

/// The columns before the firmware registers.
pub const LOG_COLUMNS: [&str; 9] = [
    "t",
    "goal",
    "t_goal",
    "q",
    "v",
    "load",
    "current",
    "voltage",
    "temperature",
];

#[derive(Debug, Clone, PartialEq, Default)]
pub struct ServoLog {
    pub file: String,
    pub servo: Option<ServoType>,
    /// The servo's bus id, where the first line names it (`... RX-28 id 3`).
    pub id: Option<u8>,
    pub t: Vec<f64>,
    pub goal: Vec<f64>,
    /// When each row's goal was sent (the previous row's time where the log has no
    /// `t_goal` column).
    pub t_goal: Vec<f64>,
    pub q: Vec<f64>,
    pub v: Vec<f64>,
    /// A per row where the servo senses current.
    pub current: Option<Vec<f64>>,
    pub voltage: Vec<f64>,
    pub firmware: Vec<[f64; 3]>,
    /// Torque Enable per row, where the log switches it (BAM's lift-and-drop lets
    /// the load fall); `None`: on throughout, as `experiment servo` runs.
    pub torque: Option<Vec<bool>>,
}

impl ServoLog {
    pub fn len(&self) -> usize {
        self.t.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Read a log; `servo` overrides (or supplies) the type its first line names.
    pub fn read(path: &Path, servo: Option<ServoType>) -> Result<ServoLog, ActuatorError> {
        let file = path.display().to_string();
        let text = twinloop_io::input::read_to_string(path)
            .map_err(|e| ActuatorError::new(&file, "", format!("cannot read: {e}")))?;
        let table =
            Table::parse(&text).map_err(|e| ActuatorError::new(&file, "", e.to_string()))?;
        ServoLog::from_table(&file, &text, &table, servo)
    }

    /// A log from its table and its leading comment lines (`header`, whose first
    /// line names the servo: a CSV's text, or the note an MCAP log keeps them in,
    /// [`SERVO_LOG_NOTE`]); `file` names it in errors.
    pub fn from_table(
        file: &str,
        header: &str,
        table: &Table,
        servo: Option<ServoType>,
    ) -> Result<ServoLog, ActuatorError> {
        let file = file.to_string();
        let first = header
            .lines()
            .next()
            .and_then(|l| l.strip_prefix(LOG_PREFIX));
        let named = first
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(ServoType::parse);
        let id = first.and_then(|rest| {
            let words: Vec<&str> = rest.split_whitespace().collect();
            words
                .windows(2)
                .find(|w| w[0] == "id")
                .and_then(|w| w[1].parse::<u8>().ok())
        });
        let servo = servo.or(named).ok_or_else(|| {
            ActuatorError::new(
                &file,
                "line 1",
                format!("no servo named (expected \"{LOG_PREFIX} MODEL ...\"); give --servo MODEL"),
            )
        })?;
        let col = |name: &str| -> Result<usize, ActuatorError> {
            table
                .column_index(name)
                .ok_or_else(|| ActuatorError::new(&file, format!("column \"{name}\""), "missing"))
        };
        let fw = servo.firmware_columns();
        let idx: Vec<usize> = ["t", "goal", "q", "v", "voltage", fw[0], fw[1], fw[2]]
            .iter()
            .map(|c| col(c))
            .collect::<Result<_, _>>()?;
        let t_goal_col = table.column_index("t_goal");
        if let Some(c) = t_goal_col {
            table
                .check_finite(&[c])
                .map_err(|e| ActuatorError::new(&file, "", e.to_string()))?;
        }
        let io = |e: twinloop_io::IoError| ActuatorError::new(&file, "", e.to_string());
        table.check_finite(&idx).map_err(io)?;
        let current_col = match servo.current_unit() {
            Some(_) => {
                let c = col("current")?;
                table.check_finite(&[c]).map_err(io)?;
                Some(c)
            }
            None => None,
        };
        if table.rows.len() < 10 {
            return Err(ActuatorError::new(
                &file,
                "",
                format!("{} data rows: too few to fit", table.rows.len()),
            ));
        }
        let mut log = ServoLog {
            file: file.clone(),
            servo: Some(servo),
            id,
            current: current_col.map(|_| Vec::new()),
            ..Default::default()
        };
        for (r, row) in table.rows.iter().enumerate() {
            if r > 0 && row[idx[0]] <= log.t[r - 1] {
                return Err(ActuatorError::new(
                    &file,
                    format!("data row {}, column \"t\"", r + 1),
                    format!(
                        "time {} does not increase (previous {})",
                        row[idx[0]],
                        log.t[r - 1]
                    ),
                ));
            }
            let previous = log.t.last().copied().unwrap_or(row[idx[0]]);
            log.t_goal.push(t_goal_col.map_or(previous, |c| row[c]));
            log.t.push(row[idx[0]]);
            log.goal.push(row[idx[1]]);
            log.q.push(row[idx[2]]);
            log.v.push(row[idx[3]]);
            log.voltage.push(row[idx[4]]);
            log.firmware.push([row[idx[5]], row[idx[6]], row[idx[7]]]);
            if let (Some(c), Some(cur)) = (current_col, log.current.as_mut()) {
                cur.push(row[c]);
            }
        }
        Ok(log)
    }
}

/// Writes a log row by row, flushed as it goes, as a recording of
/// `twinloop_io::output` (written beside the file and given its name however the
/// run ends, when it holds a row: a run cut short keeps its rows, a run that
/// recorded nothing leaves an older log in place). A path whose extension a program
/// registered another format for (`twinloop`: `.mcap`) is written in it, the comment
/// lines kept as its [`SERVO_LOG_NOTE`].
pub struct LogWriter {
    out: LogOut,
    pub rows: usize,
}

enum LogOut {
    Csv {
        out: twinloop_io::output::AtomicFile,
        line: String,
    },
    Other(Box<dyn twinloop_io::RowSink>),
}

impl LogWriter {
    pub fn create(path: &Path, servo: ServoType, what: &str) -> std::io::Result<LogWriter> {
        Self::create_with(path, servo, what, "")
    }

    /// [`LogWriter::create`] with `comments` (whole `#` lines, each ending in a
    /// newline) after the first line: what the load was (a limb's robot, joint and
    /// pose).
    pub fn create_with(
        path: &Path,
        servo: ServoType,
        what: &str,
        comments: &str,
    ) -> std::io::Result<LogWriter> {
        let header = format!("{LOG_PREFIX} {} {what}\n{comments}", servo.name());
        let fw = servo.firmware_columns();
        if twinloop_io::sink::registered(path) {
            let columns: Vec<String> = LOG_COLUMNS
                .iter()
                .chain(&fw)
                .map(|c| c.to_string())
                .collect();
            let mut sink =
                twinloop_io::sink::open_recording(path, &columns).map_err(std::io::Error::other)?;
            sink.note(SERVO_LOG_NOTE, &header)
                .map_err(std::io::Error::other)?;
            return Ok(LogWriter {
                out: LogOut::Other(sink),
                rows: 0,
            });
        }
        let place =
            twinloop_io::output::Output::resolve("", path).map_err(std::io::Error::other)?;
        let mut out =
            twinloop_io::output::AtomicFile::recording(&place).map_err(std::io::Error::other)?;
        out.write_all(header.as_bytes())?;
        writeln!(
            out,
            "{},{},{},{}",
            LOG_COLUMNS.join(","),
            fw[0],
            fw[1],
            fw[2]
        )?;
        out.header_written();
        Ok(LogWriter {
            out: LogOut::Csv {
                out,
                line: String::with_capacity(256),
            },
            rows: 0,
        })
    }

    /// One row: the [`LOG_COLUMNS`] values then the three firmware registers.
    pub fn write(&mut self, values: &[f64; 9], firmware: &[f64; 3]) -> std::io::Result<()> {
        match &mut self.out {
            LogOut::Csv { out, line } => {
                line.clear();
                for (k, x) in values.iter().chain(firmware).enumerate() {
                    if k > 0 {
                        line.push(',');
                    }
                    // f64's Display is the shortest text that reads back to the same number.
                    let _ = write!(line, "{x}");
                }
                line.push('\n');
                out.write_all(line.as_bytes())?;
            }
            LogOut::Other(sink) => {
                let mut row = [0.0; 12];
                row[..9].copy_from_slice(values);
                row[9..].copy_from_slice(firmware);
                sink.write_row(&row).map_err(std::io::Error::other)?;
            }
        }
        self.rows += 1;
        Ok(())
    }

    pub fn finish(self) -> std::io::Result<()> {
        match self.out {
            LogOut::Csv { out, .. } => out.commit().map_err(std::io::Error::other),
            LogOut::Other(sink) => sink.finish().map_err(std::io::Error::other),
        }
    }
}
