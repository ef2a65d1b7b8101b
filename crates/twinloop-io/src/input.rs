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
pub fn read_to_string(path: &Path) -> std::io::Result<String> {
    let bytes = read_limited(path, MAX_INPUT_BYTES)?;
    String::from_utf8(bytes).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("is not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        )
    })
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
        _ => format!("cannot read: {e}"),
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
