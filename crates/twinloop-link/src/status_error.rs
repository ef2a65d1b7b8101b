//! The error field of a status packet, decoded into types.
//!
//! Protocol 1.0 sends a bit field (several faults at once); Protocol 2.0 sends an
//! error number in bits 0-6 plus an Alert bit (bit 7) meaning "a hardware fault is
//! latched: read Hardware Error Status". Some of these say the instruction was not
//! executed; others report the servo's condition while the instruction (and the data
//! read) is still good. [`StatusError::rejected_instruction`] tells them apart.

use crate::protocol::Protocol;
use std::fmt;

/// One Protocol 1.0 error bit (EM-P1 "Error").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorBitV1 {
    /// Bit 0: input voltage outside the Min/Max Voltage Limit.
    InputVoltage,
    /// Bit 1: goal position outside the CW/CCW angle limits.
    AngleLimit,
    /// Bit 2: temperature above the Temperature Limit.
    Overheating,
    /// Bit 3: an instruction or value out of range.
    Range,
    /// Bit 4: the instruction packet's checksum was wrong.
    Checksum,
    /// Bit 5: the load cannot be held with the set torque.
    Overload,
    /// Bit 6: undefined instruction, or ACTION without REG_WRITE.
    Instruction,
}

impl ErrorBitV1 {
    pub const ALL: [ErrorBitV1; 7] = [
        ErrorBitV1::InputVoltage,
        ErrorBitV1::AngleLimit,
        ErrorBitV1::Overheating,
        ErrorBitV1::Range,
        ErrorBitV1::Checksum,
        ErrorBitV1::Overload,
        ErrorBitV1::Instruction,
    ];

    pub const fn mask(self) -> u8 {
        1 << (self as u8)
    }

    pub const fn name(self) -> &'static str {
        match self {
            ErrorBitV1::InputVoltage => "input voltage error",
            ErrorBitV1::AngleLimit => "angle limit error",
            ErrorBitV1::Overheating => "overheating error",
            ErrorBitV1::Range => "range error",
            ErrorBitV1::Checksum => "checksum error",
            ErrorBitV1::Overload => "overload error",
            ErrorBitV1::Instruction => "instruction error",
        }
    }
}

impl ErrorBitV1 {
    /// What the bit means, in words (EM-P1 "Error" and the RX-28 e-manual's
    /// status packet table); the range error is what a servo of another model than
    /// the one assumed answers to a register its table does not have.
    pub const fn meaning(self) -> &'static str {
        match self {
            ErrorBitV1::InputVoltage => "supply voltage outside the voltage limits",
            ErrorBitV1::AngleLimit => "goal position outside the CW/CCW angle limits",
            ErrorBitV1::Overheating => "temperature above the temperature limit",
            ErrorBitV1::Range => {
                "an instruction or value out of range: an address, length or value this \
                 servo's control table does not have; is the servo the model assumed?"
            }
            ErrorBitV1::Checksum => "the instruction packet's checksum was wrong",
            ErrorBitV1::Overload => "the load cannot be held with the set torque",
            ErrorBitV1::Instruction => "an undefined instruction, or ACTION without REG_WRITE",
        }
    }
}

/// A Protocol 2.0 error number (EM-P2 "Error").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorNumberV2 {
    /// 0x01: failed to process the instruction.
    ResultFail,
    /// 0x02: undefined instruction, or ACTION without REG_WRITE.
    Instruction,
    /// 0x03: the instruction packet's CRC did not match.
    Crc,
    /// 0x04: value outside the register's range.
    DataRange,
    /// 0x05: data shorter than the register (e.g. 2 bytes into a 4-byte register).
    DataLength,
    /// 0x06: value outside the register's limit (e.g. position limits).
    DataLimit,
    /// 0x07: write to a read-only or undefined address, read of a write-only one, or
    /// write to EEPROM while torque is on.
    Access,
    /// A number the e-manual does not define.
    Unknown(u8),
}

impl ErrorNumberV2 {
    pub const fn from_number(n: u8) -> ErrorNumberV2 {
        match n {
            1 => ErrorNumberV2::ResultFail,
            2 => ErrorNumberV2::Instruction,
            3 => ErrorNumberV2::Crc,
            4 => ErrorNumberV2::DataRange,
            5 => ErrorNumberV2::DataLength,
            6 => ErrorNumberV2::DataLimit,
            7 => ErrorNumberV2::Access,
            n => ErrorNumberV2::Unknown(n),
        }
    }

    pub const fn number(self) -> u8 {
        match self {
            ErrorNumberV2::ResultFail => 1,
            ErrorNumberV2::Instruction => 2,
            ErrorNumberV2::Crc => 3,
            ErrorNumberV2::DataRange => 4,
            ErrorNumberV2::DataLength => 5,
            ErrorNumberV2::DataLimit => 6,
            ErrorNumberV2::Access => 7,
            ErrorNumberV2::Unknown(n) => n,
        }
    }

