//! The servo side of the protocol: virtual servos on a virtual bus, a backend
//! trait the simulator implements (crate `twinloop-virtual`), a stand-in servo
//! model, and serving a bus on a transport (pty, TCP) with the wire time and
//! return delay emulated.

mod backend;
mod bus;
mod priority;
mod serve;
mod virtual_servo;

pub use backend::{ServoMeasurement, TrackingServoModel, VirtualServoBackend};
pub use bus::{BusBoard, BusClock, BusServo, BusStats, ReplyMark, VIRTUAL_FIRMWARE, VirtualBus};
pub use priority::{ReplyPriority, favour_reply_thread};
pub use serve::{ServeOptions, serve};
pub use virtual_servo::{Fault, VirtualServo, WriteEffects};
