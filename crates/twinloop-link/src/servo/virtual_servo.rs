//! One virtual servo: its control-table memory and the rules a real servo applies
//! to reads and writes (ranges, read-only registers, EEPROM lock, position limits),
//! with each violation answered by the error the e-manual names.

use crate::board_type::BoardType;
use crate::protocol::Protocol;
use crate::register::{Access, Area, Item, Register};
use crate::servo_model::ServoModel;
use std::sync::Arc;
use std::sync::atomic::AtomicU8;
use std::time::Duration;

/// Why a servo refuses an instruction, before it is turned into the protocol's
/// error byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// Undefined instruction, malformed parameters, ACTION without REG_WRITE.
    Instruction,
    /// The instruction's checksum / CRC did not match.
    Checksum,
    /// A value outside the register's range.
    DataRange,
    /// A write covering only part of a register (2.0).
    DataLength,
    /// A goal position outside the position limits.
    DataLimit,
    /// A read-only or undefined register written, EEPROM written with torque on
    /// (2.0) or locked (1.0), an address past the table.
    Access,
    /// Could not execute (e.g. CLEAR while moving).
    ResultFail,
}

impl Fault {
    /// The error byte of a status packet for this fault. Protocol 1.0 has only
    /// bits: range-type faults become the Range bit, a position outside the limits
    /// the Angle Limit bit (EM-P1); 2.0 has a number for each (EM-P2).
    pub fn error_byte(self, protocol: Protocol) -> u8 {
        match protocol {
            Protocol::V1 => match self {
                Fault::Instruction => 0x40,
                Fault::Checksum => 0x10,
                Fault::DataLimit => 0x02,
                Fault::DataRange | Fault::DataLength | Fault::Access | Fault::ResultFail => 0x08,
            },
            Protocol::V2 => match self {
                Fault::ResultFail => 0x01,
                Fault::Instruction => 0x02,
                Fault::Checksum => 0x03,
                Fault::DataRange => 0x04,
                Fault::DataLength => 0x05,
                Fault::DataLimit => 0x06,
                Fault::Access => 0x07,
            },
        }
    }
}

/// Which registers a write touched, so the bus can tell the backend.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WriteEffects {
    pub goal_position: bool,
    pub torque_enable: bool,
    /// Bytes written: `start..end` (empty if nothing was).
    pub start: u16,
    pub end: u16,
}

/// A servo's memory and identity.
#[derive(Debug, Clone)]
pub struct VirtualServo {
    /// The servo's model (or the catalogue model of a board: the CM-730); `None`
    /// for a board whose table is its [`BoardType`] ([`VirtualServo::board`]).
    pub model: Option<ServoModel>,
    /// A board type with a table of its own (the OpenCR, a profile's custom board).
    pub board: Option<&'static BoardType>,
    pub firmware: u8,
    pub memory: Vec<u8>,
    /// REG_WRITE staged for the next ACTION: address and data.
    staged_address: u16,
    staged: Vec<u8>,
    has_staged: bool,
    /// Hardware condition bits added to every status packet this servo sends
    /// (Protocol 1.0 error bits: overload 0x20, overheating 0x04, input voltage
    /// 0x01; on 2.0 any bit sets the Alert bit). Shared, so a test can make a
    /// served servo report a fault mid-run; 0 (the default) reports nothing.
    pub condition: Arc<AtomicU8>,
}

impl VirtualServo {
    pub fn new(id: u8, model: ServoModel, firmware: u8) -> VirtualServo {
        VirtualServo {
            model: Some(model),
            board: None,
            firmware,
            memory: model.table().factory_memory(id, firmware),
            staged_address: 0,
            staged: Vec::with_capacity(64),
            has_staged: false,
            condition: Arc::new(AtomicU8::new(0)),
        }
    }

    /// A board of type `board` at `id`, served from the type's own table (a type
    /// with a catalogue model, the CM-730, is served as that model).
    pub fn new_board(id: u8, board: &'static BoardType) -> VirtualServo {
        if let Some(model) = board.catalogue {
            return VirtualServo::new(id, model, board.firmware);
        }
        VirtualServo {
            model: None,
            board: Some(board),
            firmware: board.firmware,
            memory: board.factory_memory(id),
            staged_address: 0,
            staged: Vec::with_capacity(64),
            has_staged: false,
            condition: Arc::new(AtomicU8::new(0)),
        }
    }

