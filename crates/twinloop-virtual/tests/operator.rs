//! The virtual robot's operator catches a falling km20 and stands it up again, as a person does
//! between the runs of a tip-over, on the floor the tip-over study uses; stepped on
//! the test's thread, so the outcome is exact.

use twinloop_link::{Instruction, PacketWriter, Protocol, RobotMapping, VirtualBus};
use twinloop_virtual::{SimServoBackend, Snapshot, VirtualRobot, VirtualRobotOptions};

/// WRITE Goal Position (RX, address 30) of servo `id` to `angle` rad.
fn goal(bus: &mut VirtualBus<SimServoBackend>, id: u8, angle: f64) {
    let unit = 300f64.to_radians() / 1024.0;
    let raw = ((512.0 + angle / unit).round() as u16).to_le_bytes();
    write(bus, id, 30, &raw);
}

fn write(bus: &mut VirtualBus<SimServoBackend>, id: u8, address: u8, data: &[u8]) {
    let mut req = Vec::new();
    let mut w = PacketWriter::instruction(&mut req, Protocol::V1, id, Instruction::Write);
    w.bytes(&[address]).bytes(data);
    w.finish().unwrap();
    let mut reply = Vec::new();
    bus.handle(&req, &mut reply);
    assert_eq!(reply.get(4), Some(&0), "servo {id}: {reply:02X?}");
}

/// The trunk's tilt from upright, deg (the base's up axis against the world's).
fn tilt_deg(vr: &mut VirtualRobot) -> f64 {
    let q = &vr.simulator().q;
    (1.0 - 2.0 * (q[3] * q[3] + q[4] * q[4]))
        .acos()
        .to_degrees()
}

#[test]
fn a_km20_pushed_over_is_caught_and_stood_up_and_stands() {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let mapping = RobotMapping::builtin("km20").unwrap();
    let options = VirtualRobotOptions {
        catch_falls: true,
        ground_sink: Some(1e-5),
        ..Default::default()
    };
    let mut vr = VirtualRobot::new(&robot, &mapping, &options).unwrap();
    let mut bus = vr.bus();
    // Stiffened as the tip-over protocol does: compliance margins 0, slopes 2.
    for j in &mapping.joints {
        write(&mut bus, j.id, 26, &[0, 0, 2, 2]);
    }
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
    let mut max_tilt: f64 = 0.0;
    for _ in 0..200 {
        vr.step_for(0.005).unwrap();
        max_tilt = max_tilt.max(tilt_deg(&mut vr));
    }
    assert!(
        vr.pick_ups() >= 1,
        "never caught (tilted {max_tilt:.1} deg at most)"
    );
    assert!(
        max_tilt <= twinloop_virtual::CATCH_DEG + 2.0,
        "caught late: {max_tilt:.1} deg"
    );
    for &(id, _) in &ankles {
        goal(&mut bus, id, 0.0);
    }
    vr.step_for(4.0).unwrap();
    let t = tilt_deg(&mut vr);
    assert!(
        (t - t0).abs() < 1.5,
        "stood up but tilted {t:.2} deg ({t0:.2} before)"
    );
    let mut s = Snapshot::default();
    vr.snapshot(&mut s);
    assert!(s.error.is_none(), "{:?}", s.error);
}
