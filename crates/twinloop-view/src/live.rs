//! The live view: a running simulation or robot publishes its state, and every page
//! connected to `/live` (a websocket) receives the newest one.
//!
//! Nothing queues: the feed keeps only the latest state, so a 1 kHz source and a
//! 60 Hz screen never build a backlog, and a slow or stalled client only skips
//! states. The publisher decimates too ([`Decimator`]), and copies numbers into a
//! slot sized once (no allocation, no JSON on the producer's thread); each client
//! thread copies the slot out and makes the JSON itself.

use serde::Serialize;
use std::io::{BufRead, BufReader, Seek, SeekFrom};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, TryLockError};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// One state as the page receives it.
#[derive(Debug, Clone, Default, Serialize)]
pub(crate) struct LiveFrame {
    /// The source's time, s.
    pub t: f64,
    /// Wall clock when the source published it, ms since the Unix epoch (the page's
    /// lag is the time it drew the state minus this).
    pub sent_ms: f64,
    /// Joint positions in the scene's joint order (NaN, sent as null: not known).
    pub q: Vec<f64>,
    /// Base position and quaternion (x, y, z, qx, qy, qz, qw), when known.
    pub base: Option<[f64; 7]>,
}

impl LiveFrame {
    fn copy_from(&mut self, t: f64, q: &[f64], base: Option<[f64; 7]>) {
        self.t = t;
        self.sent_ms = now_ms();
        self.q.clear();
        self.q.extend_from_slice(q);
        self.base = base;
    }
}

#[derive(Default)]
struct Slot {
    seq: u64,
    frame: LiveFrame,
    closed: bool,
}

/// How often a page's thread looks for a new state: at most this much lag added.
const POLL: Duration = Duration::from_millis(1);

#[derive(Default)]
struct Inner {
    slot: Mutex<Slot>,
    /// Pages connected now.
    clients: AtomicUsize,
    /// Pages connected since the start.
    connections: AtomicUsize,
}

/// The latest state, shared between the publisher and the websocket clients.
#[derive(Clone, Default)]
pub struct LiveFeed {
    inner: Arc<Inner>,
}

fn now_ms() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64() * 1e3)
}

impl LiveFeed {
    pub fn new() -> LiveFeed {
        LiveFeed::default()
    }

    /// Replace the latest state (joints in the scene's order), waiting for the lock
    /// if a client holds it (for a few microseconds, while it copies the state out).
    pub fn publish(&self, t: f64, q: &[f64], base: Option<[f64; 7]>) {
        let mut slot = self.inner.slot.lock().unwrap_or_else(|p| p.into_inner());
        Self::put(&mut slot, t, q, base);
    }

    /// Replace the latest state unless a client is copying it out right now; false
    /// then (the caller publishes a later state instead). Never waits: a producer
    /// with a deadline uses this.
    pub fn try_publish(&self, t: f64, q: &[f64], base: Option<[f64; 7]>) -> bool {
        let mut slot = match self.inner.slot.try_lock() {
            Ok(s) => s,
            Err(TryLockError::Poisoned(p)) => p.into_inner(),
            Err(TryLockError::WouldBlock) => return false,
        };
        Self::put(&mut slot, t, q, base);
        true
    }

    fn put(slot: &mut Slot, t: f64, q: &[f64], base: Option<[f64; 7]>) {
        slot.seq += 1;
        slot.frame.copy_from(t, q, base);
    }

    /// No more states: clients are told and their threads end.
    pub fn close(&self) {
        self.inner
            .slot
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .closed = true;
    }

    /// Pages connected now.
    pub fn clients(&self) -> usize {
        self.inner.clients.load(Ordering::SeqCst)
    }

    /// Pages that connected since the start.
    pub fn connections(&self) -> usize {
        self.inner.connections.load(Ordering::SeqCst)
    }

    /// Count a page in, unless `max` are connected already (false then).
    pub(crate) fn join(&self, max: usize) -> bool {
        if self.inner.clients.fetch_add(1, Ordering::SeqCst) >= max {
            self.inner.clients.fetch_sub(1, Ordering::SeqCst);
            return false;
        }
        self.inner.connections.fetch_add(1, Ordering::SeqCst);
        true
    }

    pub(crate) fn leave(&self) {
        self.inner.clients.fetch_sub(1, Ordering::SeqCst);
    }

    /// Copy the newest state after `seen` into `out`, waiting up to `timeout`:
    /// Some(its number), or None on timeout or when closed.
    ///
    /// The client looks every [`POLL`] rather than being woken: waking a thread
    /// from the producer's would cost the producer a system call and, on a busy
    /// machine, its core (measured: 130 to 200 us per state with a condition
    /// variable, against a 12 us simulation step).
    pub(crate) fn next(&self, seen: u64, timeout: Duration, out: &mut LiveFrame) -> Option<u64> {
        let start = Instant::now();
        let slot = loop {
            let slot = self.inner.slot.lock().unwrap_or_else(|p| p.into_inner());
            if slot.closed {
                return None;
            }
            if slot.seq != seen {
                break slot;
            }
            drop(slot);
            if start.elapsed() >= timeout {
                return None;
            }
            std::thread::sleep(POLL);
        };
        let f = &slot.frame;
        out.t = f.t;
        out.sent_ms = f.sent_ms;
        out.q.clear();
        out.q.extend_from_slice(&f.q);
        out.base = f.base;
        Some(slot.seq)
    }

    pub(crate) fn is_closed(&self) -> bool {
        self.inner
            .slot
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .closed
    }
}