    pub const fn name(self) -> &'static str {
        match self {
            ErrorNumberV2::ResultFail => "result fail",
            ErrorNumberV2::Instruction => "instruction error",
            ErrorNumberV2::Crc => "CRC error",
            ErrorNumberV2::DataRange => "data range error",
            ErrorNumberV2::DataLength => "data length error",
            ErrorNumberV2::DataLimit => "data limit error",
            ErrorNumberV2::Access => "access error",
            ErrorNumberV2::Unknown(_) => "unknown error number",
        }
    }
}

/// The error field of one status packet. `raw` is kept so nothing is lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StatusError {
    pub protocol: Protocol,
    pub raw: u8,
}

/// Protocol 2.0 Alert bit.
pub const ALERT_BIT: u8 = 0x80;

impl StatusError {
    pub const fn new(protocol: Protocol, raw: u8) -> StatusError {
        StatusError { protocol, raw }
    }

    /// Nothing reported.
    pub const fn is_none(self) -> bool {
        self.raw == 0
    }

    /// The Protocol 1.0 bits set (empty for 2.0).
    pub fn bits_v1(self) -> impl Iterator<Item = ErrorBitV1> {
        let raw = if self.protocol == Protocol::V1 {
            self.raw
        } else {
            0
        };
        ErrorBitV1::ALL
            .into_iter()
            .filter(move |b| raw & b.mask() != 0)
    }

    /// The Protocol 2.0 error number, if any (None for 1.0 or for 0).
    pub const fn number_v2(self) -> Option<ErrorNumberV2> {
        match self.protocol {
            Protocol::V2 if self.raw & 0x7F != 0 => {
                Some(ErrorNumberV2::from_number(self.raw & 0x7F))
            }
            _ => None,
        }
    }

    /// Protocol 2.0 Alert: a hardware fault is latched (read Hardware Error Status).
    pub const fn alert(self) -> bool {
        matches!(self.protocol, Protocol::V2) && self.raw & ALERT_BIT != 0
    }

    /// Whether the servo refused the instruction (so a read's data, or a write's
    /// effect, must not be trusted). Protocol 1.0: instruction, checksum, range or
    /// angle-limit bits. Protocol 2.0: any error number. Overload, overheating,
    /// voltage (1.0) and Alert (2.0) describe the servo, not the instruction.
    pub const fn rejected_instruction(self) -> bool {
        match self.protocol {
            Protocol::V1 => {
                self.raw
                    & (ErrorBitV1::Instruction.mask()
                        | ErrorBitV1::Checksum.mask()
                        | ErrorBitV1::Range.mask()
                        | ErrorBitV1::AngleLimit.mask())
                    != 0
            }
            Protocol::V2 => self.raw & 0x7F != 0,
        }
    }

    /// The servo received the instruction damaged (1.0 checksum bit, 2.0 CRC
    /// error): nothing was executed and sending it again may work.
    pub const fn instruction_damaged(self) -> bool {
        match self.protocol {
            Protocol::V1 => self.raw & ErrorBitV1::Checksum.mask() != 0,
            Protocol::V2 => self.raw & 0x7F == 3,
        }
    }

    /// A hardware condition is reported (1.0 voltage/overheating/overload, 2.0 Alert).
    pub const fn hardware_fault(self) -> bool {
        match self.protocol {
            Protocol::V1 => {
                self.raw
                    & (ErrorBitV1::InputVoltage.mask()
                        | ErrorBitV1::Overheating.mask()
                        | ErrorBitV1::Overload.mask())
                    != 0
            }
            Protocol::V2 => self.raw & ALERT_BIT != 0,
        }
    }
}

impl fmt::Display for StatusError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.raw == 0 {
            return f.write_str("no error");
        }
        let mut first = true;
        let mut sep = |f: &mut fmt::Formatter<'_>| -> fmt::Result {
            if !first {
                f.write_str(", ")?;
            }
            first = false;
            Ok(())
        };
        match self.protocol {
            Protocol::V1 => {
                for b in self.bits_v1() {
                    sep(f)?;
                    write!(f, "{} ({})", b.name(), b.meaning())?;
                }
                if self.raw & 0x80 != 0 {
                    sep(f)?;
                    f.write_str("bit 7 set (undefined)")?;
                }
            }
            Protocol::V2 => {
                if let Some(n) = self.number_v2() {
                    sep(f)?;
                    write!(f, "{} (0x{:02X})", n.name(), n.number())?;
                }
                if self.alert() {
                    sep(f)?;
                    f.write_str("alert: hardware error status is set")?;
                }
            }
        }
        write!(f, " [error byte 0x{:02X}]", self.raw)
    }
}

impl std::error::Error for StatusError {}
