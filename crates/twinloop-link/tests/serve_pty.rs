//! A virtual robot served on a real pseudo-terminal with wire time emulated, and our
//! client talking to it through the pty path, as a user's program would.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use twinloop_link::servo::{ServeOptions, serve};
use twinloop_link::transport::{self, PtyTransport, SerialOptions};
use twinloop_link::{
    BusServo, Client, ClientConfig, ControlCycle, CycleServo, Protocol, ReadMethod, ServoModel,
    ServoReading, VirtualBus,
};

#[test]
fn client_over_a_pty_with_emulated_wire_time() {
    let servos: Vec<BusServo> = (1..=4)
        .map(|id| BusServo {
            id,
            model: ServoModel::Xm430W350,
        })
        .chain((5..=6).map(|id| BusServo {
            id,
            model: ServoModel::Rx28,
        }))
        .collect();
    let mut pty = PtyTransport::open().unwrap();
    let path = pty.path().to_str().unwrap().to_string();
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = stop.clone();
    let servos2 = servos.clone();
    let server = std::thread::spawn(move || {
        let mut bus = VirtualBus::with_tracking_model(&servos2);
        let options = ServeOptions {
            emulate_baud: Some(57_600),
            stop_on_eof: false,
            warn_stalls: false,
        };
        serve(&mut bus, &mut pty, &options, &stop2).unwrap();
    });

    let t = transport::open(&path, 57_600, &SerialOptions::default()).unwrap();
    let mut c = Client::with_config(
        t,
        ClientConfig {
            baud: 57_600,
            latency: Duration::from_millis(30),
            ..ClientConfig::default()
        },
    );
    let found = c.broadcast_ping(Duration::from_millis(100)).unwrap();
    assert_eq!(
        found.iter().map(|s| s.id).collect::<Vec<_>>(),
        vec![1, 2, 3, 4]
    );
    assert_eq!(
        c.ping(Protocol::V1, 6).unwrap().model,
        Some(ServoModel::Rx28)
    );

    // One READ of 4 bytes at 57600 bps: request 14 B + reply 15 B = 29 bytes =
    // 5.0 ms of wire, plus 500 us return delay: the emulation must take at least
    // that long.
    let mut b = [0u8; 4];
    let t0 = Instant::now();
    c.read(Protocol::V2, 1, 132, &mut b).unwrap();
    let took = t0.elapsed();
    assert!(took >= Duration::from_micros(5_500), "{took:?}");
    assert_eq!(i32::from_le_bytes(b), 2048);

    let cs: Vec<CycleServo> = servos
        .iter()
        .map(|s| CycleServo::new(s.id, s.model))
        .collect();
    let mut cycle = ControlCycle::new(&cs, ReadMethod::Auto).unwrap();
    let mut readings = vec![ServoReading::default(); cs.len()];
    c.sync_write(Protocol::V2, 64, 1, &[1, 2, 3, 4], &[1; 4])
        .unwrap();
    c.sync_write(Protocol::V1, 24, 1, &[5, 6], &[1; 2]).unwrap();
    let goals = [2100, 2200, 2300, 2400, 530, 560];
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_millis(800) {
        let s = cycle.run(&mut c, Some(&goals), &mut readings).unwrap();
        assert_eq!(s.failed, 0, "{readings:?}");
    }
    for (r, g) in readings.iter().zip(goals) {
        assert!((r.position - g).abs() <= 3, "{} vs {g}", r.position);
    }
    stop.store(true, Ordering::Relaxed);
    server.join().unwrap();
}
