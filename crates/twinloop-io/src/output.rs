//! Every file twinloop writes goes through here (issue 29: nothing a user has is lost).
//!
//! - [`Output::check`] runs before a command does any work: the place must be a
//!   regular file or nothing, in a folder that exists, and not one of the command's
//!   inputs (same device and inode). A device, FIFO, socket or folder is refused. A
//!   symlink is written through: its target gets the new content and the link stays a
//!   link (what a shell's `>` does), so `latest.csv -> run-42.csv` keeps working; a
//!   link to nothing is refused.
//! - The bytes go to a temporary file beside the target (`FILE.partial`), are flushed
//!   and fsynced, and only then renamed over the target: a full disk, an error or a
//!   crash leaves the old file as it was.
//! - A recording ([`AtomicFile::recording`]) is streamed into `FILE.partial` and
//!   renamed at the end whatever ends it (an error, Ctrl-C, a dropped writer), as long
//!   as one data line reached it; with none, the old file stays untouched. A process
//!   killed outright leaves its rows under `FILE.partial`; the next run writing that
//!   output keeps them as `FILE.partial.1` (then `.2`, ...) before it starts.
//! - The partial file is locked while written (`flock`): a second run writing the
//!   same output at the same time is refused, naming it, instead of mixing the two.

use crate::IoError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Path, PathBuf};

/// An output place, checked: where the bytes finally go (a symlink resolved).
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    /// The path as the user gave it (for messages).
    pub path: PathBuf,
    /// The file that gets the bytes (the symlink's target for a symlink).
    pub target: PathBuf,
}

/// The name a file is written under until it is complete: `FILE.partial`.
pub fn in_progress(path: &Path) -> PathBuf {
    let mut p = path.as_os_str().to_owned();
    p.push(".partial");
    PathBuf::from(p)
}

fn kind_of(t: &std::fs::FileType) -> Option<&'static str> {
    if t.is_dir() {
        Some("a folder")
    } else if t.is_fifo() {
        Some("a FIFO (named pipe)")
    } else if t.is_socket() {
        Some("a socket")
    } else if t.is_char_device() || t.is_block_device() {
        Some("a device")
    } else {
        None
    }
}

fn refused(flag: &str, path: &Path, why: impl std::fmt::Display) -> IoError {
    let place = if flag.is_empty() {
        path.display().to_string()
    } else {
        format!("{flag} {}", path.display())
    };
    IoError::new(format!("{place}: {why}"))
}

impl Output {
    /// Where `path` may be written (see the module's rules), without comparing it to
    /// inputs. `flag` names the option in the message (`--out`), or is empty.
    pub fn resolve(flag: &str, path: &Path) -> Result<Output, IoError> {
        let mut target = path.to_path_buf();
        if let Ok(m) = std::fs::symlink_metadata(path)
            && m.file_type().is_symlink()
        {
            target = std::fs::canonicalize(path).map_err(|_| {
                refused(
                    flag,
                    path,
                    "is a symlink to nothing; give the file to write, not a dangling link",
                )
            })?;
        }
        if let Ok(m) = std::fs::metadata(&target)
            && let Some(kind) = kind_of(&m.file_type())
        {
            return Err(refused(
                flag,
                path,
                format!("is {kind}, not a regular file; twinloop writes only regular files"),
            ));
        }
        if path.as_os_str().as_encoded_bytes().ends_with(b"/") {
            return Err(refused(
                flag,
                path,
                "names a folder (it ends in /); give the file to write",
            ));
        }
        let folder = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !folder.is_dir() {
            let why = if folder.exists() {
                format!("{} is a file, not a folder", folder.display())
            } else {
                format!(
                    "the folder {} does not exist; create it first",
                    folder.display()
                )
            };
            return Err(refused(flag, path, why));
        }
        writable(&folder).map_err(|e| {
            refused(
                flag,
                path,
                format!(
                    "cannot write in the folder {}: {}",
                    folder.display(),
                    crate::io_words(&e)
                ),
            )
        })?;
        Ok(Output {
            path: path.to_path_buf(),
            target,
        })
    }

