//! One virtual servo: its control-table memory and the rules a real servo applies
//! to reads and writes (ranges, read-only registers, EEPROM lock, position limits,
//! indirect addressing), with each violation answered by the error the e-manual
//! names; the protocol it talks (Protocol Type) and the turns its Present Position
//! has been unwound by (CLEAR, reboot).

use crate::board_type::BoardType;
use crate::control_table::{IndirectBlock, ModelTable};
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
    /// bits (EM-P1 Status Packet: bit 6 Instruction, bit 4 Checksum, bit 3 Range,
    /// bit 1 Angle Limit); 2.0 has a number for each (EM-P2).
    ///
    /// Where EM-P1 is silent: it names no bit for a write to a read-only, undefined
    /// or locked address, nor for a bad length; those get the Range bit, as the
    /// RX-64 manual's Example 20 shows for a write to a locked address (status
    /// `FF FF 00 02 08 F5`). Malformed parameters (a READ without its length) get
    /// the Instruction bit, like an undefined instruction. Result Fail has no 1.0
    /// instruction that could raise it (CLEAR is 2.0 only).
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
    pub operating_mode: bool,
    /// Bytes written, through Indirect Data too: within `start..end` (empty if
    /// nothing was).
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
    /// The protocol the servo talks: its model's, or what its Protocol Type
    /// register selects (kept in step with the register by every write).
    protocol: Protocol,
    /// Whole turns, in counts, taken out of the measured position since the servo
    /// was last unwound ([`VirtualServo::unwind`]): Present Position = measured
    /// position + Homing Offset - `turn_offset`.
    pub turn_offset: i64,
}

