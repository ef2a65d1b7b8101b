//! The servo models twinloop knows: model numbers, protocol, datasheet figures.

use crate::protocol::Protocol;
use crate::register::RPM;
use std::fmt;

/// A servo model with the firmware protocol it runs. MX servos exist with either
/// firmware (different control tables, different model numbers: EM-COMPAT).
///
/// One entry is not a servo: [`ServoModel::Cm730`], the ROBOTIS CM-730
/// sub-controller of Darwin-OP, which answers on the same bus with a control table
/// of its own (its gyroscope and accelerometer among it). It is a "model" here
/// because everything the bus does with a servo's identity (PING, model number,
/// control table) it does with the board's; [`ServoModel::is_board`] tells them
/// apart, and a mapping's `[[joint]]` refuses it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ServoModel {
    Rx28,
    Rx64,
    Mx28,
    Mx64,
    Mx106,
    Mx28V2,
    Mx64V2,
    Mx106V2,
    Xm430W350,
    Xl430W250,
    /// ROBOTIS CM-730 sub-controller (Darwin-OP), Protocol 1.0, usually id 200.
    Cm730,
}

/// Datasheet figures of a model, used to turn load or current into torque and by
/// the virtual servo. Approximate: stall torque at the voltage in `voltage`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoSpec {
    /// Stall torque, N m.
    pub stall_torque: f64,
    /// Stall current, A (None where the e-manual gives none).
    pub stall_current: Option<f64>,
    /// No-load speed, rad/s.
    pub no_load_speed: f64,
    /// Supply voltage the figures hold at, V.
    pub voltage: f64,
    pub gear_ratio: f64,
}

impl ServoSpec {
    /// N m per ampere at stall (the slope used to turn a current into a torque).
    pub fn torque_per_amp(&self) -> Option<f64> {
        self.stall_current.map(|i| self.stall_torque / i)
    }
}

impl ServoModel {
    /// Every model twinloop has a control table for: the servos, then the boards.
    pub const ALL: [ServoModel; 11] = [
        ServoModel::Rx28,
        ServoModel::Rx64,
        ServoModel::Mx28,
        ServoModel::Mx64,
        ServoModel::Mx106,
        ServoModel::Mx28V2,
        ServoModel::Mx64V2,
        ServoModel::Mx106V2,
        ServoModel::Xm430W350,
        ServoModel::Xl430W250,
        ServoModel::Cm730,
    ];

    /// The servos (what a `[[joint]]` may name).
    pub const SERVOS: [ServoModel; 10] = [
        ServoModel::Rx28,
        ServoModel::Rx64,
        ServoModel::Mx28,
        ServoModel::Mx64,
        ServoModel::Mx106,
        ServoModel::Mx28V2,
        ServoModel::Mx64V2,
        ServoModel::Mx106V2,
        ServoModel::Xm430W350,
        ServoModel::Xl430W250,
    ];

