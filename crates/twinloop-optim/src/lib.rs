//! Derivative-free minimisation for the fits whose cost has no usable derivative (a
//! backlash's impacts, PoWER's and CMA-ES's comparison on the compliant model):
//! one CMA-ES for the whole workspace ([`cmaes`]).

pub mod cmaes;

pub use cmaes::{CmaOptions, CmaResult, StepTolerance, Stop, minimize};
