//! twinloop-io: the data files (docs/architecture.md, "Data files").
//!
//! A [`Table`] is a CSV file with a header row and numeric cells. Columns are
//! named `t`, `q:<joint>`, `v:<joint>`, `a:<joint>`, `tau:<joint>`, with the floating
//! base as `q:base.x ... q:base.qw`, `v:base.vx ... v:base.wz`, `tau:base.fx ...
//! tau:base.tz`. [`StateColumns`] maps a table's columns onto a model's vectors
//! (given the model's coordinate names, so this crate needs no dynamics).
//! Numbers are written with Rust's shortest round-trip formatting, so a value read
//! back is bit-for-bit the value computed; but the time `t`, which is written to the
//! nanosecond (`2.0`, not a step sum's `1.9999999999998905`).
//!
//! Every file a command writes goes through [`output`] (checked before any work,
//! written beside its place and renamed when complete), and input files are read
//! through [`input`] (regular files only, with a size bound).

mod columns;
pub mod input;
pub mod output;
pub mod sink;
mod table;

pub use columns::{Quantity, StateColumns, nearest};
pub use sink::{RowSink, open_recording};
pub use table::{CsvWriter, IoError, Table, clean_time, format_f64};
