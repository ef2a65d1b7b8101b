//! One owner per port: a serial device or pty is taken for this process alone, and
//! a program that finds it taken is told who has it.
//!
//! Two locks, as the `serialport` crate takes them (posix/tty.rs, TTYPort::open):
//! an exclusive `flock` on the device, which every program that asks for one
//! respects (twinloop, serialport-based tools), root included; and the TIOCEXCL
//! ioctl, with which the kernel refuses any further open() of the tty (EBUSY) to
//! programs without CAP_SYS_ADMIN, such as the ROBOTIS SDK's (tty_ioctl(4)). Both
//! end when the descriptor is closed. A busy port is named with the process that
//! holds its flock, read from /proc/locks (proc(5)).

use nix::fcntl::{FlockArg, flock};
use std::io;
use std::os::fd::RawFd;
use std::os::unix::fs::MetadataExt;
use std::path::Path;

/// Take the port open on `fd` (opened from `path`) for this process alone.
pub(crate) fn claim(fd: RawFd, path: &Path) -> io::Result<()> {
    match flock(fd, FlockArg::LockExclusiveNonblock) {
        Ok(()) => {}
        Err(nix::Error::EWOULDBLOCK) => return Err(busy(path)),
        Err(e) => {
            return Err(io::Error::new(
                io::Error::from(e).kind(),
                format!("cannot lock {}: {e}", path.display()),
            ));
        }
    }
    // SAFETY: TIOCEXCL takes no argument and only sets a flag on the open tty.
    // Its failure (not a tty) leaves the flock, which is what matters among us.
    let _ = unsafe { nix::libc::ioctl(fd, nix::libc::TIOCEXCL) };
    Ok(())
}

/// The error for a port another process has: `port P is busy: process N (NAME)
/// has it open`.
pub(crate) fn busy(path: &Path) -> io::Error {
    let who = match holder(path) {
        Some((pid, name)) => format!("process {pid} ({name})"),
        None => "another process".to_string(),
    };
    io::Error::new(
        io::ErrorKind::ResourceBusy,
        format!(
            "port {} is busy: {who} has it open (one program at a time talks to a bus)",
            path.display()
        ),
    )
}

/// The process holding an exclusive flock on `path`, with its name, from
/// /proc/locks: lines `N: FLOCK ADVISORY WRITE PID MAJ:MIN:INODE START END`, the
/// device numbers in hex (fs/locks.c, lock_get_status).
fn holder(path: &Path) -> Option<(u32, String)> {
    let meta = std::fs::metadata(path).ok()?;
    let (major, minor) = (
        nix::sys::stat::major(meta.dev()),
        nix::sys::stat::minor(meta.dev()),
    );
    let locks = std::fs::read_to_string("/proc/locks").ok()?;
    let pid = locks.lines().find_map(|line| {
        let f: Vec<&str> = line.split_whitespace().collect();
        // A waiting lock is marked "->" and shifts the fields.
        let f = if f.get(1) == Some(&"->") {
            &f[1..]
        } else {
            &f[..]
        };
        if f.get(1) != Some(&"FLOCK") || f.get(3) != Some(&"WRITE") {
            return None;
        }
        let mut id = f.get(5)?.split(':');
        let maj = u64::from_str_radix(id.next()?, 16).ok()?;
        let min = u64::from_str_radix(id.next()?, 16).ok()?;
        let ino: u64 = id.next()?.parse().ok()?;
        (maj == major && min == minor && ino == meta.ino())
            .then(|| f.get(4)?.parse::<u32>().ok())
            .flatten()
    })?;
    let name = std::fs::read_to_string(format!("/proc/{pid}/comm"))
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|_| "?".into());
    Some((pid, name))
}
