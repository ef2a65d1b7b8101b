//! Reading input files with a bound (issue 29: no command eats the machine): only
//! regular files (a device such as `/dev/zero`, a FIFO or a folder never ends or is
//! no data), and at most a stated size, so a wrong file is refused at once instead
//! of filling the memory.

use crate::IoError;
use std::io::Read;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The files this process read as input, by (device, inode), with the path read:
/// an output is never renamed over one of them ([`crate::output`]), whichever way it
/// was reached (an option, a profile's description, an MJCF `<include>`, a servo
/// parameter file named inside another file). Files this process wrote itself are
/// not counted when read back (a demo reads the tip-over it wrote).
static READ: Mutex<Vec<(u64, u64, PathBuf)>> = Mutex::new(Vec::new());
static WRITTEN: Mutex<Vec<(u64, u64)>> = Mutex::new(Vec::new());

/// Note that `path` (with metadata `meta`) is read as an input of this process.
pub fn note_read(path: &Path, meta: &std::fs::Metadata) {
    let key = (meta.dev(), meta.ino());
    if WRITTEN.lock().is_ok_and(|w| w.contains(&key)) {
        return;
    }
    if let Ok(mut read) = READ.lock()
        && !read.iter().any(|(d, i, _)| (*d, *i) == key)
    {
        read.push((key.0, key.1, path.to_path_buf()));
    }
}

/// The input path this process read that is the same file as `meta`, if any.
pub fn read_as_input(meta: &std::fs::Metadata) -> Option<PathBuf> {
    let read = READ.lock().ok()?;
    read.iter()
        .find(|(d, i, _)| (*d, *i) == (meta.dev(), meta.ino()))
        .map(|(_, _, p)| p.clone())
}

/// Note that this process wrote the file with metadata `meta` (reading it back is
/// no input of the user's).
pub(crate) fn note_written(meta: &std::fs::Metadata) {
    if let Ok(mut w) = WRITTEN.lock() {
        w.push((meta.dev(), meta.ino()));
    }
}

/// The largest input file read, bytes: 1 GiB, some 30 times the largest real data
/// a command here reads (an hour of a 20-servo recording at 100 Hz is 35 MB; the
/// largest description in models/, TALOS's MJCF with its meshes, 12 MB).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// The bytes of the regular file `path`, at most `max` of them: `std::fs::read` with
/// the bound (the error keeps its kind; a file that is not regular or too big is
/// `InvalidInput`, its message saying which).
pub fn read_limited(path: &Path, max: u64) -> std::io::Result<Vec<u8>> {
    let invalid = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidInput, m);
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a folder"
        } else {
            "a device, FIFO or socket"
        };
        return Err(invalid(format!("is {kind}, not a regular file")));
    }
    note_read(path, &meta);
    if meta.len() > max {
        return Err(invalid(format!(
            "is {} bytes, more than the {max} bytes an input may have",
            meta.len()
        )));
    }
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // The file may grow while it is read: never more than `max`.
    file.take(max + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(invalid(format!(
            "grew past the {max} bytes an input may have"
        )));
    }
    Ok(bytes)
}

/// `std::fs::read_to_string` for input files: regular files of at most
/// [`MAX_INPUT_BYTES`] (a drop-in for it, with the same error type).
/// A UTF-8 byte order mark (what some Windows editors put first) is dropped, so a
/// JSON, TOML or CSV file saved with one reads as without (issue 29, class 5).
pub fn read_to_string(path: &Path) -> std::io::Result<String> {
    let bytes = read_limited(path, MAX_INPUT_BYTES)?;
    let mut text = String::from_utf8(bytes).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("is not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        )
    })?;
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

/// [`read_limited`] with errors naming the file.
pub fn read_bounded(path: &Path, max: u64) -> Result<Vec<u8>, IoError> {
    read_limited(path, max).map_err(|e| read_error(path, e))
}

/// [`read_to_string`] with errors naming the file.
pub fn read_text(path: &Path) -> Result<String, IoError> {
    read_to_string(path).map_err(|e| read_error(path, e))
}

