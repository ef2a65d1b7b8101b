//! twinloop-servos: the servo catalogue. One [`ServoModel`] per Dynamixel model
//! twinloop knows, each with the facts of its ROBOTIS e-manual page: identity on the
//! bus (Model Number, protocol), encoder resolution, ratings at the rated voltage
//! ([`ServoSpec`]), the position loop's family and factory gains, and how an
//! experiment makes it stiff and puts it back ([`LoopRegister`],
//! [`ServoModel::stiff_values`]). It depends on nothing: the link (control tables,
//! the bus), the actuator models, the simulator and the robot descriptions read
//! their servo facts from here.
//!
//! e-manual pages are cited by ROBOTIS' short names: EM-RX28 is
//! emanual.robotis.com/docs/en/dxl/rx/rx-28, EM-XM430 .../dxl/x/xm430-w350, and so on.

pub mod model;
pub mod protocol;
pub mod stiffening;

pub use model::{LoopFamily, RPM, ServoModel, ServoSpec};
pub use protocol::{BROADCAST_ID, Protocol};
pub use stiffening::LoopRegister;
