//! The simulator as `simulate`, `bench sim` and the 3D replay build it: the servo
//! choice (`--servo`) mapped onto `Simulator::standing_on_servos`, and the record's
//! columns and rows.

use crate::error::CliError;
use clap::ValueEnum;
use twinloop_robot::{Robot, RobotState};
use twinloop_sim::{DynamixelServo, SimConfig, Simulator};

/// Which servo model drives every joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ServoChoice {
    /// From the description: effort limit as stall torque and velocity limit as no-load
    /// speed where they look real, else an XM430-class servo scaled to the robot's mass.
    Auto,
    /// Dynamixel RX-28 (3.7 N m, 85 rpm).
    Rx28,
    /// Dynamixel RX-64 (5.3 N m, 64 rpm).
    Rx64,
    /// Dynamixel XM430-W350 (4.1 N m, 46 rpm at 12 V).
    Xm430,
}

fn servo_for(
    choice: ServoChoice,
    robot_name: &str,
    model: &twinloop_dynamics::Model,
    i: usize,
) -> DynamixelServo {
    match choice {
        ServoChoice::Rx28 => DynamixelServo::rx28(),
        ServoChoice::Rx64 => DynamixelServo::rx64(),
        // An XM430 is what `servo_from_limits` assumes when the limits say nothing.
        ServoChoice::Xm430 => twinloop_sim::servo_from_limits(f64::NAN, f64::NAN, 0.0),
        ServoChoice::Auto => twinloop_sim::servo_for_joint(robot_name, model, i),
    }
}

/// A simulator of `robot` standing on the ground on its servos.
pub fn standing_simulator(
    robot: &twinloop_description::Description,
    dt: f64,
    servo: ServoChoice,
) -> Result<Simulator, CliError> {
    let cfg = SimConfig {
        dt,
        ..Default::default()
    };
    let (sim, _) =
        Simulator::standing_on_servos(robot, cfg, &|m, i| servo_for(servo, &robot.name, m, i))?;
    Ok(sim)
}

/// The column names of a simulation record: time, state, servo torques, CoM, IMU
/// and feet.
pub fn record_columns(sim: &Simulator) -> Vec<String> {
    let names = &sim.model.joint_names;
    let mut cols = vec!["t".to_string()];
    cols.extend(sim.model.q_names().iter().map(|n| format!("q:{n}")));
    cols.extend(sim.model.v_names().iter().map(|n| format!("v:{n}")));
    cols.extend(names.iter().map(|n| format!("tau:{n}")));
    cols.extend(["com.x", "com.y", "com.z"].map(String::from));
    let imu_name = sim.model.links[sim.sensors().imu_link].name.clone();
    for s in ["gx", "gy", "gz", "ax", "ay", "az"] {
        cols.push(format!("imu:{imu_name}.{s}"));
    }
    for &l in &sim.sensors().feet {
        let f = &sim.model.links[l].name;
        for s in ["fz", "cop.x", "cop.y"] {
            cols.push(format!("foot:{f}.{s}"));
        }
    }
    cols
}

/// The simulator's state as a row of [`record_columns`], with `time` in the `t` column.
pub fn state_row(
    sim: &mut Simulator,
    st: &mut RobotState,
    time: f64,
    row: &mut Vec<f64>,
) -> Result<(), CliError> {
    sim.read(st)?;
    row.clear();
    row.push(time);
    row.extend_from_slice(&sim.q);
    row.extend_from_slice(&sim.v);
    row.extend_from_slice(&sim.applied);
    row.extend(sim.center_of_mass().iter());
    let imu = st.imu.unwrap_or_default();
    row.extend(imu.gyro);
    row.extend(imu.accel);
    for f in &st.feet {
        let cop = f.cop.unwrap_or([f64::NAN, f64::NAN]);
        row.extend([f.force, cop[0], cop[1]]);
    }
    Ok(())
}
