//! A twinloop table written as an MCAP file of ROS 2 messages that Foxglove and
//! Rerun open without twinloop: `/joint_states` (sensor_msgs/JointState), the
//! floating base on `/tf` (tf2_msgs/TFMessage, `world` -> the root link), each IMU on
//! `/imu` (sensor_msgs/Imu; `/imu/<link>` when there are several), every other
//! column on `/twinloop/columns` (std_msgs/Float64MultiArray whose one dimension's
//! label lists the column names; [`McapLog::create_grouped`] puts named groups of
//! columns on topics of their own), and the description once at the start on
//! `/robot_description` (std_msgs/String, the topic ROS 2's robot_state_publisher
//! publishes it on, with transient-local durability). A result file adds
//! attachments (the adapted URDF) and metadata records (its provenance).
use crate::bag::Bag;
use crate::cdr::CdrWriter;
use crate::error::LogError;
use crate::msgs::{self, JointState, Kind, Transform};
use mcap::records::MessageHeader;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use twinloop_io::output::{Output, PartialFile};

/// The QoS rosbag2 records for a transient-local topic (its `offered_qos_profiles`
/// channel metadata, YAML as rosbag2 Humble and later write it), so a ROS 2 player
/// re-publishes the description as latched.
const LATCHED_QOS: &str = "- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 2147483647\n    nsec: 4294967295\n  avoid_ros_namespace_conventions: false";

/// Which column feeds which message field, found once from the header.
#[derive(Debug, Default)]
struct Layout {
    t: usize,
    joints: Vec<String>,
    q: Vec<usize>,
    v: Option<Vec<usize>>,
    tau: Option<Vec<usize>>,
    base: Option<[usize; 7]>,
    /// Link name and the six gx..az columns of each IMU.
    imus: Vec<(String, [usize; 6])>,
    /// Every other column, on Float64MultiArray topics.
    arrays: Vec<Array>,
}

/// Columns written as one `std_msgs/Float64MultiArray` a row.
#[derive(Debug, Default)]
struct Array {
    topic: String,
    columns: Vec<usize>,
    /// The column names, comma-separated: the array's label (made once, not a row).
    label: String,
    channel: u16,
}

/// A group of columns written on a Float64MultiArray topic of its own (a result's
/// `/measured`, `/prior`, `/adapted`), its label naming them so that a reader needs
/// no `--topic TOPIC=NAMES`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ArrayTopic {
    pub topic: String,
    pub columns: Vec<String>,
}

fn layout(columns: &[String], groups: &[ArrayTopic]) -> Result<Layout, LogError> {
    let find = |n: &str| columns.iter().position(|c| c == n);
    let mut l = Layout {
        t: find("t").ok_or_else(|| LogError::new("the table has no t column"))?,
        ..Layout::default()
    };
    let base_cols = ["x", "y", "z", "qx", "qy", "qz", "qw"].map(|s| find(&format!("q:base.{s}")));
    if base_cols.iter().all(Option::is_some) {
        l.base = Some(base_cols.map(|c| c.expect("checked")));
    }
    for (i, c) in columns.iter().enumerate() {
        if let Some(j) = c.strip_prefix("q:")
            && !j.starts_with("base.")
        {
            l.joints.push(j.to_string());
            l.q.push(i);
        }
        if let Some(link) = c.strip_prefix("imu:").and_then(|s| s.strip_suffix(".gx")) {
            let cols =
                ["gx", "gy", "gz", "ax", "ay", "az"].map(|s| find(&format!("imu:{link}.{s}")));
            if cols.iter().all(Option::is_some) {
                l.imus
                    .push((link.to_string(), cols.map(|c| c.expect("checked"))));
            }
        }
    }
    let all = |p: &str| -> Option<Vec<usize>> {
        l.joints.iter().map(|j| find(&format!("{p}{j}"))).collect()
    };
    l.v = all("v:").filter(|_| !l.joints.is_empty());
    l.tau = all("tau:").filter(|_| !l.joints.is_empty());
    let mut used = vec![l.t];
    used.extend(&l.q);
    used.extend(l.v.iter().flatten());
    used.extend(l.tau.iter().flatten());
    used.extend(l.base.iter().flatten());
    used.extend(l.imus.iter().flat_map(|(_, c)| c));
    for g in groups {
        let mut array = Array {
            topic: g.topic.clone(),
            ..Array::default()
        };
        for name in &g.columns {
            let i = find(name).ok_or_else(|| {
                LogError::new(format!("topic {}: the table has no column {name}", g.topic))
            })?;
            if used.contains(&i) {
                return Err(LogError::new(format!(
                    "topic {}: column {name} is written on another topic already",
                    g.topic
                )));
            }
            used.push(i);
            array.columns.push(i);
        }
        l.arrays.push(array);
    }
    let rest: Vec<usize> = (0..columns.len()).filter(|i| !used.contains(i)).collect();
    if !rest.is_empty() {
        l.arrays.push(Array {
            topic: "/twinloop/columns".into(),
            columns: rest,
            ..Array::default()
        });
    }
    for a in &mut l.arrays {
        let names: Vec<&str> = a.columns.iter().map(|&i| columns[i].as_str()).collect();
        a.label = names.join(",");
    }
    Ok(l)
}

