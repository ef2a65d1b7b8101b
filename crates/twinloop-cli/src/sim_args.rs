//! The simulator as `simulate`, `bench sim` and the 3D replay build it: the servo
//! choice (`--servo`) mapped onto `Simulator::standing_on_servos`, and the record's
//! columns and rows.

use crate::error::CliError;
use crate::units::read_trajectory;
use clap::ValueEnum;
use std::path::Path;
use twinloop_io::{Quantity, StateColumns, Table};
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

/// Goal trajectory: times and, per joint, goal positions (NaN: hold).
pub(crate) struct Goals {
    t: Vec<f64>,
    cols: Vec<Option<usize>>,
    table: Table,
}

impl Goals {
    pub(crate) fn load(path: &Path, model: &twinloop_dynamics::Model) -> Result<Goals, CliError> {
        let joints = &model.joint_names;
        let table = read_trajectory(path, model)?;
        StateColumns::check_known(&table, Quantity::Q, &model.q_names())?;
        let tc = table
            .column_index("t")
            .ok_or_else(|| CliError::new(format!("{}: a `t` column is needed", path.display())))?;
        // Finite and increasing: checked as the table was read.
        let t: Vec<f64> = table.rows.iter().map(|r| r[tc]).collect();
        if t[0] < 0.0 {
            // The run starts at 0: goals before it would be passed over unseen.
            let line = table
                .line_of_row(0)
                .map_or(String::new(), |l| format!(":{l}"));
            return Err(CliError::new(format!(
                "{}{line}: column \"t\": the first goal is at {} s: the simulation starts at \
                 0 s, so goals at negative times would never be reached (shift the times)",
                path.display(),
                t[0]
            )));
        }
        multi_dof_goals(&table, model, path)?;
        let cols: Vec<Option<usize>> = joints
            .iter()
            .map(|j| table.column_index(&format!("q:{j}")))
            .collect();
        if cols.iter().all(Option::is_none) {
            return Err(CliError::new(format!(
                "{}: no q:<joint> column names a joint of the robot",
                path.display()
            )));
        }
        table.check_finite(&cols.iter().flatten().copied().collect::<Vec<_>>())?;
        Ok(Goals { t, cols, table })
    }

    /// The first goal's time.
    pub(crate) fn start(&self) -> f64 {
        self.t.first().copied().unwrap_or(0.0)
    }

    /// The last goal's time.
    pub(crate) fn end(&self) -> f64 {
        self.t.last().copied().unwrap_or(0.0)
    }

    pub(crate) fn at(&self, time: f64, hold: &[f64], out: &mut [f64]) {
        let k = self.t.partition_point(|&x| x <= time);
        let (i0, i1, w) = if k == 0 {
            (0, 0, 0.0)
        } else if k >= self.t.len() {
            (self.t.len() - 1, self.t.len() - 1, 0.0)
        } else {
            let (a, b) = (self.t[k - 1], self.t[k]);
            (k - 1, k, (time - a) / (b - a))
        };
        for (j, c) in self.cols.iter().enumerate() {
            out[j] = match c {
                Some(c) => self.table.rows[i0][*c] * (1.0 - w) + self.table.rows[i1][*c] * w,
                None => hold[j],
            };
        }
    }
}

/// Goals drive a joint's servo, one angle each: a ball joint's quaternion columns
/// (`q:j.qx` ..) have no servo to go to and would be ignored, so they are refused.
/// A floating base's columns are the trajectory's own record, not goals (ignored as
/// documented).
fn multi_dof_goals(
    table: &Table,
    model: &twinloop_dynamics::Model,
    path: &Path,
) -> Result<(), CliError> {
    use twinloop_dynamics::JointType;
    for (name, ty) in model.joint_names.iter().zip(&model.joint_types) {
        if *ty != JointType::Spherical {
            continue;
        }
        let prefix = format!("q:{name}.");
        if let Some(c) = table.columns.iter().find(|c| c.starts_with(&prefix)) {
            return Err(CliError::new(format!(
                "{}: column \"{c}\": {name} is a ball joint, which has no servo to take a \
                 goal (goals are for hinges and sliders); remove its columns",
                path.display()
            )));
        }
    }
    Ok(())
}
