//! The servo models twinloop knows, each with its identity on the bus (e-manual
//! control tables: Model Number at address 0, the protocol the firmware speaks) and
//! its datasheet (e-manual specification tables).

use crate::protocol::Protocol;
use std::fmt;

/// One rpm in rad/s.
pub const RPM: f64 = 2.0 * std::f64::consts::PI / 60.0;

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
    pub const fn spec(self) -> ServoSpec {
        const fn s(
            stall_torque: f64,
            stall_current: Option<f64>,
            rpm: f64,
            voltage: f64,
            gear_ratio: f64,
        ) -> ServoSpec {
            ServoSpec {
                stall_torque,
                stall_current,
                no_load_speed: rpm * RPM,
                voltage,
                gear_ratio,
            }
        }
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

/// How the firmware closes the position loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LoopFamily {
    /// RX/AX/EX: compliance margin and slope, punch (EM-RX28 "Compliance").
    Compliance,
    /// MX and X: a PID on the encoder count (EM-MX28 "PID Gain": K_p = P/8 on
    /// Protocol 1.0; EM-XM430 "Position PID Gain": K_P = P/128, K_I = I/65536,
    /// K_D = D/16 on MX(2.0) and X, output as PWM).
    Pid,
}

impl ServoModel {
    /// One encoder count, rad: 300 deg / 1024 (EM-RX28 "Goal Position": 0-1023 over
    /// 0-300 deg, 0.29 deg), 360 deg / 4096 (EM-MX28 and EM-XM430: 0.088 deg). The
    /// CM-730 has no encoder; it reads 0.
    pub fn resolution(self) -> f64 {
        use std::f64::consts::PI;
        match self {
            ServoModel::Rx28 | ServoModel::Rx64 => 300.0 / 1024.0 * PI / 180.0,
            ServoModel::Cm730 => 0.0,
            _ => 2.0 * PI / 4096.0,
        }
    }

    /// The position loop's family; `None` for a board.
    pub const fn family(self) -> Option<LoopFamily> {
        match self {
            ServoModel::Rx28 | ServoModel::Rx64 => Some(LoopFamily::Compliance),
            ServoModel::Cm730 => None,
            _ => Some(LoopFamily::Pid),
        }
    }

    /// Whether this is the Protocol 2.0 firmware of an MX or an X servo: the one
    /// whose position loop the e-manual states in PWM per count (EM-XM430).
    pub const fn is_v2_firmware(self) -> bool {
        matches!(self.protocol(), Protocol::V2)
    }

    /// The divisor of the P gain register, `K_p = P / divisor`: 8 on MX (Protocol
    /// 1.0, EM-MX28 "PID Gain"), 128 on MX(2.0) and X (EM-XM430 "Position PID
    /// Gain"). `None` where the loop has no P gain.
    pub const fn p_gain_divisor(self) -> Option<f64> {
        match self {
            ServoModel::Mx28 | ServoModel::Mx64 | ServoModel::Mx106 => Some(8.0),
            ServoModel::Rx28 | ServoModel::Rx64 | ServoModel::Cm730 => None,
            _ => Some(128.0),
        }
    }

    /// The loop's full output in the firmware's units: 1023 (RX and MX Torque Limit,
    /// EM-RX28/EM-MX28 address 34), 885 (MX(2.0)/X PWM Limit, EM-XM430 address 36).
    pub const fn full_output(self) -> f64 {
        if self.is_v2_firmware() { 885.0 } else { 1023.0 }
    }

    /// Factory values of the loop's gain registers: RX `[slope, margin, punch]` =
    /// `[32, 1, 32]` (EM-RX28 addresses 28/29, 26/27, 48); MX and X `[P, I, D]`
    /// position gains: MX (1.0) `[32, 0, 0]` (EM-MX28 addresses 28, 27, 26), MX(2.0)
    /// `[850, 0, 0]` (EM-MX28-2 addresses 84, 82, 80), XM430-W350 `[800, 0, 0]`
    /// (EM-XM430-W350), XL430-W250 `[640, 0, 0]` (EM-XL430-W250). `None` for a board.
    pub const fn factory_gains(self) -> Option<[i32; 3]> {
        Some(match self {
            ServoModel::Rx28 | ServoModel::Rx64 => [32, 1, 32],
            ServoModel::Mx28 | ServoModel::Mx64 | ServoModel::Mx106 => [32, 0, 0],
            ServoModel::Mx28V2 | ServoModel::Mx64V2 | ServoModel::Mx106V2 => [850, 0, 0],
            ServoModel::Xm430W350 => [800, 0, 0],
            ServoModel::Xl430W250 => [640, 0, 0],
            ServoModel::Cm730 => return None,
        })
    }

    /// The position error at which a P gain of `p` drives the motor at full output,
    /// rad, on the 2.0 firmware whose e-manual states its loop in PWM per count
    /// (EM-XM430: PWM = K_P * error, K_P = P/128, full PWM 885): `885 * 128 / P`
    /// counts. `None` on RX, on MX (1.0), whose e-manual gives no output unit, and on a
    /// board; infinite for P = 0 (no position control).
    pub fn full_output_error(self, p: i32) -> Option<f64> {
        if !self.is_v2_firmware() || self.is_board() {
            return None;
        }
        let div = self.p_gain_divisor()?;
        if p <= 0 {
            return Some(f64::INFINITY);
        }
        Some(self.full_output() * div / p as f64 * self.resolution())
    }
}
