//! CRC-16 of Protocol 2.0: polynomial 0x8005 (x^16 + x^15 + x^2 + 1), initial value 0,
//! most significant bit first, no final XOR (EM-P2 "CRC"). It covers the packet from
//! its first header byte to its last parameter, after byte stuffing.

/// The 256-entry table, computed at compile time from the polynomial (the same table
/// the e-manual and the SDK print, which `tests/packets.rs` checks entry by entry).
pub const CRC16_TABLE: [u16; 256] = build_table();

const POLYNOMIAL: u16 = 0x8005;

const fn build_table() -> [u16; 256] {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = (i as u16) << 8;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ POLYNOMIAL
            } else {
                crc << 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
}

/// Continue a CRC over `bytes` (start with `crc = 0`).
#[inline]
pub fn crc16_update(mut crc: u16, bytes: &[u8]) -> u16 {
    for &b in bytes {
        let i = ((crc >> 8) as u8 ^ b) as usize;
        crc = (crc << 8) ^ CRC16_TABLE[i];
    }
    crc
}

/// CRC-16 of `bytes` from the initial value 0.
#[inline]
pub fn crc16(bytes: &[u8]) -> u16 {
    crc16_update(0, bytes)
}

/// Protocol 1.0 checksum: the inverted low byte of the sum of id, length,
/// instruction (or error) and parameters (EM-P1).
#[inline]
pub fn checksum_v1(bytes: &[u8]) -> u8 {
    let mut sum: u8 = 0;
    for &b in bytes {
        sum = sum.wrapping_add(b);
    }
    !sum
}
