//! Reading input files with a bound (issue 29: no command eats the machine): only
//! regular files (a device such as `/dev/zero`, a FIFO or a folder never ends or is
//! no data), and at most a stated size, so a wrong file is refused at once instead
//! of filling the memory.

use crate::IoError;
use std::io::Read;
use std::path::Path;

/// The largest input file read, bytes: 1 GiB, some 30 times the largest real data
/// a command here reads (an hour of a 20-servo recording at 100 Hz is 35 MB; the
/// largest description in models/, TALOS's MJCF with its meshes, 12 MB).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// The bytes of the regular file `path`, at most `max` of them; errors name the file.
pub fn read_bounded(path: &Path, max: u64) -> Result<Vec<u8>, IoError> {
    let err = |m: String| IoError::new(m).in_file(path);
    let meta = std::fs::metadata(path).map_err(|e| err(format!("cannot read: {e}")))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a folder"
        } else {
            "a device, FIFO or socket"
        };
        return Err(err(format!("is {kind}, not a regular file")));
    }
    if meta.len() > max {
        return Err(err(format!(
            "is {} bytes, more than the {max} bytes an input may have",
            meta.len()
        )));
    }
    let file = std::fs::File::open(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // The file may grow while it is read: never more than `max`.
    file.take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| err(format!("cannot read: {e}")))?;
    if bytes.len() as u64 > max {
        return Err(err(format!("grew past the {max} bytes an input may have")));
    }
    Ok(bytes)
}

/// [`read_bounded`] with [`MAX_INPUT_BYTES`], as UTF-8 text.
pub fn read_text(path: &Path) -> Result<String, IoError> {
    let bytes = read_bounded(path, MAX_INPUT_BYTES)?;
    String::from_utf8(bytes).map_err(|e| {
        IoError::new(format!(
            "is not UTF-8 text (byte {})",
            e.utf8_error().valid_up_to()
        ))
        .in_file(path)
    })
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
