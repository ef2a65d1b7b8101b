//! Control tables against the e-manual's addresses and units (e-manual control tables of the RX-28/RX-64 and the XM430-W350
//! and the e-manual model pages), and unit conversions against hand-computed values.

use std::f64::consts::PI;
use twinloop_link::ModelTable;
use twinloop_link::{Encoding, Item, Protocol, ServoModel, baud_from_register};

fn addr(model: ServoModel, item: Item) -> (u16, u8) {
    let r = model
        .table()
        .item(item)
        .unwrap_or_else(|| panic!("{model} has no {item:?}"));
    (r.address, r.size)
}

#[test]
fn addresses_match_the_emanual() {
    for m in [ServoModel::Rx28, ServoModel::Rx64] {
        assert_eq!(m.protocol(), Protocol::V1);
        assert_eq!(addr(m, Item::ModelNumber), (0, 2));
        assert_eq!(addr(m, Item::Id), (3, 1));
        assert_eq!(addr(m, Item::ReturnDelayTime), (5, 1));
        assert_eq!(addr(m, Item::MinPositionLimit), (6, 2));
        assert_eq!(addr(m, Item::MaxPositionLimit), (8, 2));
        assert_eq!(addr(m, Item::StatusReturnLevel), (16, 1));
        assert_eq!(addr(m, Item::TorqueEnable), (24, 1));
        assert_eq!(addr(m, Item::GoalPosition), (30, 2));
        assert_eq!(addr(m, Item::MovingSpeed), (32, 2));
        assert_eq!(addr(m, Item::TorqueLimit), (34, 2));
        assert_eq!(addr(m, Item::PresentPosition), (36, 2));
        assert_eq!(addr(m, Item::PresentVelocity), (38, 2));
        assert_eq!(addr(m, Item::PresentLoad), (40, 2));
        assert_eq!(addr(m, Item::PresentVoltage), (42, 1));
        assert_eq!(addr(m, Item::PresentTemperature), (43, 1));
        assert_eq!(addr(m, Item::Registered), (44, 1));
        assert_eq!(addr(m, Item::Moving), (46, 1));
        assert_eq!(m.table().by_name("punch").unwrap().address, 48);
    }
    for m in [ServoModel::Mx28, ServoModel::Mx64, ServoModel::Mx106] {
        assert_eq!(addr(m, Item::GoalPosition), (30, 2));
        assert_eq!(addr(m, Item::PresentPosition), (36, 2));
        assert_eq!(m.table().by_name("Goal Acceleration").unwrap().address, 73);
    }
    assert_eq!(addr(ServoModel::Mx64, Item::PresentCurrent), (68, 2));
    assert!(
        ServoModel::Mx28
            .table()
            .item(Item::PresentCurrent)
            .is_none()
    );
    for m in [
        ServoModel::Xm430W350,
        ServoModel::Xl430W250,
        ServoModel::Mx28V2,
        ServoModel::Mx64V2,
        ServoModel::Mx106V2,
    ] {
        assert_eq!(m.protocol(), Protocol::V2);
        assert_eq!(addr(m, Item::FirmwareVersion), (6, 1));
        assert_eq!(addr(m, Item::Id), (7, 1));
        assert_eq!(addr(m, Item::BaudRate), (8, 1));
        assert_eq!(addr(m, Item::OperatingMode), (11, 1));
        assert_eq!(addr(m, Item::MaxPositionLimit), (48, 4));
        assert_eq!(addr(m, Item::MinPositionLimit), (52, 4));
        assert_eq!(addr(m, Item::TorqueEnable), (64, 1));
        assert_eq!(addr(m, Item::StatusReturnLevel), (68, 1));
        assert_eq!(addr(m, Item::HardwareErrorStatus), (70, 1));
        assert_eq!(addr(m, Item::GoalPosition), (116, 4));
        assert_eq!(addr(m, Item::PresentVelocity), (128, 4));
        assert_eq!(addr(m, Item::PresentPosition), (132, 4));
        assert_eq!(addr(m, Item::PresentVoltage), (144, 2));
        assert_eq!(addr(m, Item::PresentTemperature), (146, 1));
    }
    assert_eq!(addr(ServoModel::Xm430W350, Item::PresentCurrent), (126, 2));
    assert_eq!(addr(ServoModel::Xm430W350, Item::CurrentLimit), (38, 2));
    assert_eq!(addr(ServoModel::Xl430W250, Item::PresentLoad), (126, 2));
    assert!(
        ServoModel::Xl430W250
            .table()
            .item(Item::CurrentLimit)
            .is_none()
    );
}

