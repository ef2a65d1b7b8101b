//! twinloop-loop: the robot-in-the-loop adaptation, below the CLI and the Python
//! package, which fill its plans from their arguments and print what comes back.
//!
//! | piece | module |
//! |---|---|
//! | a robot spec (`builtin:NAME`, a profile TOML, a URDF or MJCF) resolved into a description with its joint roles | [`profile`] |
//! | a draft profile from what answers on a bus (`link scan --out`) | [`draft_profile`] |
//! | the bus a plan opens (port, timeouts, silence window) | [`port`] |
//! | the plan of the tip-over over a robot's bus | [`bus_plan`] |
//! | the plan run: on a port, or in lockstep with a simulated model | [`tipover_bus`] |
//! | the protocol passes: the adaptation made again less the protocol's bias | [`protocol_bias`] |
//! | a part on the legs: the other places tried, and the one kept or none | [`other_places`] |
//! | the kept place's feet roll near the robot's | [`roll_check`] |
//! | the fitted floor's share of the CoM's resolution | [`floor_share`] |
//! | the demo's scenario: a hidden change served on a pty, measured, adapted, checked | [`demo`] |
//! | the crate's error | [`error`] |

pub mod adaptation;
pub mod bus_plan;
pub mod demo;
pub mod draft_profile;
pub mod error;
pub mod floor_fit;
pub mod floor_share;
pub mod other_places;
pub mod port;
pub mod profile;
pub mod protocol_bias;
pub mod roll_check;
pub mod tipover_bus;

pub use adaptation::adapt_to_protocol;
pub use bus_plan::BusPlan;
pub use error::{ErrorKind, LoopError};
pub use port::BusPort;
