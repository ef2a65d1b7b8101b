//! The live view: a running simulation or robot publishes its state, and every page
//! connected to `/live` (a websocket) receives the newest one.
//!
//! Nothing queues: the feed keeps only the latest state, so a 1 kHz source and a
//! 60 Hz screen never build a backlog, and a slow or stalled client only skips
//! states. The publisher decimates too ([`Decimator`]), so the JSON is made at the
//! screen's rate, not the source's.

use serde::Serialize;
use std::io::{BufRead, BufReader, Seek, SeekFrom};
use std::path::Path;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// One state as the page receives it.
#[derive(Debug, Clone, Serialize)]
struct LiveFrame<'a> {
    /// The source's time, s.
    t: f64,
    /// Wall clock when published, ms since the Unix epoch (the page's lag is its
    /// receipt time minus this).
    sent_ms: f64,
    /// Joint positions in the scene's joint order (NaN: not known).
    q: &'a [f64],
    /// Base position and quaternion (x, y, z, qx, qy, qz, qw), when known.
    base: Option<[f64; 7]>,
}

#[derive(Default)]
struct Slot {
    seq: u64,
    json: Arc<str>,
    closed: bool,
}

/// The latest state, shared between the publisher and the websocket clients.
#[derive(Clone, Default)]
pub struct LiveFeed {
    inner: Arc<(Mutex<Slot>, Condvar)>,
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

    /// Replace the latest state (joints in the scene's order).
    pub fn publish(&self, t: f64, q: &[f64], base: Option<[f64; 7]>) {
        let frame = LiveFrame {
            t,
            sent_ms: now_ms(),
            q,
            base,
        };
        // Non-finite numbers are not JSON: the page reads null as "not known".
        let json = serde_json::to_string(&frame).unwrap_or_default();
        let (lock, ready) = &*self.inner;
        let mut slot = lock.lock().unwrap_or_else(|p| p.into_inner());
        slot.seq += 1;
        slot.json = json.into();
        ready.notify_all();
    }

    /// No more states: clients are told and their threads end.
    pub fn close(&self) {
        let (lock, ready) = &*self.inner;
        lock.lock().unwrap_or_else(|p| p.into_inner()).closed = true;
        ready.notify_all();
    }

    /// The newest state after `seen`, waiting up to `timeout`: Some((seq, json)),
    /// or None on timeout or when closed.
    pub(crate) fn next(&self, seen: u64, timeout: Duration) -> Option<(u64, Arc<str>)> {
        let (lock, ready) = &*self.inner;
        let slot = lock.lock().unwrap_or_else(|p| p.into_inner());
        let (slot, _) = ready
            .wait_timeout_while(slot, timeout, |s| s.seq == seen && !s.closed)
            .unwrap_or_else(|p| p.into_inner());
        (slot.seq != seen && !slot.closed).then(|| (slot.seq, Arc::clone(&slot.json)))
    }

    pub(crate) fn is_closed(&self) -> bool {
        self.inner
            .0
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .closed
    }
}

/// Lets through one state per `period` of source time.
#[derive(Debug, Clone)]
pub struct Decimator {
    period: f64,
    last: f64,
}

impl Decimator {
    /// `rate`: states per second let through.
    pub fn new(rate: f64) -> Decimator {
        Decimator {
            period: 1.0 / rate,
            last: f64::NEG_INFINITY,
        }
    }

    /// Whether the state at `t` goes out.
    pub fn admit(&mut self, t: f64) -> bool {
        if t - self.last >= self.period || t < self.last {
            self.last = t;
            true
        } else {
            false
        }
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
    let file = loop {
        match std::fs::File::open(path) {
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
    }

    #[test]
    fn the_feed_keeps_only_the_newest_state() {
        let feed = LiveFeed::new();
        for k in 0..1000 {
            feed.publish(k as f64, &[k as f64], None);
        }
        let (seq, json) = feed.next(0, Duration::from_millis(1)).unwrap();
        assert_eq!(seq, 1000);
        assert!(json.contains("\"q\":[999.0]"), "{json}");
        assert!(feed.next(seq, Duration::from_millis(1)).is_none());
        feed.close();
        assert!(feed.is_closed());
    }
}
