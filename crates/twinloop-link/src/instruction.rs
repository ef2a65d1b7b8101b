//! Instruction codes of both protocols (EM-P1, EM-P2, SDK `robotis_def.py`) and which
//! protocol has which.

use crate::protocol::Protocol;
use std::fmt;

/// An instruction code. `Status` (0x55) is the code of a Protocol 2.0 status packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Instruction {
    Ping = 0x01,
    Read = 0x02,
    Write = 0x03,
    RegWrite = 0x04,
    Action = 0x05,
    FactoryReset = 0x06,
    Reboot = 0x08,
    Clear = 0x10,
    Status = 0x55,
    SyncRead = 0x82,
    SyncWrite = 0x83,
    FastSyncRead = 0x8A,
    BulkRead = 0x92,
    BulkWrite = 0x93,
    FastBulkRead = 0x9A,
}

impl Instruction {
    pub fn from_code(code: u8) -> Option<Instruction> {
        use Instruction::*;
        Some(match code {
            0x01 => Ping,
            0x02 => Read,
            0x03 => Write,
            0x04 => RegWrite,
            0x05 => Action,
            0x06 => FactoryReset,
            0x08 => Reboot,
            0x10 => Clear,
            0x55 => Status,
            0x82 => SyncRead,
            0x83 => SyncWrite,
            0x8A => FastSyncRead,
            0x92 => BulkRead,
            0x93 => BulkWrite,
            0x9A => FastBulkRead,
            _ => return None,
        })
    }

    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Whether `protocol` defines this instruction. Protocol 1.0 has PING, READ,
    /// WRITE, REG_WRITE, ACTION, RESET, SYNC_WRITE and BULK_READ (MX only: RX servos
    /// answer it with an Instruction Error); it has no SYNC_READ, REBOOT or BULK_WRITE
    /// (EM-P1; SDK `Protocol1PacketHandler` returns COMM_NOT_AVAILABLE for them).
    pub const fn in_protocol(self, protocol: Protocol) -> bool {
        use Instruction::*;
        match protocol {
            Protocol::V1 => matches!(
                self,
                Ping | Read | Write | RegWrite | Action | FactoryReset | SyncWrite | BulkRead
            ),
            Protocol::V2 => true,
        }
    }

    /// The name the e-manual uses.
    pub const fn name(self) -> &'static str {
        use Instruction::*;
        match self {
            Ping => "PING",
            Read => "READ",
            Write => "WRITE",
            RegWrite => "REG_WRITE",
            Action => "ACTION",
            FactoryReset => "FACTORY_RESET",
            Reboot => "REBOOT",
            Clear => "CLEAR",
            Status => "STATUS",
            SyncRead => "SYNC_READ",
            SyncWrite => "SYNC_WRITE",
            FastSyncRead => "FAST_SYNC_READ",
            BulkRead => "BULK_READ",
            BulkWrite => "BULK_WRITE",
            FastBulkRead => "FAST_BULK_READ",
        }
    }
}

impl fmt::Display for Instruction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
