//! Our client against our virtual robot, through the in-memory loopback: every
//! instruction, every error status, stuffing, mixed protocols, the control cycle.

use std::time::Duration;
use twinloop_link::servo::Fault;
use twinloop_link::transport::LoopbackTransport;
use twinloop_link::{
    BulkRead, BusServo, Client, ControlCycle, CycleServo, ErrorNumberV2, Item, LinkError,
    PacketWriter, Protocol, ReadMethod, ServoModel, ServoReading, StatusError, TrackingServoModel,
    Transport, VirtualBus,
};

type Bus = VirtualBus<TrackingServoModel>;

fn client(servos: &[(u8, ServoModel)]) -> Client<LoopbackTransport<Bus>> {
    let servos: Vec<BusServo> = servos
        .iter()
        .map(|&(id, model)| BusServo { id, model })
        .collect();
    Client::new(LoopbackTransport::new(VirtualBus::with_tracking_model(
        &servos,
    )))
}

fn bus(c: &mut Client<LoopbackTransport<Bus>>) -> &mut Bus {
    &mut c.transport_mut().responder
}

fn rejected_v2(r: Result<StatusError, LinkError>) -> ErrorNumberV2 {
    match r {
        Err(LinkError::Rejected { error, .. }) => error.number_v2().expect("a 2.0 error number"),
        other => panic!("expected a rejection, got {other:?}"),
    }
}

fn rejected_v1(r: Result<StatusError, LinkError>) -> u8 {
    match r {
        Err(LinkError::Rejected { error, .. }) => error.raw,
        other => panic!("expected a rejection, got {other:?}"),
    }
}

#[test]
fn ping_and_scan_on_a_mixed_bus() {
    let mut c = client(&[
        (1, ServoModel::Rx28),
        (2, ServoModel::Rx64),
        (3, ServoModel::Mx28),
        (1, ServoModel::Xm430W350),
        (5, ServoModel::Xl430W250),
    ]);
    let s = c.ping(Protocol::V1, 2).unwrap();
    assert_eq!((s.model, s.firmware), (Some(ServoModel::Rx64), 45));
    let s = c.ping(Protocol::V2, 1).unwrap();
    assert_eq!(s.model, Some(ServoModel::Xm430W350));
    assert!(matches!(
        c.ping(Protocol::V2, 9),
        Err(LinkError::Timeout { id: 9 })
    ));
    let found = c.broadcast_ping(Duration::from_millis(10)).unwrap();
    let ids: Vec<(u8, Option<ServoModel>)> = found.iter().map(|s| (s.id, s.model)).collect();
    assert_eq!(
        ids,
        vec![
            (1, Some(ServoModel::Xm430W350)),
            (5, Some(ServoModel::Xl430W250))
        ]
    );
    let p1 = c.scan(Protocol::V1, 0..=253).unwrap();
    let ids: Vec<u8> = p1.iter().map(|s| s.id).collect();
    assert_eq!(ids, vec![1, 2, 3]);
    assert_eq!(p1[2].model, Some(ServoModel::Mx28));
    let p2 = c.scan(Protocol::V2, 0..=252).unwrap();
    assert_eq!(p2.len(), 2);
}

#[test]
fn write_goal_and_watch_the_servo_move() {
    let mut c = client(&[(7, ServoModel::Xm430W350), (8, ServoModel::Rx28)]);
    c.write(Protocol::V2, 7, 64, &[1]).unwrap();
    c.write(Protocol::V2, 7, 116, &3000i32.to_le_bytes())
        .unwrap();
    c.write(Protocol::V1, 8, 24, &[1]).unwrap();
    c.write(Protocol::V1, 8, 30, &700u16.to_le_bytes()).unwrap();
    let mut moved = [0u8; 4];
    c.read(Protocol::V2, 7, 132, &mut moved).unwrap();
    assert_eq!(i32::from_le_bytes(moved), 2048, "no time has passed");
    bus(&mut c).step(2.0);
    c.read(Protocol::V2, 7, 132, &mut moved).unwrap();
    assert!((i32::from_le_bytes(moved) - 3000).abs() <= 1, "{moved:?}");
    let mut p1 = [0u8; 2];
    c.read(Protocol::V1, 8, 36, &mut p1).unwrap();
    assert!((u16::from_le_bytes(p1) as i32 - 700).abs() <= 1);
    // Torque off: the servo stays where it is.
    c.write(Protocol::V2, 7, 64, &[0]).unwrap();
    c.write(Protocol::V2, 7, 116, &1000i32.to_le_bytes())
        .unwrap();
    bus(&mut c).step(1.0);
    c.read(Protocol::V2, 7, 132, &mut moved).unwrap();
    assert!((i32::from_le_bytes(moved) - 3000).abs() <= 1);
}

