//! twinloop-experiments: identification experiments written once against
//! [`twinloop_robot::Robot`], so they run on the simulator, on a virtual robot served
//! over a Dynamixel bus, and on the real robot alike; and the simulated experiments
//! that make the seeds' datasets.
//!
//! | experiment | seed | module |
//! |---|---|---|
//! | tip-over: lean over the ankles in four directions until the robot tips | 000, 001 | [`tipover`] (on any `Robot`; the simulated study with its static reference and CoM estimates is twinloop-ident's `tipover_study`) |
//! | lean: centre -> forward -> backward -> centre over the ankles, ankle and knee torques recorded | 001 section F, Figs 8-11 | [`lean`] (on any `Robot`); its comparison with a simulated lean, before and after adaptation: [`lean_validation`] |
//! | walk: lab17's 13-stage walk with foot gyros, the identification dataset | 003 section 7 | [`walk`] |
//! | compliant walk: COMAN's ZMP walk on series-elastic joints | 002 section 4 | [`compliant_walk`] |

pub mod compliant_walk;
pub mod error;
pub mod guarded;
pub mod lean;
pub mod lean_validation;
pub mod stiffen;
pub mod tipover;
pub mod walk;

pub use error::ExperimentError;
pub use lean::{LeanConfig, LeanJointNames, LeanRecord, LeanRow, run_lean, summarize};
pub use lean_validation::{LeanAdaptationCheck, LeanComparison, compare_leans, lean_comparison};
pub use tipover::{Direction, TipoverConfig, TipoverResult, run_tipover};
pub use walk::{DatasetOptions, WalkDataset, ld2015_two_loop, record_walk};