    /// Registers in address order.
    pub fn registers(&self) -> &'static [Register] {
        match (self.board, self.model) {
            (Some(b), _) => &b.registers,
            (None, Some(m)) => &m.table().registers,
            (None, None) => &[],
        }
    }

    pub fn protocol(&self) -> Protocol {
        match (self.board, self.model) {
            (Some(b), _) => b.protocol,
            (None, Some(m)) => m.protocol(),
            (None, None) => Protocol::V2,
        }
    }

    /// What PING reports.
    pub fn model_number(&self) -> u16 {
        match (self.board, self.model) {
            (Some(b), _) => b.model_number,
            (None, Some(m)) => m.model_number(),
            (None, None) => 0,
        }
    }

    /// Whether the device answers BULK_READ on Protocol 1.0 (MX and the CM-730 do;
    /// every 2.0 device does).
    pub fn has_bulk_read(&self) -> bool {
        match self.model {
            Some(m) => m.has_bulk_read(),
            None => self.protocol() == Protocol::V2,
        }
    }

    /// A sub-controller board (no motor: the backend does not move it).
    pub fn is_board(&self) -> bool {
        self.board.is_some() || self.model.is_some_and(|m| m.is_board())
    }

    /// The register playing `item`, if the table has one.
    pub fn register(&self, item: Item) -> Option<&'static Register> {
        self.registers().iter().find(|r| r.item == Some(item))
    }

    fn containing(&self, address: u16) -> Option<&'static Register> {
        self.registers()
            .iter()
            .find(|r| r.address <= address && address < r.end())
    }

    /// The memory at power-on with `id`.
    fn fresh_memory(&self, id: u8) -> Vec<u8> {
        match (self.board, self.model) {
            (Some(b), _) => b.factory_memory(id),
            (None, Some(m)) => m.table().factory_memory(id, self.firmware),
            (None, None) => Vec::new(),
        }
    }

    /// The decoded value of `item` (0 if the model lacks it).
    pub fn value(&self, item: Item) -> i32 {
        self.register(item)
            .map(|r| r.decode(&self.memory[r.address as usize..r.end() as usize]))
            .unwrap_or(0)
    }

    /// Store `value` in `item` (clamped to its range), bypassing access rules: how
    /// the servo itself updates its present values.
    pub fn set_value(&mut self, item: Item, value: i32) {
        if let Some(r) = self.register(item) {
            let v = value.clamp(r.min, r.max);
            r.encode(v, &mut self.memory[r.address as usize..r.end() as usize]);
        }
    }

    pub fn id(&self) -> u8 {
        self.value(Item::Id) as u8
    }

    pub fn status_return_level(&self) -> u8 {
        self.value(Item::StatusReturnLevel) as u8
    }

    /// Return Delay Time: 2 us per unit.
    pub fn return_delay(&self) -> Duration {
        Duration::from_micros(2 * self.value(Item::ReturnDelayTime).max(0) as u64)
    }

    pub fn torque_enabled(&self) -> bool {
        self.value(Item::TorqueEnable) != 0
    }

    /// Check a READ of `len` bytes at `address`.
    pub fn check_read(&self, address: u16, len: u16) -> Result<(), Fault> {
        if len == 0 {
            return Err(Fault::DataLength);
        }
        if address as usize + len as usize > self.memory.len() {
            return Err(Fault::Access);
        }
        Ok(())
    }

    /// The bytes a READ returns.
    pub fn read(&self, address: u16, len: u16) -> &[u8] {
        &self.memory[address as usize..address as usize + len as usize]
    }

    /// Check a WRITE of `data` at `address` against the servo's rules, without
    /// changing anything.
    pub fn check_write(&self, address: u16, data: &[u8]) -> Result<(), Fault> {
        let protocol = self.protocol();
        let start = address as usize;
        let end = start + data.len();
        if data.is_empty() {
            return Err(Fault::DataLength);
        }
        if end > self.memory.len() {
            return Err(Fault::Access);
        }
        let eeprom_locked = match protocol {
            Protocol::V2 => self.torque_enabled(),
            Protocol::V1 => self.value(Item::Lock) != 0,
        };
        let mut a = start;
        while a < end {
            let Some(r) = self.containing(a as u16) else {
                // A byte no register owns.
                return Err(Fault::Access);
            };
            let (rs, re) = (r.address as usize, r.end() as usize);
            if protocol == Protocol::V2 && (rs < start || re > end) {
                return Err(Fault::DataLength);
            }
            if r.access == Access::Read {
                return Err(Fault::Access);
            }
            if r.area == Area::Eeprom && eeprom_locked {
                return Err(Fault::Access);
            }
            // The register's value after the write (1.0 may write part of one).
            let mut bytes = [0u8; 4];
            for (k, b) in bytes.iter_mut().take(r.size as usize).enumerate() {
                let addr = rs + k;
                *b = if addr >= start && addr < end {
                    data[addr - start]
                } else {
                    self.memory[addr]
                };
            }
            let v = r.decode(&bytes[..r.size as usize]);
            if v < r.min || v > r.max {
                return Err(Fault::DataRange);
            }
            if r.item == Some(Item::GoalPosition) && !self.goal_within_limits(v) {
                return Err(Fault::DataLimit);
            }
            a = re;
        }
        Ok(())
    }

    /// Whether a goal position is inside the limits that apply: CW..CCW Angle Limit
    /// in 1.0 joint mode (both 0 is wheel mode: no limit), Min..Max Position Limit
    /// in 2.0 position control mode (3); extended modes have none.
    fn goal_within_limits(&self, goal: i32) -> bool {
        let lo = self.value(Item::MinPositionLimit);
        let hi = self.value(Item::MaxPositionLimit);
        match self.protocol() {
            Protocol::V1 => (lo == 0 && hi == 0) || (lo <= goal && goal <= hi),
            Protocol::V2 => self.value(Item::OperatingMode) != 3 || (lo <= goal && goal <= hi),
        }
    }

    /// Apply a write already checked with [`VirtualServo::check_write`].
    pub fn apply_write(&mut self, address: u16, data: &[u8]) -> WriteEffects {
        let start = address as usize;
        self.memory[start..start + data.len()].copy_from_slice(data);
        let end = (start + data.len()) as u16;
        let touches =
            |r: Option<&Register>| r.is_some_and(|r| r.address < end && r.end() > address);
        WriteEffects {
            goal_position: touches(self.register(Item::GoalPosition)),
            torque_enable: touches(self.register(Item::TorqueEnable)),
            start: address,
            end,
        }
    }

    /// Stage a REG_WRITE.
    pub fn stage(&mut self, address: u16, data: &[u8]) {
        self.staged_address = address;
        self.staged.clear();
        self.staged.extend_from_slice(data);
        self.has_staged = true;
        self.set_value(Item::Registered, 1);
    }

    /// Apply the staged REG_WRITE (ACTION); `None` if nothing was staged.
    pub fn take_staged(&mut self) -> Option<WriteEffects> {
        if !self.has_staged {
            return None;
        }
        self.has_staged = false;
        self.set_value(Item::Registered, 0);
        let data = std::mem::take(&mut self.staged);
        // Limits may have changed since staging: check again.
        let effects = if self.check_write(self.staged_address, &data).is_ok() {
            self.apply_write(self.staged_address, &data)
        } else {
            WriteEffects::default()
        };
        self.staged = data;
        Some(effects)
    }

    /// FACTORY_RESET: 1.0 resets everything, id included; 2.0 `option` 0xFF all,
    /// 0x01 all but id, 0x02 all but id and baud rate.
    pub fn factory_reset(&mut self, option: u8) {
        let id = self.id();
        let baud = self.value(Item::BaudRate);
        // Servos come back as id 1; a board as its own id (the CM-730: 200).
        let factory_id = if self.is_board() {
            self.register(Item::Id)
                .and_then(|r| r.initial)
                .filter(|&v| v > 0)
                .unwrap_or(id as i32) as u8
        } else {
            1
        };
        self.memory = self.fresh_memory(factory_id);
        if self.protocol() == Protocol::V2 {
            if option == 0x01 || option == 0x02 {
                self.set_value(Item::Id, id as i32);
            }
            if option == 0x02 {
                self.set_value(Item::BaudRate, baud);
            }
        }
        self.has_staged = false;
    }

    /// REBOOT: RAM back to its initial values, EEPROM kept.
    pub fn reboot(&mut self) {
        let fresh = self.fresh_memory(self.id());
        for r in self.registers() {
            if r.area == Area::Ram {
                let (s, e) = (r.address as usize, r.end() as usize);
                self.memory[s..e].copy_from_slice(&fresh[s..e]);
            }
        }
        self.has_staged = false;
    }
}