#[test]
fn model_numbers_and_names() {
    let expected = [
        (ServoModel::Rx28, 28),
        (ServoModel::Rx64, 64),
        (ServoModel::Mx28, 29),
        (ServoModel::Mx64, 310),
        (ServoModel::Mx106, 320),
        (ServoModel::Mx28V2, 30),
        (ServoModel::Mx64V2, 311),
        (ServoModel::Mx106V2, 321),
        (ServoModel::Xm430W350, 1020),
        (ServoModel::Xl430W250, 1060),
    ];
    for (m, n) in expected {
        assert_eq!(m.model_number(), n);
        assert_eq!(ServoModel::from_model_number(n), Some(m));
        assert_eq!(ServoModel::parse(m.name()), Some(m), "{}", m.name());
    }
    assert_eq!(ServoModel::parse("mx-28-2"), Some(ServoModel::Mx28V2));
    assert_eq!(
        ServoModel::parse("xm430-w350-t"),
        Some(ServoModel::Xm430W350)
    );
    assert_eq!(ServoModel::parse("ax-12"), None);
}

#[test]
fn tables_are_consistent() {
    for m in ServoModel::ALL {
        let t = m.table();
        let mut end = 0;
        for r in &t.registers {
            assert!(
                r.address >= end,
                "{m}: {} overlaps the register before it",
                r.name
            );
            assert!(
                matches!(r.size, 1 | 2 | 4),
                "{m}: {} size {}",
                r.name,
                r.size
            );
            assert!(r.min <= r.max, "{m}: {}", r.name);
            if let Some(v) = r.initial {
                assert!(v >= r.min && v <= r.max, "{m}: {} initial {v}", r.name);
            }
            end = r.end();
        }
        if m.protocol() == Protocol::V1 {
            assert!(t.len() <= 256, "1.0 addresses are one byte");
        }
        if m.is_board() {
            continue; // a board drives nothing: tests/cm730_board.rs checks it
        }
        for item in [
            Item::ModelNumber,
            Item::Id,
            Item::TorqueEnable,
            Item::GoalPosition,
            Item::PresentPosition,
            Item::PresentVelocity,
            Item::PresentVoltage,
            Item::PresentTemperature,
            Item::StatusReturnLevel,
            Item::ReturnDelayTime,
            Item::MinPositionLimit,
            Item::MaxPositionLimit,
        ] {
            assert!(t.item(item).is_some(), "{m} lacks {item:?}");
        }
        assert!(
            t.item(Item::PresentLoad).is_some() || t.item(Item::PresentCurrent).is_some(),
            "{m} reports neither load nor current"
        );
    }
}

#[test]
fn factory_memory_holds_model_number_and_initial_values() {
    let t = ServoModel::Rx64.table();
    let mem = t.factory_memory(7, 24);
    assert_eq!(&mem[0..2], &[64, 0]);
    assert_eq!(mem[2], 24);
    assert_eq!(mem[3], 7);
    assert_eq!(mem[4], 34, "baud 57600");
    assert_eq!(mem[5], 250, "return delay 500 us");
    assert_eq!(&mem[8..10], &1023u16.to_le_bytes());
    assert_eq!(
        &mem[34..36],
        &1023u16.to_le_bytes(),
        "torque limit = max torque"
    );
    let t = ServoModel::Xm430W350.table();
    let mem = t.factory_memory(1, 45);
    assert_eq!(&mem[0..2], &1020u16.to_le_bytes());
    assert_eq!(mem[7], 1);
    assert_eq!(mem[11], 3, "position control mode");
    assert_eq!(&mem[38..40], &1193u16.to_le_bytes());
    assert_eq!(&mem[48..52], &4095u32.to_le_bytes());
}

