//! Robot profiles: the built-ins, `[roles]`, the description path relative to the
//! profile file, the OpenCR's registers (against ROBOTIS's OP3 firmware and host
//! code) and a custom board, served and read back by the host.

use twinloop_link::board_type::opencr;
use twinloop_link::transport::LoopbackTransport;
use twinloop_link::{
    BoardType, Client, DynamixelRobot, Item, Protocol, ReadMethod, RobotMapping, VirtualBus,
};
use twinloop_robot::{Robot, RobotState};

const G: f64 = 9.806_65;

#[test]
fn every_builtin_profile_round_trips_through_its_toml() {
    for name in RobotMapping::BUILTINS {
        let m = RobotMapping::builtin(name).unwrap();
        assert_eq!(m.joints.len(), 20, "{name}");
        assert_eq!(m.boards.len(), 1, "{name}");
        assert_eq!(m.roles.len(), 8, "{name}: every role named");
        assert_eq!(
            m.urdf.as_ref().map(|p| p.display().to_string()),
            Some(format!("builtin:{name}"))
        );
        let back = RobotMapping::parse(&m.to_toml(), "round trip").unwrap();
        assert_eq!(back.roles, m.roles, "{name}");
        assert_eq!(back.urdf, m.urdf, "{name}");
        for (a, b) in back.joints.iter().zip(&m.joints) {
            assert_eq!(
                (&a.name, a.id, a.model, a.zero, a.direction),
                (&b.name, b.id, b.model, b.zero, b.direction)
            );
        }
        let (a, b) = (&back.boards[0], &m.boards[0]);
        assert_eq!(
            (a.id, a.kind, a.axes, &a.link),
            (b.id, b.kind, b.axes, &b.link)
        );
    }
}

#[test]
fn the_builtin_profiles_carry_robotis_facts() {
    let op3 = RobotMapping::builtin("op3").unwrap();
    // OP3.robot: XM-430 ids 1-20 on 2.0, OPEN-CR at 200 on 2.0, 2 Mbps.
    assert_eq!(op3.baud, Some(2_000_000));
    assert!(op3.joints.iter().all(|j| j.protocol == Protocol::V2));
    let b = &op3.boards[0];
    assert_eq!(
        (b.id, b.protocol, b.kind.name.as_str()),
        (200, Protocol::V2, "OpenCR")
    );
    assert_eq!(b.axes.names(), ["-x", "-y", "z"].map(String::from));
    // offset.yaml: l_hip_roll -0.03577924966588375 rad.
    let hip = op3.joints.iter().find(|j| j.name == "l_hip_roll").unwrap();
    assert_eq!((hip.id, hip.zero), (10, -0.03577924966588375));
    let darwin = RobotMapping::builtin("darwin_op").unwrap();
    // JointData: ID_R_SHOULDER_PITCH = 1 ... ID_HEAD_TILT = 20; MX-28 on 1.0.
    assert_eq!(darwin.joints[0].name, "j_shoulder_r");
    assert_eq!(darwin.joints[16].name, "j_ankle2_r");
    assert_eq!(darwin.joints[19].id, 20);
    assert!(darwin.joints.iter().all(|j| j.protocol == Protocol::V1));
    assert_eq!(darwin.role("left_ankle_pitch"), Some("j_ankle1_l"));
    assert_eq!(darwin.boards[0].kind.name, "CM-730");
}

