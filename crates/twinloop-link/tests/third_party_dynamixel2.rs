//! A third-party Protocol 2.0 host, the `dynamixel2` crate (serial2 underneath), as
//! a client of twinloop's virtual bus on a pseudo-terminal: what another Rust
//! program would see.

use dynamixel2::instructions::SyncWriteData;
use dynamixel2::{ReadError, TransferError};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use twinloop_link::servo::{ServeOptions, serve};
use twinloop_link::transport::PtyTransport;
use twinloop_link::{BusServo, ServoModel, VirtualBus};

fn motor_error(e: TransferError) -> u8 {
    match e {
        TransferError::ReadError(ReadError::MotorError(m)) => m.error_number(),
        other => panic!("expected a motor error, got {other:?}"),
    }
}

#[test]
fn dynamixel2_drives_the_virtual_bus() {
    let servos: Vec<BusServo> = (1..=4)
        .map(|id| BusServo {
            id,
            model: ServoModel::Xm430W350,
        })
        .collect();
    let mut pty = PtyTransport::open().unwrap();
    let path = pty.path().to_path_buf();
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = stop.clone();
    let server = std::thread::spawn(move || {
        let mut bus = VirtualBus::with_tracking_model(&servos);
        let options = ServeOptions {
            emulate_baud: None,
            stop_on_eof: false,
            warn_stalls: false,
        };
        serve(&mut bus, &mut pty, &options, &stop2).unwrap();
    });

    let mut bus = dynamixel2::Bus::open(&path, 1_000_000).unwrap();
    let ping = bus.ping(3).unwrap();
    assert_eq!((ping.motor_id, ping.data.model), (3, 1020));
    let found = bus.scan().unwrap();
    let ids: Vec<u8> = found
        .iter()
        .filter_map(|r| r.as_ref().ok())
        .map(|r| r.motor_id)
        .collect();
    assert_eq!(ids, vec![1, 2, 3, 4]);

    assert_eq!(bus.read_u16(2, 0).unwrap().data, 1020);
    bus.write_u8(1, 64, 1).unwrap();
    bus.write_u32(1, 116, 2222).unwrap();
    assert_eq!(bus.read_u32(1, 116).unwrap().data, 2222);
    // Stuffing both ways: -131073 is FF FF FD FF.
    bus.write_u32(2, 20, (-131073i32) as u32).unwrap();
    assert_eq!(bus.read_u32(2, 20).unwrap().data as i32, -131073);
    bus.write_u32(2, 20, (-131073i32 - 2048) as u32).unwrap();
    let positions = bus.sync_read_u32(&[1, 2, 3], 132).unwrap();
    assert_eq!(positions[1].data as i32, -131073);
    assert_eq!(positions[2].data, 2048);

    bus.sync_write_u32(
        116,
        &[
            SyncWriteData {
                motor_id: 3,
                data: 1000u32,
            },
            SyncWriteData {
                motor_id: 4,
                data: 3000u32,
            },
        ],
    )
    .unwrap();
    assert_eq!(bus.read_u32(3, 116).unwrap().data, 1000);
    assert_eq!(bus.read_u32(4, 116).unwrap().data, 3000);

    bus.reg_write_u8(4, 65, 1).unwrap();
    assert_eq!(bus.read_u8(4, 65).unwrap().data, 0);
    bus.broadcast_action().unwrap();
    assert_eq!(bus.read_u8(4, 65).unwrap().data, 1);

    // Error statuses as dynamixel2 reports them.
    assert_eq!(motor_error(bus.write_u32(3, 132, 0).unwrap_err()), 7);
    assert_eq!(motor_error(bus.write_u16(3, 116, 5).unwrap_err()), 5);
    assert_eq!(motor_error(bus.write_u8(3, 64, 9).unwrap_err()), 4);

    bus.reboot(1).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    assert_eq!(bus.read_u8(1, 64).unwrap().data, 0);

    stop.store(true, Ordering::Relaxed);
    server.join().unwrap();
}