/// The channels a log declares, in file order: joints, tf, each IMU, the arrays (their
/// ids kept in the layout), the description.
struct Channels {
    joints: u16,
    tf: u16,
    imus: Vec<u16>,
    imu_topics: Vec<String>,
    description: Option<u16>,
    /// Each channel: id, topic, type, QoS (what a bag's metadata lists).
    declared: Vec<(u16, String, Kind, String)>,
}

impl Channels {
    /// Declare the schema and channel of each topic `layout` has (and the description's,
    /// latched, if `description`); 0 for a topic with no columns.
    fn declare(
        out: &mut mcap::Writer<BufWriter<File>>,
        layout: &mut Layout,
        description: bool,
    ) -> Result<Channels, LogError> {
        let mut declared: Vec<(u16, String, Kind, String)> = Vec::new();
        let mut channel =
            |kind: Kind, topic: &str, meta: &BTreeMap<String, String>| -> Result<u16, LogError> {
                let s =
                    out.add_schema(kind.schema_name(), "ros2msg", kind.schema_text().as_bytes())?;
                let id = out.add_channel(s, topic, "cdr", meta)?;
                let qos = meta
                    .get("offered_qos_profiles")
                    .cloned()
                    .unwrap_or_default();
                declared.push((id, topic.to_string(), kind, qos));
                Ok(id)
            };
        let none = BTreeMap::new();
        let joints = if layout.joints.is_empty() {
            0
        } else {
            channel(Kind::JointState, "/joint_states", &none)?
        };
        let tf = if layout.base.is_some() {
            channel(Kind::Tf, "/tf", &none)?
        } else {
            0
        };
        let mut imus = Vec::new();
        let mut imu_topics = Vec::new();
        for (link, _) in &layout.imus {
            let topic = if layout.imus.len() == 1 {
                "/imu".to_string()
            } else {
                format!("/imu/{link}")
            };
            imus.push(channel(Kind::Imu, &topic, &none)?);
            imu_topics.push(topic);
        }
        for a in &mut layout.arrays {
            a.channel = channel(Kind::MultiArray, &a.topic, &none)?;
        }
        let latched =
            BTreeMap::from([("offered_qos_profiles".to_string(), LATCHED_QOS.to_string())]);
        let description = if description {
            Some(channel(Kind::String, "/robot_description", &latched)?)
        } else {
            None
        };
        Ok(Channels {
            joints,
            tf,
            imus,
            imu_topics,
            description,
            declared,
        })
    }
}

/// An MCAP file being written row by row.
pub struct McapLog {
    path: PathBuf,
    /// Open until finished; `None` once closed.
    out: Option<mcap::Writer<BufWriter<File>>>,
    /// Where it goes once complete (written as `FILE.partial` until then).
    place: Option<PartialFile>,
    /// Kept (closed and named) when dropped unfinished with a row in it.
    recording: bool,
    rows: u64,
    layout: Layout,
    columns: Vec<String>,
    cdr: CdrWriter,
    joints: JointState,
    tf: Vec<Transform>,
    imu: msgs::Imu,
    extra: Vec<f64>,
    /// Channel ids: joints, tf, each IMU, description (the arrays' are in `layout`).
    ch_joints: u16,
    ch_tf: u16,
    ch_imus: Vec<u16>,
    imu_topics: Vec<String>,
    ch_description: Option<u16>,
    /// A rosbag2 folder's metadata, when the output is one.
    bag: Option<Bag>,
    sequence: u32,
    wrote_description: bool,
    description: Option<String>,
}

