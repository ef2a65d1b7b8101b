//! Pseudo-terminals: a virtual robot's end ([`PtyTransport`], the master side) and a
//! plain tty opened by path without serial-port ioctls ([`TtyTransport`], what the
//! host uses on a pty's slave path).
//!
//! The slave side is put in raw mode (no echo, no line editing, no CR/LF
//! translation): Dynamixel packets are binary and 0x0D or 0x03 must pass untouched.

use super::Transport;
use nix::poll::{PollFd, PollFlags, poll};
use nix::sys::termios::{SetArg, cfmakeraw, tcgetattr, tcsetattr};
use std::fs::{File, OpenOptions};
use std::io::{self, Read, Write};
use std::os::fd::{AsRawFd, FromRawFd, RawFd};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn nix_err(e: nix::Error, what: &str) -> io::Error {
    io::Error::new(io::Error::from(e).kind(), format!("{what}: {e}"))
}

fn make_raw(fd: RawFd) -> io::Result<()> {
    let mut t = tcgetattr(fd).map_err(|e| nix_err(e, "tcgetattr"))?;
    cfmakeraw(&mut t);
    tcsetattr(fd, SetArg::TCSANOW, &t).map_err(|e| nix_err(e, "tcsetattr"))
}

/// Wait up to `timeout` for `fd` to be readable.
fn wait_readable(fd: RawFd, timeout: Duration) -> io::Result<bool> {
    // poll counts milliseconds: round up so a short timeout still waits.
    let ms = timeout.as_micros().div_ceil(1000).min(i32::MAX as u128) as i32;
    let mut fds = [PollFd::new(fd, PollFlags::POLLIN)];
    match poll(&mut fds, ms) {
        Ok(0) => Ok(false),
        Ok(_) => Ok(true),
        // A signal (Ctrl-C) ends the wait early: report "nothing yet".
        Err(nix::Error::EINTR) => Ok(false),
        Err(e) => Err(nix_err(e, "poll")),
    }
}

/// Poll without blocking until `fd` is readable or `spin` has passed.
pub(crate) fn spin_readable(fd: RawFd, spin: Duration) -> io::Result<bool> {
    if spin.is_zero() {
        return Ok(false);
    }
    let start = std::time::Instant::now();
    loop {
        if wait_readable(fd, Duration::ZERO)? {
            return Ok(true);
        }
        if start.elapsed() >= spin {
            return Ok(false);
        }
        std::hint::spin_loop();
    }
}

fn read_with_timeout(
    file: &mut File,
    buf: &mut [u8],
    timeout: Duration,
    spin: Duration,
) -> io::Result<usize> {
    let ready = spin_readable(file.as_raw_fd(), spin.min(timeout))?;
    if !ready && !wait_readable(file.as_raw_fd(), timeout.saturating_sub(spin))? {
        return Ok(0);
    }
    match file.read(buf) {
        Ok(0) => Err(io::Error::new(io::ErrorKind::UnexpectedEof, "tty closed")),
        Ok(n) => Ok(n),
        Err(e) if e.kind() == io::ErrorKind::Interrupted => Ok(0),
        Err(e) => Err(e),
    }
}

fn drain(file: &mut File) -> io::Result<usize> {
    let mut scratch = [0u8; 512];
    let mut dropped = 0;
    while wait_readable(file.as_raw_fd(), Duration::ZERO)? {
        let n = file.read(&mut scratch)?;
        if n == 0 {
            break;
        }
        dropped += n;
    }
    Ok(dropped)
}

/// The master side of a new pseudo-terminal. Programs open [`PtyTransport::path`]
/// as if it were a USB serial adapter.
pub struct PtyTransport {
    spin: Duration,
    master: File,
    /// Held open so the master does not see end-of-file between clients.
    _slave: File,
    path: PathBuf,
}

impl PtyTransport {
    pub fn open() -> io::Result<PtyTransport> {
        let pair = nix::pty::openpty(None, None).map_err(|e| nix_err(e, "openpty"))?;
        // SAFETY: openpty returned two fresh descriptors that nothing else owns.
        let (master, slave) = unsafe {
            (
                File::from_raw_fd(pair.master),
                File::from_raw_fd(pair.slave),
            )
        };
        make_raw(slave.as_raw_fd())?;
        let path = nix::unistd::ttyname(slave.as_raw_fd()).map_err(|e| nix_err(e, "ttyname"))?;
        Ok(PtyTransport {
            spin: Duration::ZERO,
            master,
            _slave: slave,
            path,
        })
    }

    /// The slave device path to hand to clients (`/dev/pts/N`).
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Transport for PtyTransport {
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.master.write_all(bytes)
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        read_with_timeout(&mut self.master, buf, timeout, self.spin)
    }

    fn set_spin(&mut self, spin: Duration) {
        self.spin = spin;
    }

    fn discard_input(&mut self) -> io::Result<usize> {
        drain(&mut self.master)
    }

    fn describe(&self) -> String {
        format!("pseudo-terminal {}", self.path.display())
    }
}

/// A tty opened by path in raw mode, without the serial ioctls a pseudo-terminal
/// may refuse; taken for this process alone (flock and TIOCEXCL).
pub struct TtyTransport {
    spin: Duration,
    file: File,
    path: PathBuf,
}

impl TtyTransport {
    pub fn open(path: impl AsRef<Path>) -> io::Result<TtyTransport> {
        let path = path.as_ref().to_path_buf();
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(nix::libc::O_NOCTTY)
            .open(&path)
            .map_err(|e| match e.raw_os_error() {
                // TIOCEXCL set by the process that has it.
                Some(nix::libc::EBUSY) => super::lock::busy(&path),
                _ => io::Error::new(e.kind(), format!("cannot open {}: {e}", path.display())),
            })?;
        super::lock::claim(file.as_raw_fd(), &path)?;
        make_raw(file.as_raw_fd())?;
        Ok(TtyTransport {
            spin: Duration::ZERO,
            file,
            path,
        })
    }
}

impl Transport for TtyTransport {
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.file.write_all(bytes)
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        read_with_timeout(&mut self.file, buf, timeout, self.spin)
    }

    fn set_spin(&mut self, spin: Duration) {
        self.spin = spin;
    }

    fn discard_input(&mut self) -> io::Result<usize> {
        drain(&mut self.file)
    }

    fn describe(&self) -> String {
        format!("tty {}", self.path.display())
    }
}