    /// [`Output::resolve`], and refused when it is the same file as one of `inputs`
    /// (`(flag, path)` pairs): writing it would destroy what the command reads.
    pub fn check(flag: &str, path: &Path, inputs: &[(String, PathBuf)]) -> Result<Output, IoError> {
        let out = Output::resolve(flag, path)?;
        let Ok(me) = std::fs::metadata(&out.target) else {
            return Ok(out); // a new file is no input
        };
        for (what, input) in inputs {
            if let Ok(m) = std::fs::metadata(input)
                && m.dev() == me.dev()
                && m.ino() == me.ino()
            {
                let what = if what.is_empty() {
                    "an input".to_string()
                } else {
                    format!("the {what} input")
                };
                return Err(refused(
                    flag,
                    path,
                    format!("is also {what} of this command; write the result to another file"),
                ));
            }
        }
        Ok(out)
    }

    /// Write `bytes` as the whole new content: all of it, or the old file untouched.
    pub fn write_atomic(&self, bytes: &[u8]) -> Result<(), IoError> {
        let mut f = AtomicFile::create(self)?;
        f.write_all(bytes).map_err(|e| f.error(e))?;
        f.commit()
    }
}

/// Whether files can be created in `folder` (permissions, a read-only mount): a
/// probe file made and removed, so that a long run is refused before its work, not
/// at its end when the result is written.
fn writable(folder: &Path) -> std::io::Result<()> {
    let probe = folder.join(format!(".twinloop-probe-{}", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map(|_| {
            let _ = std::fs::remove_file(&probe);
        })
        .or_else(|e| match e.kind() {
            // Left by a killed run of this process id: the folder is writable.
            std::io::ErrorKind::AlreadyExists => Ok(()),
            _ => Err(e),
        })
}

/// Whether two output paths name the same file: the same file (device and inode)
/// when it exists, else the same name in the same folder (a symlink followed).
pub fn same_place(a: &Path, b: &Path) -> bool {
    if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        return x.dev() == y.dev() && x.ino() == y.ino();
    }
    let place = |p: &Path| {
        let p = std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        let folder = match p.parent() {
            Some(f) if !f.as_os_str().is_empty() => f.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let folder = std::fs::canonicalize(&folder).unwrap_or(folder);
        (folder, p.file_name().map(|n| n.to_owned()))
    };
    place(a) == place(b)
}

/// [`Output::resolve`] then [`Output::write_atomic`]: the one way to write a whole file.
pub fn write_atomic(path: &Path, bytes: impl AsRef<[u8]>) -> Result<(), IoError> {
    Output::resolve("", path)?.write_atomic(bytes.as_ref())
}

/// What a partial file leaves when it is dropped unfinished.
#[derive(Debug, Clone, Copy, PartialEq)]
enum OnDrop {
    /// Removed: an output that is not complete must not look complete.
    Remove,
    /// Renamed over the target if it holds more than its first line (a recording).
    KeepRecorded,
}

/// A file being written under its in-progress name (see the module's rules).
pub struct AtomicFile<W: Write + Durable = File> {
    target: PathBuf,
    shown: PathBuf,
    partial: PathBuf,
    out: Option<BufWriter<W>>,
    on_drop: OnDrop,
    /// Newlines written: a recording with only its header holds nothing recorded.
    lines: u64,
    /// The lines of the header (1 unless [`AtomicFile::header_written`] says more).
    header: u64,
    /// Flush at every newline, so a viewer following the partial file sees each row.
    flush_lines: bool,
    /// A write failed (a full disk): a recording then stays under its partial name,
    /// rows kept, and the old file stays as it was.
    failed: bool,
    /// Bytes the writer took, and of them the bytes up to the last row flushed whole:
    /// a recording cut by a full disk is trimmed to its last whole row.
    accepted: u64,
    whole_rows: u64,
}

/// A writer that can make its bytes durable (fsync); a test writer says it did.
pub trait Durable {
    fn sync(&mut self) -> std::io::Result<()>;
}

impl Durable for File {
    fn sync(&mut self) -> std::io::Result<()> {
        self.sync_all()
    }
}

impl AtomicFile<File> {
    /// An output, removed if dropped before [`AtomicFile::commit`].
    pub fn create(out: &Output) -> Result<Self, IoError> {
        AtomicFile::open(out, OnDrop::Remove)
    }

    /// A recording: every line flushed as written, and kept (renamed to its name)
    /// however the run ends, when it holds at least one line after the first.
    pub fn recording(out: &Output) -> Result<Self, IoError> {
        AtomicFile::open(out, OnDrop::KeepRecorded)
    }

    fn open(out: &Output, on_drop: OnDrop) -> Result<Self, IoError> {
        let (partial, file) = create_partial(out)?;
        Ok(AtomicFile::with_writer(out, partial, file, on_drop))
    }
}

/// `FILE.partial` created for `out` and locked (an advisory `flock`, held while the
/// file is open) so that a second run writing the same output at the same time is
/// refused rather than mixed into it. A partial file nobody holds was left by a killed
/// run: its rows are kept under the first free `FILE.partial.N` (a recording's rows
/// are a user's data) and a new one is started; anything else in the way is refused.
/// The file gets the old one's permissions.
fn create_partial(out: &Output) -> Result<(PathBuf, File), IoError> {
    not_an_input(&out.target, &out.path)?;
    let partial = in_progress(&out.target);
    if let Ok(m) = std::fs::symlink_metadata(&partial) {
        if !m.file_type().is_file() {
            return Err(refused(
                "",
                &partial,
                "is in the way of the file being written (not a regular file)",
            ));
        }
        set_aside(&partial, m.len(), &out.path)?;
    }
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create_new(true)
        .open(&partial)
        .map_err(|e| {
            IoError::new(format!("cannot create: {}", crate::io_words(&e))).in_file(&out.path)
        })?;
    // A file system without locks (some network mounts) writes unguarded, as before.
    let _ = file.try_lock();
    if let Ok(m) = std::fs::metadata(&out.target) {
        let _ = file.set_permissions(m.permissions());
    }
    Ok((partial, file))
}

/// Moves a partial file out of the way of a new run: refused while another run holds
/// it; a killed run's rows (`len` bytes) kept under `FILE.partial.N`, an empty one removed.
fn set_aside(partial: &Path, len: u64, shown: &Path) -> Result<(), IoError> {
    if let Ok(f) = File::open(partial)
        && let Err(std::fs::TryLockError::WouldBlock) = f.try_lock()
    {
        return Err(refused(
            "",
            shown,
            format!(
                "another run is writing it now ({} is held); wait for it to finish or write elsewhere",
                partial.display()
            ),
        ));
    }
    if len > 0 {
        let kept = (1..=99).map(|n| {
            let mut p = partial.as_os_str().to_owned();
            p.push(format!(".{n}"));
            PathBuf::from(p)
        });
        if let Some(free) = kept
            .into_iter()
            .find(|p| std::fs::symlink_metadata(p).is_err())
        {
            return std::fs::rename(partial, &free).map_err(|e| {
                IoError::new(format!(
                    "cannot keep a killed run's {}: {e}",
                    partial.display()
                ))
                .in_file(shown)
            });
        }
    }
    let _ = std::fs::remove_file(partial);
    Ok(())
}

/// Refuse to replace `target` when this process read it as an input (however it was
/// named: an option, a file named inside another, an include); `shown` is the path
/// the user gave.
fn not_an_input(target: &Path, shown: &Path) -> Result<(), IoError> {
    if let Some(input) = std::fs::metadata(target)
        .ok()
        .and_then(|m| crate::input::read_as_input(&m))
    {
        return Err(refused(
            "",
            shown,
            format!(
                "is also an input this command read ({}); write the result to another file",
                input.display()
            ),
        ));
    }
    Ok(())
}

/// `partial` renamed over `target`, unless `target` was read as an input; the new
/// file is noted as this process's own (reading it back is no input).
fn rename_over(partial: &Path, target: &Path, shown: &Path) -> Result<(), IoError> {
    not_an_input(target, shown)?;
    std::fs::rename(partial, target).map_err(|e| {
        IoError::new(format!("cannot write: {}", crate::io_words(&e))).in_file(shown)
    })?;
    if let Ok(m) = std::fs::metadata(target) {
        crate::input::note_written(&m);
    }
    Ok(())
}

/// A file written under its in-progress name by a writer that seeks back (an MCAP
/// writes its summary last), under the same rules as [`AtomicFile`]: the caller
/// writes the [`File`] it is given and hands it back to [`PartialFile::commit`];
/// dropped uncommitted, the partial file is removed and the old file stays.
pub struct PartialFile {
    target: PathBuf,
    shown: PathBuf,
    partial: PathBuf,
    committed: bool,
}

impl PartialFile {
    /// The place for `out` and the file to write.
    pub fn open(out: &Output) -> Result<(PartialFile, File), IoError> {
        let (partial, file) = create_partial(out)?;
        let place = PartialFile {
            target: out.target.clone(),
            shown: out.path.clone(),
            partial,
            committed: false,
        };
        Ok((place, file))
    }

    /// Fsync `file` (what [`PartialFile::open`] gave) and rename it over the target.
    pub fn commit(mut self, file: File) -> Result<(), IoError> {
        let err = |e: std::io::Error| {
            IoError::new(format!("cannot write: {}", crate::io_words(&e))).in_file(&self.shown)
        };
        file.sync_all().map_err(err)?;
        rename_over(&self.partial, &self.target, &self.shown)?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for PartialFile {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}

impl<W: Write + Durable> AtomicFile<W> {
    fn with_writer(out: &Output, partial: PathBuf, w: W, on_drop: OnDrop) -> Self {
        AtomicFile {
            target: out.target.clone(),
            shown: out.path.clone(),
            partial,
            out: Some(BufWriter::new(w)),
            on_drop,
            lines: 0,
            header: 1,
            flush_lines: on_drop == OnDrop::KeepRecorded,
            failed: false,
            accepted: 0,
            whole_rows: 0,
        }
    }

    /// An I/O error as an [`IoError`] naming the file.
    pub fn error(&self, e: std::io::Error) -> IoError {
        IoError::new(format!("cannot write: {}", crate::io_words(&e))).in_file(&self.shown)
    }

    /// The lines written so far are the header: a recording with nothing after them
    /// holds nothing recorded and is not kept.
    pub fn header_written(&mut self) {
        self.header = self.lines;
    }

    /// The file the bytes go to (the path the user gave).
    pub fn path(&self) -> &Path {
        &self.shown
    }

    /// Flush, fsync, rename over the target: the new content, complete, in its place.
    pub fn commit(mut self) -> Result<(), IoError> {
        self.finish()
    }

    /// Give up: the partial file is removed, the old file stays as it was.
    pub fn discard(mut self) {
        self.out = None;
        let _ = std::fs::remove_file(&self.partial);
    }

    fn finish(&mut self) -> Result<(), IoError> {
        let Some(out) = self.out.take() else {
            return Ok(());
        };
        let synced = out
            .into_inner()
            .map_err(|e| e.into_error())
            .and_then(|mut w| w.sync());
        let synced = match synced {
            Ok(()) if self.failed => Err(std::io::Error::other("an earlier write failed")),
            r => r,
        };
        if let Err(e) = synced {
            let e = self.failed_with(e);
            if self.on_drop == OnDrop::Remove {
                let _ = std::fs::remove_file(&self.partial);
            } else {
                self.trim_to_whole_rows();
            }
            return Err(self.error(e));
        }
        rename_over(&self.partial, &self.target, &self.shown).inspect_err(|_| {
            // A recording stays under its partial name: nothing recorded is lost.
            if self.on_drop == OnDrop::Remove {
                let _ = std::fs::remove_file(&self.partial);
            }
        })
    }
}

impl<W: Write + Durable> Write for AtomicFile<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let out = self
            .out
            .as_mut()
            .ok_or_else(|| std::io::Error::other("the file is already closed"))?;
        let n = match out.write(buf) {
            Ok(n) => n,
            Err(e) => return Err(self.failed_with(e)),
        };
        let newlines = buf[..n].iter().filter(|&&b| b == b'\n').count() as u64;
        self.lines += newlines;
        let before = self.accepted;
        self.accepted += n as u64;
        if self.flush_lines && newlines > 0 {
            if let Err(e) = out.flush() {
                return Err(self.failed_with(e));
            }
            if let Some(last) = buf[..n].iter().rposition(|&b| b == b'\n') {
                self.whole_rows = before + last as u64 + 1;
            }
        }
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let r = self.out.as_mut().map_or(Ok(()), |o| o.flush());
        r.map_err(|e| self.failed_with(e))
    }
}

impl<W: Write + Durable> AtomicFile<W> {
    /// A recording whose write failed ends at its last whole row (a full disk may
    /// have taken half of the next), so that every line of `FILE.partial` is a row.
    fn trim_to_whole_rows(&self) {
        if let Ok(f) = std::fs::OpenOptions::new().write(true).open(&self.partial)
            && f.metadata().is_ok_and(|m| m.len() > self.whole_rows)
        {
            let _ = f.set_len(self.whole_rows);
        }
    }

    /// A write error noted; a recording's says where its rows are kept.
    fn failed_with(&mut self, e: std::io::Error) -> std::io::Error {
        self.failed = true;
        if self.on_drop == OnDrop::KeepRecorded {
            std::io::Error::new(
                e.kind(),
                format!(
                    "{}; the rows written before it are in {}, the old file is as it was",
                    crate::io_words(&e),
                    self.partial.display()
                ),
            )
        } else {
            e
        }
    }
}

impl<W: Write + Durable> Drop for AtomicFile<W> {
    fn drop(&mut self) {
        if self.out.is_none() {
            return;
        }
        if self.on_drop == OnDrop::KeepRecorded && self.failed {
            // A write failed: the rows stay under the partial name, the old file whole.
            self.out = None;
            self.trim_to_whole_rows();
        } else if self.on_drop == OnDrop::KeepRecorded && self.lines > self.header {
            // What was recorded is kept: nothing a user recorded is ever lost.
            let _ = self.finish();
        } else {
            self.out = None;
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("twinloop-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    /// A disk that fills after `room` bytes: ENOSPC, as `write(2)` says it.
    struct FullDisk {
        room: usize,
    }

    impl Write for FullDisk {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.room == 0 {
                return Err(std::io::Error::from_raw_os_error(28));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            Ok(n)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Durable for FullDisk {
        fn sync(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_full_disk_leaves_the_old_file_whole_and_no_partial_one() {
        let path = scratch("model.urdf");
        std::fs::write(&path, "<robot name=\"old\"/>\n").unwrap();
        let out = Output::resolve("--out", &path).unwrap();
        let partial = in_progress(&path);
        std::fs::write(&partial, "").unwrap();
        let mut f =
            AtomicFile::with_writer(&out, partial.clone(), FullDisk { room: 10 }, OnDrop::Remove);
        let big = vec![b'x'; 64 * 1024];
        let e = f.write_all(&big).map_err(|e| f.error(e)).unwrap_err();
        drop(f);
        assert!(e.to_string().contains("model.urdf"), "{e}");
        assert!(e.to_string().contains("No space left on device"), "{e}");
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "<robot name=\"old\"/>\n"
        );
        assert!(!partial.exists());
        // Full at the final flush (the bytes fit the buffer): commit fails the same way.
        std::fs::write(&partial, "").unwrap();
        let mut f =
            AtomicFile::with_writer(&out, partial.clone(), FullDisk { room: 3 }, OnDrop::Remove);
        f.write_all(b"<robot name=\"new\"/>\n").unwrap();
        assert!(
            f.commit()
                .unwrap_err()
                .to_string()
                .contains("No space left")
        );
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "<robot name=\"old\"/>\n"
        );
        assert!(!partial.exists());
    }

    #[test]
    fn a_recording_on_a_full_disk_keeps_its_rows_aside_and_the_old_file_whole() {
        let path = scratch("old-rec.csv");
        std::fs::write(&path, "t\n1\n").unwrap();
        let out = Output::resolve("", &path).unwrap();
        let partial = in_progress(&path);
        std::fs::write(&partial, "").unwrap();
        let mut r = AtomicFile::with_writer(
            &out,
            partial.clone(),
            FullDisk { room: 12 },
            OnDrop::KeepRecorded,
        );
        r.write_all(b"t,q\n0,1\n").unwrap();
        let e = r
            .write_all(b"0.001,2\n")
            .map_err(|e| r.error(e))
            .unwrap_err();
        drop(r);
        assert!(e.to_string().contains("old-rec.csv.partial"), "{e}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "t\n1\n");
        assert!(partial.exists());
    }

    #[test]
    fn a_complete_write_replaces_the_file_and_a_symlink_stays_a_link() {
        let target = scratch("run-42.csv");
        let link = scratch("latest.csv");
        std::fs::write(&target, "old\n").unwrap();
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_atomic(&link, "t\n1\n").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "t\n1\n");
        let dangling = scratch("dangling.csv");
        let _ = std::fs::remove_file(&dangling);
        std::os::unix::fs::symlink(scratch("nowhere"), &dangling).unwrap();
        let e = write_atomic(&dangling, "x").unwrap_err().to_string();
        assert!(e.contains("dangling.csv") && e.contains("symlink"), "{e}");
    }

    #[test]
    fn special_files_missing_folders_and_inputs_are_refused() {
        for dev in ["/dev/null", "/dev/zero"] {
            let e = Output::check("--out", Path::new(dev), &[]).unwrap_err();
            assert!(
                e.to_string().contains(&format!("--out {dev}: is a device")),
                "{e}"
            );
        }
        let e = Output::check("--json", &scratch("no/such/folder/x.json"), &[]).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        let input = scratch("goals.csv");
        std::fs::write(&input, "t\n0\n").unwrap();
        let inputs = vec![("--trajectory".to_string(), input.clone())];
        let e = Output::check("--out", &input, &inputs)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--out") && e.contains("--trajectory"), "{e}");
        // The same file by another name is the same file.
        let other = input.parent().unwrap().join(".").join("goals.csv");
        assert!(Output::check("--out", &other, &inputs).is_err());
    }

    #[test]
    fn a_file_read_as_an_input_is_not_written_over_but_one_written_and_read_back_is() {
        // Read however it was named (here: the include of an include), refused as output.
        let part = scratch("part.xml");
        std::fs::write(&part, "<mujoco/>").unwrap();
        crate::input::read_text(&part).unwrap();
        let e = write_atomic(&part, "<robot/>").unwrap_err().to_string();
        assert!(e.contains("part.xml") && e.contains("input"), "{e}");
        assert_eq!(std::fs::read_to_string(&part).unwrap(), "<mujoco/>");
        assert!(!in_progress(&part).exists());
        // A file this process wrote, read back and written again is its own.
        let tip = scratch("tipover.json");
        write_atomic(&tip, "{}").unwrap();
        crate::input::read_text(&tip).unwrap();
        write_atomic(&tip, "{\"a\": 1}").unwrap();
        assert_eq!(std::fs::read_to_string(&tip).unwrap(), "{\"a\": 1}");
    }

    #[test]
    fn a_recording_is_kept_when_dropped_but_not_when_nothing_was_recorded() {
        let path = scratch("rec.csv");
        std::fs::write(&path, "t\n1\n2\n").unwrap();
        let out = Output::resolve("", &path).unwrap();
        {
            let mut r = AtomicFile::recording(&out).unwrap();
            r.write_all(b"t,q\n").unwrap();
        }
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "t\n1\n2\n");
        {
            let mut r = AtomicFile::recording(&out).unwrap();
            r.write_all(b"t,q\n0,1\n").unwrap();
            // While it runs, the rows are on disk under the partial name.
            assert_eq!(
                std::fs::read_to_string(in_progress(&path)).unwrap(),
                "t,q\n0,1\n"
            );
        }
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "t,q\n0,1\n");
        assert!(!in_progress(&path).exists());
    }

    /// Two runs writing one output at once: the second is refused, naming the file,
    /// and the first's rows are whole; a killed run's partial file is kept aside, not
    /// replaced.
    #[test]
    fn a_second_writer_is_refused_and_a_killed_runs_rows_are_kept() {
        let path = scratch("twice.csv");
        let _ = std::fs::remove_file(&path);
        let out = Output::resolve("--out", &path).unwrap();
        let mut first = AtomicFile::recording(&out).unwrap();
        first.write_all(b"t,q\n0,1\n").unwrap();
        let e = AtomicFile::recording(&out).err().unwrap().to_string();
        assert!(e.contains("another run is writing it now"), "{e}");
        assert!(e.contains("twice.csv"), "{e}");
        first.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "t,q\n0,1\n");

        // A killed run: its partial file is left, held by nobody.
        let partial = in_progress(&path);
        std::fs::write(&partial, "t,q\n5,6\n").unwrap();
        let mut next = AtomicFile::recording(&out).unwrap();
        next.write_all(b"t,q\n7,8\n").unwrap();
        next.commit().unwrap();
        let mut kept = partial.as_os_str().to_owned();
        kept.push(".1");
        assert_eq!(std::fs::read_to_string(&kept).unwrap(), "t,q\n5,6\n");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "t,q\n7,8\n");
        let _ = std::fs::remove_file(&kept);
    }
}
