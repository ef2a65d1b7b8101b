//! Encoding packets of both protocols into a reusable buffer, and Protocol 2.0 byte
//! stuffing.
//!
//! Protocol 1.0: `FF FF | ID | LEN | INST | P1..PN | CK`, LEN = N + 2, CK = the
//! inverted low byte of the sum from ID to PN (EM-P1).
//! Protocol 2.0: `FF FF FD 00 | ID | LEN_L LEN_H | INST | P1..PN | CRC_L CRC_H`,
//! LEN = N + 3 counted after stuffing, CRC over everything before it after stuffing
//! (EM-P2 "Packet Process": stuff, fix LENGTH, then CRC).
//! A status packet is an instruction packet whose INST is the error byte (1.0) or
//! 0x55 followed by the error byte (2.0).

use crate::crc16::{checksum_v1, crc16};
use crate::instruction::Instruction;
use crate::protocol::Protocol;
use std::fmt;

/// A packet that cannot be encoded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EncodeError {
    /// LENGTH would not fit its field (255 in 1.0, 65535 in 2.0).
    TooLong { protocol: Protocol, length: usize },
    /// A register address or data length above 255 in Protocol 1.0.
    AddressTooLarge { address: u16 },
    /// Protocol 1.0 has no such instruction.
    NotInProtocol {
        protocol: Protocol,
        instruction: Instruction,
    },
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EncodeError::TooLong { protocol, length } => {
                write!(f, "packet LENGTH {length} does not fit {protocol}")
            }
            EncodeError::AddressTooLarge { address } => write!(
                f,
                "address or length {address} does not fit one byte (Protocol 1.0)"
            ),
            EncodeError::NotInProtocol {
                protocol,
                instruction,
            } => write!(f, "{protocol} has no {instruction} instruction"),
        }
    }
}

impl std::error::Error for EncodeError {}

/// The three bytes whose appearance inside a 2.0 packet gets an extra 0xFD.
const STUFF_PATTERN: [u8; 3] = [0xFF, 0xFF, 0xFD];

/// Appends one packet to a buffer. Start with [`PacketWriter::instruction`] or
/// [`PacketWriter::status`], push parameters, then [`PacketWriter::finish`], which
/// stuffs (2.0), writes LENGTH and the checksum. Nothing allocates once `out` has
/// grown to the largest packet.
pub struct PacketWriter<'a> {
    out: &'a mut Vec<u8>,
    protocol: Protocol,
    start: usize,
    error: Option<EncodeError>,
}

