//! `serve --servo-params` for a whole robot: one file for every servo of its type,
//! `ID=FILE` for one servo; the virtual robot's simulator then drives those joints
//! by the file's model (full drive kt V/R, no-load speed V/kt, armature, friction,
//! backlash), the others by their datasheet; a file of the wrong type is refused
//! naming the servo.

use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::params::{BACKLASH, KT};
use twinloop_actuator::params_set::ServoParamsSet;
use twinloop_actuator::{ModelLevel, ServoParams, ServoType};
use twinloop_link::RobotMapping;
use twinloop_sim::Actuator;
use twinloop_virtual::{VirtualRobot, VirtualRobotOptions};

fn write(dir: &std::path::Path, name: &str, p: &ServoParams) -> String {
    let path = dir.join(name);
    std::fs::write(&path, p.to_toml("test")).unwrap();
    path.display().to_string()
}

#[test]
fn the_files_drive_the_joints_they_name() {
    let dir = std::env::temp_dir().join(format!("twinloop-servo-params-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let mapping = RobotMapping::builtin("km20").unwrap();
    let rx64 = mapping
        .joints
        .iter()
        .find(|j| j.model.name() == "RX-64")
        .expect("km20 has RX-64s");
    // Every RX-28: a weaker motor with a backlash; one RX-64 by its id.
    let mut rx28 = defaults(ServoType::Rx28, ModelLevel::M1);
    rx28.values[KT] *= 0.8;
    rx28.values[BACKLASH] = 0.4f64.to_radians();
    let mut one = defaults(ServoType::Rx64, ModelLevel::M1);
    one.values[KT] *= 1.2;
    let args = vec![
        write(&dir, "rx28.toml", &rx28),
        format!("{}={}", rx64.id, write(&dir, "rx64.toml", &one)),
    ];
    let options = VirtualRobotOptions {
        servo_params: ServoParamsSet::read(&args, "--servo-params").unwrap(),
        ..Default::default()
    };
    let mut vr = VirtualRobot::new(&robot, &mapping, &options).expect("stands on them");
    let sim = vr.simulator();
    for j in &mapping.joints {
        let i = sim.joint_index(&j.name).unwrap();
        let Actuator::Dynamixel(s) = sim.actuators[i] else {
            panic!("{} has no servo", j.name)
        };
        let (stall, backlash) = match j.model.name() {
            "RX-28" => (
                rx28.kt() / rx28.resistance() * rx28.voltage,
                rx28.values[BACKLASH],
            ),
            _ if j.id == rx64.id => (one.kt() / one.resistance() * one.voltage, 0.0),
            // The other RX-64: its datasheet's 5.3 N m.
            _ => (5.3, 0.0),
        };
        assert!(
            (s.stall_torque - stall).abs() < 1e-9 && s.backlash == backlash,
            "{} (id {}): {s:?}",
            j.name,
            j.id
        );
    }
    // The wrong type for an id, a type the robot has not: refused, naming them.
    let wrong = vec![format!("{}={}", rx64.id, dir.join("rx28.toml").display())];
    let e = VirtualRobot::new(
        &robot,
        &mapping,
        &VirtualRobotOptions {
            servo_params: ServoParamsSet::read(&wrong, "--servo-params").unwrap(),
            ..Default::default()
        },
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains(&format!("parameters of RX-28, but servo id {}", rx64.id))
            && e.contains("RX-64"),
        "{e}"
    );
    let x = vec![write(
        &dir,
        "xm.toml",
        &defaults(ServoType::Xm430W350, ModelLevel::M1),
    )];
    let e = VirtualRobot::new(
        &robot,
        &mapping,
        &VirtualRobotOptions {
            servo_params: ServoParamsSet::read(&x, "--servo-params").unwrap(),
            ..Default::default()
        },
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("the robot has no such servo (its servos: RX-28, RX-64)"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
