//! twinloop-sim: a physics simulator for any URDF humanoid over the
//! reduced-coordinate dynamics of `twinloop-dynamics`.
//!
//! - Ground contact with friction on every collision primitive (`contact`).
//! - Joint limits, description damping and friction.
//! - Actuators (`actuator`): the Dynamixel P servo (seed 000), the two-loop servo
//!   (seed 003), the series-elastic joint (seed 002, eq 1-6), or torque.
//! - Sensors (`sensors`): encoders with Dynamixel quantisation, an MPU-6050 IMU,
//!   joint load, foot force and centre of pressure.
//! - A fixed step (1 ms default), linearly implicit in every spring and damper so that
//!   stiff servos and contacts stay stable (`Simulator::step`).
//!
//! The simulator implements [`twinloop_robot::Robot`], so experiments written for a
//! real robot run on it unchanged.

pub mod actuator;
pub mod backlash;
pub mod contact;
pub mod ltdl;
mod robot_impl;
pub mod sensors;
pub mod servo_model;
pub mod servo_params;
pub mod simulator;
pub mod standing;
pub mod statics;

pub use actuator::{
    Actuator, DynamixelServo, SeriesElastic, TwoLoopServo, servo_for_joint, servo_from_limits,
};
pub use contact::{ContactParams, ContactPoint, ContactState};
pub use sensors::{SensorState, quantize};
pub use servo_params::servo_from_params;
pub use simulator::{SimConfig, SimError, Simulator};
pub use standing::standing_pose;
