//! The robot mapping file: built-ins, round trip, conversions, and errors that name
//! the file, line, field and servo id.

use twinloop_link::{Protocol, RobotMapping, ServoModel};

#[test]
fn builtins_parse_and_round_trip() {
    for name in RobotMapping::BUILTINS {
        let m = RobotMapping::resolve(&format!("builtin:{name}")).unwrap();
        assert_eq!(m.joints.len(), 20);
        let again = RobotMapping::parse(&m.to_toml(), "round-trip").unwrap();
        assert_eq!(
            again.joints,
            m.joints
                .iter()
                .map(|j| {
                    let mut j = j.clone();
                    j.line = again.joints.iter().find(|k| k.name == j.name).unwrap().line;
                    j
                })
                .collect::<Vec<_>>()
        );
    }
    let km = RobotMapping::builtin("km20").unwrap();
    assert_eq!(km.joints[0].model, ServoModel::Rx28);
    // The seed robot's knees are RX-64, everything else RX-28 (the built-in km20).
    for j in &km.joints {
        let want = if j.name.ends_with("knee") {
            ServoModel::Rx64
        } else {
            ServoModel::Rx28
        };
        assert_eq!(j.model, want, "{}", j.name);
    }
    assert!(km.joints.iter().all(|j| j.protocol == Protocol::V1));
    let op3 = RobotMapping::builtin("op3").unwrap();
    assert!(op3.joints.iter().all(|j| j.protocol == Protocol::V2));
    assert!(
        RobotMapping::resolve("builtin:nao")
            .unwrap_err()
            .message
            .contains("km20, op3")
    );
}

const GOOD: &str = r#"
[robot]
name = "test"

[[joint]]
name = "knee"
id = 3
model = "MX-28(2.0)"
protocol = 2
zero = 0.5
direction = -1
min = -1.0
max = 1.0

[[joint]]
name = "hip"
id = 3
model = "RX-28"
"#;

#[test]
fn conversions_follow_zero_and_direction() {
    let m = RobotMapping::parse(GOOD, "good.toml").unwrap();
    let knee = &m.joints[0];
    assert_eq!(
        (knee.protocol, knee.model, knee.line),
        (Protocol::V2, ServoModel::Mx28V2, 5)
    );
    // servo = 0.5 - q
    assert!((knee.servo_angle(0.2) - 0.3).abs() < 1e-12);
    assert!((knee.joint_angle(0.3) - 0.2).abs() < 1e-12);
    let raw = knee.goal_raw(0.2);
    assert!(
        (knee.position(raw) - 0.2).abs() < 0.0016,
        "one raw unit is 1.5 mrad"
    );
    assert_eq!(
        knee.goal_raw(5.0),
        knee.goal_raw(1.0),
        "clamped to the joint limits"
    );
    // Same id on the other protocol is a different servo.
    let hip = &m.joints[1];
    assert_eq!((hip.id, hip.protocol), (3, Protocol::V1));
    assert!((hip.min + 150f64.to_radians()).abs() < 1e-12);
}

fn error(text: &str) -> String {
    RobotMapping::parse(text, "robot.toml")
        .unwrap_err()
        .to_string()
}

#[test]
fn errors_name_file_line_field_and_servo() {
    let e = error(&GOOD.replace("model = \"RX-28\"", "model = \"AX-12\""));
    assert!(
        e.starts_with("robot.toml:18:9: joint \"hip\": model: unknown model \"AX-12\""),
        "{e}"
    );
    let e = error(&GOOD.replace("name = \"hip\"\nid = 3", "name = \"hip\"\nid = 300"));
    assert!(
        e.starts_with("robot.toml:17:6:") && e.contains("servo id 300"),
        "{e}"
    );
    // An RX-28 has no Protocol Type register: it talks 1.0 only (EM-RX28).
    let e = error(&GOOD.replace("model = \"RX-28\"", "model = \"RX-28\"\nprotocol = 2"));
    assert!(
        e.starts_with("robot.toml:19:12:") && e.contains("RX-28 runs Protocol 1.0 only"),
        "{e}"
    );
    let e = error(&GOOD.replace("direction = -1", "direction = 2"));
    assert!(
        e.starts_with("robot.toml:11:13:") && e.contains("direction: 2 is not 1 or -1"),
        "{e}"
    );
    let e = error(&GOOD.replace("max = 1.0", "max = 9.0"));
    assert!(
        e.starts_with("robot.toml:13:7:") && e.contains("servo id 3 (MX-28(2.0))"),
        "{e}"
    );
    let e = error(&GOOD.replace("min = -1.0", "min = 1.5"));
    assert!(e.contains("knee") && e.contains("empty"), "{e}");
    let e = error(&GOOD.replace(
        "name = \"hip\"\nid = 3\nmodel = \"RX-28\"",
        "name = \"hip\"\nid = 3\nmodel = \"XL430-W250\"",
    ));
    assert!(
        e.starts_with("robot.toml:17:6:")
            && e.contains("servo id 3 (Protocol 2.0) already drives joint \"knee\" (line 5)"),
        "{e}"
    );
    let e = error(&GOOD.replace("name = \"hip\"", "name = \"knee\""));
    assert!(e.contains("joint listed twice (first on line 5)"), "{e}");
    let e = error(&GOOD.replace("zero = 0.5", "zero = 0.5\ngear = 2"));
    assert!(
        e.starts_with("robot.toml:11:1:") && e.contains("gear"),
        "{e}"
    );
    let e = error("[[joint]]\nname = \"a\"\nid = \"one\"\nmodel = \"RX-28\"\n");
    assert!(e.starts_with("robot.toml:3:6:"), "{e}");
    let e = error("[[joint]\n");
    assert!(e.starts_with("robot.toml:1:"), "{e}");
    let e = error("[robot]\nname = \"x\"\n");
    assert!(e.contains("no [[joint]] entries"), "{e}");
    let e = RobotMapping::load("/nonexistent/robot.toml")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("/nonexistent/robot.toml: cannot read"), "{e}");
}
