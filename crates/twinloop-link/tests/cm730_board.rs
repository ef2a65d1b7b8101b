//! The CM-730 sub-controller on the virtual bus: its control table against the
//! DARwIn-OP framework's addresses and the documented scales, its counts for a
//! known tilt, PING and scan finding it at id 200, the mapping's `[[board]]`, and
//! `DynamixelRobot` filling the trunk IMU from it.

use twinloop_link::ModelTable;
use twinloop_link::board::{CM730_ACCEL_M_S2_PER_COUNT, CM730_GYRO_RAD_S_PER_COUNT};
use twinloop_link::servo::ServoMeasurement;
use twinloop_link::transport::LoopbackTransport;
use twinloop_link::{
    BusServo, Client, DynamixelRobot, ImuSample, Item, Protocol, ReadMethod, RobotMapping,
    ServoModel, VirtualBus, VirtualServoBackend,
};
use twinloop_robot::{Robot, RobotState};

/// A board whose IMU reads `sample` (board axes); no servos.
struct Fixed {
    sample: ImuSample,
}

impl VirtualServoBackend for Fixed {
    fn set_torque_enabled(&mut self, _: usize, _: bool) {}
    fn set_goal_position(&mut self, _: usize, _: f64) {}
    fn measure(&self, _: usize) -> ServoMeasurement {
        unreachable!("a board is never measured as a servo")
    }
    fn step(&mut self, _: f64) {}
    fn board_imu(&self, _: usize) -> Option<ImuSample> {
        Some(self.sample)
    }
}

fn cm730() -> BusServo {
    BusServo {
        id: 200,
        model: ServoModel::Cm730,
    }
}

#[test]
fn the_cm730_table_has_the_framework_addresses_sizes_and_scales() {
    let t = ServoModel::Cm730.table();
    assert_eq!(ServoModel::Cm730.protocol(), Protocol::V1);
    assert_eq!(ServoModel::Cm730.model_number(), 0x7300);
    assert_eq!(
        ServoModel::from_model_number(29440),
        Some(ServoModel::Cm730)
    );
    assert_eq!(ServoModel::parse("cm730"), Some(ServoModel::Cm730));
    // CM730.h: P_MODEL_NUMBER_L 0 .. P_ACCEL_Z_H 49, P_VOLTAGE 50, ADCs to 80.
    for (name, address, size) in [
        ("Model Number", 0, 2),
        ("Firmware Version", 2, 1),
        ("ID", 3, 1),
        ("Baud Rate", 4, 1),
        ("Return Delay Time", 5, 1),
        ("Status Return Level", 16, 1),
        ("Dynamixel Power", 24, 1),
        ("LED Panel", 25, 1),
        ("LED Head", 26, 2),
        ("LED Eye", 28, 2),
        ("Button", 30, 1),
        ("Gyro Z", 38, 2),
        ("Gyro Y", 40, 2),
        ("Gyro X", 42, 2),
        ("Accel X", 44, 2),
        ("Accel Y", 46, 2),
        ("Accel Z", 48, 2),
        ("Present Voltage", 50, 1),
        ("Left Mic", 51, 2),
        ("Right Mic", 67, 2),
        ("ADC 15", 79, 2),
    ] {
        let r = t.by_name(name).unwrap_or_else(|| panic!("no {name}"));
        assert_eq!((r.address, r.size), (address, size), "{name}");
    }
    assert_eq!(t.len(), 81, "CM730::MAXNUM_ADDRESS");
    // Gyro: +-1600 deg/s over 10 bits centred on 512; accelerometer +-4 g.
    let gz = t.item(Item::GyroZ).unwrap();
    assert_eq!((gz.min, gz.max), (0, 1023));
    assert!((gz.to_si(1023) - (511.0 * 1600.0 / 512.0f64).to_radians()).abs() < 1e-12);
    assert!((gz.to_si(0) + 1600f64.to_radians()).abs() < 1e-12);
    let ax = t.item(Item::AccelX).unwrap();
    assert!((ax.to_si(0) + 4.0 * 9.80665).abs() < 1e-12);
    assert!((CM730_GYRO_RAD_S_PER_COUNT.to_degrees() - 3.125).abs() < 1e-12);
    assert!((CM730_ACCEL_M_S2_PER_COUNT - 9.80665 / 128.0).abs() < 1e-12);
    // Factory memory: id 200, 1 Mbps, lying level and still.
    let mem = t.factory_memory(200, 19);
    assert_eq!(&mem[0..2], &[0x00, 0x73]);
    assert_eq!((mem[3], mem[4]), (200, 1));
    let word = |a: usize| u16::from_le_bytes([mem[a], mem[a + 1]]);
    assert_eq!(
        [word(38), word(40), word(42), word(44), word(46), word(48)],
        [512, 512, 512, 512, 512, 640]
    );
}

