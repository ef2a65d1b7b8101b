//! The held virtual robot (`serve --held`): km20's trunk welded upright at the
//! origin and no ground, so its feet (below the trunk, at negative heights) touch
//! nothing and every servo holds its joint at 0; the IMU reads gravity straight up.
//! Stepped on the test's thread, so the outcome is exact.

use twinloop_link::RobotMapping;
use twinloop_virtual::{Snapshot, VirtualRobot, VirtualRobotOptions};

#[test]
fn a_held_km20_hangs_in_the_air_holding_its_pose() {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let mapping = RobotMapping::builtin("km20").unwrap();
    let options = VirtualRobotOptions {
        held: true,
        ..Default::default()
    };
    let mut vr = VirtualRobot::new(&robot, &mapping, &options).unwrap();
    let sim = vr.simulator();
    assert!(!sim.model.is_floating());
    assert_eq!(sim.q.len(), 20, "joint coordinates only");
    // The bus turns the servos' torque on, as `serve` does.
    let _bus = vr.bus();
    vr.step_for(2.0).unwrap();
    let mut snap = Snapshot::default();
    vr.snapshot(&mut snap);
    assert!(snap.error.is_none(), "{:?}", snap.error);
    // Each servo holds its joint within a few encoder counts (0.29 deg) against
    // its limb's weight: nothing but gravity acts (a ground at z = 0 would be
    // above the feet and push the legs far off).
    for (name, q) in vr.simulator().model.joint_names.clone().iter().zip(&snap.q) {
        assert!(q.abs() < 0.03, "{name} at {q} rad");
    }
    // The trunk's accelerometer, held still and upright: +g along its z.
    let imu = snap.state.imu.as_ref().expect("the trunk IMU");
    assert!(
        imu.accel[0].abs() < 0.05 && imu.accel[1].abs() < 0.05,
        "{:?}",
        imu.accel
    );
    assert!((imu.accel[2] - 9.81).abs() < 0.05, "{:?}", imu.accel);
}
