//! The bus a plan opens: the port and how its replies are waited for, as `twinloop
//! link`'s flags give them and Python's keywords; opened as a client whose failures
//! name the port.

use std::time::Duration;
use twinloop_link::transport::{self, SerialOptions, Transport};
use twinloop_link::{Client, ClientConfig};

use crate::LoopError;

/// How a bus is opened.
#[derive(Debug, Clone)]
pub struct BusPort {
    /// A serial device, a pty path from `twinloop serve`, or tcp:HOST:PORT; `None`:
    /// the mapping's.
    pub port: Option<String>,
    pub baud: u32,
    /// Allowance per reply on top of its wire time, ms.
    pub timeout_ms: f64,
    /// Extra attempts after a lost or damaged reply.
    pub retries: u32,
    /// Set the USB adapter's latency timer to 1 ms (FTDI, via sysfs).
    pub low_latency: bool,
    /// Busy-check the port this long before sleeping while waiting for a reply, us.
    pub spin_us: u64,
    /// How long a servo may stay silent before it is declared lost, s of wall time.
    pub silence_window: f64,
}

impl BusPort {
    /// The options of a port opened by a program rather than a person: the
    /// defaults but `port`, `timeout_ms` and `retries`.
    pub fn quick(port: Option<String>, timeout_ms: f64, retries: u32) -> BusPort {
        BusPort {
            port,
            baud: 1_000_000,
            timeout_ms,
            retries,
            low_latency: false,
            spin_us: 0,
            silence_window: twinloop_experiments::guarded::SILENCE_WINDOW_S,
        }
    }

    pub fn silence_window(&self) -> Duration {
        Duration::from_secs_f64(self.silence_window)
    }

    /// Open the bus `port` names (or `default_port`).
    pub fn open(
        &self,
        default_port: Option<&str>,
    ) -> Result<Client<Box<dyn Transport>>, LoopError> {
        let Some(port) = self.port.as_deref().or(default_port) else {
            return Err(LoopError::new(
                "--port is required (a serial device, a pty path or tcp:HOST:PORT)",
            )
            .at("port"));
        };
        let options = SerialOptions {
            low_latency: self.low_latency,
        };
        let t = transport::open(port, self.baud, &options).map_err(|e| match e.kind() {
            // The message names the port and who has it.
            std::io::ErrorKind::ResourceBusy => LoopError::io(e.to_string()),
            _ => LoopError::io(format!("{port}: {e}")),
        })?;
        let mut t: Box<dyn Transport> = Box::new(Named {
            inner: t,
            port: port.to_string(),
        });
        t.set_spin(Duration::from_micros(self.spin_us));
        let config = ClientConfig {
            latency: Duration::from_secs_f64(self.timeout_ms.max(0.0) / 1000.0),
            retries: self.retries,
            baud: self.baud,
            write_replies: true,
        };
        Ok(Client::with_config(t, config))
    }
}

/// A transport whose failures name its port: an adapter unplugged or a peer gone in
/// the middle of any command over the bus says which port went away.
struct Named {
    inner: Box<dyn Transport>,
    port: String,
}

impl Named {
    fn name(&self, e: std::io::Error) -> std::io::Error {
        if e.kind() == std::io::ErrorKind::ResourceBusy {
            // A refusal names the port already.
            return e;
        }
        std::io::Error::new(e.kind(), format!("{}: {e}", self.port))
    }
}

impl Transport for Named {
    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.inner.write_all(bytes).map_err(|e| self.name(e))
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        self.inner.read(buf, timeout).map_err(|e| self.name(e))
    }

    fn discard_input(&mut self) -> std::io::Result<usize> {
        self.inner.discard_input().map_err(|e| self.name(e))
    }

    fn baud(&self) -> Option<u32> {
        self.inner.baud()
    }

    fn set_spin(&mut self, spin: Duration) {
        self.inner.set_spin(spin)
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}