    /// The e-manual's name.
    pub const fn name(self) -> &'static str {
        match self {
            ServoModel::Rx28 => "RX-28",
            ServoModel::Rx64 => "RX-64",
            ServoModel::Mx28 => "MX-28",
            ServoModel::Mx64 => "MX-64",
            ServoModel::Mx106 => "MX-106",
            ServoModel::Mx28V2 => "MX-28(2.0)",
            ServoModel::Mx64V2 => "MX-64(2.0)",
            ServoModel::Mx106V2 => "MX-106(2.0)",
            ServoModel::Xm430W350 => "XM430-W350",
            ServoModel::Xl430W250 => "XL430-W250",
            ServoModel::Cm730 => "CM-730",
        }
    }

    /// Parse a model name, forgiving case, spaces and the e-manual's URL spelling
    /// (`rx-28`, `MX-28(2.0)`, `mx-28-2`, `xm430-w350`).
    pub fn parse(text: &str) -> Option<ServoModel> {
        let norm: String = text
            .chars()
            .filter(|c| c.is_ascii_alphanumeric() || *c == '.')
            .map(|c| c.to_ascii_lowercase())
            .collect();
        let norm = norm.replace("2.0", "v2");
        Some(match norm.as_str() {
            "rx28" => ServoModel::Rx28,
            "rx64" => ServoModel::Rx64,
            "mx28" | "mx28v1" => ServoModel::Mx28,
            "mx64" | "mx64v1" => ServoModel::Mx64,
            "mx106" | "mx106v1" => ServoModel::Mx106,
            "mx28v2" | "mx282" => ServoModel::Mx28V2,
            "mx64v2" | "mx642" => ServoModel::Mx64V2,
            "mx106v2" | "mx1062" => ServoModel::Mx106V2,
            "xm430w350" | "xm430w350t" | "xm430w350r" => ServoModel::Xm430W350,
            "xl430w250" | "xl430w250t" => ServoModel::Xl430W250,
            "cm730" => ServoModel::Cm730,
            _ => return None,
        })
    }

    /// Servo names accepted by [`ServoModel::parse`], for error messages.
    pub fn known_names() -> String {
        ServoModel::SERVOS
            .iter()
            .map(|m| m.name())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Whether this is a sub-controller board rather than a servo.
    pub const fn is_board(self) -> bool {
        matches!(self, ServoModel::Cm730)
    }

    /// Board names accepted by [`ServoModel::parse`], for error messages.
    pub fn known_boards() -> String {
        ServoModel::ALL
            .iter()
            .filter(|m| m.is_board())
            .map(|m| m.name())
            .collect::<Vec<_>>()
            .join(", ")
    }

    pub const fn protocol(self) -> Protocol {
        match self {
            ServoModel::Rx28
            | ServoModel::Rx64
            | ServoModel::Mx28
            | ServoModel::Mx64
            | ServoModel::Mx106
            | ServoModel::Cm730 => Protocol::V1,
            _ => Protocol::V2,
        }
    }

    /// Model Number (address 0) as the servo reports it (e-manual control tables).
    pub const fn model_number(self) -> u16 {
        match self {
            ServoModel::Rx28 => 28,
            ServoModel::Rx64 => 64,
            ServoModel::Mx28 => 29,
            ServoModel::Mx64 => 310,
            ServoModel::Mx106 => 320,
            ServoModel::Mx28V2 => 30,
            ServoModel::Mx64V2 => 311,
            ServoModel::Mx106V2 => 321,
            ServoModel::Xm430W350 => 1020,
            ServoModel::Xl430W250 => 1060,
            // 0x7300: not in the e-manual copy read; the DARwIn-OP framework's
            // CM-730 emulation (HROS1-Framework, CM730.cpp Reset_CM730_Emulation:
            // model number bytes 0x00, 0x73) and NimbRo-OP's CM730 register map
            // (its own firmware reports 0x7301) agree on it.
            ServoModel::Cm730 => 0x7300,
        }
    }

    pub fn from_model_number(number: u16) -> Option<ServoModel> {
        ServoModel::ALL
            .into_iter()
            .find(|m| m.model_number() == number)
    }

    /// Whether the servo answers BULK_READ. In 1.0 only MX does (RX-UM lists no
    /// BULK_READ; ROBOTIS e-manual, Protocol 1.0 instruction set); every 2.0 model does.
    /// The CM-730 does: the DARwIn-OP framework bulk-reads it with the MX-28s
    /// (MotionManager::Process, CM730::BulkRead).
    pub const fn has_bulk_read(self) -> bool {
        !matches!(self, ServoModel::Rx28 | ServoModel::Rx64)
    }

    /// Whether the servo answers SYNC_READ (Protocol 2.0 only).
    pub const fn has_sync_read(self) -> bool {
        matches!(self.protocol(), Protocol::V2)
    }

    /// Whether the servo answers FAST_SYNC_READ. The SDK offers it for 2.0; the
    /// firmware needed is not in the e-manual copy read, so it is assumed for the X
    /// series only (MX(2.0) falls back to SYNC_READ).
    pub const fn has_fast_sync_read(self) -> bool {
        matches!(self, ServoModel::Xm430W350 | ServoModel::Xl430W250)
    }

    /// Datasheet figures (e-manual specification tables); all zero for a board,
    /// which drives nothing.
    pub fn spec(self) -> ServoSpec {
        let s = |stall_torque, stall_current, rpm: f64, voltage, gear_ratio| ServoSpec {
            stall_torque,
            stall_current,
            no_load_speed: rpm * RPM,
            voltage,
            gear_ratio,
        };
        match self {
            ServoModel::Rx28 => s(3.7, Some(1.9), 85.0, 18.5, 193.0),
            ServoModel::Rx64 => s(5.3, Some(2.6), 64.0, 18.5, 200.0),
            ServoModel::Mx28 | ServoModel::Mx28V2 => s(2.5, Some(1.4), 55.0, 12.0, 193.0),
            ServoModel::Mx64 | ServoModel::Mx64V2 => s(6.0, Some(4.1), 63.0, 12.0, 200.0),
            ServoModel::Mx106 | ServoModel::Mx106V2 => s(8.4, Some(5.2), 45.0, 12.0, 225.0),
            ServoModel::Xm430W350 => s(4.1, Some(2.3), 46.0, 12.0, 353.5),
            ServoModel::Xl430W250 => s(1.5, Some(1.4), 61.0, 12.0, 258.5),
            ServoModel::Cm730 => s(0.0, None, 0.0, 12.0, 1.0),
        }
    }
}

