//! Control-table registers written over the protocol change how the simulated
//! servos move: Moving Speed limits the speed towards the goal, the compliance
//! slope sets how far a loaded servo sags, Torque Enable 0 leaves the joints limp.
//! Stepped on the test's thread (no real time), so the numbers are exact.

use twinloop_link::{Instruction, PacketWriter, Protocol, RobotMapping, VirtualBus};
use twinloop_virtual::{SimServoBackend, Snapshot, VirtualRobot, VirtualRobotOptions};

fn km20() -> (VirtualRobot, VirtualBus<SimServoBackend>, RobotMapping) {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let mapping = RobotMapping::builtin("km20").unwrap();
    let vr = VirtualRobot::new(&robot, &mapping, &VirtualRobotOptions::default()).unwrap();
    let bus = vr.bus();
    (vr, bus, mapping)
}

/// WRITE `data` at `address` of servo `id` (Protocol 1.0); the servo must accept.
fn write(bus: &mut VirtualBus<SimServoBackend>, id: u8, address: u8, data: &[u8]) {
    let mut req = Vec::new();
    let mut w = PacketWriter::instruction(&mut req, Protocol::V1, id, Instruction::Write);
    w.bytes(&[address]).bytes(data);
    w.finish().unwrap();
    let mut reply = Vec::new();
    bus.handle(&req, &mut reply);
    // FF FF id 02 error checksum: error 0.
    assert_eq!(reply.len(), 6, "{reply:02X?}");
    assert_eq!(
        reply[4], 0,
        "servo {id} refused the write at {address}: {reply:02X?}"
    );
}

fn raw_goal(angle: f64) -> [u8; 2] {
    let unit = 300f64.to_radians() / 1024.0;
    ((512.0 + angle / unit).round() as u16).to_le_bytes()
}

fn joint(vr: &mut VirtualRobot, name: &str) -> usize {
    vr.simulator().joint_index(name).unwrap()
}

fn position(vr: &VirtualRobot, j: usize) -> f64 {
    let mut s = Snapshot::default();
    vr.snapshot(&mut s);
    s.state.positions[j]
}

#[test]
fn moving_speed_limits_the_speed_towards_the_goal() {
    let unit_speed = 0.111 * std::f64::consts::TAU / 60.0;
    let mut reached = Vec::new();
    for speed_raw in [0u16, 100] {
        let (mut vr, mut bus, m) = km20();
        let id = m.joints.iter().find(|j| j.name == "head_pan").unwrap().id;
        let j = joint(&mut vr, "head_pan");
        write(&mut bus, id, 32, &speed_raw.to_le_bytes());
        write(&mut bus, id, 30, &raw_goal(0.5));
        vr.step_for(0.2).unwrap();
        reached.push(position(&vr, j));
        vr.step_for(0.8).unwrap();
        let end = position(&vr, j);
        assert!((end - 0.5).abs() < 0.02, "speed {speed_raw}: ends at {end}");
    }
    // Moving Speed 100 = 1.16 rad/s: 0.23 rad in 0.2 s (a little less: the position
    // loop lags its profile). 0 is the motor's own speed (RX-28: 8.9 rad/s no-load),
    // nearly there after 0.2 s.
    let limited = 100.0 * unit_speed * 0.2;
    assert!(
        reached[1] > 0.8 * limited && reached[1] < 1.02 * limited,
        "{reached:?} vs {limited}"
    );
    assert!(reached[0] > 0.45, "{reached:?}");
}

#[test]
fn a_steeper_compliance_slope_sags_less_under_load() {
    // The right arm held forward, horizontal: gravity loads the shoulder pitch servo.
    let mut sag = Vec::new();
    for slope in [8u8, 64] {
        let (mut vr, mut bus, m) = km20();
        let id = m
            .joints
            .iter()
            .find(|j| j.name == "r_sho_pitch")
            .unwrap()
            .id;
        let j = joint(&mut vr, "r_sho_pitch");
        write(&mut bus, id, 28, &[slope, slope]);
        let goal = -std::f64::consts::FRAC_PI_2;
        let g = raw_goal(goal);
        write(&mut bus, id, 30, &g);
        vr.step_for(1.5).unwrap();
        let goal_q = (u16::from_le_bytes(g) as f64 - 512.0) * 300f64.to_radians() / 1024.0;
        sag.push((position(&vr, j) - goal_q).abs());
    }
    // Error at a duty d: margin + d * slope, so beyond the factory margin (1 unit)
    // slope 64 sags 8 times as far as slope 8 (the same torque holds the arm).
    let margin = 300f64.to_radians() / 1024.0;
    let beyond = [sag[0] - margin, sag[1] - margin];
    assert!(beyond[0] > 0.0, "{sag:?}");
    let ratio = beyond[1] / beyond[0];
    assert!((ratio - 8.0).abs() < 0.8, "{sag:?}: ratio {ratio}");
}

#[test]
fn torque_off_leaves_the_robot_limp_and_it_falls() {
    let (mut vr, mut bus, m) = km20();
    let mut s = Snapshot::default();
    vr.step_for(0.5).unwrap();
    vr.snapshot(&mut s);
    let standing = s.base_height;
    for j in &m.joints {
        write(&mut bus, j.id, 24, &[0]);
    }
    vr.step_for(1.5).unwrap();
    vr.snapshot(&mut s);
    assert!(
        s.base_height < standing - 0.05,
        "base from {standing} to {}",
        s.base_height
    );
}

#[test]
fn a_mapping_naming_other_joints_is_refused_with_the_joint_and_line() {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let op3 = RobotMapping::builtin("op3").unwrap();
    let e = match VirtualRobot::new(&robot, &op3, &VirtualRobotOptions::default()) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("op3's joint names are not km20's"),
    };
    assert!(e.contains("builtin:op3"), "{e}");
    assert!(e.contains("is not a joint of robot \"km20\""), "{e}");
}
