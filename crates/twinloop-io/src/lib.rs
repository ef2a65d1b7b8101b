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

/// An I/O error as people read it: the system's words without Rust's
/// ` (os error N)` (`Permission denied`, `File too large`).
pub fn io_words(e: &std::io::Error) -> String {
    without_os_error(&e.to_string())
}

/// `text` with every ` (os error N)` that Rust's I/O errors append removed.
pub fn without_os_error(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(k) = rest.find(" (os error ") {
        let tail = &rest[k + " (os error ".len()..];
        let digits = tail.bytes().take_while(u8::is_ascii_digit).count();
        if digits > 0 && tail[digits..].starts_with(')') {
            out.push_str(&rest[..k]);
            rest = &tail[digits + 1..];
        } else {
            out.push_str(&rest[..k + 1]);
            rest = &rest[k + 1..];
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn os_error_numbers_are_left_out() {
        assert_eq!(
            super::without_os_error("a: Permission denied (os error 13); b (os error x)"),
            "a: Permission denied; b (os error x)"
        );
    }
}