/// Lets through one state per `period` of source time, on a fixed grid (a 100 Hz
/// source decimated to 60 Hz gives 60 states a second, not 50).
#[derive(Debug, Clone)]
pub struct Decimator {
    period: f64,
    next: f64,
}

impl Decimator {
    /// `rate`: states per second let through.
    pub fn new(rate: f64) -> Decimator {
        Decimator {
            period: 1.0 / rate,
            next: f64::NEG_INFINITY,
        }
    }

    /// Whether the state at `t` goes out.
    pub fn admit(&mut self, t: f64) -> bool {
        if t < self.next - 2.0 * self.period || t - self.next >= self.period {
            // The source started over, paused, or this is its first state: the grid
            // starts again here.
            self.next = t + self.period;
            true
        } else if t >= self.next {
            self.next += self.period;
            true
        } else {
            false
        }
    }

    /// Let the next state through whatever its time (it could not be published).
    pub fn retry(&mut self) {
        self.next = f64::NEG_INFINITY;
    }
}

/// Follow a CSV as another program writes it (`simulate --out`, `link record --out`):
/// wait for its header, then publish the newest complete row, at most `rate` per
/// second of the file's time, until `stop` says so. Columns: `t`, `q:<joint>` in
/// `joints` order (missing ones are NaN), `q:base.*` when all seven are there.
pub fn follow_csv(
    path: &Path,
    joints: &[String],
    rate: f64,
    feed: &LiveFeed,
    stop: &dyn Fn() -> bool,
) -> std::io::Result<()> {
    let poll = Duration::from_millis(2);
    // A recording is written under its in-progress name until it ends
    // (twinloop_io::output): follow that while it is there.
    let growing = twinloop_io::output::in_progress(path);
    let file = loop {
        match std::fs::File::open(&growing).or_else(|_| std::fs::File::open(path)) {
            Ok(f) => break f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && !stop() => {
                std::thread::sleep(Duration::from_millis(50))
            }
            Err(e) => return Err(e),
        }
    };
    let mut reader = BufReader::new(file);
    let mut header = String::new();
    while !header.ends_with('\n') {
        if stop() {
            return Ok(());
        }
        if reader.read_line(&mut header)? == 0 {
            std::thread::sleep(poll);
        }
    }
    let names: Vec<&str> = header.trim_end().split(',').map(str::trim).collect();
    let find = |n: &str| names.iter().position(|c| *c == n);
    let t_col = find("t")
        .ok_or_else(|| std::io::Error::other(format!("{}: no \"t\" column", path.display())))?;
    let q_cols: Vec<Option<usize>> = joints.iter().map(|j| find(&format!("q:{j}"))).collect();
    let base_cols: Option<Vec<usize>> = crate::recording::BASE_COLUMNS
        .iter()
        .map(|c| find(c))
        .collect();
    let mut decimate = Decimator::new(rate);
    let (mut line, mut partial) = (String::new(), String::new());
    let mut q = vec![f64::NAN; joints.len()];
    let mut cells: Vec<f64> = Vec::with_capacity(names.len());
    while !stop() {
        let mut newest: Option<String> = None;
        loop {
            line.clear();
            let n = reader.read_line(&mut line)?;
            if n == 0 {
                break;
            }
            partial.push_str(&line);
            if partial.ends_with('\n') {
                newest = Some(std::mem::take(&mut partial));
            }
        }
        let Some(row) = newest else {
            // The writer may have started over (a new run to the same file).
            let pos = reader.stream_position()?;
            if std::fs::metadata(path)
                .map(|m| m.len() < pos)
                .unwrap_or(false)
            {
                reader.seek(SeekFrom::Start(0))?;
                header.clear();
                reader.read_line(&mut header)?;
            }
            std::thread::sleep(poll);
            continue;
        };
        cells.clear();
        cells.extend(
            row.trim_end()
                .split(',')
                .map(|c| c.trim().parse::<f64>().unwrap_or(f64::NAN)),
        );
        let Some(&t) = cells.get(t_col) else { continue };
        if !decimate.admit(t) {
            continue;
        }
        for (v, c) in q.iter_mut().zip(&q_cols) {
            *v = c.and_then(|c| cells.get(c).copied()).unwrap_or(f64::NAN);
        }
        let base = base_cols.as_ref().and_then(|cols| {
            let mut b = [0.0; 7];
            for (v, &c) in b.iter_mut().zip(cols) {
                *v = *cells.get(c)?;
            }
            Some(b)
        });
        feed.publish(t, &q, base);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_1khz_source_is_let_through_at_the_screen_rate() {
        let mut d = Decimator::new(60.0);
        let n = (0..1000).filter(|&k| d.admit(k as f64 * 1e-3)).count();
        assert!((59..=61).contains(&n), "{n}");
        // A 100 Hz source (a robot read at 100 Hz) still gives 60, not every other
        // state (50).
        let mut d = Decimator::new(60.0);
        let n = (0..1000).filter(|&k| d.admit(k as f64 * 1e-2)).count();
        assert!((599..=601).contains(&n), "{n} in 10 s");
        // A source that starts over is followed at once.
        assert!(d.admit(0.0));
    }

    #[test]
    fn the_feed_keeps_only_the_newest_state() {
        let feed = LiveFeed::new();
        for k in 0..1000 {
            feed.publish(k as f64, &[k as f64], None);
        }
        let mut frame = LiveFrame::default();
        let seq = feed.next(0, Duration::from_millis(1), &mut frame).unwrap();
        assert_eq!(seq, 1000);
        assert_eq!(frame.q, [999.0]);
        assert!(
            feed.next(seq, Duration::from_millis(1), &mut frame)
                .is_none()
        );
        feed.close();
        assert!(feed.is_closed());
    }
}
