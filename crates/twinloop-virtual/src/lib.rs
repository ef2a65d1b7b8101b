//! twinloop-virtual: a simulated robot on a virtual Dynamixel bus.
//!
//! [`VirtualRobot`] builds a [`Simulator`](twinloop_sim::Simulator) of a robot standing
//! on the ground, ties its joints to servos through a
//! [`RobotMapping`](twinloop_link::RobotMapping), and runs it on its own thread in
//! real time. The bus (twinloop-link's [`VirtualBus`](twinloop_link::VirtualBus))
//! talks to it through [`SimServoBackend`]:
//!
//! ```text
//!   bus thread (serve loop)                      simulator thread
//!   ----------------------                       ----------------
//!   WRITE Goal Position  --> commands (mutex) --> copied at each batch of steps
//!   READ Present ...     <-- snapshot (mutex) <-- written after each batch
//! ```
//!
//! A reply never waits for a simulation step: the bus reads the latest snapshot
//! (a copy of a few hundred bytes under an uncontended lock), and a write only
//! stores a number. Both buffers are sized once; neither thread allocates per step.
//!
//! Time: the simulation follows the wall clock, not the wire. A real robot keeps
//! moving (and falling) while the host is silent, and a host on a real bus measures
//! its cycle against the wall clock; locking simulated time to bus traffic would
//! freeze the robot whenever no packet is on the line. When a step costs more than
//! its time step, the simulator falls behind and says so ([`SimStatus::behind_s`]).

mod backend;
mod bench_backend;
mod drive;
mod error;
mod lockstep;
mod pty_server;
mod runner;
mod shared;
mod virtual_robot;

pub use backend::SimServoBackend;
pub use bench_backend::{BenchBackend, link_model, servo_type};
pub use drive::{DriveRegisters, servo_with_registers};
pub use error::VirtualError;
pub use lockstep::Lockstep;
pub use pty_server::PtyServer;
pub use runner::{CATCH_DEG, SimStatus};
pub use shared::{Snapshot, thermal_step};
pub use virtual_robot::{SimHandle, VirtualRobot, VirtualRobotOptions};