#[test]
fn a_board_pitched_thirty_degrees_and_turning_reads_the_expected_counts() {
    // Pitched 30 deg forward at rest, turning at 10 deg/s about its Y axis:
    // specific force g (-sin 30, 0, cos 30) along the board's axes.
    let g = 9.80665;
    let p = 30f64.to_radians();
    let sample = ImuSample {
        gyro: [0.0, 10f64.to_radians(), -100f64.to_radians()],
        accel: [-g * p.sin(), 0.0, g * p.cos()],
    };
    let bus = VirtualBus::new(&[cm730()], Fixed { sample });
    let mut c = Client::new(LoopbackTransport::new(bus));
    let mut block = [0u8; 12];
    c.read(Protocol::V1, 200, 38, &mut block).unwrap();
    let w = |k: usize| u16::from_le_bytes([block[2 * k], block[2 * k + 1]]);
    let block0 = block;
    // Gyro Z, Y, X: 512 + rate / 3.125 deg/s, rounded.
    assert_eq!(w(0), 512 - 32, "-100 deg/s = -32 counts");
    assert_eq!(w(1), 512 + 3, "10 deg/s = 3.2 counts");
    assert_eq!(w(2), 512);
    // Accel X, Y, Z: 512 + 128 counts per g.
    assert_eq!(w(3), 512 - 64, "-0.5 g");
    assert_eq!(w(4), 512);
    assert_eq!(w(5), 512 + 111, "0.866 g = 110.9 counts");
    // Beyond full scale the converter saturates.
    let bus = VirtualBus::new(
        &[cm730()],
        Fixed {
            sample: ImuSample {
                gyro: [40.0, 0.0, 0.0],
                accel: [-50.0, 0.0, 0.0],
            },
        },
    );
    let mut c = Client::new(LoopbackTransport::new(bus));
    let mut block = [0u8; 12];
    c.read(Protocol::V1, 200, 38, &mut block).unwrap();
    let w = |k: usize| u16::from_le_bytes([block[2 * k], block[2 * k + 1]]);
    assert_eq!((w(2), w(3)), (1023, 0));
    let _ = block0;
}

#[test]
fn ping_and_scan_find_the_cm730_at_id_200_beside_the_servos() {
    let bus = VirtualBus::with_tracking_model(&[
        BusServo {
            id: 1,
            model: ServoModel::Rx28,
        },
        cm730(),
    ]);
    let mut c = Client::new(LoopbackTransport::new(bus));
    let s = c.ping(Protocol::V1, 200).unwrap();
    assert_eq!((s.model, s.model_number), (Some(ServoModel::Cm730), 29440));
    let found = c.scan(Protocol::V1, 0..=253).unwrap();
    let ids: Vec<u8> = found.iter().map(|s| s.id).collect();
    assert_eq!(ids, vec![1, 200]);
    // Its RAM registers take writes within range; the sensors are read-only.
    let mut err = [0u8; 1];
    c.write(Protocol::V1, 200, 25, &[7]).unwrap();
    assert!(c.write(Protocol::V1, 200, 25, &[8]).is_err());
    assert!(c.write(Protocol::V1, 200, 38, &[0, 2]).is_err());
    c.read(Protocol::V1, 200, 25, &mut err).unwrap();
    assert_eq!(err[0], 7);
}

