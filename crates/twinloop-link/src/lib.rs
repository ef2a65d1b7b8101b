//! twinloop-link: the robot link. Dynamixel Protocol 1.0 and 2.0 packets, control
//! tables, transports, a host client, virtual servos answering the servo side of the
//! protocol, a robot mapping file and the real-robot backend of
//! [`twinloop_robot::Robot`].
//!
//! Protocol facts come from the ROBOTIS e-manual (EM-P1, EM-P2: the Protocol 1.0 and
//! 2.0 pages) and the official DynamixelSDK; the tests hold the e-manual's example
//! packets and packets built by the SDK byte for byte. Nothing here knows dynamics:
//! a simulator plugs into the virtual robot through [`VirtualServoBackend`].

pub mod board;
pub mod board_type;
pub mod client;
pub mod control_cycle;
pub mod control_table;
pub mod crc16;
pub mod decoder;
pub mod instruction;
pub mod link_error;
pub mod mapping;
pub mod packet;
pub mod protocol;
pub mod real_robot;
pub mod register;
pub mod servo;
pub mod servo_model;
pub mod status_error;
pub mod transport;
pub mod wire_time;

pub use board::{BoardAxes, BoardError, ImuSample, TiltFilter};
pub use board_type::{BoardType, CustomBoard};
pub use client::{BulkRead, Client, ClientConfig, ClientStats, FoundServo};
pub use control_cycle::{ControlCycle, CycleServo, CycleSummary, ReadMethod, ServoReading};
pub use control_table::{ControlTable, ModelTable};
pub use crc16::{checksum_v1, crc16, crc16_update};
pub use decoder::{Accept, DecodeEvent, Decoder, DecoderStats, Frame};
pub use instruction::Instruction;
pub use link_error::{LinkError, Outcome};
pub use mapping::{JointMapping, MappingError, RobotMapping};
pub use packet::{EncodeError, PacketWriter};
pub use protocol::{BROADCAST_ID, Protocol};
pub use real_robot::{DynamixelRobot, HostClock};
pub use register::{Access, Area, Encoding, Item, Reading, Register, Unit};
pub use servo::{BusBoard, BusServo, TrackingServoModel, VirtualBus, VirtualServoBackend};
pub use servo_model::{ServoModel, ServoSpec, baud_from_register, baud_to_register};
pub use status_error::{ErrorBitV1, ErrorNumberV2, StatusError};
pub use transport::Transport;
/// The servo catalogue (models, datasheets, how to stiffen them).
pub use twinloop_servos as servos;
pub use wire_time::{CyclePlan, plan_cycle};