#[test]
fn reg_write_waits_for_action() {
    let mut c = client(&[(1, ServoModel::Xm430W350), (2, ServoModel::Rx64)]);
    c.reg_write(Protocol::V2, 1, 65, &[1]).unwrap();
    let mut b = [0u8; 2];
    c.read(Protocol::V2, 1, 65, &mut b[..1]).unwrap();
    assert_eq!(b[0], 0, "LED not yet on");
    c.read(Protocol::V2, 1, 69, &mut b[..1]).unwrap();
    assert_eq!(b[0], 1, "Registered Instruction");
    c.action(Protocol::V2, 0xFE).unwrap();
    c.read(Protocol::V2, 1, 65, &mut b[..1]).unwrap();
    assert_eq!(b[0], 1);
    // ACTION with nothing registered is an instruction error.
    assert_eq!(
        rejected_v2(c.action(Protocol::V2, 1)),
        ErrorNumberV2::Instruction
    );
    // Protocol 1.0 likewise, unicast ACTION answered.
    c.reg_write(Protocol::V1, 2, 25, &[1]).unwrap();
    c.action(Protocol::V1, 2).unwrap();
    c.read(Protocol::V1, 2, 25, &mut b[..1]).unwrap();
    assert_eq!(b[0], 1);
    assert_eq!(rejected_v1(c.action(Protocol::V1, 2)), 0x40);
}

#[test]
fn every_error_status_both_protocols() {
    let mut c = client(&[(1, ServoModel::Xm430W350), (2, ServoModel::Rx28)]);
    // 2.0: access (read-only), data range, data length, data limit, EEPROM with
    // torque on, read past the table.
    assert_eq!(
        rejected_v2(c.write(Protocol::V2, 1, 132, &[0; 4])),
        ErrorNumberV2::Access
    );
    assert_eq!(
        rejected_v2(c.write(Protocol::V2, 1, 64, &[5])),
        ErrorNumberV2::DataRange
    );
    assert_eq!(
        rejected_v2(c.write(Protocol::V2, 1, 116, &[0; 2])),
        ErrorNumberV2::DataLength
    );
    assert_eq!(
        rejected_v2(c.write(Protocol::V2, 1, 116, &5000i32.to_le_bytes())),
        ErrorNumberV2::DataLimit
    );
    c.write(Protocol::V2, 1, 64, &[1]).unwrap();
    assert_eq!(
        rejected_v2(c.write(Protocol::V2, 1, 48, &[0; 4])),
        ErrorNumberV2::Access
    );
    let mut big = [0u8; 8];
    assert_eq!(
        // The table ends with Indirect Data 56 at 661 (EM-XM).
        rejected_v2(c.read(Protocol::V2, 1, 658, &mut big)),
        ErrorNumberV2::Access
    );
    // 1.0: range bit for read-only / out of range, angle limit bit for a goal
    // outside CW..CCW.
    assert_eq!(rejected_v1(c.write(Protocol::V1, 2, 36, &[0, 0])), 0x08);
    assert_eq!(rejected_v1(c.write(Protocol::V1, 2, 24, &[2])), 0x08);
    c.write(Protocol::V1, 2, 8, &600u16.to_le_bytes()).unwrap();
    assert_eq!(
        rejected_v1(c.write(Protocol::V1, 2, 30, &700u16.to_le_bytes())),
        0x02
    );
    // Undefined instruction for the protocol: REBOOT to a 1.0 servo is refused by
    // the encoder; a raw 0x08 is answered with the instruction error bit.
    assert!(matches!(
        c.reboot(Protocol::V1, 2),
        Err(LinkError::Encode(_))
    ));
}

#[test]
fn damaged_instruction_gets_checksum_and_crc_errors() {
    let mut c = client(&[(1, ServoModel::Xm430W350), (2, ServoModel::Rx28)]);
    for (protocol, id, expected) in [(Protocol::V2, 1, 0x03), (Protocol::V1, 2, 0x10)] {
        let mut p = Vec::new();
        let mut w =
            PacketWriter::instruction(&mut p, protocol, id, twinloop_link::Instruction::Read);
        w.address(0).address(2);
        w.finish().unwrap();
        let n = p.len();
        p[n - 1] ^= 0x5A;
        let t = c.transport_mut();
        t.write_all(&p).unwrap();
        let mut buf = [0u8; 64];
        let k = t.read(&mut buf, Duration::ZERO).unwrap();
        let mut d = twinloop_link::Decoder::new(twinloop_link::Accept::Both);
        d.push(&buf[..k]);
        let f = d.next_frame().expect("a status packet");
        let error = match protocol {
            Protocol::V1 => f.instruction,
            Protocol::V2 => f.params[0],
        };
        assert_eq!((f.id, error), (id, expected));
        assert_eq!(expected, Fault::Checksum.error_byte(protocol));
    }
}

