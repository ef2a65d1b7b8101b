//! A real serial port through the `serialport` crate.

use super::Transport;
use serialport::{ClearBuffer, SerialPort, TTYPort};
use std::io::{self, Read, Write};
use std::time::Duration;

/// Options for opening a serial port.
#[derive(Debug, Clone, Default)]
pub struct SerialOptions {
    /// Ask the USB adapter to pass bytes on at once: FTDI chips (USB2Dynamixel,
    /// U2D2) hold received bytes up to their latency timer, 16 ms by default, which
    /// would dominate a 1 Mbps control cycle. On Linux this writes 1 to
    /// `/sys/bus/usb-serial/devices/<tty>/latency_timer` (needs write permission).
    pub low_latency: bool,
}

/// A serial port (8N1, no flow control).
pub struct SerialTransport {
    port: TTYPort,
    path: String,
    baud: u32,
    timeout: Duration,
    spin: Duration,
    /// What the low-latency request did, for the user.
    pub low_latency_note: Option<String>,
}

impl SerialTransport {
    pub fn open(path: &str, baud: u32, options: &SerialOptions) -> io::Result<SerialTransport> {
        let timeout = Duration::from_millis(10);
        let port = serialport::new(path, baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(timeout)
            // Exclusive (the default, said for the reader): TIOCEXCL and a flock.
            .exclusive(true)
            .open_native()
            .map_err(|e| match e.kind() {
                // serialport's word for "already in use" (EBUSY from TIOCEXCL, or
                // the flock taken).
                serialport::ErrorKind::NoDevice => super::lock::busy(std::path::Path::new(path)),
                _ => io::Error::other(format!("cannot open serial port {path}: {e}")),
            })?;
        let low_latency_note = options.low_latency.then(|| set_low_latency(path));
        Ok(SerialTransport {
            port,
            path: path.to_string(),
            baud,
            timeout,
            spin: Duration::ZERO,
            low_latency_note,
        })
    }
}

/// Set an FTDI adapter's latency timer to 1 ms through sysfs; returns what happened.
fn set_low_latency(path: &str) -> String {
    let real = std::fs::canonicalize(path).unwrap_or_else(|_| path.into());
    let Some(name) = real.file_name().and_then(|n| n.to_str()) else {
        return format!("low latency: cannot name the device of {path}");
    };
    let sysfs = format!("/sys/bus/usb-serial/devices/{name}/latency_timer");
    match std::fs::write(&sysfs, "1") {
        Ok(()) => format!("low latency: {sysfs} = 1 ms"),
        Err(e) => format!("low latency: cannot write {sysfs}: {e}"),
    }
}

impl Transport for SerialTransport {
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.port.write_all(bytes)?;
        self.port.flush()
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        let spun = self.spin.min(timeout);
        let timeout =
            if super::pty::spin_readable(std::os::fd::AsRawFd::as_raw_fd(&self.port), spun)? {
                timeout
            } else {
                timeout.saturating_sub(spun)
            };
        if timeout != self.timeout {
            self.port.set_timeout(timeout)?;
            self.timeout = timeout;
        }
        match self.port.read(buf) {
            Ok(0) => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!("serial port {} closed", self.path),
            )),
            Ok(n) => Ok(n),
            Err(e) if e.kind() == io::ErrorKind::TimedOut => Ok(0),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn discard_input(&mut self) -> io::Result<usize> {
        // What the driver holds, counted before it is flushed (a byte arriving in
        // between is flushed uncounted).
        let held = self.port.bytes_to_read().unwrap_or(0) as usize;
        self.port
            .clear(ClearBuffer::Input)
            .map_err(|e| io::Error::other(e.to_string()))?;
        Ok(held)
    }

    fn baud(&self) -> Option<u32> {
        Some(self.baud)
    }

    fn set_spin(&mut self, spin: Duration) {
        self.spin = spin;
    }

    fn describe(&self) -> String {
        format!("serial port {} at {} bps", self.path, self.baud)
    }
}