impl<'a> PacketWriter<'a> {
    /// Begin an instruction packet at the end of `out`.
    pub fn instruction(
        out: &'a mut Vec<u8>,
        protocol: Protocol,
        id: u8,
        instruction: Instruction,
    ) -> PacketWriter<'a> {
        let mut w = Self::begin(out, protocol, id, instruction.code());
        if !instruction.in_protocol(protocol) {
            w.error = Some(EncodeError::NotInProtocol {
                protocol,
                instruction,
            });
        }
        w
    }

    /// Begin a status packet (what a servo answers) with error byte `error`.
    pub fn status(out: &'a mut Vec<u8>, protocol: Protocol, id: u8, error: u8) -> PacketWriter<'a> {
        match protocol {
            Protocol::V1 => Self::begin(out, protocol, id, error),
            Protocol::V2 => {
                let w = Self::begin(out, protocol, id, Instruction::Status.code());
                w.out.push(error);
                w
            }
        }
    }

    /// Begin a packet with a raw instruction byte (tests and fuzzing use codes the
    /// enum does not know).
    pub fn raw(out: &'a mut Vec<u8>, protocol: Protocol, id: u8, code: u8) -> PacketWriter<'a> {
        Self::begin(out, protocol, id, code)
    }

    fn begin(out: &'a mut Vec<u8>, protocol: Protocol, id: u8, code: u8) -> PacketWriter<'a> {
        let start = out.len();
        match protocol {
            Protocol::V1 => out.extend_from_slice(&[0xFF, 0xFF, id, 0, code]),
            Protocol::V2 => out.extend_from_slice(&[0xFF, 0xFF, 0xFD, 0x00, id, 0, 0, code]),
        }
        PacketWriter {
            out,
            protocol,
            start,
            error: None,
        }
    }

    pub fn u8(&mut self, v: u8) -> &mut Self {
        self.out.push(v);
        self
    }

    pub fn u16(&mut self, v: u16) -> &mut Self {
        self.out.extend_from_slice(&v.to_le_bytes());
        self
    }

    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.out.extend_from_slice(&v.to_le_bytes());
        self
    }

    pub fn bytes(&mut self, v: &[u8]) -> &mut Self {
        self.out.extend_from_slice(v);
        self
    }

    /// A register address or data length: one byte in 1.0, two (little-endian) in 2.0.
    pub fn address(&mut self, v: u16) -> &mut Self {
        match self.protocol {
            Protocol::V1 => {
                if v > 0xFF && self.error.is_none() {
                    self.error = Some(EncodeError::AddressTooLarge { address: v });
                }
                self.out.push(v as u8);
            }
            Protocol::V2 => {
                self.out.extend_from_slice(&v.to_le_bytes());
            }
        }
        self
    }

    /// Close the packet: stuffing (2.0), LENGTH and checksum. On error the partial
    /// packet is removed from `out`.
    pub fn finish(self) -> Result<usize, EncodeError> {
        let PacketWriter {
            out,
            protocol,
            start,
            error,
        } = self;
        if let Some(e) = error {
            out.truncate(start);
            return Err(e);
        }
        match protocol {
            Protocol::V1 => {
                // LENGTH counts INST, parameters and the checksum.
                let length = out.len() - (start + 4) + 1;
                if length > 0xFF {
                    out.truncate(start);
                    return Err(EncodeError::TooLong { protocol, length });
                }
                out[start + 3] = length as u8;
                let ck = checksum_v1(&out[start + 2..]);
                out.push(ck);
            }
            Protocol::V2 => {
                stuff_in_place(out, start + 7);
                let length = out.len() - (start + 7) + 2;
                if length > 0xFFFF {
                    out.truncate(start);
                    return Err(EncodeError::TooLong { protocol, length });
                }
                out[start + 5..start + 7].copy_from_slice(&(length as u16).to_le_bytes());
                let crc = crc16(&out[start..]);
                out.extend_from_slice(&crc.to_le_bytes());
            }
        }
        Ok(out.len() - start)
    }
}

/// Number of `FF FF FD` patterns in `region` (they cannot overlap).
fn count_stuffing(region: &[u8]) -> usize {
    region.windows(3).filter(|w| *w == STUFF_PATTERN).count()
}

/// Insert 0xFD after every `FF FF FD` in `buf[from..]`, in place (no allocation once
/// `buf` has the capacity).
pub fn stuff_in_place(buf: &mut Vec<u8>, from: usize) {
    let n = count_stuffing(&buf[from..]);
    if n == 0 {
        return;
    }
    let old_len = buf.len();
    buf.resize(old_len + n, 0);
    // Walk backwards so every byte is read before anything is written over it: the
    // write index stays ahead of the read index by the insertions still to make.
    let mut w = old_len + n;
    let mut r = old_len;
    while r > from {
        r -= 1;
        let b = buf[r];
        let completes = b == 0xFD && r >= from + 2 && buf[r - 1] == 0xFF && buf[r - 2] == 0xFF;
        if completes {
            w -= 1;
            buf[w] = 0xFD;
        }
        w -= 1;
        buf[w] = b;
    }
    debug_assert_eq!(w, r);
}

/// Append `src` to `dst` with every `FF FF FD FD` turned back into `FF FF FD`.
pub fn unstuff_into(src: &[u8], dst: &mut Vec<u8>) {
    let base = dst.len();
    let mut k = 0;
    while k < src.len() {
        let b = src[k];
        dst.push(b);
        k += 1;
        let n = dst.len() - base;
        if b == 0xFD
            && n >= 3
            && dst[dst.len() - 2] == 0xFF
            && dst[dst.len() - 3] == 0xFF
            && k < src.len()
            && src[k] == 0xFD
        {
            k += 1;
        }
    }
}

/// Whether a (stuffed) region holds any stuffing to remove.
pub fn has_stuffing(region: &[u8]) -> bool {
    region.windows(4).any(|w| w == [0xFF, 0xFF, 0xFD, 0xFD])
}