#[test]
fn minus_131073_is_stuffed_and_read_back_every_way() {
    let mut c = client(&[(1, ServoModel::Xm430W350), (2, ServoModel::Xm430W350)]);
    // Present Position = actual + Homing Offset (EM-XM): the servo sits at 2048.
    let offset: i32 = -131073 - 2048;
    c.write(Protocol::V2, 1, 20, &offset.to_le_bytes()).unwrap();
    let mut b = [0u8; 4];
    c.read(Protocol::V2, 1, 132, &mut b).unwrap();
    assert_eq!(i32::from_le_bytes(b), -131073);
    let mut out = [0u8; 8];
    let mut outcomes = [
        Ok(StatusError::new(Protocol::V2, 0)),
        Ok(StatusError::new(Protocol::V2, 0)),
    ];
    c.sync_read(132, 4, &[1, 2], &mut out, &mut outcomes)
        .unwrap();
    assert!(outcomes.iter().all(|o| o.is_ok()), "{outcomes:?}");
    assert_eq!(i32::from_le_bytes(out[..4].try_into().unwrap()), -131073);
    assert_eq!(i32::from_le_bytes(out[4..].try_into().unwrap()), 2048);
    c.fast_sync_read(132, 4, &[1, 2], &mut out, &mut outcomes)
        .unwrap();
    assert!(outcomes.iter().all(|o| o.is_ok()), "{outcomes:?}");
    assert_eq!(i32::from_le_bytes(out[..4].try_into().unwrap()), -131073);
    assert_eq!(c.stats.retries, 0, "no fallback to single reads was needed");
}

#[test]
fn group_instructions() {
    let mut c = client(&[
        (1, ServoModel::Xm430W350),
        (2, ServoModel::Xl430W250),
        (3, ServoModel::Mx64),
        (4, ServoModel::Mx106),
        (5, ServoModel::Rx28),
    ]);
    // SYNC_WRITE torque on, then goals (2.0).
    c.sync_write(Protocol::V2, 64, 1, &[1, 2], &[1, 1]).unwrap();
    let goals: Vec<u8> = [1000i32, 3000]
        .iter()
        .flat_map(|g| g.to_le_bytes())
        .collect();
    c.sync_write(Protocol::V2, 116, 4, &[1, 2], &goals).unwrap();
    // BULK_WRITE: different registers per servo.
    c.bulk_write(&[(1, 65, &[1u8][..]), (2, 84, &700u16.to_le_bytes()[..])])
        .unwrap();
    let mut out = [0u8; 8];
    let ok = || Ok(StatusError::new(Protocol::V2, 0));
    let mut outcomes = [ok(), ok()];
    c.sync_read(116, 4, &[1, 2], &mut out, &mut outcomes)
        .unwrap();
    assert_eq!(&out[..], &goals[..]);
    // BULK_READ (2.0): LED of 1, Position P Gain of 2.
    let items = [
        BulkRead {
            id: 1,
            address: 65,
            len: 1,
        },
        BulkRead {
            id: 2,
            address: 84,
            len: 2,
        },
    ];
    let mut out = [0u8; 3];
    c.bulk_read(Protocol::V2, &items, &mut out, &mut outcomes)
        .unwrap();
    assert!(outcomes.iter().all(|o| o.is_ok()));
    assert_eq!(out, [1, 0xBC, 0x02]);
    // Protocol 1.0: SYNC_WRITE goals to the MX pair and RX, BULK_READ the MX pair.
    c.sync_write(Protocol::V1, 24, 1, &[3, 4, 5], &[1, 1, 1])
        .unwrap();
    let g: Vec<u8> = [1500u16, 2500]
        .iter()
        .flat_map(|g| g.to_le_bytes())
        .collect();
    c.sync_write(Protocol::V1, 30, 2, &[3, 4], &g).unwrap();
    bus(&mut c).step(3.0);
    let items = [
        BulkRead {
            id: 3,
            address: 36,
            len: 2,
        },
        BulkRead {
            id: 4,
            address: 30,
            len: 2,
        },
    ];
    let mut out = [0u8; 4];
    c.bulk_read(Protocol::V1, &items, &mut out, &mut outcomes)
        .unwrap();
    assert!(outcomes.iter().all(|o| o.is_ok()), "{outcomes:?}");
    assert!((u16::from_le_bytes([out[0], out[1]]) as i32 - 1500).abs() <= 1);
    assert_eq!(u16::from_le_bytes([out[2], out[3]]), 2500);
    // RX has no BULK_READ: its item times out, then the single READ fallback works.
    let items = [BulkRead {
        id: 5,
        address: 3,
        len: 1,
    }];
    let mut out = [0u8; 1];
    let mut one = [ok()];
    c.bulk_read(Protocol::V1, &items, &mut out, &mut one)
        .unwrap();
    assert!(one[0].is_ok());
    assert_eq!(out[0], 5);
}

