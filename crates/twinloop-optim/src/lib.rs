//! Minimisation for twinloop's fits: one CMA-ES for the costs that have no usable
//! derivative (a backlash's impacts, PoWER's and CMA-ES's comparison on the compliant
//! model, [`cmaes`]) and one Levenberg-Marquardt with a central-difference Jacobian
//! for the servo fits' simulated residuals ([`lm`]). Both have a serial form for an
//! objective that cannot be shared between threads and a parallel one
//! ([`parallel`]: rayon's pool) that returns the same bits on any number of threads.

pub mod cmaes;
pub mod lm;
pub mod parallel;

pub use cmaes::{CmaOptions, CmaResult, StepTolerance, Stop, minimize, minimize_parallel};
pub use lm::{LmOptions, LmResult, levenberg_marquardt, levenberg_marquardt_parallel};
