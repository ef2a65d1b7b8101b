//! The real-robot backend (Robot trait) over a virtual bus: commands in joint
//! radians reach the servos through zero offsets and directions, reads come back in
//! joint radians, failures name the joint.

use twinloop_link::ModelTable;
use twinloop_link::transport::LoopbackTransport;
use twinloop_link::{
    BusServo, Client, DynamixelRobot, ReadMethod, RobotMapping, TrackingServoModel, VirtualBus,
};
use twinloop_robot::{Robot, RobotState};

fn robot_on_virtual_bus(
    mapping: &RobotMapping,
    bus_servos: &[BusServo],
) -> DynamixelRobot<LoopbackTransport<VirtualBus<TrackingServoModel>>> {
    // The mapping's boards with a table of their own (the OP3's OpenCR) after them.
    let bus = VirtualBus::with_tracking_model_and_boards(bus_servos, &mapping.bus_boards());
    DynamixelRobot::new(
        Client::new(LoopbackTransport::new(bus)),
        mapping.clone(),
        ReadMethod::Auto,
    )
    .unwrap()
}

fn servos_of(m: &RobotMapping) -> Vec<BusServo> {
    m.bus()
}

#[test]
fn builtin_robots_follow_joint_commands() {
    for name in ["km20", "op3"] {
        let m = RobotMapping::builtin(name).unwrap();
        let mut robot = robot_on_virtual_bus(&m, &servos_of(&m));
        assert_eq!(robot.joint_names().len(), 20);
        assert_eq!(robot.joint_index("r_knee"), Some(12));
        robot.set_torque(true).unwrap();
        let goals: Vec<f64> = (0..20).map(|k| -0.5 + 0.05 * k as f64).collect();
        robot.command_positions(&goals).unwrap();
        for _ in 0..200 {
            robot.client.transport_mut().responder.step(0.01);
        }
        let mut state = RobotState::default();
        robot.read(&mut state).unwrap();
        for (k, (&q, &g)) in state.positions.iter().zip(&goals).enumerate() {
            // One raw unit: 0.29 deg (RX) or 0.088 deg (XM).
            assert!((q - g).abs() < 0.006, "{name} joint {k}: {q} vs {g}");
        }
        let v = state.velocities.as_ref().unwrap();
        assert!(v.iter().all(|v| v.abs() < 0.05), "at rest: {v:?}");
        assert!(state.efforts.is_some());
    }
}

#[test]
fn zero_offset_and_direction_are_applied() {
    let text = r#"
[[joint]]
name = "a"
id = 1
model = "XM430-W350"
zero = 0.3
direction = -1

[[joint]]
name = "b"
id = 2
model = "RX-28"
zero = -0.2
"#;
    let m = RobotMapping::parse(text, "t.toml").unwrap();
    let mut robot = robot_on_virtual_bus(&m, &servos_of(&m));
    robot.set_torque(true).unwrap();
    robot.command_positions(&[0.1, 0.4]).unwrap();
    robot.client.transport_mut().responder.step(2.0);
    // The servos themselves sit at zero + direction * q.
    use twinloop_link::VirtualServoBackend;
    let bus = &robot.client.transport().responder;
    let xm_angle = bus.backend.measure(0).position;
    let rx_angle = bus.backend.measure(1).position;
    assert!((xm_angle - (0.3 - 0.1)).abs() < 0.002, "{xm_angle}");
    assert!((rx_angle - (-0.2 + 0.4)).abs() < 0.006, "{rx_angle}");
    let mut state = RobotState::default();
    robot.read(&mut state).unwrap();
    assert!((state.positions[0] - 0.1).abs() < 0.002);
    assert!((state.positions[1] - 0.4).abs() < 0.006);
}

#[test]
fn a_missing_servo_is_named_and_the_rest_still_read() {
    let m = RobotMapping::builtin("op3").unwrap();
    let mut servos = servos_of(&m);
    servos.retain(|s| s.id != 13); // r_knee unplugged
    let mut robot = robot_on_virtual_bus(&m, &servos);
    let mut state = RobotState::default();
    let e = robot.read(&mut state).unwrap_err();
    assert_eq!(e.joint.as_deref(), Some("r_knee"));
    assert!(e.message.contains("servo id 13"), "{e}");
    assert!(state.positions[12].is_nan());
    assert!(
        state
            .positions
            .iter()
            .enumerate()
            // Each servo rests at its centre: the joint angle is minus its zero offset
            // (op3's offsets are ROBOTIS's offset.yaml).
            .all(|(k, p)| k == 12 || (p + m.joints[k].zero * m.joints[k].direction).abs() < 1e-9)
    );
    assert!(robot.command_positions(&[0.0; 3]).is_err());
}

/// The Goal Position register of servo `k` as the servo holds it.
fn goal_held(
    robot: &DynamixelRobot<LoopbackTransport<VirtualBus<TrackingServoModel>>>,
    k: usize,
) -> i32 {
    let j = &robot.mapping().joints[k];
    let reg = j
        .model
        .table()
        .item(twinloop_link::Item::GoalPosition)
        .unwrap();
    let bus = &robot.client.transport().responder;
    reg.decode(bus.servos[k].read(reg.address, reg.size as u16))
}

#[test]
fn dithered_goals_average_to_a_goal_between_counts() {
    let m = RobotMapping::builtin("km20").unwrap();
    let mut robot = robot_on_virtual_bus(&m, &servos_of(&m));
    // RX-28 and RX-64 (e-manual): 1024 counts over 300 deg, 512 at the centre.
    let count = (300.0f64 / 1024.0).to_radians();
    let (a, b) = (m.joints[14].clone(), m.joints[15].clone());
    let raw_of =
        |j: &twinloop_link::JointMapping, q: f64| 512.0 + (j.zero + j.direction * q) / count;
    // A goal 0.3 of a count past the count below 0.1 rad.
    let e = raw_of(&a, 0.1);
    let mut goals = vec![0.0; 20];
    goals[14] = 0.1 + a.direction * (e.floor() + 0.3 - e) * count;
    goals[15] = 0.1;
    let base = |j: &twinloop_link::JointMapping| raw_of(j, 0.1).round() as i32;
    robot.set_dithered(|k| k == 14);
    let (mut sum, n) = (0.0, 1000);
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..n {
        robot.command_positions(&goals).unwrap();
        let g = goal_held(&robot, 14);
        seen.insert(g);
        sum += g as f64;
        // The joint not dithered always gets the rounded goal.
        assert_eq!(goal_held(&robot, 15), base(&b));
    }
    let exact = raw_of(&a, goals[14]);
    assert_eq!(seen.len(), 2, "two neighbouring counts: {seen:?}");
    assert!(
        (sum / n as f64 - exact).abs() < 2.0 / n as f64,
        "{} vs {exact}",
        sum / n as f64
    );
    // Off again: plain rounding.
    robot.set_dithered(|_| false);
    robot.command_positions(&goals).unwrap();
    assert_eq!(goal_held(&robot, 14), exact.round() as i32);
}