impl fmt::Display for ServoModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The bit rates a Dynamixel bus can run at, bit/s: from 8000 (protocol 1.0's
/// slowest, register 249: 2 000 000 / 250) to 10.5 M (the fastest register value
/// of DYNAMIXEL-P, EM-PH54). A rate inside is taken as given (a serial adapter
/// approximates it, as the servos do: 57 600 for RX register 34's 57 143).
pub const BAUD_RANGE: std::ops::RangeInclusive<u32> = 8_000..=10_500_000;

/// The bit rate a Baud Rate register value selects. 1.0: 2 000 000 / (value + 1)
/// (EM-RX28: 1 -> 1 M, 34 -> 57 143 listed as 57 600), and for MX 250 -> 2.25 M,
/// 251 -> 2.5 M, 252 -> 3 M. 2.0 (EM-XM): 0 -> 9600, 1 -> 57 600, 2 -> 115 200,
/// 3 -> 1 M, 4 -> 2 M, 5 -> 3 M, 6 -> 4 M, 7 -> 4.5 M.
pub fn baud_from_register(protocol: Protocol, value: u8) -> Option<u32> {
    match protocol {
        Protocol::V1 => match value {
            250 => Some(2_250_000),
            251 => Some(2_500_000),
            252 => Some(3_000_000),
            253..=255 => None,
            v => Some(2_000_000 / (v as u32 + 1)),
        },
        Protocol::V2 => match value {
            0 => Some(9_600),
            1 => Some(57_600),
            2 => Some(115_200),
            3 => Some(1_000_000),
            4 => Some(2_000_000),
            5 => Some(3_000_000),
            6 => Some(4_000_000),
            7 => Some(4_500_000),
            _ => None,
        },
    }
}

/// The Baud Rate register value that selects `baud` on a model of `protocol`'s
/// table: the code whose rate ([`baud_from_register`]) is nearest, if within 3 %
/// of it (the e-manual's baud tables list margins of error up to about 2 %, e.g.
/// RX register 34: 57 143 for 57 600, -0.79 %). 1 Mbps is 1 on the 1.0 tables
/// (EM-RX28) and 3 on the 2.0 ones (EM-XM).
pub fn baud_to_register(protocol: Protocol, baud: u32) -> Option<u8> {
    let error = |v: u8| {
        baud_from_register(protocol, v).map(|b| (b as f64 - baud as f64).abs() / baud.max(1) as f64)
    };
    (0..=u8::MAX)
        .filter_map(|v| error(v).map(|e| (v, e)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .filter(|&(_, e)| e <= 0.03)
        .map(|(v, _)| v)
}