impl McapLog {
    /// The writer while the log is open; a write after it was finished or
    /// discarded is an error naming the file, not a panic.
    fn open_writer<'a>(
        out: &'a mut Option<mcap::Writer<BufWriter<File>>>,
        path: &Path,
    ) -> Result<&'a mut mcap::Writer<BufWriter<File>>, LogError> {
        out.as_mut()
            .ok_or_else(|| LogError::new("the log is already closed").in_file(path))
    }

    /// Create `path` for rows of `columns` (a `t` column and twinloop's names);
    /// `description` (URDF text) goes on `/robot_description`, `root` names the
    /// floating base's frame on `/tf`.
    pub fn create(
        path: &Path,
        columns: &[String],
        description: Option<&str>,
        root: &str,
    ) -> Result<McapLog, LogError> {
        McapLog::create_grouped(path, columns, description, root, &[])
    }

    /// [`McapLog::create`], with `groups` of columns on Float64MultiArray topics of
    /// their own (the other columns no ROS type takes stay on `/twinloop/columns`).
    pub fn create_grouped(
        path: &Path,
        columns: &[String],
        description: Option<&str>,
        root: &str,
        groups: &[ArrayTopic],
    ) -> Result<McapLog, LogError> {
        let err = |e: LogError| e.in_file(path);
        let mut layout = layout(columns, groups).map_err(err)?;
        let (mut bag, file_path) = if twinloop_io::sink::is_folder_output(path) {
            let (bag, file) = Bag::open(path)?;
            (Some(bag), file)
        } else {
            (None, path.to_path_buf())
        };
        let (place, file) = PartialFile::open(&Output::resolve("", &file_path)?)?;
        let mut out = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("ros2")
            .library(concat!("twinloop ", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))
            .map_err(|e| err(e.into()))?;
        let ch = Channels::declare(&mut out, &mut layout, description.is_some()).map_err(err)?;
        if let Some(bag) = &mut bag {
            for (id, topic, kind, qos) in &ch.declared {
                bag.channel(*id, topic, *kind, qos);
            }
        }
        let joints = JointState {
            names: layout.joints.clone(),
            ..JointState::default()
        };
        Ok(McapLog {
            path: path.to_path_buf(),
            out: Some(out),
            place: Some(place),
            recording: false,
            rows: 0,
            columns: columns.to_vec(),
            cdr: CdrWriter::new(),
            joints,
            tf: vec![Transform {
                parent: "world".into(),
                child: root.to_string(),
                ..Transform::default()
            }],
            imu: msgs::Imu::default(),
            extra: Vec::new(),
            layout,
            ch_joints: ch.joints,
            ch_tf: ch.tf,
            ch_imus: ch.imus,
            imu_topics: ch.imu_topics,
            ch_description: ch.description,
            bag,
            sequence: 0,
            wrote_description: false,
            description: description.map(str::to_string),
        })
    }

    fn emit(&mut self, channel: u16, time: i64) -> Result<(), LogError> {
        self.sequence += 1;
        if let Some(bag) = &mut self.bag {
            bag.count(channel, time);
        }
        let header = MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: time as u64,
            publish_time: time as u64,
        };
        let out = Self::open_writer(&mut self.out, &self.path)?;
        out.write_to_known_channel(&header, self.cdr.bytes())
            .map_err(|e| LogError::from(e).in_file(&self.path))
    }

    /// Write one row (as many values as columns; `t` in seconds is the stamp).
    pub fn write_row(&mut self, row: &[f64]) -> Result<(), LogError> {
        self.write_row_on(row, |_| true)
    }

    /// Write one row's messages on the topics `keep` takes only (`/joint_states`,
    /// `/tf`, the IMUs' and the arrays' topics; the description goes at the first
    /// row all the same): for a result whose parts have times of their own (`adapt`'s
    /// four fall angles, then its lean), each row filling its part's topics.
    pub fn write_row_on(
        &mut self,
        row: &[f64],
        keep: impl Fn(&str) -> bool,
    ) -> Result<(), LogError> {
        if row.len() != self.columns.len() {
            return Err(LogError::new(format!(
                "a row of {} values for {} columns",
                row.len(),
                self.columns.len()
            ))
            .in_file(&self.path));
        }
        let t = row[self.layout.t];
        if !(t.is_finite() && t >= 0.0) {
            return Err(LogError::new(format!(
                "t = {t}: a log's time is a finite, non-negative number of seconds"
            ))
            .in_file(&self.path));
        }
        let time = (t * 1e9).round() as i64;
        if let (false, Some(ch), Some(d)) = (
            self.wrote_description,
            self.ch_description,
            &self.description,
        ) {
            self.cdr.reset();
            msgs::encode_string(&mut self.cdr, d);
            self.emit(ch, time)?;
            self.wrote_description = true;
        }
        if !self.layout.joints.is_empty() && keep("/joint_states") {
            let l = &self.layout;
            let j = &mut self.joints;
            j.stamp_ns = time;
            j.position.clear();
            j.position.extend(l.q.iter().map(|&i| row[i]));
            j.velocity.clear();
            j.velocity.extend(l.v.iter().flatten().map(|&i| row[i]));
            j.effort.clear();
            j.effort.extend(l.tau.iter().flatten().map(|&i| row[i]));
            self.cdr.reset();
            j.encode(&mut self.cdr, "");
            self.emit(self.ch_joints, time)?;
        }
        if let Some(b) = self.layout.base.filter(|_| keep("/tf")) {
            let tr = &mut self.tf[0];
            tr.stamp_ns = time;
            tr.translation = [row[b[0]], row[b[1]], row[b[2]]];
            tr.rotation = [row[b[3]], row[b[4]], row[b[5]], row[b[6]]];
            self.cdr.reset();
            msgs::encode_tf(&mut self.cdr, &self.tf);
            self.emit(self.ch_tf, time)?;
        }
        for k in 0..self.layout.imus.len() {
            if !keep(&self.imu_topics[k]) {
                continue;
            }
            let (link, c) = &self.layout.imus[k];
            if self.imu.frame != *link {
                self.imu.frame = link.clone();
            }
            self.imu.stamp_ns = time;
            self.imu.orientation = [0.0, 0.0, 0.0, 1.0];
            self.imu.angular_velocity = [row[c[0]], row[c[1]], row[c[2]]];
            self.imu.linear_acceleration = [row[c[3]], row[c[4]], row[c[5]]];
            self.cdr.reset();
            self.imu.encode(&mut self.cdr, false);
            self.emit(self.ch_imus[k], time)?;
        }
        for k in 0..self.layout.arrays.len() {
            let a = &self.layout.arrays[k];
            if !keep(&a.topic) {
                continue;
            }
            self.extra.clear();
            self.extra.extend(a.columns.iter().map(|&i| row[i]));
            self.cdr.reset();
            msgs::encode_multi_array(&mut self.cdr, &a.label, &self.extra);
            let ch = a.channel;
            self.emit(ch, time)?;
        }
        self.rows += 1;
        Ok(())
    }

    /// Attach a file (`name`, its media type, its bytes): a result's adapted URDF. A
    /// reader lists attachments apart from the messages (`mcap` Python:
    /// `reader.iter_attachments()`; Foxglove: the file's attachments).
    pub fn attach(&mut self, name: &str, media_type: &str, data: &[u8]) -> Result<(), LogError> {
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        let attachment = mcap::Attachment {
            log_time: now,
            create_time: now,
            name: name.to_string(),
            media_type: media_type.to_string(),
            data: std::borrow::Cow::Borrowed(data),
        };
        let out = Self::open_writer(&mut self.out, &self.path)?;
        out.attach(&attachment)
            .map_err(|e| LogError::from(e).in_file(&self.path))
    }

    /// Write a metadata record (`name` and its string pairs): a result's provenance.
    pub fn metadata(
        &mut self,
        name: &str,
        pairs: BTreeMap<String, String>,
    ) -> Result<(), LogError> {
        let record = mcap::records::Metadata {
            name: name.to_string(),
            metadata: pairs,
        };
        let out = Self::open_writer(&mut self.out, &self.path)?;
        out.write_metadata(&record)
            .map_err(|e| LogError::from(e).in_file(&self.path))
    }

    /// Put `urdf` on `/robot_description` (once, at the first row's time), as
    /// `description` does at [`McapLog::create`]: for a recording opened where the
    /// robot is not known yet ([`open_mcap_recording`]). Before the first row only.
    pub fn describe(&mut self, urdf: &str) -> Result<(), LogError> {
        if self.rows > 0 || self.wrote_description {
            return Err(
                LogError::new("the robot description goes before the first row")
                    .in_file(&self.path),
            );
        }
        if self.ch_description.is_none() {
            let out = Self::open_writer(&mut self.out, &self.path)?;
            let latched =
                BTreeMap::from([("offered_qos_profiles".to_string(), LATCHED_QOS.to_string())]);
            let kind = Kind::String;
            let add = |out: &mut mcap::Writer<BufWriter<File>>| -> Result<u16, LogError> {
                let s =
                    out.add_schema(kind.schema_name(), "ros2msg", kind.schema_text().as_bytes())?;
                Ok(out.add_channel(s, "/robot_description", "cdr", &latched)?)
            };
            let id = add(out).map_err(|e| e.in_file(&self.path))?;
            if let Some(bag) = &mut self.bag {
                bag.channel(id, "/robot_description", kind, LATCHED_QOS);
            }
            self.ch_description = Some(id);
        }
        self.description = Some(urdf.to_string());
        Ok(())
    }

    /// A recording: dropped unfinished (an error, Ctrl-C) with a row in it, the file is
    /// closed and given its name all the same: nothing recorded is lost.
    pub fn recording(mut self) -> McapLog {
        self.recording = true;
        self
    }

    /// Write the summary, make the file durable and give it its name.
    pub fn finish(mut self) -> Result<(), LogError> {
        self.close()
    }

    /// Give up: nothing is written, an older file of the name stays.
    pub fn discard(mut self) {
        self.recording = false;
    }

    fn close(&mut self) -> Result<(), LogError> {
        let (Some(mut out), Some(place)) = (self.out.take(), self.place.take()) else {
            return Ok(());
        };
        let in_file = |e: LogError| e.in_file(&self.path);
        out.finish().map_err(|e| in_file(e.into()))?;
        let file = out
            .into_inner()
            .into_inner()
            .map_err(|e| in_file(LogError::new(format!("cannot write: {}", e.error()))))?;
        place.commit(file)?;
        match self.bag.take() {
            Some(bag) => bag.finish(),
            None => Ok(()),
        }
    }
}

