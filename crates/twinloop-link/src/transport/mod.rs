//! Byte transports between a host and a bus: a serial port (USB2Dynamixel,
//! U2D2, any RS-485/TTL adapter), TCP (a bus behind a network bridge or a virtual
//! robot), a pseudo-terminal (a virtual robot that looks like a serial port to any
//! program, the official SDK included), and in-memory loopbacks for tests.

mod lock;
mod loopback;
mod noisy;
mod pty;
mod serial;
mod tcp;

pub use loopback::{LoopbackTransport, Responder};
pub use noisy::{NoiseStats, NoisyTransport};
pub use pty::{PtyTransport, TtyTransport};
pub use serial::{SerialOptions, SerialTransport};
pub use tcp::{REFUSAL, TcpTransport, refuse};

use std::io;
use std::time::Duration;

/// A half-duplex byte pipe to a bus.
pub trait Transport: Send {
    /// Send every byte (blocking).
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()>;

    /// Wait at most `timeout` for bytes and read what is there into `buf`.
    /// `Ok(0)` means nothing arrived in time. An error means the link is gone
    /// (adapter unplugged, peer closed).
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize>;

    /// Drop bytes received but not yet read (late replies of an earlier exchange);
    /// returns how many were dropped (as far as the transport can tell).
    fn discard_input(&mut self) -> io::Result<usize>;

    /// The line's bit rate, where there is one (wire-time estimates use it).
    fn baud(&self) -> Option<u32> {
        None
    }

    /// Before sleeping in [`Transport::read`], check for bytes without blocking
    /// for up to `spin`: a short reply then costs no scheduler wake-up (tens of
    /// microseconds on a loaded machine) at the price of a busy CPU meanwhile.
    /// Zero (the default) always sleeps. Transports without a file descriptor
    /// ignore it.
    fn set_spin(&mut self, spin: Duration) {
        let _ = spin;
    }

    /// What this transport is connected to, for messages.
    fn describe(&self) -> String;
}

impl<T: Transport + ?Sized> Transport for Box<T> {
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        (**self).write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        (**self).read(buf, timeout)
    }
    fn discard_input(&mut self) -> io::Result<usize> {
        (**self).discard_input()
    }
    fn baud(&self) -> Option<u32> {
        (**self).baud()
    }
    fn set_spin(&mut self, spin: Duration) {
        (**self).set_spin(spin)
    }
    fn describe(&self) -> String {
        (**self).describe()
    }
}

/// Open a transport from a user's port string: `tcp:HOST:PORT` for TCP, anything
/// else a serial device path (a pty path from `twinloop serve` works too). A device
/// is opened for this process alone; one another process has is refused with an
/// error of kind `ResourceBusy` naming it (see `lock`).
pub fn open(port: &str, baud: u32, options: &SerialOptions) -> io::Result<Box<dyn Transport>> {
    if let Some(addr) = port.strip_prefix("tcp:") {
        return Ok(Box::new(TcpTransport::connect(addr)?));
    }
    match SerialTransport::open(port, baud, options) {
        Ok(s) => Ok(Box::new(s)),
        Err(e) if e.kind() == io::ErrorKind::ResourceBusy => Err(e),
        // A pseudo-terminal refuses some serial ioctls; talk to it as a plain tty.
        Err(e) if is_pty_path(port) => TtyTransport::open(port)
            .map(|t| Box::new(t) as Box<dyn Transport>)
            .map_err(|e2| io::Error::new(e2.kind(), format!("{e}; as a tty: {e2}"))),
        Err(e) => Err(e),
    }
}

fn is_pty_path(port: &str) -> bool {
    port.starts_with("/dev/pts/") || port.starts_with("/dev/ttyp")
}