#[test]
fn profile_errors_name_the_file_line_and_field() {
    let joint = "[[joint]]\nname = \"knee\"\nid = 3\nmodel = \"RX-28\"\n";
    let cases = [
        (
            format!("[roles]\nleft_toe = \"knee\"\n{joint}"),
            "p.toml:2:12: roles.left_toe: not a role",
        ),
        (
            format!("[roles]\nleft_knee = \"elbow\"\n{joint}"),
            "p.toml:2:13: roles.left_knee: \"elbow\" is no [[joint]] of this profile",
        ),
        (
            format!("[robot]\ndescription = \"a.urdf\"\nurdf = \"b.urdf\"\n{joint}"),
            "p.toml:3:8: robot.urdf: the description is already given",
        ),
        (
            format!(
                "{joint}[[board]]\nname = \"imu\"\nid = 100\nmodel = \"custom\"\nprotocol = 2\nlink = \"torso\"\n"
            ),
            "p.toml:8:9: board \"imu\": model_number: a custom board needs it",
        ),
        (
            format!(
                "{joint}[[board]]\nname = \"imu\"\nid = 200\nmodel = \"OpenCR\"\nlink = \"torso\"\ngyro = [1, 2, 3]\n"
            ),
            "p.toml:10:8: board \"imu\": gyro: only a model = \"custom\" board takes this",
        ),
        (
            format!(
                "{joint}[[board]]\nname = \"imu\"\nid = 200\nmodel = \"OpenCR\"\nprotocol = 1\nlink = \"torso\"\n"
            ),
            "p.toml:9:12: board \"imu\": protocol: OpenCR runs Protocol 2.0",
        ),
    ];
    for (text, expected) in cases {
        let e = RobotMapping::parse(&text, "p.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(expected), "{e}\nexpected {expected}");
    }
}

#[test]
fn a_relative_description_is_relative_to_the_profile_file() {
    let dir = std::env::temp_dir().join(format!("twinloop-profile-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("robots")).unwrap();
    let file = dir.join("robots").join("mine.toml");
    std::fs::write(
        &file,
        "[robot]\ndescription = \"../models/mine.urdf\"\n[[joint]]\nname = \"a\"\nid = 1\nmodel = \"MX-28\"\n",
    )
    .unwrap();
    let m = RobotMapping::load(&file).unwrap();
    assert_eq!(m.urdf, Some(dir.join("robots").join("../models/mine.urdf")));
    // A built-in name and an absolute path are kept as they are.
    let abs = dir.join("abs.toml");
    std::fs::write(
        &abs,
        "[robot]\nurdf = \"/opt/robot.urdf\"\n[[joint]]\nname = \"a\"\nid = 1\nmodel = \"MX-28\"\n",
    )
    .unwrap();
    assert_eq!(
        RobotMapping::load(&abs).unwrap().urdf,
        Some("/opt/robot.urdf".into())
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The OpenCR's table against the OP3 firmware's `dxl_mem_op3_t` and
/// `open_cr_module.h` (numbers typed from those files, not from twinloop's constants).
#[test]
fn the_opencr_table_has_the_op3_firmware_addresses_and_scales() {
    let b = BoardType::opencr();
    assert_eq!((b.protocol, b.model_number), (Protocol::V2, 0x7400));
    let at = |item| b.register(item).map(|r| (r.address, r.size));
    assert_eq!(at(Item::ModelNumber), Some((0, 2)));
    assert_eq!(at(Item::Id), Some((3, 1)));
    assert_eq!(at(Item::StatusReturnLevel), Some((16, 1)));
    assert_eq!(at(Item::GyroX), Some((32, 2)));
    assert_eq!(at(Item::GyroY), Some((34, 2)));
    assert_eq!(at(Item::GyroZ), Some((36, 2)));
    assert_eq!(at(Item::AccelX), Some((38, 2)));
    assert_eq!(at(Item::AccelY), Some((40, 2)));
    assert_eq!(at(Item::AccelZ), Some((42, 2)));
    assert_eq!(b.imu_span(), (32, 12));
    // int16, 2000 deg/s over 32800 counts and 2 g over 32768: -16400 counts is
    // -1000 deg/s; 16384 counts is 1 g.
    let gx = b.register(Item::GyroX).unwrap();
    assert!((gx.to_si(-16400) - (-1000f64).to_radians()).abs() < 1e-12);
    assert_eq!(gx.decode(&(-16400i16).to_le_bytes()), -16400);
    let az = b.register(Item::AccelZ).unwrap();
    assert!((az.to_si(16384) - G).abs() < 1e-12);
    assert_eq!(opencr::ID, 200);
}

/// The served OpenCR answers PING with its model number, and the host's robot
/// reads its IMU: a board lying level reads 1 g up in the link frame, its X and Y
/// turned by the profile's axes.
#[test]
fn the_host_reads_the_served_opencr_imu() {
    let m = RobotMapping::builtin("op3").unwrap();
    let bus = VirtualBus::with_tracking_model_and_boards(&m.bus(), &m.bus_boards());
    let mut client = Client::new(LoopbackTransport::new(bus));
    let ping = client.ping(Protocol::V2, 200).unwrap();
    assert_eq!(ping.model_number, 0x7400);
    let mut raw = [0u8; 12];
    client.read(Protocol::V2, 200, 32, &mut raw).unwrap();
    // Level and still: gyro 0, accelerometer Z 16384 counts (1 g), in int16.
    assert_eq!(&raw[..10], &[0u8; 10]);
    assert_eq!(i16::from_le_bytes([raw[10], raw[11]]), 16384);
    let mut robot = DynamixelRobot::new(client, m, ReadMethod::Auto).unwrap();
    let mut state = RobotState::default();
    robot.read(&mut state).unwrap();
    let imu = state.imu.expect("the OpenCR's IMU");
    assert_eq!(imu.gyro, [0.0; 3]);
    assert!(
        (imu.accel[2] - G).abs() < 1e-3 && imu.accel[0].abs() < 1e-12,
        "{:?}",
        imu.accel
    );
}

/// A board described only in the profile: served from its fields, read back.
#[test]
fn a_custom_board_is_served_and_read_from_the_profile_alone() {
    let text = "[[joint]]\nname = \"a\"\nid = 1\nmodel = \"XM430-W350\"\n\
        [[board]]\nname = \"imu\"\nid = 120\nmodel = \"custom\"\nprotocol = 2\n\
        model_number = 4660\ngyro = [100, 104, 108]\naccel = [112, 116, 120]\nsize = 4\n\
        signed = true\ngyro_deg_s_per_count = 0.01\naccel_g_per_count = 0.0001\n\
        link = \"torso\"\n";
    let m = RobotMapping::parse(text, "custom.toml").unwrap();
    let kind = m.boards[0].kind;
    assert_eq!((kind.imu_span(), kind.model_number), ((100, 24), 4660));
    let back = RobotMapping::parse(&m.to_toml(), "round trip").unwrap();
    assert!(std::ptr::eq(back.boards[0].kind, kind), "{}", m.to_toml());
    let bus = VirtualBus::with_tracking_model_and_boards(&m.bus(), &m.bus_boards());
    let mut client = Client::new(LoopbackTransport::new(bus));
    assert_eq!(client.ping(Protocol::V2, 120).unwrap().model_number, 4660);
    let mut raw = [0u8; 4];
    client.read(Protocol::V2, 120, 120, &mut raw).unwrap();
    // 1 g at 0.0001 g per count.
    assert_eq!(i32::from_le_bytes(raw), 10000);
    let mut robot = DynamixelRobot::new(client, m, ReadMethod::Auto).unwrap();
    let mut state = RobotState::default();
    robot.read(&mut state).unwrap();
    let imu = state.imu.unwrap();
    assert!((imu.accel[2] - G).abs() < 1e-9, "{:?}", imu.accel);
}
