//! twinloop-sysid: black-box identification of a robot's input/output behaviour
//! (seed 003).

pub mod arx;
pub mod data;
pub mod error;
pub mod freq;
pub mod gramian;
pub mod identify;
pub mod json;
pub mod linalg;
pub mod metrics;
pub mod pem;
pub mod report;
pub mod resid;
pub mod ss;
pub mod stats;
pub mod subspace;

pub use arx::{ArxModel, ArxOrders, arx_regressor, estimate_arx};
pub use data::IoData;
pub use error::{ErrorKind, Result, SysidError};
pub use identify::{
    ArxIdentification, EvaluationOptions, SsMethod, SsOptions, StateSpaceIdentification, evaluate,
    identify_arx, identify_state_space,
};
pub use ss::StateSpace;
