//! twinloop-robot: the seam that makes robot-in-the-loop real.
//!
//! Experiments (tip-over, identification runs, recordings) are written once against
//! [`Robot`]; the simulator implements it, and so does a real robot on a Dynamixel
//! bus (through a mapping file that ties each joint to a servo). A virtual robot
//! served on a bus is the simulator behind the servo side of the protocol, so the
//! same experiment also runs through the real protocol path without hardware.
//!
//! Units are SI at this interface: radians, rad/s, N m, seconds. Conversions to raw
//! servo units happen below it.

use std::fmt;

/// What a robot measured at one instant. Fields a robot cannot measure stay `None`
/// (or empty); experiments say which they need.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RobotState {
    /// Time of the measurement, seconds since the robot was opened.
    pub time: f64,
    /// Joint positions (rad), in [`Robot::joint_names`] order.
    pub positions: Vec<f64>,
    /// Joint velocities (rad/s), if measured.
    pub velocities: Option<Vec<f64>>,
    /// Joint load or torque (N m), if measured.
    pub efforts: Option<Vec<f64>>,
    /// Trunk IMU, if the robot has one.
    pub imu: Option<Imu>,
    /// Per foot contact sensing, if the robot has it.
    pub feet: Vec<FootSensor>,
}

/// An inertial measurement unit on the trunk.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Imu {
    /// Angular velocity in the IMU frame, rad/s.
    pub gyro: [f64; 3],
    /// Specific force (acceleration minus gravity) in the IMU frame, m/s^2; at rest it
    /// reads +9.81 along the IMU's up axis.
    pub accel: [f64; 3],
    /// Orientation of the IMU frame in the world as a unit quaternion (x, y, z, w),
    /// when the robot estimates or knows it (the simulator does).
    pub orientation: Option<[f64; 4]>,
}

/// Force under one foot.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FootSensor {
    pub name: String,
    /// Total vertical force, N.
    pub force: f64,
    /// Centre of pressure in the world frame (x, y), m, when the force is non-zero.
    pub cop: Option<[f64; 2]>,
}

/// An error from a robot: which joint or servo, and what happened.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotError {
    /// The joint (or servo, as "id 7") at fault, if one is.
    pub joint: Option<String>,
    pub message: String,
}

impl RobotError {
    pub fn new(message: impl Into<String>) -> Self {
        RobotError {
            joint: None,
            message: message.into(),
        }
    }

    pub fn at_joint(joint: impl Into<String>, message: impl Into<String>) -> Self {
        RobotError {
            joint: Some(joint.into()),
            message: message.into(),
        }
    }
}

impl fmt::Display for RobotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.joint {
            Some(j) => write!(f, "{j}: {}", self.message),
            None => write!(f, "{}", self.message),
        }
    }
}

impl std::error::Error for RobotError {}

/// A robot an experiment can drive: read joints and sensors, command joint positions,
/// and let time pass. The simulator's time is simulated; a real robot's is the wall clock.
pub trait Robot {
    /// The joints this robot commands and reports, in the order every vector uses.
    fn joint_names(&self) -> &[String];

    /// Seconds since the robot was opened.
    fn time(&self) -> f64;

    /// The latest measurements, written into `state` (reuse it across calls: no allocation
    /// once its vectors have the right length).
    fn read(&mut self, state: &mut RobotState) -> Result<(), RobotError>;

    /// Goal positions (rad) for all joints, in [`Robot::joint_names`] order.
    fn command_positions(&mut self, goals: &[f64]) -> Result<(), RobotError>;

    /// Let `dt` seconds pass: the simulator integrates, a real robot waits for its clock.
    fn advance(&mut self, dt: f64) -> Result<(), RobotError>;

    /// Index of a joint by name.
    fn joint_index(&self, name: &str) -> Option<usize> {
        self.joint_names().iter().position(|n| n == name)
    }
}
