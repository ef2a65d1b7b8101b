//! The km20 virtual robot's CM-730 board: its gyro and accelerometer registers
//! read the simulated trunk IMU in the board's counts and along the board's axes,
//! PING / scan / a whole-table READ (what `twinloop link scan` and `link read
//! --id 200` do) find it on a served km20, and a board on a link the robot lacks
//! is named.

use std::time::Duration;
use twinloop_link::ModelTable;
use twinloop_link::board::{CM730_ACCEL_M_S2_PER_COUNT, CM730_GYRO_RAD_S_PER_COUNT};
use twinloop_link::transport::{self, LoopbackTransport, SerialOptions};
use twinloop_link::{BoardAxes, Client, ClientConfig, Item, Protocol, RobotMapping, ServoModel};
use twinloop_virtual::{PtyServer, Snapshot, VirtualRobot, VirtualRobotOptions};

fn km20() -> (twinloop_description::Description, RobotMapping) {
    (
        twinloop_description::builtin::resolve("builtin:km20").unwrap(),
        RobotMapping::builtin("km20").unwrap(),
    )
}

/// Gyro Z, Y, X and accelerometer X, Y, Z counts of the board at id 200 after the
/// robot stood for `seconds`, and the simulated IMU (torso frame) they come from.
fn board_counts(mapping: &RobotMapping, seconds: f64) -> ([i32; 6], twinloop_robot::Imu) {
    let (robot, _) = km20();
    let mut vr = VirtualRobot::new(&robot, mapping, &VirtualRobotOptions::default()).unwrap();
    let bus = vr.bus();
    let mut c = Client::new(LoopbackTransport::new(bus));
    vr.step_for(seconds).unwrap();
    let mut block = [0u8; 12];
    c.read(Protocol::V1, 200, 38, &mut block).unwrap();
    let mut snap = Snapshot::default();
    vr.snapshot(&mut snap);
    let counts =
        std::array::from_fn(|k| u16::from_le_bytes([block[2 * k], block[2 * k + 1]]) as i32);
    (counts, snap.state.imu.unwrap())
}

/// The CM-730's count for an SI value: 512 + value / scale, rounded.
fn count(si: f64, per_count: f64) -> i32 {
    512 + (si / per_count).round() as i32
}

#[test]
fn the_board_reads_the_simulated_trunk_imu_in_cm730_counts() {
    let (_, mapping) = km20();
    // 0.2 s after torque on the robot still rocks in pitch (about 10 deg/s).
    let ([gz, gy, gx, ax, ay, az], imu) = board_counts(&mapping, 0.2);
    let (g, a) = (CM730_GYRO_RAD_S_PER_COUNT, CM730_ACCEL_M_S2_PER_COUNT);
    assert_eq!(
        [gx, gy, gz],
        [
            count(imu.gyro[0], g),
            count(imu.gyro[1], g),
            count(imu.gyro[2], g)
        ]
    );
    assert_eq!(
        [ax, ay, az],
        [
            count(imu.accel[0], a),
            count(imu.accel[1], a),
            count(imu.accel[2], a)
        ]
    );
    assert!(gy != 512, "the rocking shows on the gyro's Y: {gy}");
    // Upright: 1 g = 128 counts up; the torso leans a few degrees forward at most
    // (1 count of X = 0.45 deg).
    assert_eq!(az, 640);
    assert!((ax - 512).abs() <= 12 && (ay - 512).abs() <= 1, "{ax} {ay}");
}

#[test]
fn a_board_mounted_on_its_side_reads_gravity_along_its_own_x() {
    // Board X along the torso's z (up), Y along y, Z along -x.
    let (_, mut mapping) = km20();
    mapping.boards[0].axes = BoardAxes::parse(&["z", "y", "-x"].map(String::from)).unwrap();
    let ([_, _, _, ax, ay, az], imu) = board_counts(&mapping, 0.2);
    let a = CM730_ACCEL_M_S2_PER_COUNT;
    assert_eq!(ax, 640);
    assert_eq!(ay, count(imu.accel[1], a));
    assert_eq!(az, count(-imu.accel[0], a));
}

#[test]
fn scan_and_a_whole_table_read_find_the_cm730_on_a_served_km20() {
    let (robot, mapping) = km20();
    let vr = VirtualRobot::new(&robot, &mapping, &VirtualRobotOptions::default()).unwrap();
    let server = PtyServer::start(vr, None, |_| {}).unwrap();
    let t = transport::open(server.path(), 1_000_000, &SerialOptions::default()).unwrap();
    let mut c = Client::with_config(
        t,
        ClientConfig {
            latency: Duration::from_millis(200),
            ..ClientConfig::default()
        },
    );
    // The ids around the servos and the board, silent ones on both sides: each
    // silent id costs a whole reply timeout (all 254 ids took 47 s of CI).
    let mut found = c.scan(Protocol::V1, 0..=22).unwrap();
    found.extend(c.scan(Protocol::V1, 198..=202).unwrap());
    let ids: Vec<u8> = found.iter().map(|s| s.id).collect();
    let mut expected: Vec<u8> = (1..=20).collect();
    expected.push(200);
    assert_eq!(ids, expected);
    let board = found.last().unwrap();
    assert_eq!(board.model, Some(ServoModel::Cm730));
    // `link read --id 200`: one READ of the whole table.
    let table = ServoModel::Cm730.table();
    let mut memory = vec![0u8; table.len()];
    c.read(Protocol::V1, 200, 0, &mut memory).unwrap();
    let value = |item| {
        let r = table.item(item).unwrap();
        r.decode(&memory[r.address as usize..r.end() as usize])
    };
    assert_eq!(value(Item::ModelNumber), 0x7300);
    assert_eq!(value(Item::Id), 200);
    let up = table.item(Item::AccelZ).unwrap().to_si(value(Item::AccelZ));
    assert!((up - 9.81).abs() < 0.1, "{up} m/s^2");
    drop(c);
    server.stop().unwrap();
}

#[test]
fn a_board_on_a_link_the_robot_lacks_is_named_with_its_line() {
    let (robot, _) = km20();
    let text = "[[joint]]\nname = \"r_knee\"\nid = 13\nmodel = \"RX-64\"\n\n\
                [[board]]\nname = \"imu\"\nid = 200\nmodel = \"CM-730\"\nlink = \"chest\"\n";
    let mapping = RobotMapping::parse(text, "m.toml").unwrap();
    let e = VirtualRobot::new(&robot, &mapping, &VirtualRobotOptions::default())
        .err()
        .unwrap();
    assert!(
        e.to_string()
            .starts_with("m.toml:6: board \"imu\": link \"chest\" is not a link of robot \"km20\""),
        "{e}"
    );
}
