//! `twinloop log info`: what a recorded log (MCAP file, rosbag2 folder) holds and
//! which columns twinloop reads from each topic. A group of its own rather than a
//! `model info` or `link info` option: a log is neither a description nor a bus, and
//! more log verbs (conversion, results written as MCAP) belong beside it.

use crate::common::{JSON_HELP, ROBOT_HELP, emit, load_model};
use crate::error::{CliResult, Outcome};
use clap::{Args, Subcommand};
use serde::Serialize;
use std::fmt::Write;
use std::path::PathBuf;
use twinloop_dynamics::BaseKind;
use twinloop_logs::{TopicInfo, format_ns};

#[derive(Subcommand)]
pub enum LogCommand {
    /// List a log's topics, their message types and counts, and the columns twinloop reads
    #[command(
        long_about = "List a recorded log's topics (an .mcap file, or a rosbag2 folder with MCAP or \
SQLite storage): each topic's message type, message count, time span and rate, and the table \
columns twinloop reads from it (q:<joint>, v:, tau: from sensor_msgs/JointState; imu:<frame>.gx..az \
from sensor_msgs/Imu; wrench:<frame>.fx..tz from geometry_msgs/WrenchStamped; q:base.* or \
pose:<frame>.* from tf2_msgs/TFMessage; a std_msgs/Float64MultiArray's values once named with \
--topic TOPIC=NAME,..). With --robot, the joints of each JointState topic that the robot lacks \
and the robot's joints no topic gives.",
        after_long_help = "Example:\n  twinloop log info run.mcap\n  \
twinloop log info rosbag2_2026_01_01/ --robot builtin:km20 --json -\n\n\
Output: one block per topic: name, type, messages, span (s) and rate (Hz), then the columns or \
why there are none.\n\n\
With --json FILE (- for stdout): {file, topics [{topic, schema, encoding, messages, first_s, \
last_s, columns [names], note}], unknown_joints [names], missing_joints [names]}.\n\n\
Exit code 0, 1 when --robot is given and a JointState topic names a joint the robot lacks, 2 when \
the log cannot be read (the message names the file, topic and message time)."
    )]
    Info(InfoArgs),
}

#[derive(Args)]
pub struct InfoArgs {
    /// The log: an .mcap file, a .db3, or a rosbag2 folder (holding metadata.yaml)
    pub file: PathBuf,
    #[arg(long, help = ROBOT_HELP)]
    pub robot: Option<String>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
}

pub fn run(cmd: LogCommand) -> CliResult {
    match cmd {
        LogCommand::Info(a) => info(&a),
    }
}

#[derive(Serialize)]
struct TopicJson<'a> {
    topic: &'a str,
    schema: &'a str,
    encoding: &'a str,
    messages: u64,
    first_s: f64,
    last_s: f64,
    columns: &'a [String],
    note: Option<&'a str>,
}

#[derive(Serialize)]
struct InfoJson<'a> {
    file: String,
    topics: Vec<TopicJson<'a>>,
    unknown_joints: Vec<String>,
    missing_joints: Vec<String>,
}

fn info(a: &InfoArgs) -> CliResult {
    let topics = twinloop_logs::log_info(&a.file)?;
    let (unknown, missing) = match &a.robot {
        Some(spec) => {
            let (_, model) = load_model(spec, BaseKind::Floating)?;
            joint_match(&topics, &model.q_names())
        }
        None => (Vec::new(), Vec::new()),
    };
    let mut text = format!("{}: {} topics\n", a.file.display(), topics.len());
    for t in &topics {
        text += &topic_text(t);
    }
    if a.robot.is_some() {
        let list = |v: &[String]| {
            if v.is_empty() {
                "none".to_string()
            } else {
                v.join(", ")
            }
        };
        let _ = writeln!(text, "joints the robot lacks: {}", list(&unknown));
        let _ = writeln!(text, "robot joints no topic gives: {}", list(&missing));
    }
    let json = InfoJson {
        file: a.file.display().to_string(),
        topics: topics
            .iter()
            .map(|t| TopicJson {
                topic: &t.topic,
                schema: &t.schema,
                encoding: &t.encoding,
                messages: t.messages,
                first_s: t.first_ns as f64 / 1e9,
                last_s: t.last_ns as f64 / 1e9,
                columns: &t.columns,
                note: t.note.as_deref(),
            })
            .collect(),
        unknown_joints: unknown.clone(),
        missing_joints: missing,
    };
    emit(&text, a.json.as_ref(), &json)?;
    Ok(if unknown.is_empty() {
        Outcome::Ok
    } else {
        Outcome::Problems
    })
}

fn topic_text(t: &TopicInfo) -> String {
    let span = (t.last_ns - t.first_ns) as f64 / 1e9;
    let rate = if span > 0.0 {
        format!(", {:.1} Hz", (t.messages - 1) as f64 / span)
    } else {
        String::new()
    };
    let mut s = format!(
        "\n{}  {}  {} messages from t={} s over {:.3} s{rate}\n",
        t.topic,
        t.schema,
        t.messages,
        format_ns(t.first_ns),
        span
    );
    if t.columns.is_empty() {
        let _ = writeln!(
            s,
            "  reads: nothing ({})",
            t.note.as_deref().unwrap_or("no columns")
        );
    } else {
        let shown: Vec<&str> = t.columns.iter().take(12).map(String::as_str).collect();
        let more = t.columns.len().saturating_sub(12);
        let more = if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        };
        let _ = writeln!(s, "  reads: {}{more}", shown.join(" "));
    }
    s
}

/// The `q:` joints of the log's topics the robot lacks, and the robot's joints
/// (its `q_names`, the floating base aside) no topic gives.
fn joint_match(topics: &[TopicInfo], q_names: &[String]) -> (Vec<String>, Vec<String>) {
    let given: Vec<&str> = topics
        .iter()
        .flat_map(|t| &t.columns)
        .filter_map(|c| c.strip_prefix("q:"))
        .filter(|j| !j.starts_with("base."))
        .collect();
    let unknown = given
        .iter()
        .filter(|j| !q_names.iter().any(|q| q == *j))
        .map(|j| j.to_string())
        .collect();
    let missing = q_names
        .iter()
        .filter(|q| !q.starts_with("base.") && !given.contains(&q.as_str()))
        .cloned()
        .collect();
    (unknown, missing)
}
