//! The servo models twinloop knows: the catalogue's [`ServoModel`] (crate
//! `twinloop-servos`, re-exported here so that `twinloop_link::ServoModel` keeps
//! working), and the bus's bit rates.

use crate::protocol::Protocol;

pub use twinloop_servos::{ServoModel, ServoSpec};

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