#[test]
fn unit_conversions() {
    let rx = ServoModel::Rx28.table();
    let pos = rx.item(Item::PresentPosition).unwrap();
    assert_eq!(pos.to_si(512), 0.0);
    // 0.29 degree per unit (300 degrees over 1024 units).
    assert!((pos.to_si(513) - 300.0 / 1024.0 * PI / 180.0).abs() < 1e-15);
    assert!((pos.to_si(0) + 150.0_f64.to_radians()).abs() < 1e-12);
    assert_eq!(pos.from_si(0.0), 512);
    assert_eq!(pos.from_si(10.0), 1023, "clamped to the range");
    assert_eq!(pos.from_si(f64::NAN), 0);

    // Protocol 1.0 load: bit 10 = clockwise = negative.
    let load = rx.item(Item::PresentLoad).unwrap();
    assert_eq!(load.encoding, Encoding::SignMagnitude);
    assert_eq!(load.decode(&(1024u16 + 500).to_le_bytes()), -500);
    assert_eq!(load.decode(&300u16.to_le_bytes()), 300);
    assert!((load.to_si(-500) + 0.5).abs() < 1e-12);
    let mut b = [0u8; 2];
    load.encode(-500, &mut b);
    assert_eq!(u16::from_le_bytes(b), 1524);
    assert!(
        !load.plausible(&0x0800u16.to_le_bytes()),
        "bit 11 cannot be set"
    );

    let speed = rx.item(Item::PresentVelocity).unwrap();
    assert!((speed.to_si(100) - 100.0 * 0.111 * 2.0 * PI / 60.0).abs() < 1e-12);

    let xm = ServoModel::Xm430W350.table();
    let pos = xm.item(Item::PresentPosition).unwrap();
    assert_eq!(pos.to_si(2048), 0.0);
    assert!((pos.to_si(4096) - PI).abs() < 1e-12);
    assert_eq!(pos.decode(&(-131073i32).to_le_bytes()), -131073);
    let vel = xm.item(Item::PresentVelocity).unwrap();
    assert!((vel.to_si(-10) + 10.0 * 0.229 * 2.0 * PI / 60.0).abs() < 1e-12);
    assert_eq!(vel.decode(&(-10i32).to_le_bytes()), -10);
    let cur = xm.item(Item::PresentCurrent).unwrap();
    assert!((cur.to_si(-100) + 0.269).abs() < 1e-12);
    let volt = xm.item(Item::PresentVoltage).unwrap();
    assert!((volt.to_si(120) - 12.0).abs() < 1e-12);
    let mx = ServoModel::Mx64.table();
    let cur = mx.item(Item::PresentCurrent).unwrap();
    assert!(
        (cur.to_si(2148) - 0.45).abs() < 1e-12,
        "e-manual: 2148 is 450 mA"
    );
}

#[test]
fn baud_registers() {
    assert_eq!(baud_from_register(Protocol::V1, 1), Some(1_000_000));
    assert_eq!(baud_from_register(Protocol::V1, 34), Some(57_142));
    assert_eq!(baud_from_register(Protocol::V1, 207), Some(9_615));
    assert_eq!(baud_from_register(Protocol::V2, 1), Some(57_600));
    assert_eq!(baud_from_register(Protocol::V2, 3), Some(1_000_000));
    assert_eq!(baud_from_register(Protocol::V2, 8), None);
}

#[test]
fn wire_time_matches_the_documented_table() {
    use std::time::Duration;
    use twinloop_link::{ReadMethod, plan_cycle};
    // Rows of the wire-time table in docs/link.md (20 servos): (protocol, method, read len, baud, RDT us,
    // write B, read B, wire ms, round trips).
    let rows = [
        (
            Protocol::V1,
            ReadMethod::Read,
            2,
            57_600,
            0,
            68,
            320,
            67.361,
            21,
        ),
        (
            Protocol::V1,
            ReadMethod::Read,
            6,
            1_000_000,
            0,
            68,
            400,
            4.680,
            21,
        ),
        (
            Protocol::V1,
            ReadMethod::Read,
            2,
            1_000_000,
            500,
            68,
            320,
            13.880,
            21,
        ),
        (
            Protocol::V2,
            ReadMethod::SyncRead,
            4,
            1_000_000,
            0,
            114,
            334,
            4.480,
            2,
        ),
        (
            Protocol::V2,
            ReadMethod::FastSyncRead,
            4,
            1_000_000,
            0,
            114,
            202,
            3.160,
            2,
        ),
        (
            Protocol::V2,
            ReadMethod::SyncRead,
            10,
            1_000_000,
            0,
            114,
            454,
            5.680,
            2,
        ),
        (
            Protocol::V2,
            ReadMethod::FastSyncRead,
            10,
            1_000_000,
            0,
            114,
            322,
            4.360,
            2,
        ),
        (
            Protocol::V2,
            ReadMethod::SyncRead,
            4,
            1_000_000,
            500,
            114,
            334,
            14.480,
            2,
        ),
        (
            Protocol::V2,
            ReadMethod::FastSyncRead,
            10,
            1_000_000,
            500,
            114,
            322,
            4.860,
            2,
        ),
        (
            Protocol::V2,
            ReadMethod::FastSyncRead,
            4,
            4_500_000,
            0,
            114,
            202,
            0.702,
            2,
        ),
    ];
    for (p, m, l, baud, rdt, wb, rb, ms, rt) in rows {
        let goal = if p == Protocol::V1 { 2 } else { 4 };
        let plan = plan_cycle(p, m, 20, l, goal, baud, Duration::from_micros(rdt));
        assert_eq!(
            (plan.write_bytes, plan.read_bytes, plan.round_trips),
            (wb, rb, rt),
            "{p} {m:?} {l}"
        );
        let got = plan.wire.as_secs_f64() * 1e3;
        assert!(
            (got - ms).abs() < 0.0006,
            "{p} {m:?} {l} @{baud}: {got} ms vs {ms}"
        );
    }
}