#[test]
fn reboot_and_factory_reset() {
    let mut c = client(&[(4, ServoModel::Xm430W350)]);
    c.write(Protocol::V2, 4, 64, &[1]).unwrap();
    c.reboot(Protocol::V2, 4).unwrap();
    let mut b = [0u8; 1];
    c.read(Protocol::V2, 4, 64, &mut b).unwrap();
    assert_eq!(b[0], 0, "torque off after reboot");
    c.write(Protocol::V2, 4, 9, &[0]).unwrap();
    c.factory_reset(Protocol::V2, 4, 0x01).unwrap();
    c.read(Protocol::V2, 4, 9, &mut b).unwrap();
    assert_eq!(b[0], 250, "return delay back to its factory value");
    c.read(Protocol::V2, 4, 7, &mut b).unwrap();
    assert_eq!(b[0], 4, "id kept with option 0x01");
    c.factory_reset(Protocol::V2, 4, 0xFF).unwrap();
    assert!(c.ping(Protocol::V2, 1).is_ok(), "id reset to 1");
}

#[test]
fn status_return_level_zero_answers_only_ping() {
    let mut c = client(&[(3, ServoModel::Xm430W350)]);
    c.write(Protocol::V2, 3, 68, &[0]).unwrap_err(); // level 0 from this write on: no reply
    assert!(c.ping(Protocol::V2, 3).is_ok());
    let mut b = [0u8; 1];
    assert!(matches!(
        c.read(Protocol::V2, 3, 68, &mut b),
        Err(LinkError::Timeout { id: 3 })
    ));
    c.config.write_replies = false;
    c.write(Protocol::V2, 3, 68, &[2]).unwrap();
    c.config.write_replies = true;
    c.read(Protocol::V2, 3, 68, &mut b).unwrap();
    assert_eq!(b[0], 2);
}

#[test]
fn control_cycle_on_a_mixed_humanoid_bus() {
    // 8 RX-28 and 4 RX-64 on 1.0, 6 XM430 and 2 XL430 on 2.0, ids shared between
    // protocols.
    let mut servos = Vec::new();
    for id in 1..=8 {
        servos.push((id, ServoModel::Rx28));
    }
    for id in 9..=12 {
        servos.push((id, ServoModel::Rx64));
    }
    for id in 1..=6 {
        servos.push((id, ServoModel::Xm430W350));
    }
    servos.push((7, ServoModel::Xl430W250));
    servos.push((8, ServoModel::Xl430W250));
    let mut c = client(&servos);
    let cycle_servos: Vec<CycleServo> = servos
        .iter()
        .map(|&(id, model)| CycleServo::new(id, model))
        .collect();
    let mut cycle = ControlCycle::new(&cycle_servos, ReadMethod::Auto).unwrap();
    assert_eq!(cycle.method(Protocol::V1), Some(ReadMethod::Read));
    assert_eq!(cycle.method(Protocol::V2), Some(ReadMethod::FastSyncRead));
    // Torque on everywhere.
    c.sync_write(Protocol::V1, 24, 1, &(1..=12).collect::<Vec<_>>(), &[1; 12])
        .unwrap();
    c.sync_write(Protocol::V2, 64, 1, &(1..=8).collect::<Vec<_>>(), &[1; 8])
        .unwrap();
    let goals: Vec<i32> = servos
        .iter()
        .enumerate()
        .map(|(k, (_, m))| {
            if m.protocol() == Protocol::V1 {
                400 + 20 * k as i32
            } else {
                1800 + 40 * k as i32
            }
        })
        .collect();
    let mut readings = vec![ServoReading::default(); servos.len()];
    for _ in 0..100 {
        let s = cycle.run(&mut c, Some(&goals), &mut readings).unwrap();
        assert_eq!(s.failed, 0);
        bus(&mut c).step(0.02);
    }
    for (k, r) in readings.iter().enumerate() {
        assert!(r.outcome.is_ok());
        assert!(
            (r.position - goals[k]).abs() <= 2,
            "servo {k}: {} vs {}",
            r.position,
            goals[k]
        );
        let pos_si = cycle.position_register(k).to_si(r.position);
        let goal_si = cycle.goal_register(k).to_si(goals[k]);
        assert!((pos_si - goal_si).abs() < 0.01);
    }
    // SYNC_READ and explicit single reads give the same answers.
    for m in [ReadMethod::SyncRead, ReadMethod::Read] {
        let only_v2: Vec<CycleServo> = cycle_servos[12..].to_vec();
        let mut other = ControlCycle::new(&only_v2, m).unwrap();
        let mut r2 = vec![ServoReading::default(); only_v2.len()];
        other.run(&mut c, None, &mut r2).unwrap();
        for (a, b) in r2.iter().zip(&readings[12..]) {
            assert_eq!(a.position, b.position);
        }
    }
    // Asking RX for what it lacks is an error naming the servo.
    let e = ControlCycle::new(&cycle_servos[..3], ReadMethod::BulkRead)
        .err()
        .unwrap();
    assert!(
        e.0.contains("servo id 1") && e.0.contains("BULK_READ"),
        "{e}"
    );
    let e = ControlCycle::new(&cycle_servos, ReadMethod::FastSyncRead)
        .err()
        .unwrap();
    assert!(e.0.contains("RX-28"), "{e}");
}

