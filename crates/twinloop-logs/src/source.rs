//! Where messages come from: an MCAP file, or a rosbag2 folder whose
//! `metadata.yaml` names MCAP or SQLite (`.db3`) files.
//!
//! MCAP records are read by the `mcap` crate's sans-io linear reader, which inflates
//! zstd and lz4 chunks (the compressions the MCAP spec names and the Python writer
//! and rosbag2 use) and checks chunk CRCs; a message record's 22-byte header
//! (channel id u16, sequence u32, log time u64, publish time u64, all little-endian:
//! the MCAP spec's "Message" record) is parsed here so no message is copied.
//! rosbag2's SQLite storage is its `topics(id, name, type, serialization_format, ..)`
//! and `messages(id, topic_id, timestamp, data)` tables (rosbag2_storage_sqlite3's
//! schema).
use crate::error::LogError;
use mcap::records::op;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender, SyncSender};

/// A topic as the container declares it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Channel {
    pub topic: String,
    /// The schema (message type) name, `sensor_msgs/msg/JointState`.
    pub schema: String,
    /// The message encoding, `cdr` for ROS 2.
    pub encoding: String,
}

/// Is `path` a log twinloop reads through this crate (rather than a CSV table)?
/// An `.mcap` or `.db3` file, or a folder holding a rosbag2 `metadata.yaml`.
pub fn is_log(path: &Path) -> bool {
    if path.is_dir() {
        return path.join("metadata.yaml").is_file();
    }
    matches!(
        path.extension().and_then(|e| e.to_str()),
        Some("mcap" | "MCAP" | "db3")
    )
}

/// The MCAP Header's `library` of the files twinloop writes (`twinloop VERSION`).
pub const WRITER: &str = "twinloop ";

/// Call `f(channel, log_time_ns, cdr_bytes)` for every message of the log at `path`,
/// in file order (a bag folder's files in the order its metadata lists them).
/// Returns whether twinloop wrote every file: then each stamp is its table's `t`
/// (write.rs), which a reader keeps rather than counting from the first row.
pub fn for_each_message(
    path: &Path,
    mut f: impl FnMut(&Channel, i64, &[u8]) -> Result<(), LogError>,
) -> Result<bool, LogError> {
    let files = if path.is_dir() {
        bag_files(path)?
    } else {
        vec![path.to_path_buf()]
    };
    let mut ours = true;
    for file in &files {
        let r = match file.extension().and_then(|e| e.to_str()) {
            Some("db3") => sqlite_messages(file, &mut f).map(|()| false),
            _ => mcap_messages(file, &mut f),
        };
        ours &= r.map_err(|e| e.in_file(file))?;
    }
    Ok(ours)
}

/// The storage files of a rosbag2 folder, from its `metadata.yaml`
/// (`storage_identifier` and `relative_file_paths`, rosbag2's BagMetadata fields).
/// Only those keys are read, so no YAML library is needed.
fn bag_files(dir: &Path) -> Result<Vec<PathBuf>, LogError> {
    let meta = dir.join("metadata.yaml");
    let text = twinloop_io::input::read_to_string(&meta)
        .map_err(|e| LogError::new(format!("cannot read: {e}")).in_file(&meta))?;
    let mut files = Vec::new();
    let mut in_paths = false;
    let mut storage = String::new();
    for line in text.lines() {
        let l = line.trim();
        if let Some(v) = l.strip_prefix("storage_identifier:") {
            storage = v.trim().trim_matches(['"', '\'']).to_string();
        }
        if let Some(v) = l.strip_prefix("compression_format:") {
            let v = v.trim().trim_matches(['"', '\'']);
            if !v.is_empty() {
                return Err(LogError::new(format!(
                    "the bag is compressed by rosbag2 ({v}): decompress it first (ros2 bag decompress)"
                ))
                .in_file(&meta));
            }
        }
        if l.starts_with("relative_file_paths:") {
            in_paths = true;
            continue;
        }
        if in_paths {
            match l.strip_prefix("- ") {
                Some(p) => files.push(dir.join(p.trim().trim_matches(['"', '\'']))),
                None => in_paths = false,
            }
        }
    }
    if !matches!(storage.as_str(), "mcap" | "sqlite3") {
        return Err(LogError::new(format!(
            "storage_identifier \"{storage}\": twinloop reads mcap and sqlite3 bags"
        ))
        .in_file(&meta));
    }
    if files.is_empty() {
        return Err(LogError::new("relative_file_paths lists no file").in_file(&meta));
    }
    if !cfg!(feature = "sqlite") && storage == "sqlite3" {
        return Err(LogError::new(
            "this twinloop was built without SQLite bags (cargo feature `sqlite`)",
        )
        .in_file(&meta));
    }
    Ok(files)
}

