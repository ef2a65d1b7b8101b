//! A bus that degrades instead of breaking (issue 28): a server that was stalled
//! answers only the request still waiting, and the host never takes a late reply
//! to a request it gave up on for a later request's.
//!
//! Packets are written and read by hand from the e-manual's Protocol 1.0 layout
//! (EM-P1: `FF FF ID LEN INSTR PARAMS CHECKSUM`, checksum = !(ID + LEN + INSTR +
//! PARAMS) & 0xFF) and the RX-28 control table (EM-RX28: Model Number 28 at address
//! 0, Goal Position at 30, Present Position at 36).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;
use twinloop_link::servo::{ServeOptions, serve};
use twinloop_link::transport::{PtyTransport, Transport, TtyTransport};
use twinloop_link::{BusServo, Client, ClientConfig, Protocol, ServoModel, VirtualBus};

/// A Protocol 1.0 instruction packet, checksum by EM-P1.
fn packet(id: u8, instruction: u8, params: &[u8]) -> Vec<u8> {
    let len = params.len() as u8 + 2;
    let mut p = vec![0xFF, 0xFF, id, len, instruction];
    p.extend_from_slice(params);
    let sum: u32 = p[2..].iter().map(|&b| u32::from(b)).sum();
    p.push(!(sum as u8));
    p
}

const READ: u8 = 0x02;
const WRITE: u8 = 0x03;

/// Status packets in `bytes` as (id, error, params), each checksum checked.
fn statuses(bytes: &[u8]) -> Vec<(u8, u8, Vec<u8>)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 4 <= bytes.len() {
        assert_eq!(
            &bytes[i..i + 2],
            &[0xFF, 0xFF],
            "no header at {i}: {bytes:?}"
        );
        let (id, len) = (bytes[i + 2], bytes[i + 3] as usize);
        let end = i + 4 + len;
        let sum: u32 = bytes[i + 2..end - 1].iter().map(|&b| u32::from(b)).sum();
        assert_eq!(
            bytes[end - 1],
            !(sum as u8),
            "checksum of {:?}",
            &bytes[i..end]
        );
        out.push((id, bytes[i + 4], bytes[i + 5..end - 1].to_vec()));
        i = end;
    }
    out
}

fn rx28(id: u8) -> BusServo {
    BusServo {
        id,
        model: ServoModel::Rx28,
    }
}

#[test]
fn a_burst_of_requests_is_answered_by_the_last_only_and_every_write_takes_effect() {
    // A host that timed out on a WRITE and a READ, then asked for Goal Position.
    let mut burst = packet(1, WRITE, &[30, 0x2C, 0x01]); // Goal Position = 300
    burst.extend(packet(1, READ, &[0, 2])); // Model Number
    burst.extend(packet(1, READ, &[30, 2])); // Goal Position
    let mut bus = VirtualBus::with_tracking_model(&[rx28(1), rx28(2)]);
    bus.latest_reply_only = true;
    let mut reply = Vec::new();
    bus.handle(&burst, &mut reply);
    let got = statuses(&reply);
    // One reply, the last request's, and the write before it took effect.
    assert_eq!(got, vec![(1, 0, vec![0x2C, 0x01])], "{reply:?}");
    assert_eq!(bus.stats.superseded, 2);
    assert_eq!(bus.marks.len(), 1);
    assert_eq!(bus.marks[0].end, reply.len());

    // Without the rule (an in-memory bus) each request is answered, in order.
    let mut bus = VirtualBus::with_tracking_model(&[rx28(1), rx28(2)]);
    let mut reply = Vec::new();
    bus.handle(&burst, &mut reply);
    let got = statuses(&reply);
    assert_eq!(
        got,
        vec![
            (1, 0, vec![]),
            (1, 0, 28u16.to_le_bytes().to_vec()),
            (1, 0, vec![0x2C, 0x01]),
        ]
    );
}

/// The server's side of a pty whose reads wait while `stalled` is set: a server
/// descheduled by a loaded machine.
struct Stalling {
    inner: PtyTransport,
    stalled: Arc<AtomicBool>,
}

impl Transport for Stalling {
    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.inner.write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        while self.stalled.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(1));
        }
        self.inner.read(buf, timeout)
    }
    fn discard_input(&mut self) -> std::io::Result<usize> {
        self.inner.discard_input()
    }
    fn describe(&self) -> String {
        self.inner.describe()
    }
}

