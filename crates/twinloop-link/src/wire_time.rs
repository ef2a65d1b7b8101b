//! Bytes and wire time of one control cycle (the model of docs/link.md, "Wire time"): 10 bits per byte
//! (8N1) at the bit rate, plus each servo's Return Delay Time before its status
//! packet. Byte stuffing is ignored (it adds a byte only where data holds FF FF FD).

use crate::control_cycle::ReadMethod;
use crate::protocol::Protocol;
use std::time::Duration;

/// One cycle's budget on the wire.
#[derive(Debug, Clone, PartialEq)]
pub struct CyclePlan {
    pub protocol: Protocol,
    pub method: ReadMethod,
    pub servos: usize,
    /// Bytes read per servo.
    pub read_len: usize,
    pub baud: u32,
    /// Bytes of the goal SYNC_WRITE.
    pub write_bytes: usize,
    /// Bytes of the read: requests and replies.
    pub read_bytes: usize,
    /// Status packets (each preceded by a Return Delay Time).
    pub status_packets: usize,
    /// Request/reply exchanges (the SYNC_WRITE counts as one).
    pub round_trips: usize,
    /// Wire time with the Return Delay Time given.
    pub wire: Duration,
}

impl CyclePlan {
    pub fn total_bytes(&self) -> usize {
        self.write_bytes + self.read_bytes
    }

    pub fn cycles_per_second(&self) -> f64 {
        1.0 / self.wire.as_secs_f64()
    }
}

/// The cycle of `servos` servos on `protocol` read with `method`: SYNC_WRITE of a
/// goal (`goal_len` bytes each: 2 in 1.0, 4 in 2.0) and a read of `read_len` bytes
/// per servo, at `baud` with `return_delay` before each status packet.
pub fn plan_cycle(
    protocol: Protocol,
    method: ReadMethod,
    servos: usize,
    read_len: usize,
    goal_len: usize,
    baud: u32,
    return_delay: Duration,
) -> CyclePlan {
    let n = servos;
    let l = read_len;
    let (write_bytes, read_bytes, status_packets, reads) = match protocol {
        Protocol::V1 => {
            // FF FF FE LEN 83 ADDR L [ID D..]xN CK
            let write = 8 + n * (goal_len + 1);
            match method {
                ReadMethod::BulkRead => (write, (7 + 3 * n) + n * (6 + l), n, 1),
                // READ: FF FF ID 04 02 ADDR LEN CK; status FF FF ID LEN ERR D.. CK
                _ => (write, n * (8 + 6 + l), n, n),
            }
        }
        Protocol::V2 => {
            // FF FF FD 00 FE LL LH 83 AL AH LL LH [ID D..]xN CL CH
            let write = 14 + n * (goal_len + 1);
            let request = 14 + n;
            match method {
                ReadMethod::FastSyncRead => (write, request + 8 + n * (l + 4), 1, 1),
                ReadMethod::BulkRead => (write, (10 + 5 * n) + n * (11 + l), n, 1),
                ReadMethod::Read => (write, n * (14 + 11 + l), n, n),
                _ => (write, request + n * (11 + l), n, 1),
            }
        }
    };
    let bits = (write_bytes + read_bytes) as u64 * 10;
    let wire = Duration::from_nanos(bits * 1_000_000_000 / baud.max(1) as u64)
        + return_delay * status_packets as u32;
    CyclePlan {
        protocol,
        method,
        servos,
        read_len,
        baud,
        write_bytes,
        read_bytes,
        status_packets,
        round_trips: 1 + reads,
        wire,
    }
}