fn read_error(path: &Path, e: std::io::Error) -> IoError {
    let m = match e.kind() {
        std::io::ErrorKind::InvalidInput | std::io::ErrorKind::InvalidData => e.to_string(),
        _ => format!("cannot read: {}", crate::io_words(&e)),
    };
    IoError::new(m).in_file(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_folders_are_refused_at_once_and_sizes_are_bounded() {
        for p in ["/dev/zero", "/dev/null", "/tmp"] {
            let e = read_bounded(Path::new(p), 10).unwrap_err().to_string();
            assert!(e.starts_with(p) && e.contains("not a regular file"), "{e}");
        }
        let f = std::env::temp_dir().join(format!("twinloop-input-{}", std::process::id()));
        std::fs::write(&f, "0123456789ab").unwrap();
        let e = read_bounded(&f, 10).unwrap_err().to_string();
        assert!(e.contains("12 bytes, more than the 10"), "{e}");
        assert_eq!(read_bounded(&f, 12).unwrap().len(), 12);
        let _ = std::fs::remove_file(&f);
    }
}

/// What kind of text file `text` looks like, for an error that names a wrong kind
/// of file instead of a parser's complaint ("expected ident at line 1 column 2" for a
/// CSV given as JSON): `JSON`, `XML (URDF, MJCF)`, `a CSV table`, `TOML`, or `None`.
/// A guess from the first line that is neither blank nor a `#` comment.
pub fn looks_like(text: &str) -> Option<&'static str> {
    let first = text
        .trim_start_matches('\u{feff}')
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))?;
    if first.starts_with('{') || first.starts_with('[') && !first.ends_with(']') {
        Some("JSON")
    } else if first.starts_with('<') {
        Some("XML (URDF, MJCF)")
    } else if first.starts_with('[') || first.contains(" = ") || first.contains("= \"") {
        Some("TOML")
    } else if first.contains(',') {
        Some("a CSV table")
    } else {
        None
    }
}

/// The error for `file`, expected to be `expected`, whose parser said `err`: where
/// the text looks like another kind of file, says that kind and its first line;
/// else `err` as it is.
pub fn wrong_kind(file: &str, text: &str, expected: &str, err: &str) -> String {
    let kind = looks_like(text);
    let expected_kind = looks_like_name(expected);
    match kind {
        Some(k) if Some(k) != expected_kind => {
            let first: String = text
                .trim_start_matches('\u{feff}')
                .lines()
                .map(str::trim)
                .find(|l| !l.is_empty() && !l.starts_with('#'))
                .unwrap_or("")
                .chars()
                .take(60)
                .collect();
            format!("{file}: this is not {expected}: it looks like {k} (its first line: {first:?})")
        }
        _ => {
            // `expected` may come with its article ("a tip-over JSON").
            let bare = ["a ", "an "]
                .iter()
                .find_map(|a| expected.strip_prefix(a))
                .unwrap_or(expected);
            format!("{file}: not a valid {bare}: {err}")
        }
    }
}

/// The kind [`looks_like`] returns for a file described as `expected`.
fn looks_like_name(expected: &str) -> Option<&'static str> {
    let e = expected.to_ascii_lowercase();
    if e.contains("json") {
        Some("JSON")
    } else if e.contains("toml") {
        Some("TOML")
    } else if e.contains("csv") {
        Some("a CSV table")
    } else if e.contains("urdf") || e.contains("mjcf") || e.contains("xml") {
        Some("XML (URDF, MJCF)")
    } else {
        None
    }
}

#[cfg(test)]
mod kind_tests {
    use super::*;

    #[test]
    fn a_csv_given_as_json_is_named_a_csv_table() {
        let m = wrong_kind(
            "stand.csv",
            "t,q:l_ank_roll\n0,0.1\n",
            "tip-over JSON",
            "expected ident at line 1 column 2",
        );
        assert!(m.contains("looks like a CSV table"), "{m}");
        assert!(!m.contains("expected ident"), "{m}");
        assert_eq!(looks_like("{\"a\": 1}"), Some("JSON"));
        assert_eq!(looks_like("<robot name=\"x\">"), Some("XML (URDF, MJCF)"));
        assert_eq!(looks_like("# c\n[servo]\nmodel = \"RX-28\""), Some("TOML"));
        // A JSON file with a real JSON error keeps the parser's place.
        let m = wrong_kind("a.json", "{\"a\": }", "tip-over JSON", "line 1 column 7");
        assert!(m.contains("line 1 column 7"), "{m}");
    }
}
