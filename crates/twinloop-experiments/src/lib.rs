//! twinloop-experiments: identification experiments written once against
//! [`twinloop_robot::Robot`], so they run on the simulator, on a virtual robot served
//! over a Dynamixel bus, and on the real robot alike.

pub mod study;
pub mod tipover;

pub use study::{StudyOptions, StudyReport, run_study};
pub use tipover::{Direction, TipoverConfig, TipoverResult, run_tipover};
