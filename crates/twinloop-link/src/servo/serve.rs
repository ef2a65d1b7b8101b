//! Serving a virtual bus on a transport: read what the host sends, answer, and (by
//! default) take as long as a real bus would: the request's and each reply's wire
//! time at the chosen bit rate plus each servo's Return Delay Time.

use super::backend::VirtualServoBackend;
use super::bus::{BusClock, VirtualBus};
use crate::transport::Transport;
use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

#[derive(Debug, Clone)]
pub struct ServeOptions {
    /// Bit rate whose wire time is emulated; `None` answers at once.
    pub emulate_baud: Option<u32>,
    /// Stop when the transport reports end-of-file (a TCP client left). A pty
    /// never does: clients come and go.
    pub stop_on_eof: bool,
    /// Say on stderr (at most once a second) when requests piled up while the
    /// server was not running and only the last was answered.
    pub warn_stalls: bool,
}

impl Default for ServeOptions {
    fn default() -> ServeOptions {
        ServeOptions {
            emulate_baud: Some(1_000_000),
            stop_on_eof: true,
            warn_stalls: false,
        }
    }
}

fn wire(bytes: usize, baud: u32) -> Duration {
    Duration::from_nanos(bytes as u64 * 10 * 1_000_000_000 / baud.max(1) as u64)
}

/// Requests left unanswered after stalls, told on stderr at most once a second.
#[derive(Default)]
struct StallNotes {
    told: u64,
    last: Option<Instant>,
}

impl StallNotes {
    fn note(&mut self, superseded: u64) {
        if superseded == self.told || self.last.is_some_and(|t| t.elapsed().as_secs() < 1) {
            return;
        }
        eprintln!(
            "warning: the server was stalled: {} request(s) waited past their reply and were \
             left unanswered (the host had given up on them), the last one answered; {} so far",
            superseded - self.told,
            superseded
        );
        self.told = superseded;
        self.last = Some(Instant::now());
    }
}

/// Sleep until `until`, the last stretch spinning: thread sleeps overshoot by tens of
/// microseconds, which matters at 1 Mbps.
fn wait_until(until: Instant) {
    loop {
        let now = Instant::now();
        if now >= until {
            return;
        }
        let left = until - now;
        if left > Duration::from_micros(200) {
            std::thread::sleep(left - Duration::from_micros(150));
        } else {
            std::hint::spin_loop();
        }
    }
}

/// Serve `bus` on `transport` until `stop` is set (or, with `stop_on_eof`, the peer
/// leaves). Time on the bus follows the wall clock.
///
/// A served bus answers as a real one would after the server was descheduled:
/// of the requests that piled up meanwhile only the last that needs a reply is
/// answered (see [`VirtualBus::latest_reply_only`]); the others' writes still
/// take effect.
pub fn serve<T: Transport, B: VirtualServoBackend>(
    bus: &mut VirtualBus<B>,
    transport: &mut T,
    options: &ServeOptions,
    stop: &AtomicBool,
) -> io::Result<()> {
    bus.clock = BusClock::Wall {
        last: Instant::now(),
    };
    bus.latest_reply_only = true;
    let mut stalls = StallNotes::default();
    let mut input = vec![0u8; 4096];
    let mut reply = Vec::with_capacity(8192);
    while !stop.load(Ordering::Relaxed) {
        // A short wait: silence on the line ends a truncated packet (line_idle).
        let n = match transport.read(&mut input, Duration::from_millis(20)) {
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof && !options.stop_on_eof => {
                std::thread::sleep(Duration::from_millis(20));
                continue;
            }
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(e),
        };
        let arrived = Instant::now();
        reply.clear();
        if n == 0 {
            bus.marks.clear();
            bus.line_idle(&mut reply);
        } else {
            bus.handle(&input[..n], &mut reply);
        }
        if options.warn_stalls {
            stalls.note(bus.stats.superseded);
        }
        if reply.is_empty() {
            continue;
        }
        match options.emulate_baud {
            None => transport.write_all(&reply)?,
            Some(baud) => {
                // The request was still on the wire while its first bytes arrived.
                let mut t = arrived + wire(n, baud);
                let mut begin = 0;
                for m in &bus.marks {
                    t += m.delay + wire(m.end - begin, baud);
                    wait_until(t);
                    transport.write_all(&reply[begin..m.end])?;
                    begin = m.end;
                }
            }
        }
    }
    Ok(())
}