/// The topic and log time of the last message read, named when a later record is bad.
struct Last {
    topic: Option<String>,
    time: i64,
}

impl Last {
    fn blame(&self, e: LogError) -> LogError {
        match &self.topic {
            Some(t) => LogError {
                message: format!("after this message: {}", e.message),
                ..e.at(t, self.time)
            },
            None => e,
        }
    }
}

/// Bytes of records the reading thread hands over at a time: large enough that the
/// hand-over costs nothing per message, small enough to stay in cache.
const BATCH_BYTES: usize = 1 << 20;

/// Batches in flight between the two threads (so at most a few MB held).
const BATCHES_IN_FLIGHT: usize = 4;

/// The messages of an MCAP file on two threads: one reads the file and inflates its
/// chunks (the `mcap` crate, CRCs checked), the other decodes what it hands over, so
/// on two cores the decompression's ~40 % of the work overlaps the decoding's ~60 %
/// (BENCHMARKS.md, "Reading logs"). The records cross as in the file, `opcode (u8),
/// length (u64 LE), body`, in reused buffers.
fn mcap_messages(
    path: &Path,
    f: &mut impl FnMut(&Channel, i64, &[u8]) -> Result<(), LogError>,
) -> Result<bool, LogError> {
    let file = std::fs::File::open(path).map_err(|e| LogError::new(format!("cannot read: {e}")))?;
    if let Ok(meta) = file.metadata() {
        // An output is never written over a log this command read.
        twinloop_io::input::note_read(path, &meta);
    }
    let (to_decoder, batches) = std::sync::mpsc::sync_channel(BATCHES_IN_FLIGHT);
    let (to_reader, spare) = std::sync::mpsc::channel();
    std::thread::scope(|scope| {
        scope.spawn(move || inflate(file, &to_decoder, &spare));
        // `batches` is dropped on return, so a failed decode stops the reader too.
        decode_batches(batches, &to_reader, f)
    })
}

/// The reading thread: every schema, channel and message record, in file order, in
/// batches; an error ends the stream (after the records read before it).
fn inflate(
    mut file: std::fs::File,
    out: &SyncSender<Result<Vec<u8>, LogError>>,
    spare: &Receiver<Vec<u8>>,
) {
    let mut reader = LinearReader::new();
    let mut batch = Vec::with_capacity(BATCH_BYTES);
    while let Some(event) = reader.next_event() {
        let error = match event {
            Ok(LinearReadEvent::ReadRequest(n)) => match file.read(reader.insert(n)) {
                Ok(got) => {
                    reader.notify_read(got);
                    continue;
                }
                Err(e) => LogError::new(format!("cannot read: {e}")),
            },
            Ok(LinearReadEvent::Record { data, opcode }) => {
                if matches!(opcode, op::MESSAGE | op::SCHEMA | op::CHANNEL | op::HEADER) {
                    batch.push(opcode);
                    batch.extend_from_slice(&(data.len() as u64).to_le_bytes());
                    batch.extend_from_slice(data);
                }
                if batch.len() >= BATCH_BYTES {
                    let next = spare
                        .try_recv()
                        .unwrap_or_else(|_| Vec::with_capacity(BATCH_BYTES));
                    if out.send(Ok(std::mem::replace(&mut batch, next))).is_err() {
                        return;
                    }
                }
                continue;
            }
            Err(e) => truncation(e),
        };
        let _ = out.send(Ok(batch));
        let _ = out.send(Err(error));
        return;
    }
    let _ = out.send(Ok(batch));
}

