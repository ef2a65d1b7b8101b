//! A log's messages as a twinloop table: one column group per message type, named as
//! every CSV twinloop reads names them (docs/architecture.md, "Data files").
use crate::error::LogError;
use crate::msgs::{self, JointState, Kind, Transform};
use crate::source::{self, Channel};
use crate::timebase::Series;
use std::collections::HashMap;
use std::path::Path;
use std::str::FromStr;
use twinloop_io::Table;

/// A topic to read, as `--topic` gives it: `TOPIC`, or `TOPIC=NAME,NAME,..` to name
/// the columns of a `std_msgs/Float64MultiArray`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicSpec {
    pub topic: String,
    pub columns: Option<Vec<String>>,
}

impl FromStr for TopicSpec {
    type Err = LogError;
    fn from_str(s: &str) -> Result<Self, LogError> {
        let (topic, columns) = match s.split_once('=') {
            Some((t, c)) => (
                t,
                Some(
                    c.split(',')
                        .map(|x| x.trim().to_string())
                        .collect::<Vec<_>>(),
                ),
            ),
            None => (s, None),
        };
        if topic.is_empty()
            || columns
                .as_ref()
                .is_some_and(|c| c.iter().any(String::is_empty))
        {
            return Err(LogError::new(format!(
                "--topic \"{s}\": give TOPIC or TOPIC=COLUMN,COLUMN,.."
            )));
        }
        Ok(TopicSpec {
            topic: topic.to_string(),
            columns,
        })
    }
}

/// What to read from a log.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadOptions {
    /// The topics; empty = every topic of a type twinloop maps onto columns without
    /// being told names (JointState, Imu, WrenchStamped, TFMessage).
    pub topics: Vec<TopicSpec>,
    /// Resample every column onto a fixed step by linear interpolation.
    pub dt: Option<f64>,
}

/// The decoding state of one topic.
pub(crate) enum Decoder {
    Joints {
        msg: JointState,
        series: Series,
        v: bool,
        tau: bool,
    },
    Imu {
        msg: msgs::Imu,
        series: Series,
    },
    Wrench {
        msg: msgs::Wrench,
        series: Series,
    },
    /// `required`: named by --topic (else a topic without column names is left out).
    Array {
        buf: Vec<f64>,
        series: Series,
        named: bool,
        required: bool,
    },
    Tf {
        topic: String,
        buf: Vec<Transform>,
        children: HashMap<String, Series>,
    },
}

impl Decoder {
    pub(crate) fn new(ch: &Channel, spec: Option<&TopicSpec>) -> Result<Option<Decoder>, LogError> {
        if ch.encoding != "cdr" {
            return Err(LogError::new(format!(
                "message encoding \"{}\": twinloop reads ROS 2 CDR",
                ch.encoding
            ))
            .on_topic(&ch.topic));
        }
        let series = Series::new(&ch.topic);
        Ok(Some(match Kind::from_schema(&ch.schema) {
            Some(Kind::JointState) => Decoder::Joints {
                msg: JointState::default(),
                series,
                v: false,
                tau: false,
            },
            Some(Kind::Imu) => Decoder::Imu {
                msg: msgs::Imu::default(),
                series,
            },
            Some(Kind::Wrench) => Decoder::Wrench {
                msg: msgs::Wrench::default(),
                series,
            },
            Some(Kind::MultiArray) => {
                let mut series = series;
                let named = match spec.and_then(|s| s.columns.clone()) {
                    Some(c) => {
                        series.columns = c;
                        true
                    }
                    None => false,
                };
                Decoder::Array {
                    buf: Vec::new(),
                    series,
                    named,
                    required: spec.is_some(),
                }
            }
            Some(Kind::Tf) => Decoder::Tf {
                topic: ch.topic.clone(),
                buf: Vec::new(),
                children: HashMap::new(),
            },
            _ if spec.is_some() => {
                return Err(LogError::new(format!(
                    "its type {} is not one twinloop reads (JointState, Imu, WrenchStamped, Float64MultiArray, TFMessage)",
                    ch.schema
                ))
                .on_topic(&ch.topic));
            }
            _ => return Ok(None),
        }))
    }

