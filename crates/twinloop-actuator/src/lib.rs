//! twinloop-actuator: Dynamixel servo models as documented equation sets
//! ([docs/servo-models.md](../../docs/servo-models.md)), with no dynamics of a robot.
//!
//! - [`servo_type`]: the servo types and their e-manual facts (encoder, PWM range,
//!   factory gains), [`datasheet`]: their default parameters;
//! - [`params`]: the parameter file (`[servo]`, `[params]`, `[uncertainty]`);
//! - [`firmware`]: the position loop as the servo runs it (RX compliance, MX/X PID);
//! - [`motor`]: the DC motor behind the gearbox; [`friction`]: the gearbox's friction
//!   budget (Coulomb, viscous, Stribeck, load-dependent);
//! - [`load`]: what the servo turns (inertia, gravity torque `A sin q + B cos q + C`);
//!   [`bench`]: a servo turning it (BAM's pendulum bench), stepped in fixed time steps;
//! - [`log`]: an `experiment servo` log as columns; [`bam_log`]: BAM's pendulum
//!   logs read as ours; [`replay`]: the model run against a
//!   log's commands; [`lm`]: Levenberg-Marquardt; [`identify`]: the fit, its
//!   uncertainties and what the data cannot determine; [`group`]: several servos of
//!   one type fitted together (shared and per-servo parameters) and whether each
//!   needs its own; [`load_rule`]: which pendulum a servo type needs.

pub mod bam_log;
pub mod bench;
pub mod datasheet;
pub mod delay;
pub mod error;
pub mod excitation;
pub mod firmware;
pub mod friction;
pub mod group;
pub mod identify;
pub use twinloop_optim::lm;
pub mod load;
pub mod load_rule;
pub mod log;
pub mod motor;
pub mod mujoco;
pub mod params;
pub mod params_file;
pub mod params_set;
pub mod profile;
pub mod replay;
pub mod robust_covariance;
mod segments;
pub mod servo_type;
pub mod sweep;
pub mod synthetic;

pub use bench::{Bench, Pendulum};
pub use error::ActuatorError;
pub use excitation::Excitation;
pub use firmware::Firmware;
pub use load::Load;
pub use params::{ModelLevel, ServoParams};
pub use servo_type::{LoopFamily, ServoType};
