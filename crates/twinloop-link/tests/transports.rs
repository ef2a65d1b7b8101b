//! Transports move every byte value unchanged (a pty in raw mode, TCP), time out
//! when nothing comes, and the noisy wrapper damages at the rate asked.

use std::time::{Duration, Instant};
use twinloop_link::Transport;
use twinloop_link::transport::{
    self, LoopbackTransport, NoisyTransport, PtyTransport, Responder, SerialOptions, TcpTransport,
    TtyTransport,
};

fn all_bytes() -> Vec<u8> {
    (0..=255u8).chain((0..=255u8).rev()).collect()
}

fn read_exactly(t: &mut dyn Transport, n: usize) -> Vec<u8> {
    let mut got = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(5);
    let mut buf = [0u8; 1024];
    while got.len() < n && Instant::now() < deadline {
        let k = t.read(&mut buf, Duration::from_millis(50)).unwrap();
        got.extend_from_slice(&buf[..k]);
    }
    got
}

#[test]
fn pty_passes_every_byte_both_ways() {
    let mut server = PtyTransport::open().unwrap();
    let mut client = TtyTransport::open(server.path()).unwrap();
    let data = all_bytes();
    client.write_all(&data).unwrap();
    assert_eq!(read_exactly(&mut server, data.len()), data);
    server.write_all(&data).unwrap();
    assert_eq!(read_exactly(&mut client, data.len()), data);
    // Nothing pending: a read times out with 0 bytes.
    let t0 = Instant::now();
    let mut buf = [0u8; 8];
    assert_eq!(client.read(&mut buf, Duration::from_millis(20)).unwrap(), 0);
    assert!(t0.elapsed() >= Duration::from_millis(15));
}

#[test]
fn open_by_path_works_on_a_pty() {
    let mut server = PtyTransport::open().unwrap();
    let path = server.path().to_str().unwrap().to_string();
    let mut client = transport::open(&path, 1_000_000, &SerialOptions::default()).unwrap();
    let data = all_bytes();
    client.write_all(&data).unwrap();
    assert_eq!(read_exactly(&mut server, data.len()), data);
    server.write_all(&[1, 2, 3]).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    client.discard_input().unwrap();
    let mut buf = [0u8; 8];
    assert_eq!(client.read(&mut buf, Duration::from_millis(10)).unwrap(), 0);
}

#[test]
fn tcp_passes_every_byte_both_ways() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    let t = std::thread::spawn(move || {
        let (s, _) = listener.accept().unwrap();
        let mut server = TcpTransport::from_stream(s).unwrap();
        let got = read_exactly(&mut server, 512);
        server.write_all(&got).unwrap();
        // Wait for the client to close.
        let mut buf = [0u8; 4];
        while server.read(&mut buf, Duration::from_millis(100)).is_ok() {}
    });
    let mut client =
        transport::open(&format!("tcp:{addr}"), 1_000_000, &SerialOptions::default()).unwrap();
    let data = all_bytes();
    client.write_all(&data).unwrap();
    assert_eq!(read_exactly(&mut client, data.len()), data);
    drop(client);
    t.join().unwrap();
}

struct Echo;
impl Responder for Echo {
    fn respond(&mut self, input: &[u8], reply: &mut Vec<u8>) {
        reply.extend_from_slice(input);
    }
}

#[test]
fn noise_hits_about_the_rate_asked() {
    let mut t = NoisyTransport::new(LoopbackTransport::new(Echo), 0.01, 42);
    let data = vec![0x55u8; 1000];
    let mut buf = [0u8; 4096];
    for _ in 0..200 {
        t.write_all(&data).unwrap();
        while t.read(&mut buf, Duration::ZERO).unwrap() > 0 {}
    }
    let s = t.stats;
    let hit = (s.flipped + s.dropped + s.inserted) as f64 / s.bytes as f64;
    assert!((hit - 0.01).abs() < 0.001, "{s:?}");
    assert!(s.flipped > 0 && s.dropped > 0 && s.inserted > 0);
}
