use std::fmt;
use std::path::{Path, PathBuf};

/// An error in a log: names the file, the topic and the time of the message at
/// fault (seconds since the Unix epoch, as the message's stamp or log time says), so
/// the one-line error the CLI prints says where to look.
#[derive(Debug, Clone, PartialEq)]
pub struct LogError {
    pub file: Option<PathBuf>,
    pub topic: Option<String>,
    /// Nanoseconds since the epoch of the message at fault.
    pub time_ns: Option<i64>,
    pub message: String,
}

impl LogError {
    pub fn new(message: impl Into<String>) -> Self {
        LogError {
            file: None,
            topic: None,
            time_ns: None,
            message: message.into(),
        }
    }

    /// Name the file, unless a file is already named (an inner error knows better).
    pub fn in_file(mut self, file: &Path) -> Self {
        if self.file.is_none() {
            self.file = Some(file.to_path_buf());
        }
        self
    }

    /// Name the topic and the message time, unless already named.
    pub fn at(mut self, topic: &str, time_ns: i64) -> Self {
        if self.topic.is_none() {
            self.topic = Some(topic.to_string());
            self.time_ns = Some(time_ns);
        }
        self
    }

    pub fn on_topic(mut self, topic: &str) -> Self {
        if self.topic.is_none() {
            self.topic = Some(topic.to_string());
        }
        self
    }
}

/// Nanoseconds as seconds with all nine decimals (a log's clock is integer ns).
pub fn format_ns(ns: i64) -> String {
    let sign = if ns < 0 { "-" } else { "" };
    let a = ns.unsigned_abs();
    format!("{sign}{}.{:09}", a / 1_000_000_000, a % 1_000_000_000)
}

impl fmt::Display for LogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.file {
            write!(f, "{}: ", p.display())?;
        }
        if let Some(t) = &self.topic {
            write!(f, "topic {t}")?;
            if let Some(ns) = self.time_ns {
                write!(f, " at t={} s", format_ns(ns))?;
            }
            write!(f, ": ")?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for LogError {}

impl From<mcap::McapError> for LogError {
    fn from(e: mcap::McapError) -> Self {
        if matches!(e, mcap::McapError::BadMagic) {
            // The likeliest cause: a CSV or another file given where a log was meant.
            return LogError::new(
                "not an MCAP file (it does not start with MCAP's magic bytes); \
                 a log is an .mcap file or a rosbag2 folder",
            );
        }
        match e {
            // What the system said (`File too large`, `No space left on device`), not
            // the MCAP crate's "I/O error from writing, or reading a compression stream".
            mcap::McapError::Io(io) => {
                LogError::new(format!("MCAP: {}", twinloop_io::io_words(&io)))
            }
            e => LogError::new(format!("MCAP: {e}")),
        }
    }
}

/// A log error as a data-file error, so every table reader's caller (the CLI's
/// `read_table`) handles both the same way.
impl From<LogError> for twinloop_io::IoError {
    fn from(e: LogError) -> Self {
        let mut io = twinloop_io::IoError::new(match (&e.topic, e.time_ns) {
            (Some(t), Some(ns)) => format!("topic {t} at t={} s: {}", format_ns(ns), e.message),
            (Some(t), None) => format!("topic {t}: {}", e.message),
            _ => e.message.clone(),
        });
        io.file = e.file;
        io
    }
}

/// A file-writing error (the output's checks, its rename) as a log error.
impl From<twinloop_io::IoError> for LogError {
    fn from(e: twinloop_io::IoError) -> Self {
        LogError {
            file: e.file.clone(),
            topic: None,
            time_ns: None,
            message: match e.file {
                Some(_) => {
                    let mut bare = e.clone();
                    bare.file = None;
                    bare.to_string()
                }
                None => e.to_string(),
            },
        }
    }
}
