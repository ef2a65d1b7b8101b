//! Recorded logs in and out: MCAP files and ROS 2 bag folders (MCAP or SQLite
//! storage) read into twinloop tables, and tables written as MCAP of ROS 2 messages.
//!
//! - [`source`]: the containers (the `mcap` crate's reader; rosbag2 `metadata.yaml`;
//!   SQLite `.db3` through `rusqlite`, behind the default `sqlite` feature).
//! - [`cdr`] and [`msgs`]: CDR and the six ROS 2 message types twinloop uses.
//! - [`read`]: messages to table columns (`q:<joint>`, `v:`, `tau:`, `imu:<link>.gx..`,
//!   `wrench:<frame>.fx..`, `q:base.*`, `pose:<frame>.*`, user-named array columns)
//!   and the time base (`timebase`).
//! - [`write`]: a table to `/joint_states`, `/tf`, `/imu`, `/robot_description`.
//! - [`info`]: what a log holds and what twinloop can read from it.
//! - `bag`: a recording written as a rosbag2 folder (`--out NAME/`).
mod bag;
pub mod cdr;
mod error;
pub mod info;
pub mod msgs;
pub mod read;
pub mod source;
mod timebase;
pub mod write;

pub use error::{LogError, format_ns};
pub use info::{TopicInfo, log_info};
pub use read::{ReadOptions, TopicSpec, read_log};
pub use source::{is_log, metadata};
pub use write::{ArrayTopic, McapLog, open_mcap_recording, write_mcap};
