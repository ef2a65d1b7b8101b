//! The virtual robot's operator stands a fallen km20 up again, as a person does
//! between the runs of a tip-over, on the floor the tip-over study uses; stepped on
//! the test's thread, so the outcome is exact.

use twinloop_link::{Instruction, PacketWriter, Protocol, RobotMapping, VirtualBus};
use twinloop_virtual::{SimServoBackend, Snapshot, VirtualRobot, VirtualRobotOptions};

/// WRITE Goal Position (RX, address 30) of servo `id` to `angle` rad.
fn goal(bus: &mut VirtualBus<SimServoBackend>, id: u8, angle: f64) {
    let unit = 300f64.to_radians() / 1024.0;
    let raw = ((512.0 + angle / unit).round() as u16).to_le_bytes();
    let mut req = Vec::new();
    let mut w = PacketWriter::instruction(&mut req, Protocol::V1, id, Instruction::Write);
    w.bytes(&[30]).bytes(&raw);
    w.finish().unwrap();
    let mut reply = Vec::new();
    bus.handle(&req, &mut reply);
    assert_eq!(reply.get(4), Some(&0), "servo {id}: {reply:02X?}");
}

/// The trunk's tilt from upright, deg (the base's up axis against the world's).
fn tilt_deg(vr: &mut VirtualRobot) -> f64 {
    let q = &vr.simulator().q;
    (1.0 - 2.0 * (q[3] * q[3] + q[4] * q[4])).acos().to_degrees()
}

#[test]
fn a_km20_pushed_over_is_stood_up_again_and_stands() {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let mapping = RobotMapping::builtin("km20").unwrap();
    let options = VirtualRobotOptions {
        pick_up_after_s: Some(0.3),
        ground_sink: Some(1e-5),
        ..Default::default()
    };
    let mut vr = VirtualRobot::new(&robot, &mapping, &options).unwrap();
    let mut bus = vr.bus();
    let ankles: Vec<(u8, f64)> = mapping
        .joints
        .iter()
        .filter(|j| j.name.ends_with("ank_pitch"))
        .map(|j| (j.id, j.direction))
        .collect();
    // Standing, the servos' compliance lets the trunk lean (and rock) a little.
    let t0 = tilt_deg(&mut vr);
    assert!(t0 < 3.0, "standing tilted {t0} deg");
    // Ankles 30 deg forward: km20 tips at about 10.
    for &(id, dir) in &ankles {
        goal(&mut bus, id, dir * 30f64.to_radians());
    }
    let mut fallen = false;
    for _ in 0..40 {
        vr.step_for(0.05).unwrap();
        fallen |= tilt_deg(&mut vr) > twinloop_virtual::FALLEN_DEG;
    }
    assert!(fallen, "km20 did not fall ({:.1} deg)", tilt_deg(&mut vr));
    for &(id, _) in &ankles {
        goal(&mut bus, id, 0.0);
    }
    let before = vr.pick_ups();
    vr.step_for(4.0).unwrap();
    assert!(vr.pick_ups() > before, "never stood up");
    let t = tilt_deg(&mut vr);
    assert!(
        (t - t0).abs() < 1.5,
        "stood up but tilted {t:.2} deg ({t0:.2} before)"
    );
    let mut s = Snapshot::default();
    vr.snapshot(&mut s);
    assert!(s.error.is_none(), "{:?}", s.error);
}