#[test]
fn after_a_stalled_server_each_transaction_gets_its_own_reply() {
    let pty = PtyTransport::open().unwrap();
    let path = pty.path().to_path_buf();
    let stalled = Arc::new(AtomicBool::new(false));
    let stop = Arc::new(AtomicBool::new(false));
    let (stalled2, stop2) = (stalled.clone(), stop.clone());
    let server = std::thread::spawn(move || {
        let mut bus = VirtualBus::with_tracking_model(&[rx28(1), rx28(2)]);
        let mut t = Stalling {
            inner: pty,
            stalled: stalled2,
        };
        let options = ServeOptions {
            emulate_baud: None,
            stop_on_eof: false,
            warn_stalls: false,
        };
        serve(&mut bus, &mut t, &options, &stop2).unwrap();
        bus.stats
    });
    let mut c = Client::with_config(
        TtyTransport::open(&path).unwrap(),
        ClientConfig {
            latency: Duration::from_millis(20),
            retries: 2,
            ..ClientConfig::default()
        },
    );
    let mut b = [0u8; 2];
    // Goal Position of servo 1 := 300, read back: the bus works.
    c.write(Protocol::V1, 1, 30, &300u16.to_le_bytes()).unwrap();
    c.read(Protocol::V1, 1, 30, &mut b).unwrap();
    assert_eq!(u16::from_le_bytes(b), 300);

    // The server stalls: a READ of Model Number (same id, same length as the Goal
    // Position read after it) and its two retries go unanswered.
    stalled.store(true, Ordering::Relaxed);
    // Past the server's 20 ms wait for bytes: it is in the stall, not reading.
    std::thread::sleep(Duration::from_millis(50));
    let r = c.read(Protocol::V1, 1, 0, &mut b);
    assert!(r.is_err(), "{r:?}");
    assert_eq!(c.stats.retries, 2);
    stalled.store(false, Ordering::Relaxed);
    // The server reads the three requests at once; what it sends back is late.
    std::thread::sleep(Duration::from_millis(100));

    // Each transaction after it gets its own reply, never the late one.
    for (k, goal) in [(0u16, 310u16), (1, 320), (2, 330)] {
        c.write(Protocol::V1, 2, 30, &goal.to_le_bytes()).unwrap();
        c.read(Protocol::V1, 2, 30, &mut b).unwrap();
        assert_eq!(u16::from_le_bytes(b), goal, "transaction {k}");
        c.read(Protocol::V1, 1, 30, &mut b).unwrap();
        assert_eq!(u16::from_le_bytes(b), 300, "transaction {k}");
        c.read(Protocol::V1, 1, 0, &mut b).unwrap();
        assert_eq!(u16::from_le_bytes(b), 28, "transaction {k}");
    }
    stop.store(true, Ordering::Relaxed);
    let served = server.join().unwrap();
    eprintln!("client {:?}; server {served:?}", c.stats);
    // Only the last of the three piled-up requests was answered (two superseded),
    // and that one late reply (8 bytes: FF FF 01 04 00 LO HI SUM) was dropped
    // before the next request.
    assert_eq!(served.superseded, 2, "{served:?}");
    assert_eq!(c.stats.stale_bytes, 8, "{:?}", c.stats);
    assert_eq!(c.stats.timeouts, 3);
}

/// The host's side of a pty whose reads are late by `pause` once, after the reply
/// arrived: a host descheduled between sending and reading.
struct LateHost {
    inner: TtyTransport,
    pause: Option<Duration>,
}

impl Transport for LateHost {
    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.inner.write_all(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        if let Some(p) = self.pause.take() {
            std::thread::sleep(p);
        }
        self.inner.read(buf, timeout)
    }
    fn discard_input(&mut self) -> std::io::Result<usize> {
        self.inner.discard_input()
    }
    fn describe(&self) -> String {
        self.inner.describe()
    }
}

#[test]
fn a_host_paused_half_a_second_mid_exchange_takes_the_reply_and_goes_on() {
    let mut pty = PtyTransport::open().unwrap();
    let path = pty.path().to_path_buf();
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = stop.clone();
    let server = std::thread::spawn(move || {
        let mut bus = VirtualBus::with_tracking_model(&[rx28(1)]);
        let options = ServeOptions {
            emulate_baud: None,
            stop_on_eof: false,
            warn_stalls: false,
        };
        serve(&mut bus, &mut pty, &options, &stop2).unwrap();
    });
    let host = LateHost {
        inner: TtyTransport::open(&path).unwrap(),
        pause: None,
    };
    let mut c = Client::with_config(host, ClientConfig::default());
    let mut b = [0u8; 2];
    c.transport_mut().pause = Some(Duration::from_millis(500));
    // Past its 10 ms deadline when it looks, the reply is there: taken, no retry.
    c.read(Protocol::V1, 1, 0, &mut b).unwrap();
    assert_eq!(u16::from_le_bytes(b), 28);
    c.write(Protocol::V1, 1, 30, &200u16.to_le_bytes()).unwrap();
    c.read(Protocol::V1, 1, 30, &mut b).unwrap();
    assert_eq!(u16::from_le_bytes(b), 200);
    assert_eq!(c.stats.retries, 0, "{:?}", c.stats);
    stop.store(true, Ordering::Relaxed);
    server.join().unwrap();
}

#[test]
fn a_pty_has_one_owner_and_a_second_opener_is_told_who() {
    let pty = PtyTransport::open().unwrap();
    let first = TtyTransport::open(pty.path()).unwrap();
    let Err(e) = TtyTransport::open(pty.path()) else {
        panic!("a second open of {} succeeded", pty.path().display());
    };
    assert_eq!(e.kind(), std::io::ErrorKind::ResourceBusy);
    let text = e.to_string();
    assert!(
        text.contains(&format!("port {} is busy", pty.path().display())),
        "{text}"
    );
    assert!(
        text.contains(&format!("process {}", std::process::id())),
        "{text}"
    );
    // Closed, the port is free again.
    drop(first);
    TtyTransport::open(pty.path()).unwrap();
}
