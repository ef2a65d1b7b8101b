//! A recording written as a rosbag2 folder, which `ros2 bag info|play` and the
//! `rosbags` library open (they read a folder, not a bare `.mcap`): `NAME/NAME_0.mcap`
//! (rosbag2's own name for the first file of a bag called NAME) and
//! `NAME/metadata.yaml`, written once the MCAP is complete.
//!
//! The metadata is rosbag2's `BagMetadata` at version 5, the one ROS 2 Humble
//! writes and every later rosbag2 still reads (rosbag2_storage's `yaml.hpp`: from
//! version 7 a reader takes a `type_description_hash` if there is one, from version 9
//! the QoS as a list; at 5 the QoS is one YAML string, as in the MCAP's channel
//! metadata). Keys: `version`, `storage_identifier`, `duration`, `starting_time`,
//! `message_count`, `topics_with_message_count`, `compression_format`,
//! `compression_mode`, `relative_file_paths` and `files` (per file: path, start,
//! duration, count).
use crate::error::LogError;
use crate::msgs::Kind;
use std::path::{Path, PathBuf};

/// One topic of the bag: what `topics_with_message_count` lists.
struct Topic {
    channel: u16,
    name: String,
    kind: Kind,
    /// The QoS the recorder offered (rosbag2's YAML), or empty.
    qos: String,
    count: u64,
}

/// The folder being filled and what its `metadata.yaml` will say.
pub(crate) struct Bag {
    dir: PathBuf,
    /// `NAME_0.mcap`.
    file: String,
    /// Made by this bag (removed again if it ends with nothing in it).
    made: bool,
    topics: Vec<Topic>,
    /// First and last message time, ns.
    span: Option<(i64, i64)>,
    written: bool,
}

impl Bag {
    /// Open the folder `dir` (made if new; an existing one must be empty or hold
    /// a bag: its `metadata.yaml` and `.mcap` files, which are replaced). Returns the
    /// bag and the path of its MCAP file.
    pub(crate) fn open(dir: &Path) -> Result<(Bag, PathBuf), LogError> {
        let name = dir
            .file_name()
            .and_then(|n| n.to_str())
            .filter(|n| !n.is_empty() && *n != "." && *n != "..")
            .ok_or_else(|| {
                LogError::new("a rosbag2 folder needs a name (run/, not ./ or /)").in_file(dir)
            })?;
        let made = !dir.exists();
        if made {
            std::fs::create_dir(dir).map_err(|e| {
                LogError::new(format!("cannot make the bag's folder: {e}")).in_file(dir)
            })?;
        } else {
            refuse_foreign_files(dir)?;
        }
        let file = format!("{name}_0.mcap");
        let path = dir.join(&file);
        Ok((
            Bag {
                dir: dir.to_path_buf(),
                file,
                made,
                topics: Vec::new(),
                span: None,
                written: false,
            },
            path,
        ))
    }

    /// A channel the MCAP declares.
    pub(crate) fn channel(&mut self, channel: u16, name: &str, kind: Kind, qos: &str) {
        self.topics.push(Topic {
            channel,
            name: name.to_string(),
            kind,
            qos: qos.to_string(),
            count: 0,
        });
    }

    /// A message written on `channel` at `time` ns.
    pub(crate) fn count(&mut self, channel: u16, time: i64) {
        if let Some(t) = self.topics.iter_mut().find(|t| t.channel == channel) {
            t.count += 1;
        }
        self.span = Some(match self.span {
            Some((a, b)) => (a.min(time), b.max(time)),
            None => (time, time),
        });
    }

    /// Write `metadata.yaml` (after the MCAP is in place: a reader that finds the
    /// metadata finds its file).
    pub(crate) fn finish(mut self) -> Result<(), LogError> {
        self.written = true;
        let text = self.metadata();
        twinloop_io::output::write_atomic(&self.dir.join("metadata.yaml"), text)?;
        Ok(())
    }

    fn metadata(&self) -> String {
        let (start, end) = self.span.unwrap_or((0, 0));
        let duration = end - start;
        let count: u64 = self.topics.iter().map(|t| t.count).sum();
        let mut y = String::from("rosbag2_bagfile_information:\n  version: 5\n");
        y += "  storage_identifier: mcap\n";
        y += &format!("  duration:\n    nanoseconds: {duration}\n");
        y += &format!("  starting_time:\n    nanoseconds_since_epoch: {start}\n");
        y += &format!("  message_count: {count}\n  topics_with_message_count:\n");
        for t in &self.topics {
            y += &format!(
                "    - topic_metadata:\n        name: {}\n        type: {}\n        \
                 serialization_format: cdr\n        offered_qos_profiles: {}\n      \
                 message_count: {}\n",
                t.name,
                t.kind.schema_name(),
                quoted(&t.qos),
                t.count
            );
        }
        y += "  compression_format: \"\"\n  compression_mode: \"\"\n";
        y += &format!("  relative_file_paths:\n    - {}\n", self.file);
        y += &format!(
            "  files:\n    - path: {}\n      starting_time:\n        nanoseconds_since_epoch: \
             {start}\n      duration:\n        nanoseconds: {duration}\n      message_count: {count}\n",
            self.file
        );
        y
    }
}

impl Drop for Bag {
    fn drop(&mut self) {
        // A bag that never got its metadata leaves no empty folder it made.
        if self.made && !self.written {
            let _ = std::fs::remove_dir(&self.dir);
        }
    }
}

/// A YAML double-quoted scalar (the QoS text's line breaks as `\n`).
fn quoted(s: &str) -> String {
    let mut q = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => q += "\\\"",
            '\\' => q += "\\\\",
            '\n' => q += "\\n",
            c => q.push(c),
        }
    }
    q + "\""
}

/// An existing folder is written into only if it is empty or holds a bag (so a
/// mistyped `--out docs/` does not fill a folder of other files).
fn refuse_foreign_files(dir: &Path) -> Result<(), LogError> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| LogError::new(format!("cannot read the folder: {e}")).in_file(dir))?;
    for e in entries.flatten() {
        let name = e.file_name();
        let name = name.to_string_lossy();
        if name != "metadata.yaml" && !name.ends_with(".mcap") && !name.ends_with(".partial") {
            return Err(LogError::new(format!(
                "the folder holds {name}, which is not part of a bag: a rosbag2 output is a new or empty folder"
            ))
            .in_file(dir));
        }
    }
    Ok(())
}