impl VirtualServo {
    pub fn new(id: u8, model: ServoModel, firmware: u8) -> VirtualServo {
        let mut s = VirtualServo {
            model: Some(model),
            board: None,
            firmware,
            memory: model.table().factory_memory(id, firmware),
            staged_address: 0,
            staged: Vec::with_capacity(64),
            has_staged: false,
            condition: Arc::new(AtomicU8::new(0)),
            protocol: model.protocol(),
            turn_offset: 0,
        };
        s.sync_protocol();
        s
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
            protocol: board.protocol,
            turn_offset: 0,
        }
    }

    /// The indirect-addressing blocks of the servo's table (a board with a table of
    /// its own has none).
    fn indirect_blocks(&self) -> &'static [IndirectBlock] {
        match (self.board, self.model) {
            (None, Some(m)) => &m.table().indirect,
            _ => &[],
        }
    }

    /// The Indirect Address register that redirects Indirect Data byte `address`.
    fn indirect_pointer(&self, address: u16) -> Option<u16> {
        self.indirect_blocks()
            .iter()
            .find_map(|b| b.data_index(address).map(|i| b.address + 2 * i))
    }

    /// Whether `address` lies in an Indirect Address register.
    fn is_indirect_address(&self, address: u16) -> bool {
        self.indirect_blocks()
            .iter()
            .any(|b| b.holds_address_register(address))
    }

    /// Registers in address order.
    pub fn registers(&self) -> &'static [Register] {
        match (self.board, self.model) {
            (Some(b), _) => &b.registers,
            (None, Some(m)) => &m.table().registers,
            (None, None) => &[],
        }
    }

    /// The protocol the servo answers now.
    pub fn protocol(&self) -> Protocol {
        self.protocol
    }

    /// Follow the Protocol Type register (1: Protocol 1.0, 2: Protocol 2.0; EM-XM
    /// Protocol Type(13)); a device without one keeps its own protocol.
    fn sync_protocol(&mut self) {
        self.protocol = match self.register(Item::ProtocolType) {
            Some(_) if self.value(Item::ProtocolType) == 1 => Protocol::V1,
            Some(_) => Protocol::V2,
            None => self.own_protocol(),
        };
    }

    /// The protocol of the device's model or board type.
    fn own_protocol(&self) -> Protocol {
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
            if item == Item::ProtocolType {
                self.sync_protocol();
            }
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

    /// The bytes a READ returns (after [`VirtualServo::load_indirect`] for reads
    /// that may cover Indirect Data).
    pub fn read(&self, address: u16, len: u16) -> &[u8] {
        &self.memory[address as usize..address as usize + len as usize]
    }

    /// Fill the Indirect Data bytes among `len` bytes at `address` with the bytes
    /// their Indirect Address points at, so a READ there returns the addressed
    /// registers (EM-XM Indirect Address, Indirect Data).
    pub fn load_indirect(&mut self, address: u16, len: u16) {
        for block in self.indirect_blocks() {
            let lo = address.max(block.data);
            let hi = (address as u32 + len as u32).min((block.data + block.count) as u32) as u16;
            for a in lo..hi {
                let pointer = block.address + 2 * (a - block.data);
                let target = self.word(pointer, 0, &[]) as usize;
                if target < self.memory.len() {
                    self.memory[a as usize] = self.memory[target];
                }
            }
        }
    }

    /// The 2-byte little-endian value at `address` as it is once `data` is written
    /// at `start` (memory where the write does not reach).
    fn word(&self, address: u16, start: usize, data: &[u8]) -> u16 {
        let byte = |a: usize| {
            if a >= start && a < start + data.len() {
                data[a - start]
            } else {
                self.memory[a]
            }
        };
        u16::from_le_bytes([byte(address as usize), byte(address as usize + 1)])
    }

    /// Where byte `address` of a write at `start` of `data` lands: itself, or the
    /// byte its Indirect Address points at once the write's own bytes are in (a
    /// write that also sets pointers below their data uses the new pointers, the
    /// bytes being taken in address order). An Indirect Data byte pointing at
    /// another Indirect Data byte reaches that byte's memory, not its target.
    fn destination(&self, address: u16, start: usize, data: &[u8]) -> u16 {
        match self.indirect_pointer(address) {
            Some(pointer) => self.word(pointer, start, data),
            None => address,
        }
    }

    /// Whether EEPROM is locked: by Torque Enable on the 2.0 tables (EM-XM), by
    /// Lock on the 1.0 ones (EM-RX28).
    fn eeprom_locked(&self) -> bool {
        match self.own_protocol() {
            Protocol::V2 => self.torque_enabled(),
            Protocol::V1 => self.value(Item::Lock) != 0,
        }
    }

    /// Check a WRITE of `data` at `address` against the servo's rules, without
    /// changing anything. Bytes written through Indirect Data are checked against
    /// the register they reach ("Indirect Address inherits features and
    /// properties of the Data from the specific Address", EM-XM).
    pub fn check_write(&self, address: u16, data: &[u8]) -> Result<(), Fault> {
        let start = address as usize;
        let end = start + data.len();
        if data.is_empty() {
            return Err(Fault::DataLength);
        }
        if end > self.memory.len() {
            return Err(Fault::Access);
        }
        let mut a = start;
        while a < end {
            let Some(r) = self.containing(a as u16) else {
                // A byte no register owns.
                return Err(Fault::Access);
            };
            // The SDK's indirect_address.py: "Indirect address would not
            // accessible when the torque is already enabled" (the e-manual lists
            // the registers in RAM and says nothing of a lock).
            if self.is_indirect_address(r.address) && self.torque_enabled() {
                return Err(Fault::Access);
            }
            self.check_register(r, data, &|a| (a >= start && a < end).then(|| a - start))?;
            a = r.end() as usize;
        }
        if !self.indirect_blocks().is_empty() {
            self.check_indirect(start, data)?;
        }
        Ok(())
    }

    /// Check the registers that Indirect Data bytes of the write reach.
    fn check_indirect(&self, start: usize, data: &[u8]) -> Result<(), Fault> {
        for i in 0..data.len() {
            let a = (start + i) as u16;
            if self.indirect_pointer(a).is_none() {
                continue;
            }
            let t = self.destination(a, start, data);
            if self.indirect_pointer(t).is_some() {
                continue; // plain memory: any byte goes
            }
            let Some(r) = self.containing(t) else {
                return Err(Fault::Access);
            };
            // Each register once: skip it if an earlier byte already reached it.
            let earlier = (0..i).any(|j| {
                let b = (start + j) as u16;
                self.indirect_pointer(b).is_some()
                    && self.containing(self.destination(b, start, data)) == Some(r)
            });
            if earlier {
                continue;
            }
            // Which byte of `data` lands on register byte `x`, if one does.
            let source = |x: usize| {
                (0..data.len()).find(|&j| {
                    let b = (start + j) as u16;
                    self.indirect_pointer(b).is_some()
                        && self.destination(b, start, data) as usize == x
                })
            };
            self.check_register(r, data, &source)?;
        }
        Ok(())
    }

    /// Check one register a write reaches: `source(x)` is the index in `data` of
    /// the byte written to register byte `x`, if one is. A 2.0 write must cover the
    /// whole register (Data Length error otherwise; 1.0 may write part of one).
    fn check_register(
        &self,
        r: &Register,
        data: &[u8],
        source: &dyn Fn(usize) -> Option<usize>,
    ) -> Result<(), Fault> {
        let (rs, size) = (r.address as usize, r.size as usize);
        let mut bytes = [0u8; 4];
        let mut covered = 0;
        for (k, b) in bytes.iter_mut().take(size).enumerate() {
            *b = match source(rs + k) {
                Some(j) => {
                    covered += 1;
                    data[j]
                }
                None => self.memory[rs + k],
            };
        }
        if self.protocol == Protocol::V2 && covered < size {
            return Err(Fault::DataLength);
        }
        if r.access == Access::Read {
            return Err(Fault::Access);
        }
        if r.area == Area::Eeprom && self.eeprom_locked() {
            return Err(Fault::Access);
        }
        let v = r.decode(&bytes[..size]);
        if v < r.min || v > r.max {
            return Err(Fault::DataRange);
        }
        if r.item == Some(Item::GoalPosition) && !self.goal_within_limits(v) {
            return Err(Fault::DataLimit);
        }
        Ok(())
    }

    /// Whether a goal position is inside the limits that apply: CW..CCW Angle Limit
    /// in 1.0 joint mode (both 0 is wheel mode: no limit), Min..Max Position Limit
    /// in 2.0 position control mode (3); extended modes have none.
    fn goal_within_limits(&self, goal: i32) -> bool {
        let lo = self.value(Item::MinPositionLimit);
        let hi = self.value(Item::MaxPositionLimit);
        match self.own_protocol() {
            Protocol::V1 => (lo == 0 && hi == 0) || (lo <= goal && goal <= hi),
            Protocol::V2 => self.value(Item::OperatingMode) != 3 || (lo <= goal && goal <= hi),
        }
    }

    /// Apply a write already checked with [`VirtualServo::check_write`]: the bytes
    /// at `address`, then each Indirect Data byte's copy at the byte it points at.
    pub fn apply_write(&mut self, address: u16, data: &[u8]) -> WriteEffects {
        let start = address as usize;
        self.memory[start..start + data.len()].copy_from_slice(data);
        let mut fx = WriteEffects {
            start: address,
            end: (start + data.len()) as u16,
            ..WriteEffects::default()
        };
        let end = fx.end;
        self.note_touched(&mut fx, address, end);
        if !self.indirect_blocks().is_empty() {
            for (i, &byte) in data.iter().enumerate() {
                let a = (start + i) as u16;
                if self.indirect_pointer(a).is_none() {
                    continue;
                }
                let t = self.destination(a, 0, &[]);
                if (t as usize) < self.memory.len() {
                    self.memory[t as usize] = byte;
                    fx.start = fx.start.min(t);
                    fx.end = fx.end.max(t + 1);
                    self.note_touched(&mut fx, t, t + 1);
                }
            }
        }
        if self
            .register(Item::ProtocolType)
            .is_some_and(|r| r.address < fx.end && r.end() > fx.start)
        {
            self.sync_protocol();
        }
        fx
    }

    /// Mark in `fx` the registers with an effect that bytes `start..end` overlap.
    fn note_touched(&self, fx: &mut WriteEffects, start: u16, end: u16) {
        let touches = |r: Option<&Register>| r.is_some_and(|r| r.address < end && r.end() > start);
        fx.goal_position |= touches(self.register(Item::GoalPosition));
        fx.torque_enable |= touches(self.register(Item::TorqueEnable));
        fx.operating_mode |= touches(self.register(Item::OperatingMode));
    }

    /// Counts per turn of the Present Position register where Present Position can
    /// be unwound to within one turn (the 2.0 tables: 4096), else `None`.
    fn counts_per_turn(&self) -> Option<i64> {
        self.register(Item::OperatingMode)?;
        match self.register(Item::PresentPosition)?.unit {
            crate::register::Unit::Angle { rad_per_unit, .. } => {
                Some((std::f64::consts::TAU / rad_per_unit).round() as i64)
            }
            _ => None,
        }
    }

    /// Reset Present Position "to an absolute value within one full rotation"
    /// (EM-P2 Clear; EM-XM Present Position note: also at power-on, reboot, a
    /// change to Position Control Mode and torque on in it), Homing Offset still
    /// added. `measured` is the position the servo measures, in register counts.
    /// Returns the counts Present Position moved by (what the bus takes off the
    /// Goal Position so the servo holds where it is); 0 for models without it.
    pub fn unwind(&mut self, measured: i64) -> i64 {
        let Some(turn) = self.counts_per_turn() else {
            return 0;
        };
        let offset = measured.div_euclid(turn) * turn;
        let shift = offset - self.turn_offset;
        self.turn_offset = offset;
        shift
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

    /// FACTORY_RESET: `option` 0xFF all, 0x01 all but ID, 0x02 all but ID and Baud
    /// Rate (EM-P2 Factory Reset); a 1.0 reset has no parameter and resets all,
    /// ID included (EM-P1), which the bus passes as 0xFF.
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
        if option == 0x01 || option == 0x02 {
            self.set_value(Item::Id, id as i32);
        }
        if option == 0x02 {
            self.set_value(Item::BaudRate, baud);
        }
        // Protocol Type is back at its factory value: an X servo switched to 1.0
        // talks 2.0 again.
        self.sync_protocol();
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
