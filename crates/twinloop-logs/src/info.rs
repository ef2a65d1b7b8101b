//! What a log holds, topic by topic, and what twinloop reads from each: the listing
//! behind `twinloop log info`.
use crate::error::LogError;
use crate::read::{Decoder, TopicSpec};
use crate::source::{self, Channel};
use std::path::Path;

/// One topic of a log.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicInfo {
    pub topic: String,
    pub schema: String,
    pub encoding: String,
    pub messages: u64,
    /// Log times of the first and last message, ns since the epoch.
    pub first_ns: i64,
    pub last_ns: i64,
    /// The columns twinloop reads from the topic's first message (empty if none).
    pub columns: Vec<String>,
    /// Why no columns, or what to add (`--topic /x=NAME,..`), when `columns` is empty.
    pub note: Option<String>,
}

/// List the topics of the log at `path` in the order they first appear.
pub fn log_info(path: &Path) -> Result<Vec<TopicInfo>, LogError> {
    let mut topics: Vec<TopicInfo> = Vec::new();
    source::for_each_message(path, |ch, log_time, data| {
        if let Some(t) = topics.iter_mut().find(|t| t.topic == ch.topic) {
            t.messages += 1;
            t.first_ns = t.first_ns.min(log_time);
            t.last_ns = t.last_ns.max(log_time);
            return Ok(());
        }
        let (columns, note) = first_columns(ch, log_time, data);
        topics.push(TopicInfo {
            topic: ch.topic.clone(),
            schema: ch.schema.clone(),
            encoding: ch.encoding.clone(),
            messages: 1,
            first_ns: log_time,
            last_ns: log_time,
            columns,
            note,
        });
        Ok(())
    })
    .map_err(|e| e.in_file(path))?;
    Ok(topics)
}

/// The columns a topic's first message gives, or why it gives none.
fn first_columns(ch: &Channel, log_time: i64, data: &[u8]) -> (Vec<String>, Option<String>) {
    let spec = TopicSpec {
        topic: ch.topic.clone(),
        columns: None,
    };
    let mut d = match Decoder::new(ch, Some(&spec)) {
        Ok(Some(d)) => d,
        Ok(None) => return (Vec::new(), Some("not a type twinloop reads".into())),
        Err(e) => return (Vec::new(), Some(e.message)),
    };
    if let Err(e) = d.decode(log_time, data) {
        return (Vec::new(), Some(e.message));
    }
    let columns: Vec<String> = d
        .into_series()
        .into_iter()
        .flat_map(|s| s.columns)
        .collect();
    (columns, None)
}