/// The decoding thread's side: each record of each batch to `f`; the reader's error
/// names the last message decoded before it. Whether twinloop wrote the file (its
/// Header record's `library`).
fn decode_batches(
    batches: Receiver<Result<Vec<u8>, LogError>>,
    spare: &Sender<Vec<u8>>,
    f: &mut impl FnMut(&Channel, i64, &[u8]) -> Result<(), LogError>,
) -> Result<bool, LogError> {
    let mut ours = false;
    let mut schemas: HashMap<u16, String> = HashMap::new();
    let mut channels: HashMap<u16, Channel> = HashMap::new();
    let mut last = Last {
        topic: None,
        time: 0,
    };
    for batch in batches {
        let mut batch = batch.map_err(|e| last.blame(e))?;
        let mut rest = &batch[..];
        while let [opcode, tail @ ..] = rest {
            // Our own batch encoding (opcode, length, record): a short batch would
            // be a bug here, still an error rather than a panic.
            let Some((len, tail)) = tail.split_first_chunk::<8>() else {
                return Err(LogError::new("a record batch cut short"));
            };
            let len = u64::from_le_bytes(*len) as usize;
            if len > tail.len() {
                return Err(LogError::new("a record batch cut short"));
            }
            let (data, after) = tail.split_at(len);
            rest = after;
            match *opcode {
                op::MESSAGE => {
                    let (id, log_time, payload) = message_record(data)?;
                    let ch = channels.get(&id).ok_or_else(|| {
                        LogError::new(format!(
                            "a message on channel {id}, which no record declares"
                        ))
                    })?;
                    f(ch, log_time, payload).map_err(|e| e.at(&ch.topic, log_time))?;
                    if last.topic.as_deref() != Some(ch.topic.as_str()) {
                        last.topic = Some(ch.topic.clone());
                    }
                    last.time = log_time;
                }
                opcode => {
                    ours |= declare(opcode, data, &mut schemas, &mut channels)
                        .map_err(|e| last.blame(e))?;
                }
            }
        }
        batch.clear();
        let _ = spare.send(batch);
    }
    Ok(ours)
}

/// A schema or channel record into the tables the messages are decoded by; a
/// header record: whether twinloop wrote the file.
fn declare(
    opcode: u8,
    data: &[u8],
    schemas: &mut HashMap<u16, String>,
    channels: &mut HashMap<u16, Channel>,
) -> Result<bool, LogError> {
    match mcap::parse_record(opcode, data)? {
        mcap::records::Record::Header(h) => return Ok(h.library.starts_with(WRITER)),
        mcap::records::Record::Schema { header, .. } => {
            schemas.insert(header.id, header.name);
        }
        mcap::records::Record::Channel(c) => {
            let schema = schemas.get(&c.schema_id).cloned().unwrap_or_default();
            channels.insert(
                c.id,
                Channel {
                    topic: c.topic,
                    schema,
                    encoding: c.message_encoding,
                },
            );
        }
        _ => {}
    }
    Ok(false)
}

/// The first metadata record called `name` in the log at `path` (its string pairs),
/// or `None`: twinloop's own notes on a log, such as a servo log's first lines. The
/// chunks are passed over, not inflated; SQLite bags hold no metadata records.
pub fn metadata(path: &Path, name: &str) -> Result<Option<BTreeMap<String, String>>, LogError> {
    let files = if path.is_dir() {
        bag_files(path)?
    } else {
        vec![path.to_path_buf()]
    };
    for file in files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e != "db3"))
    {
        if let Some(m) = mcap_metadata(file, name).map_err(|e| e.in_file(file))? {
            return Ok(Some(m));
        }
    }
    Ok(None)
}