    pub(crate) fn decode(&mut self, log_time: i64, data: &[u8]) -> Result<(), LogError> {
        match self {
            Decoder::Joints {
                msg,
                series,
                v,
                tau,
            } => decode_joints(msg, series, (v, tau), log_time, data),
            Decoder::Imu { msg, series } => {
                msg.decode(data)?;
                if series.times.is_empty() {
                    let link = frame_or_topic(&msg.frame, &series.topic);
                    series.columns = [".gx", ".gy", ".gz", ".ax", ".ay", ".az"]
                        .iter()
                        .map(|s| format!("imu:{link}{s}"))
                        .collect();
                }
                let row = msg
                    .angular_velocity
                    .into_iter()
                    .chain(msg.linear_acceleration);
                series.push(msg.stamp_ns, log_time, row)
            }
            Decoder::Wrench { msg, series } => {
                msg.decode(data)?;
                if series.times.is_empty() {
                    let frame = frame_or_topic(&msg.frame, &series.topic);
                    series.columns = [".fx", ".fy", ".fz", ".tx", ".ty", ".tz"]
                        .iter()
                        .map(|s| format!("wrench:{frame}{s}"))
                        .collect();
                }
                series.push(
                    msg.stamp_ns,
                    log_time,
                    msg.force.into_iter().chain(msg.torque),
                )
            }
            Decoder::Array {
                buf,
                series,
                named,
                required,
            } => {
                let label = msgs::decode_multi_array(data, buf)?;
                if !*named && series.times.is_empty() && label.split(',').count() == buf.len() {
                    series.columns = label.split(',').map(str::to_string).collect();
                    *named = true;
                }
                if !*named && !*required {
                    return Ok(());
                }
                if !*named {
                    return Err(LogError::new(format!(
                        "a std_msgs/Float64MultiArray has no column names: name its {} values with --topic {}=NAME,NAME,..",
                        buf.len(),
                        series.topic
                    ))
                    .on_topic(&series.topic));
                }
                if buf.len() != series.columns.len() {
                    return Err(LogError::new(format!(
                        "{} values, but --topic names {} columns",
                        buf.len(),
                        series.columns.len()
                    ))
                    .at(&series.topic, log_time));
                }
                series.push(0, log_time, buf.iter().copied())
            }
            Decoder::Tf {
                topic,
                buf,
                children,
            } => {
                msgs::decode_tf(data, buf)?;
                for tr in buf.iter() {
                    let s = match children.get_mut(&tr.child) {
                        Some(s) => s,
                        None => {
                            let mut s = Series::new(&format!("{topic} ({})", tr.child));
                            s.columns = pose_columns(&tr.parent, &tr.child);
                            s.quaternion = Some(3);
                            children.entry(tr.child.clone()).or_insert(s)
                        }
                    };
                    s.push(
                        tr.stamp_ns,
                        log_time,
                        tr.translation.into_iter().chain(tr.rotation),
                    )?;
                }
                Ok(())
            }
        }
    }

    pub(crate) fn into_series(self) -> Vec<Series> {
        match self {
            Decoder::Array {
                series,
                required: false,
                ..
            } if series.times.is_empty() => vec![],
            Decoder::Joints { series, .. }
            | Decoder::Imu { series, .. }
            | Decoder::Wrench { series, .. }
            | Decoder::Array { series, .. } => vec![series],
            Decoder::Tf { children, .. } => {
                let mut v: Vec<Series> = children.into_values().collect();
                v.sort_by(|a, b| a.columns.cmp(&b.columns));
                v
            }
        }
    }
}

/// One JointState into its series; the first message fixes the joints and whether
/// velocities (`vt.0`) and efforts (`vt.1`) are there.
fn decode_joints(
    msg: &mut JointState,
    series: &mut Series,
    vt: (&mut bool, &mut bool),
    log_time: i64,
    data: &[u8],
) -> Result<(), LogError> {
    let (v, tau) = vt;
    msg.decode(data)?;
    if series.times.is_empty() {
        *v = !msg.velocity.is_empty();
        *tau = !msg.effort.is_empty();
        series.columns = joint_columns(&msg.names, *v, *tau);
    } else if msg.names_changed || *v == msg.velocity.is_empty() || *tau == msg.effort.is_empty() {
        return Err(LogError::new(format!(
            "the joints or fields changed from the first message's (now {} joints: {}): twinloop reads one fixed set a topic",
            msg.names.len(),
            msg.names.join(", ")
        ))
        .at(&series.topic, msg.stamp_ns));
    }
    let row = msg
        .position
        .iter()
        .chain(&msg.velocity)
        .chain(&msg.effort)
        .copied();
    series.push(msg.stamp_ns, log_time, row)
}

