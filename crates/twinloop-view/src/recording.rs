//! A recording as the page reads it: every column of a twinloop CSV, column after
//! column as little-endian f32 (half the bytes of f64, and more than the precision
//! a screen shows), with a note of which of the robot's `q:*` columns it lacks.

use crate::scene::SceneInfo;
use serde::Serialize;
use std::path::Path;
use twinloop_io::{IoError, Table};

/// The floating base's columns, position then quaternion (scalar last).
pub const BASE_COLUMNS: [&str; 7] = [
    "q:base.x",
    "q:base.y",
    "q:base.z",
    "q:base.qx",
    "q:base.qy",
    "q:base.qz",
    "q:base.qw",
];

/// What `recording/N.json` says of a recording.
#[derive(Debug, Clone, Serialize)]
pub struct RecordingInfo {
    /// The file name, shown on the page.
    pub name: String,
    pub rows: usize,
    pub columns: Vec<String>,
    /// The robot's `q:<joint>` columns the file lacks (those joints stay at zero).
    pub missing: Vec<String>,
    /// Whether all seven `q:base.*` columns are there.
    pub has_base: bool,
    /// Time span, s.
    pub t0: f64,
    pub t1: f64,
}

/// A recording ready to serve.
#[derive(Debug, Clone)]
pub struct Recording {
    pub info: RecordingInfo,
    /// Column-major f32 little-endian: column 0's rows, then column 1's, ...
    pub data: Vec<u8>,
}

impl Recording {
    /// Read a CSV and check it against the robot. A file without a `t` column or
    /// with no data rows is an error naming the file; missing joints are not (the
    /// page says which ones).
    pub fn read(path: &Path, scene: &SceneInfo) -> Result<Recording, IoError> {
        let table = Table::read(path)?;
        Recording::from_table(&table, path, scene)
    }

    pub fn from_table(table: &Table, path: &Path, scene: &SceneInfo) -> Result<Recording, IoError> {
        let Some(t) = table.column_index("t") else {
            return Err(IoError::new("no \"t\" column (time, s)").in_file(path));
        };
        if table.rows.is_empty() {
            return Err(IoError::new("no data rows").in_file(path));
        }
        // Time must be a number and not run backwards: the page finds frames by
        // bisection.
        let row_error = |r: usize, what: &str| {
            let mut e = table.row_error(r, what);
            e.file.get_or_insert_with(|| path.to_path_buf());
            e.column = Some("t".into());
            e
        };
        for r in 0..table.rows.len() {
            if !table.rows[r][t].is_finite() {
                return Err(row_error(r, "not a finite number"));
            }
            if r > 0 && table.rows[r][t] < table.rows[r - 1][t] {
                return Err(row_error(
                    r,
                    "time decreases (the rows must be in time order)",
                ));
            }
        }
        let missing: Vec<String> = scene
            .joints
            .iter()
            .map(|j| format!("q:{}", j.name))
            .filter(|c| table.column_index(c).is_none())
            .collect();
        let has_base = BASE_COLUMNS.iter().all(|c| table.column_index(c).is_some());
        let rows = table.rows.len();
        let mut data = Vec::with_capacity(rows * table.columns.len() * 4);
        for c in 0..table.columns.len() {
            for row in &table.rows {
                data.extend_from_slice(&(row[c] as f32).to_le_bytes());
            }
        }
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Ok(Recording {
            info: RecordingInfo {
                name,
                rows,
                columns: table.columns.clone(),
                missing,
                has_base,
                t0: table.rows[0][t],
                t1: table.rows[rows - 1][t],
            },
            data,
        })
    }

    /// A one-line warning when the recording lacks some of the robot's joints.
    pub fn warning(&self) -> Option<String> {
        let m = &self.info.missing;
        if m.is_empty() {
            return None;
        }
        let shown: Vec<&str> = m.iter().take(8).map(String::as_str).collect();
        let more = if m.len() > 8 {
            format!(" and {} more", m.len() - 8)
        } else {
            String::new()
        };
        Some(format!(
            "{}: {} of the robot's joint columns are missing ({}{more}); those joints stay at 0",
            self.info.name,
            m.len(),
            shown.join(", ")
        ))
    }
}
