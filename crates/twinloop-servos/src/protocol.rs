//! The two Dynamixel protocol versions and the facts every layer shares about them.

use std::fmt;

/// Dynamixel protocol version. Protocol 1.0 is what RX/AX/MX(1.0) servos speak;
/// Protocol 2.0 is the X series, MX(2.0) and PRO. Both can share one bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Protocol {
    V1,
    V2,
}

/// The broadcast id: every servo executes, none answers (except PING in 2.0 and
/// the read instructions, which name their responders in the parameters).
pub const BROADCAST_ID: u8 = 0xFE;

impl Protocol {
    /// Highest id a servo may have: 253 in 1.0 (EM-P1), 252 in 2.0 (EM-P2).
    pub const fn max_id(self) -> u8 {
        match self {
            Protocol::V1 => 253,
            Protocol::V2 => 252,
        }
    }

    /// Bytes of a packet around its parameters: header, id, length, instruction
    /// (or error) and checksum. 1.0: `FF FF ID LEN INST .. CK` = 6; 2.0:
    /// `FF FF FD 00 ID LL LH INST .. CL CH` = 10 (before stuffing).
    pub const fn overhead(self) -> usize {
        match self {
            Protocol::V1 => 6,
            Protocol::V2 => 10,
        }
    }

    /// Bytes a status packet carries around its data: 1.0 `FF FF ID LEN ERR .. CK`
    /// = 6; 2.0 `FF FF FD 00 ID LL LH 55 ERR .. CL CH` = 11.
    pub const fn status_overhead(self) -> usize {
        match self {
            Protocol::V1 => 6,
            Protocol::V2 => 11,
        }
    }

    /// Register addresses are one byte in 1.0 and two in 2.0.
    pub const fn address_bytes(self) -> usize {
        match self {
            Protocol::V1 => 1,
            Protocol::V2 => 2,
        }
    }

    /// `"1"`/`"1.0"` or `"2"`/`"2.0"`.
    pub fn parse(text: &str) -> Option<Protocol> {
        match text.trim() {
            "1" | "1.0" => Some(Protocol::V1),
            "2" | "2.0" => Some(Protocol::V2),
            _ => None,
        }
    }

    /// 1 or 2, as users write it.
    pub const fn number(self) -> u8 {
        match self {
            Protocol::V1 => 1,
            Protocol::V2 => 2,
        }
    }
}

impl fmt::Display for Protocol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Protocol::V1 => f.write_str("Protocol 1.0"),
            Protocol::V2 => f.write_str("Protocol 2.0"),
        }
    }
}