impl Drop for McapLog {
    fn drop(&mut self) {
        if self.recording && self.rows > 0 {
            let _ = self.close();
        }
        // Otherwise the partial file goes with `place`.
    }
}

/// Write `table` to `path` as MCAP (see the module doc for the topics).
pub fn write_mcap(
    path: &Path,
    table: &Table,
    description: Option<&str>,
    root: &str,
) -> Result<(), LogError> {
    let mut log = McapLog::create(path, &table.columns, description, root)?;
    for row in &table.rows {
        log.write_row(row)?;
    }
    log.finish()
}

use twinloop_io::Table;

impl twinloop_io::RowSink for McapLog {
    fn write_row(&mut self, row: &[f64]) -> Result<(), twinloop_io::IoError> {
        Ok(McapLog::write_row(self, row)?)
    }
    fn finish(self: Box<Self>) -> Result<(), twinloop_io::IoError> {
        Ok(McapLog::finish(*self)?)
    }
    fn discard(self: Box<Self>) {
        McapLog::discard(*self)
    }
    /// A metadata record `name` whose one pair is `text`.
    fn note(&mut self, name: &str, text: &str) -> Result<(), twinloop_io::IoError> {
        let pairs = BTreeMap::from([("text".to_string(), text.to_string())]);
        Ok(self.metadata(name, pairs)?)
    }
    fn describe(&mut self, urdf: &str) -> Result<(), twinloop_io::IoError> {
        Ok(McapLog::describe(self, urdf)?)
    }
}

/// A recording as MCAP ([`twinloop_io::sink::RecordingOpener`]: what a program
/// registers for `.mcap` with [`twinloop_io::sink::register_recording_format`]):
/// kept, closed properly, if the run fails after a row; the floating base, if
/// any, under `base_link`.
pub fn open_mcap_recording(
    path: &Path,
    columns: &[String],
) -> Result<Box<dyn twinloop_io::RowSink>, twinloop_io::IoError> {
    Ok(Box::new(
        McapLog::create(path, columns, None, "base_link")?.recording(),
    ))
}
