//! The two Dynamixel protocol versions: the catalogue's (`twinloop-servos`),
//! re-exported here so that `twinloop_link::protocol::Protocol` keeps working.

pub use twinloop_servos::protocol::{BROADCAST_ID, Protocol};
