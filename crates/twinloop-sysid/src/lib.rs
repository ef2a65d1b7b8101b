//! twinloop-sysid: black-box identification of a robot's input/output behaviour
//! (seed 003).

pub mod arx;
pub mod data;
pub mod error;
pub mod freq;
pub mod gramian;
pub mod linalg;
pub mod metrics;
pub mod pem;
pub mod ss;
pub mod subspace;

pub use arx::{ArxModel, ArxOrders, arx_regressor, estimate_arx};
pub use data::IoData;
pub use error::{ErrorKind, Result, SysidError};
pub use ss::StateSpace;
