//! Recordings written row by row whatever their format: a [`RowSink`] is a CSV
//! ([`CsvWriter`]) or a format a crate above this one writes (twinloop-logs' MCAP),
//! so the code that records (a guarded robot on its bus, the bus tip-over) needs no
//! knowledge of formats. [`open_recording`] picks the format by the file's extension:
//! a program that writes more than CSV registers the others once at start-up
//! ([`register_recording_format`]; the `twinloop` command registers `.mcap`, and
//! [`FOLDER`] for a rosbag2 folder: a path that ends in `/` or names a folder).

use crate::table::{CsvWriter, IoError};
use std::path::Path;
use std::sync::Mutex;

/// Where a recording's rows go, one at a time.
pub trait RowSink: Send {
    /// One row, as many values as columns.
    fn write_row(&mut self, row: &[f64]) -> Result<(), IoError>;
    /// Make the file complete and durable and give it its name.
    fn finish(self: Box<Self>) -> Result<(), IoError>;
    /// Give the file up: nothing is written, an older file of the name stays (a run
    /// that measured nothing).
    fn discard(self: Box<Self>);
    /// Keep a note (`name`, its text) with the rows: what a CSV log keeps in its
    /// leading `#` lines (a servo log's servo and load). A format with no place for
    /// notes refuses rather than lose it.
    fn note(&mut self, name: &str, _text: &str) -> Result<(), IoError> {
        Err(IoError::new(format!(
            "this format keeps no notes (\"{name}\"): write a CSV"
        )))
    }
    /// The robot the rows are of (URDF text), before the first row: a format with a
    /// place for it keeps it (MCAP: `/robot_description`, for the viewers); a CSV
    /// keeps its rows only (a robot is named where the run's report names it).
    fn describe(&mut self, _urdf: &str) -> Result<(), IoError> {
        Ok(())
    }
}

impl RowSink for CsvWriter {
    fn write_row(&mut self, row: &[f64]) -> Result<(), IoError> {
        CsvWriter::write_row(self, row)
    }
    fn finish(self: Box<Self>) -> Result<(), IoError> {
        CsvWriter::finish(*self)
    }
    fn discard(self: Box<Self>) {
        CsvWriter::discard(*self)
    }
}

/// Opens a recording (kept, with what it holds, if the run fails) at a path, for
/// columns.
pub type RecordingOpener = fn(&Path, &[String]) -> Result<Box<dyn RowSink>, IoError>;

/// The formats registered besides CSV: (extension, lower case; opener).
static FORMATS: Mutex<Vec<(&str, RecordingOpener)>> = Mutex::new(Vec::new());

/// The "extension" of an output that is a folder ([`is_folder_output`]): a rosbag2
/// bag, in the `twinloop` command.
pub const FOLDER: &str = "/";

/// Is `path` an output written as a folder: its name ends in `/` (`--out run/`: a
/// folder, new or empty, that the recording fills), or it names an existing folder.
/// (A plain file can be neither, so no CSV or MCAP name is taken.)
pub fn is_folder_output(path: &Path) -> bool {
    use std::os::unix::ffi::OsStrExt;
    path.as_os_str().as_bytes().ends_with(b"/") || path.is_dir()
}

/// Write recordings whose path ends in `.EXTENSION` (any case) with `open`
/// ([`FOLDER`]: the outputs that are folders).
pub fn register_recording_format(extension: &'static str, open: RecordingOpener) {
    let mut formats = FORMATS.lock().unwrap_or_else(|e| e.into_inner());
    formats.retain(|(e, _)| *e != extension);
    formats.push((extension, open));
}

/// Is a format other than CSV registered for `path`'s extension?
pub fn registered(path: &Path) -> bool {
    opener(path).is_some()
}

fn opener(path: &Path) -> Option<RecordingOpener> {
    let ext = if is_folder_output(path) {
        FOLDER.to_string()
    } else {
        path.extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())?
    };
    let formats = FORMATS.lock().unwrap_or_else(|e| e.into_inner());
    formats.iter().find(|(e, _)| *e == ext).map(|(_, o)| *o)
}

/// A recording at `path`: in the format registered for its extension, else CSV
/// ([`CsvWriter::recording`]: every row on disk at once, kept if the run fails). A
/// folder output with no format registered for it is refused.
pub fn open_recording(path: &Path, columns: &[String]) -> Result<Box<dyn RowSink>, IoError> {
    match opener(path) {
        Some(open) => open(path, columns),
        None if is_folder_output(path) => Err(IoError::new(
            "is a folder: this program writes recordings to files (a CSV)",
        )
        .in_file(path)),
        None => Ok(Box::new(CsvWriter::recording(path, columns)?)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A format that writes nothing but counts the rows it is given, as a CSV of
    /// them: enough to see the extension pick it.
    fn counting(path: &Path, columns: &[String]) -> Result<Box<dyn RowSink>, IoError> {
        let csv = path.with_extension("counted.csv");
        Ok(Box::new(CsvWriter::recording(&csv, &columns[..1])?))
    }

    #[test]
    fn the_extension_picks_the_registered_format_and_csv_is_the_rest() {
        let dir = std::env::temp_dir().join(format!("twinloop-io-sink-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        register_recording_format("cnt", counting);
        let cols = vec!["t".to_string(), "q:a".to_string()];
        let mut w = open_recording(&dir.join("x.CNT"), &cols).unwrap();
        assert!(
            w.write_row(&[0.0, 1.0]).is_err(),
            "the counting format takes one column"
        );
        w.write_row(&[0.5]).unwrap();
        w.finish().unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.join("x.counted.csv")).unwrap(),
            "t\n0.5\n"
        );
        let mut w = open_recording(&dir.join("y.csv"), &cols).unwrap();
        w.write_row(&[0.0, 1.0]).unwrap();
        w.finish().unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.join("y.csv")).unwrap(),
            "t,q:a\n0.0,1.0\n"
        );
    }
}