#[test]
fn missing_servo_is_reported_per_servo_and_others_still_read() {
    let mut c = client(&[(1, ServoModel::Xm430W350), (3, ServoModel::Xm430W350)]);
    let servos = [
        CycleServo::new(1, ServoModel::Xm430W350),
        CycleServo::new(2, ServoModel::Xm430W350),
        CycleServo::new(3, ServoModel::Xm430W350),
    ];
    let mut cycle = ControlCycle::new(&servos, ReadMethod::SyncRead).unwrap();
    let mut readings = vec![ServoReading::default(); 3];
    let s = cycle.run(&mut c, None, &mut readings).unwrap();
    assert_eq!((s.ok, s.failed), (2, 1));
    assert!(readings[0].outcome.is_ok() && readings[2].outcome.is_ok());
    assert!(matches!(
        readings[1].outcome,
        Err(LinkError::Timeout { id: 2 })
    ));
    assert_eq!(readings[0].position, 2048);
    let _ = Item::PresentPosition;
}

#[test]
fn malformed_instructions_get_errors_not_panics() {
    use twinloop_link::Instruction;
    // 300 servos with duplicate ids on one protocol: a broadcast must not overflow.
    let mut servos = Vec::new();
    for k in 0..300u32 {
        servos.push(BusServo {
            id: (k % 200) as u8,
            model: ServoModel::Xm430W350,
        });
    }
    let mut bus = VirtualBus::with_tracking_model(&servos);
    let mut reply = Vec::new();
    let cases: Vec<(u8, u8, Vec<u8>)> = vec![
        (1, Instruction::Read.code(), vec![0x84]), // READ missing its length
        (1, Instruction::Read.code(), vec![0, 0, 0, 0]), // READ of 0 bytes
        (1, Instruction::Write.code(), vec![]),    // WRITE without address
        (1, 0x77, vec![1, 2, 3]),                  // undefined instruction
        (
            0xFE,
            Instruction::SyncWrite.code(),
            vec![116, 0, 4, 0, 1, 2],
        ), // truncated block
        (0xFE, Instruction::BulkRead.code(), vec![1, 0]), // truncated item
        (0xFE, Instruction::Ping.code(), vec![]),
        (
            0xFE,
            Instruction::FastSyncRead.code(),
            vec![132, 0, 4, 0, 1, 2, 250],
        ),
    ];
    for (id, code, params) in cases {
        let mut p = Vec::new();
        let mut w = PacketWriter::raw(&mut p, Protocol::V2, id, code);
        w.bytes(&params);
        w.finish().unwrap();
        reply.clear();
        twinloop_link::transport::Responder::respond(&mut bus, &p, &mut reply);
    }
    // The unicast ones were answered with error statuses.
    let mut d = twinloop_link::Decoder::new(twinloop_link::Accept::V2);
    let mut p = Vec::new();
    let mut w = PacketWriter::raw(&mut p, Protocol::V2, 1, Instruction::Read.code());
    w.bytes(&[0x84]);
    w.finish().unwrap();
    reply.clear();
    twinloop_link::transport::Responder::respond(&mut bus, &p, &mut reply);
    d.push(&reply);
    let f = d.next_frame().unwrap();
    assert_eq!(f.params[0], 0x02, "instruction error");
}