#[test]
fn the_km20_mapping_declares_a_cm730_on_the_torso() {
    let m = RobotMapping::builtin("km20").unwrap();
    assert_eq!(m.boards.len(), 1);
    let b = &m.boards[0];
    assert_eq!(
        (b.name.as_str(), b.id, b.kind.catalogue, b.link.as_str()),
        ("trunk_imu", 200, Some(ServoModel::Cm730), "torso")
    );
    assert_eq!(m.bus().len(), 21);
    let back = RobotMapping::parse(&m.to_toml(), "round trip").unwrap();
    let mut back = back.boards[0].clone();
    back.line = b.line; // the written file has its own line numbers
    assert_eq!(&back, b);
}

#[test]
fn a_bad_board_entry_is_named_with_its_line_and_field() {
    let joint = "[[joint]]\nname = \"knee\"\nid = 3\nmodel = \"RX-28\"\n";
    let cases = [
        (
            "[[board]]\nname = \"imu\"\nid = 200\nmodel = \"RX-28\"\nlink = \"torso\"\n",
            "m.toml:9:9: board \"imu\": model: unknown board \"RX-28\"; known: CM-730",
        ),
        (
            "[[board]]\nname = \"imu\"\nid = 3\nmodel = \"CM-730\"\nlink = \"torso\"\n",
            "m.toml:8:6: board \"imu\": id: id 3 (Protocol 1.0) is the servo of joint \"knee\" (line 1)",
        ),
        (
            "[[board]]\nname = \"imu\"\nid = 200\nmodel = \"CM-730\"\nprotocol = 2\nlink = \"torso\"\n",
            "m.toml:10:12: board \"imu\": protocol: CM-730 runs Protocol 1.0",
        ),
        (
            "[[board]]\nname = \"imu\"\nid = 200\nmodel = \"CM-730\"\nlink = \"torso\"\naxes = [\"y\", \"x\", \"z\"]\n",
            "m.toml:11:8: board \"imu\": axes: [\"y\", \"x\", \"z\"] is a mirror image",
        ),
    ];
    for (board, expected) in cases {
        let text = format!("{joint}\n{board}");
        let e = RobotMapping::parse(&text, "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(expected), "{e}\nexpected {expected}");
    }
    let e = RobotMapping::parse(
        "[[joint]]\nname = \"imu\"\nid = 200\nmodel = \"CM-730\"\n",
        "m.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("declare it as a [[board]]"), "{e}");
}

#[test]
fn dynamixel_robot_reads_the_trunk_imu_from_the_board() {
    let m = RobotMapping::builtin("km20").unwrap();
    // The stand-in servos, and the board lying level and still.
    let bus = VirtualBus::with_tracking_model(&m.bus());
    let mut robot = DynamixelRobot::new(
        Client::new(LoopbackTransport::new(bus)),
        m,
        ReadMethod::Auto,
    )
    .unwrap();
    assert_eq!(robot.imu_board().map(|b| b.id), Some(200));
    let mut state = RobotState::default();
    robot.read(&mut state).unwrap();
    let imu = state.imu.expect("the board's IMU");
    assert_eq!(imu.gyro, [0.0; 3]);
    let one_g = 128.0 * CM730_ACCEL_M_S2_PER_COUNT;
    assert_eq!(imu.accel, [0.0, 0.0, one_g]);
    let q = imu.orientation.expect("the tilt estimate");
    assert!((q[3] - 1.0).abs() < 1e-12, "level: {q:?}");
    // A board that stops answering is named.
    robot.client.transport_mut().responder.servos.pop();
    let e = robot.read(&mut state).unwrap_err();
    assert_eq!(e.joint.as_deref(), Some("board \"trunk_imu\""), "{e}");
    assert!(e.message.contains("200"), "{e}");
    assert!(state.imu.is_none());
}