/// `q:<j>` for every joint, then `v:<j>` and `tau:<j>` when the messages carry them.
fn joint_columns(names: &[String], v: bool, tau: bool) -> Vec<String> {
    let mut c: Vec<String> = names.iter().map(|n| format!("q:{n}")).collect();
    if v {
        c.extend(names.iter().map(|n| format!("v:{n}")));
    }
    if tau {
        c.extend(names.iter().map(|n| format!("tau:{n}")));
    }
    c
}

/// A transform from the `world` (or `odom`, `map`) frame is the floating base
/// (`q:base.*`, twinloop's base columns); any other is `pose:<child>.*`.
fn pose_columns(parent: &str, child: &str) -> Vec<String> {
    let prefix = if matches!(parent, "world" | "odom" | "map") {
        "q:base".to_string()
    } else {
        format!("pose:{child}")
    };
    ["x", "y", "z", "qx", "qy", "qz", "qw"]
        .iter()
        .map(|s| format!("{prefix}.{s}"))
        .collect()
}

fn frame_or_topic(frame: &str, topic: &str) -> String {
    if frame.is_empty() {
        topic.trim_start_matches('/').replace('/', ".")
    } else {
        frame.to_string()
    }
}

/// Read the topics `options` names (or all twinloop can use) from the log at `path`
/// into one table: `t` (seconds since the first row) and each topic's columns. The
/// first `--topic` (else the topic with most messages) gives the rows; the others are
/// interpolated linearly at its times, and rows outside any topic's time span are left
/// out (nothing is extrapolated). With `options.dt`, every column is resampled onto a
/// fixed step instead. A topic read alone with no `dt` gives its values unchanged.
pub fn read_log(path: &Path, options: &ReadOptions) -> Result<Table, LogError> {
    let (series, ours) = read_series(path, options).map_err(|e| e.in_file(path))?;
    let explicit = !options.topics.is_empty();
    let mut table =
        crate::timebase::merge(series, options.dt, explicit, ours).map_err(|e| e.in_file(path))?;
    table.path = Some(path.to_path_buf());
    Ok(table)
}

/// Every selected topic's rows, each on its own times, in selection order; whether
/// twinloop wrote the log (its stamps are its `t`).
pub(crate) fn read_series(
    path: &Path,
    options: &ReadOptions,
) -> Result<(Vec<Series>, bool), LogError> {
    let mut decoders: HashMap<String, Option<Decoder>> = HashMap::new();
    let mut order: Vec<String> = Vec::new();
    let mut seen: Vec<(String, String)> = Vec::new();
    let ours = source::for_each_message(path, |ch, log_time, data| {
        // One hash a message: the topic's decoder, or its first message.
        if let Some(d) = decoders.get_mut(&ch.topic) {
            return match d {
                Some(d) => d.decode(log_time, data),
                None => Ok(()),
            };
        }
        seen.push((ch.topic.clone(), ch.schema.clone()));
        let spec = options.topics.iter().find(|s| s.topic == ch.topic);
        let d = if options.topics.is_empty() || spec.is_some() {
            Decoder::new(ch, spec)?
        } else {
            None
        };
        decoders.insert(ch.topic.clone(), d);
        order.push(ch.topic.clone());
        match decoders.get_mut(&ch.topic) {
            Some(Some(d)) => d.decode(log_time, data),
            _ => Ok(()),
        }
    })?;
    for spec in &options.topics {
        if !decoders.contains_key(&spec.topic) {
            let held: Vec<String> = seen.iter().map(|(t, s)| format!("{t} ({s})")).collect();
            return Err(LogError::new(format!(
                "no message on topic {}; the log holds {}",
                spec.topic,
                if held.is_empty() {
                    "no message".to_string()
                } else {
                    held.join(", ")
                }
            )));
        }
    }
    if !options.topics.is_empty() {
        order = options.topics.iter().map(|s| s.topic.clone()).collect();
    }
    let series: Vec<Series> = order
        .iter()
        .filter_map(|t| decoders.remove(t).flatten())
        .flat_map(Decoder::into_series)
        .collect();
    if series.is_empty() {
        let held: Vec<String> = seen.iter().map(|(t, s)| format!("{t} ({s})")).collect();
        return Err(LogError::new(format!(
            "no topic twinloop can use without --topic; the log holds {}",
            if held.is_empty() {
                "no message".to_string()
            } else {
                held.join(", ")
            }
        )));
    }
    Ok((series, ours))
}