fn mcap_metadata(path: &Path, name: &str) -> Result<Option<BTreeMap<String, String>>, LogError> {
    let mut file =
        std::fs::File::open(path).map_err(|e| LogError::new(format!("cannot read: {e}")))?;
    let mut reader =
        LinearReader::new_with_options(LinearReaderOptions::default().with_emit_chunks(true));
    while let Some(event) = reader.next_event() {
        match event.map_err(truncation)? {
            LinearReadEvent::ReadRequest(n) => {
                let got = file
                    .read(reader.insert(n))
                    .map_err(|e| LogError::new(format!("cannot read: {e}")))?;
                reader.notify_read(got);
            }
            LinearReadEvent::Record {
                data,
                opcode: op::METADATA,
            } => {
                if let mcap::records::Record::Metadata(m) = mcap::parse_record(op::METADATA, data)?
                    && m.name == name
                {
                    return Ok(Some(m.metadata));
                }
            }
            LinearReadEvent::Record { .. } => {}
        }
    }
    Ok(None)
}

/// An MCAP error, worded for the most common cause when it is an early end.
fn truncation(e: mcap::McapError) -> LogError {
    let s = e.to_string();
    if s.contains("ended in the middle") || s.contains("end of file") {
        LogError::new(format!(
            "the file is cut short (a truncated chunk or record): {s}"
        ))
    } else {
        LogError::from(e)
    }
}

/// The MCAP spec's Message record: channel id, sequence, log time, publish time, data.
fn message_record(data: &[u8]) -> Result<(u16, i64, &[u8]), LogError> {
    if data.len() < 22 {
        return Err(LogError::new(
            "a message record shorter than its 22-byte header",
        ));
    }
    let id = u16::from_le_bytes([data[0], data[1]]);
    let log_time = u64::from_le_bytes([
        data[6], data[7], data[8], data[9], data[10], data[11], data[12], data[13],
    ]);
    Ok((id, log_time as i64, &data[22..]))
}

#[cfg(feature = "sqlite")]
fn sqlite_messages(
    path: &Path,
    f: &mut impl FnMut(&Channel, i64, &[u8]) -> Result<(), LogError>,
) -> Result<(), LogError> {
    use rusqlite::{Connection, OpenFlags};
    let sql = |e: rusqlite::Error| LogError::new(format!("SQLite: {e}"));
    let db = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY).map_err(sql)?;
    let mut channels: HashMap<i64, Channel> = HashMap::new();
    let mut st = db
        .prepare("SELECT id, name, type, serialization_format FROM topics")
        .map_err(sql)?;
    let mut rows = st.query([]).map_err(sql)?;
    while let Some(r) = rows.next().map_err(sql)? {
        let ch = Channel {
            topic: r.get(1).map_err(sql)?,
            schema: r.get(2).map_err(sql)?,
            encoding: r.get(3).map_err(sql)?,
        };
        channels.insert(r.get(0).map_err(sql)?, ch);
    }
    let mut st = db
        .prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id")
        .map_err(sql)?;
    let mut rows = st.query([]).map_err(sql)?;
    while let Some(r) = rows.next().map_err(sql)? {
        let id: i64 = r.get(0).map_err(sql)?;
        let time: i64 = r.get(1).map_err(sql)?;
        let ch = channels.get(&id).ok_or_else(|| {
            LogError::new(format!(
                "a message on topic id {id}, which the topics table lacks"
            ))
        })?;
        let data = r
            .get_ref(2)
            .map_err(sql)?
            .as_blob()
            .map_err(|e| sql(e.into()))?;
        f(ch, time, data).map_err(|e| e.at(&ch.topic, time))?;
    }
    Ok(())
}

#[cfg(not(feature = "sqlite"))]
fn sqlite_messages(
    _path: &Path,
    _f: &mut impl FnMut(&Channel, i64, &[u8]) -> Result<(), LogError>,
) -> Result<(), LogError> {
    Err(LogError::new(
        "this twinloop was built without SQLite bags (cargo feature `sqlite`)",
    ))
}
