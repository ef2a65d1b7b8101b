//! The virtual bus: servos of both protocols on one line, answering every
//! instruction the way the e-manual describes, with a [`VirtualServoBackend`]
//! moving them.
//!
//! Instructions served: PING (2.0 broadcast too), READ, WRITE, REG_WRITE, ACTION,
//! FACTORY_RESET, REBOOT and CLEAR (2.0), SYNC_WRITE, SYNC_READ, FAST_SYNC_READ,
//! BULK_READ (2.0 and MX 1.0), BULK_WRITE, FAST_BULK_READ. A packet whose checksum
//! fails is answered with the checksum / CRC error by the servo it names, like a
//! real servo. Status Return Level is honoured; broadcasts get no reply (except the
//! read instructions, which name their responders). A servo with a Protocol Type
//! register talks the protocol it selects, from the instruction after the write
//! that sets it (that write is answered in the protocol it came in).

use super::backend::{TrackingServoModel, VirtualServoBackend};
use super::virtual_servo::{Fault, VirtualServo, WriteEffects};
use crate::control_table::ModelTable;
use crate::crc16::crc16_update;
use crate::decoder::{Accept, DecodeEvent, Decoder, Frame};
use crate::instruction::Instruction;
use crate::packet::PacketWriter;
use crate::protocol::{BROADCAST_ID, Protocol};
use crate::register::{Item, Unit};
use crate::servo_model::ServoModel;
use crate::transport::Responder;
use std::time::{Duration, Instant};

/// Where one reply packet ends in the reply buffer and how long its servo waits
/// before sending it (Return Delay Time), for wire-time emulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReplyMark {
    pub end: usize,
    pub delay: Duration,
}

/// How the bus's time passes.
#[derive(Debug, Clone, Copy)]
pub enum BusClock {
    /// Only [`VirtualBus::step`] advances time (tests).
    Manual,
    /// Wall-clock time passes between packets (a served robot).
    Wall { last: Instant },
}

/// Counters over the bus's life.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BusStats {
    pub instructions: u64,
    pub replies: u64,
    pub bad_checksums: u64,
    /// Requests left unanswered because a later one in the same burst needed a reply
    /// too (see [`VirtualBus::latest_reply_only`]).
    pub superseded: u64,
}

/// A servo to put on a virtual bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusServo {
    pub id: u8,
    pub model: ServoModel,
}

/// A board to put on a virtual bus, after the servos.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BusBoard {
    pub id: u8,
    pub board: &'static crate::board_type::BoardType,
}

pub struct VirtualBus<B: VirtualServoBackend> {
    pub servos: Vec<VirtualServo>,
    pub backend: B,
    decoder: Decoder,
    pub clock: BusClock,
    /// Simulated time, s.
    pub time: f64,
    pub stats: BusStats,
    /// Reply packets of the last [`VirtualBus::handle`] call.
    pub marks: Vec<ReplyMark>,
    /// Answer only the last request of a burst that needs a reply. A host on a
    /// half-duplex bus waits for each reply before its next request; several such
    /// requests read at once mean the server was stalled (descheduled) while the
    /// host gave up on the earlier ones and retried or moved on. Real servos would
    /// have answered each on time, so those replies are past: sent now they would
    /// answer the wrong transactions. Writes and other instructions in the burst
    /// still take effect, in order. Off by default (an in-memory bus is never
    /// stalled); `serve` turns it on.
    pub latest_reply_only: bool,
}

/// Firmware version the virtual servos report.
pub const VIRTUAL_FIRMWARE: u8 = 45;

impl VirtualBus<TrackingServoModel> {
    /// A bus whose servos are moved by the stand-in [`TrackingServoModel`], each
    /// able to reach its Goal Position register's whole range, starting at rest at
    /// its centre. Boards (which must come after the servos) read level and still.
    /// A 2.0 servo reaches twice that range: its Goal Position is counted from
    /// where its Present Position was last unwound (CLEAR), which may be up to the
    /// register's range away from the centre.
    pub fn with_tracking_model(servos: &[BusServo]) -> VirtualBus<TrackingServoModel> {
        VirtualBus::with_tracking_model_and_boards(servos, &[])
    }

    /// [`VirtualBus::with_tracking_model`] with boards of their own table after the
    /// servos ([`VirtualBus::with_boards`]).
    pub fn with_tracking_model_and_boards(
        servos: &[BusServo],
        boards: &[BusBoard],
    ) -> VirtualBus<TrackingServoModel> {
        let ranges: Vec<_> = servos
            .iter()
            .filter(|s| !s.model.is_board())
            .map(|s| {
                let t = s.model.table();
                let r = t
                    .item(Item::GoalPosition)
                    .expect("every table has a goal position");
                let reach = if t.item(Item::OperatingMode).is_some() {
                    2.0
                } else {
                    1.0
                };
                (
                    s.model.spec(),
                    reach * r.to_si(r.min),
                    reach * r.to_si(r.max),
                )
            })
            .collect();
        VirtualBus::with_boards(servos, boards, TrackingServoModel::new(&ranges))
    }
}

impl<B: VirtualServoBackend> VirtualBus<B> {
    /// Servos in backend order, then any boards (sub-controllers: the backend
    /// moves no motor of theirs, it only feeds their sensors,
    /// [`VirtualServoBackend::board_imu`]).
    pub fn new(servos: &[BusServo], backend: B) -> VirtualBus<B> {
        VirtualBus::with_boards(servos, &[], backend)
    }

    /// [`VirtualBus::new`] with boards of a [`BoardType`](crate::board_type::BoardType)
    /// after the servos (the OpenCR, a profile's custom board), each answering from
    /// its type's table: bus index `servos.len() + k` is `boards[k]`.
    pub fn with_boards(servos: &[BusServo], boards: &[BusBoard], backend: B) -> VirtualBus<B> {
        let devices = servos
            .iter()
            .map(|s| VirtualServo::new(s.id, s.model, VIRTUAL_FIRMWARE))
            .chain(boards.iter().map(|b| match b.board.catalogue {
                Some(model) => VirtualServo::new(b.id, model, VIRTUAL_FIRMWARE),
                None => VirtualServo::new_board(b.id, b.board),
            }));
        let mut bus = VirtualBus {
            servos: devices.collect(),
            backend,
            decoder: Decoder::new(Accept::Both),
            clock: BusClock::Manual,
            time: 0.0,
            stats: BusStats::default(),
            marks: Vec::with_capacity(256),
            latest_reply_only: false,
        };
        for k in 0..bus.servos.len() {
            power_on(&mut bus.servos[k], &mut bus.backend, k, bus.time);
        }
        bus
    }

    /// Make servo `k` talk `protocol`, as if its Protocol Type register (EEPROM)
    /// had been set before power-on: [`Fault::Access`] if its model cannot
    /// ([`ServoModel::speaks`]).
    pub fn set_protocol(&mut self, k: usize, protocol: Protocol) -> Result<(), Fault> {
        let s = &mut self.servos[k];
        if protocol == s.protocol() {
            return Ok(());
        }
        if !s.model.is_some_and(|m| m.speaks(protocol)) {
            return Err(Fault::Access);
        }
        s.set_value(Item::ProtocolType, protocol.number() as i32);
        Ok(())
    }

    /// Set every device's Baud Rate register (EEPROM) to the code of the line's
    /// bit rate, as if set before power-on: a real servo answering on a 1 Mbps
    /// line holds the code of 1 Mbps (X series 3, RX/MX(1.0) 1), not its factory
    /// 57 600. A model with no code within 3 % of `baud` keeps its register.
    pub fn set_line_baud(&mut self, baud: u32) {
        for s in &mut self.servos {
            // A board with a table of its own keeps what its profile gives it.
            let Some(model) = s.model else { continue };
            if let Some(code) = crate::servo_model::baud_to_register(model.protocol(), baud) {
                s.set_value(Item::BaudRate, code as i32);
            }
        }
    }

    /// Write `value` to `item` of servo `k` as a host's WRITE would (same checks,
    /// same effect on the backend): how a served robot is prepared before a
    /// client arrives (e.g. torque on, so a simulated robot stands).
    pub fn host_write(&mut self, k: usize, item: Item, value: i32) -> Result<(), Fault> {
        let Some(r) = self.servos[k].register(item) else {
            return Err(Fault::Access);
        };
        let mut bytes = [0u8; 4];
        r.encode(value, &mut bytes[..r.size as usize]);
        let VirtualBus {
            servos,
            backend,
            time,
            marks,
            ..
        } = self;
        let mut scratch = Vec::new();
        let mut ctx = Ctx {
            servos,
            backend,
            marks,
            time: *time,
            out: &mut scratch,
        };
        ctx.write(k, r.address, &bytes[..r.size as usize])
    }

    /// Let `dt` seconds pass.
    pub fn step(&mut self, dt: f64) {
        self.backend.step(dt);
        self.time += dt;
    }

    fn advance_clock(&mut self) {
        if let BusClock::Wall { last } = &mut self.clock {
            let now = Instant::now();
            let dt = now.duration_since(*last).as_secs_f64();
            *last = now;
            self.backend.step(dt);
            self.time += dt;
        }
    }

    /// The line went quiet: a packet still waiting for bytes was truncated (or its
    /// LENGTH damaged). Servos drop it after an inter-byte gap (EM-P1 "Byte to Byte
    /// Time": 100 ms) and look for the next header; complete packets found after
    /// its first byte are still served. Without this a damaged LENGTH would make
    /// the servos swallow the requests that follow.
    pub fn line_idle(&mut self, reply: &mut Vec<u8>) {
        if self.decoder.buffered() == 0 {
            return;
        }
        let VirtualBus {
            servos,
            backend,
            decoder,
            time,
            stats,
            marks,
            ..
        } = self;
        let mut ctx = Ctx {
            servos,
            backend,
            marks,
            time: *time,
            out: reply,
        };
        while let Some(f) = decoder.next_frame_flushing() {
            if f.protocol == Protocol::V2 && f.instruction == Instruction::Status.code() {
                continue;
            }
            stats.instructions += 1;
            ctx.process(&f);
        }
    }

    /// Take bytes from the line; append every reply to `reply` (and its marks to
    /// [`VirtualBus::marks`]).
    pub fn handle(&mut self, input: &[u8], reply: &mut Vec<u8>) {
        self.marks.clear();
        self.advance_clock();
        let mut rest = input;
        // Where the replies of the last request answered in this call begin (in
        // `reply`, in `marks`), for `latest_reply_only`.
        let mut last: Option<(usize, usize)> = None;
        let latest_only = self.latest_reply_only;
        loop {
            let n = self.decoder.push(rest);
            rest = &rest[n..];
            let VirtualBus {
                servos,
                backend,
                decoder,
                time,
                stats,
                marks,
                ..
            } = self;
            let mut ctx = Ctx {
                servos,
                backend,
                marks,
                time: *time,
                out: reply,
            };
            while let Some(ev) = decoder.next_event() {
                let before = (ctx.out.len(), ctx.marks.len());
                match ev {
                    DecodeEvent::Frame(f) => {
                        // 2.0 status packets from other servos are not for us.
                        if f.protocol == Protocol::V2 && f.instruction == Instruction::Status.code()
                        {
                            continue;
                        }
                        stats.instructions += 1;
                        ctx.process(&f);
                    }
                    DecodeEvent::BadChecksum {
                        protocol,
                        id,
                        instruction,
                    } => {
                        stats.bad_checksums += 1;
                        if protocol == Protocol::V2 && instruction == Instruction::Status.code() {
                            continue;
                        }
                        if let Some(k) = ctx.find(protocol, id) {
                            ctx.status(k, protocol, Fault::Checksum.error_byte(protocol), &[]);
                        }
                    }
                }
                if ctx.marks.len() > before.1 {
                    if latest_only && let Some(prev) = last {
                        drop_replies(&mut ctx, prev, before);
                        stats.superseded += 1;
                        last = Some(prev);
                    } else {
                        last = Some(before);
                    }
                }
            }
            if rest.is_empty() {
                break;
            }
        }
        self.stats.replies += self.marks.len() as u64;
    }
}

/// Remove the replies between `from` and `to` (offsets into the reply buffer and
/// the marks) and shift the marks after them.
fn drop_replies<B: VirtualServoBackend>(
    ctx: &mut Ctx<'_, B>,
    from: (usize, usize),
    to: (usize, usize),
) {
    let bytes = to.0 - from.0;
    ctx.out.drain(from.0..to.0);
    ctx.marks.drain(from.1..to.1);
    for m in &mut ctx.marks[from.1..] {
        m.end -= bytes;
    }
}

impl<B: VirtualServoBackend> Responder for VirtualBus<B> {
    /// One write of the host is one burst on the line; after it the line is idle
    /// while the host waits, so an incomplete packet is given up (see
    /// [`VirtualBus::line_idle`]).
    fn respond(&mut self, input: &[u8], reply: &mut Vec<u8>) {
        self.handle(input, reply);
        self.line_idle(reply);
    }
}

/// Homing Offset (0 on the 1.0 tables, which have none).
fn homing_offset(s: &VirtualServo) -> i64 {
    s.value(Item::HomingOffset) as i64
}

/// The position servo `k` measures, in Present Position counts (before Homing
/// Offset and unwinding).
fn measured_counts<B: VirtualServoBackend>(s: &VirtualServo, backend: &B, k: usize) -> i64 {
    let r = s
        .register(Item::PresentPosition)
        .expect("every servo table has a present position");
    r.from_si(backend.measure(k).position) as i64
}

/// Unwind servo `k`'s Present Position to within one turn
/// ([`VirtualServo::unwind`]) and move its Goal Position by as much, so that the
/// goal still names the place the servo is driven to.
fn unwind<B: VirtualServoBackend>(s: &mut VirtualServo, backend: &B, k: usize) {
    if s.is_board() {
        return;
    }
    let shift = s.unwind(measured_counts(s, backend, k));
    if shift != 0 {
        let goal = s.value(Item::GoalPosition) as i64 - shift;
        s.set_value(
            Item::GoalPosition,
            goal.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
        );
    }
}

/// What a servo does when it starts (power-on, REBOOT, the reboot after
/// FACTORY_RESET): the backend learns every register, Present Position is read
/// within one turn (EM-XM Present Position note), and the goal is set where the
/// servo is, so enabling torque does not move it.
fn power_on<B: VirtualServoBackend>(s: &mut VirtualServo, backend: &mut B, k: usize, time: f64) {
    announce_registers(s, backend, k, 0, u16::MAX);
    unwind(s, backend, k);
    refresh(s, backend, k, time);
    let p = s.value(Item::PresentPosition);
    s.set_value(Item::GoalPosition, p);
}

/// Present values from the backend into the control table. 2.0 reports
/// Present Position = actual position + Homing Offset (EM-XM), less the turns
/// unwound ([`VirtualServo::turn_offset`]). A board's
/// gyroscope and accelerometer registers get the backend's IMU in counts (rounded,
/// clamped to 10 bits as the board's converter would).
fn refresh<B: VirtualServoBackend>(s: &mut VirtualServo, backend: &B, k: usize, time: f64) {
    if s.is_board() {
        let Some(imu) = backend.board_imu(k) else {
            return;
        };
        let items = crate::board::gyro_items()
            .into_iter()
            .zip(imu.gyro)
            .chain(crate::board::accel_items().into_iter().zip(imu.accel));
        for (item, si) in items {
            if let Some(r) = s.register(item) {
                s.set_value(item, r.from_si(si));
            }
        }
        return;
    }
    let Some(model) = s.model else {
        return;
    };
    let m = backend.measure(k);
    let t = model.table();
    let spec = model.spec();
    if let Some(r) = t.item(Item::PresentPosition) {
        let raw = r.from_si(m.position) as i64 + homing_offset(s) - s.turn_offset;
        s.set_value(
            Item::PresentPosition,
            raw.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
        );
    }
    if let Some(r) = t.item(Item::PresentVelocity) {
        s.set_value(Item::PresentVelocity, r.from_si(m.velocity));
    }
    if let Some(r) = t.item(Item::PresentLoad) {
        s.set_value(Item::PresentLoad, r.from_si(m.torque / spec.stall_torque));
    }
    if let (Some(r), Some(kt)) = (t.item(Item::PresentCurrent), spec.torque_per_amp()) {
        // MX(1.0) Current is a read-write register; only the servo writes it here.
        if matches!(r.unit, Unit::Current { .. }) {
            s.set_value(Item::PresentCurrent, r.from_si(m.torque / kt));
        }
    }
    if let Some(r) = t.item(Item::PresentVoltage) {
        s.set_value(Item::PresentVoltage, r.from_si(m.voltage));
    }
    s.set_value(Item::PresentTemperature, m.temperature.round() as i32);
    let is_moving = moving(s, m.velocity);
    s.set_value(Item::Moving, is_moving as i32);
    s.set_value(Item::RealtimeTick, ((time * 1000.0) as i64 % 32768) as i32);
}

/// Whether servo `s`, turning at `velocity` rad/s, is moving (its Moving
/// register; a CLEAR is refused while it is): faster than its Moving Threshold
/// where it has one (EM-XM Moving(122): "If absolute value of Present
/// Velocity(128) is greater than Moving Threshold(24)"), else than 0.01 rad/s.
fn moving(s: &VirtualServo, velocity: f64) -> bool {
    let threshold = match s.register(Item::MovingThreshold) {
        Some(r) => r.to_si(s.value(Item::MovingThreshold)),
        None => 0.01,
    };
    velocity.abs() > threshold
}

/// Tell the backend the value of every register with an item (other than Goal
/// Position and Torque Enable, which have their own calls) that lies in
/// `start..end`.
fn announce_registers<B: VirtualServoBackend>(
    s: &VirtualServo,
    backend: &mut B,
    k: usize,
    start: u16,
    end: u16,
) {
    if s.is_board() {
        return; // nothing of a board's moves the backend
    }
    for r in s.registers() {
        if r.address >= end {
            break; // registers are in address order
        }
        let Some(item) = r.item else { continue };
        if r.end() <= start {
            continue;
        }
        if matches!(
            item,
            Item::GoalPosition | Item::TorqueEnable | Item::PresentPosition
        ) || r.access == crate::register::Access::Read
        {
            continue;
        }
        backend.register_written(k, item, s.value(item));
    }
}

/// A status packet's error byte with the servo's hardware condition added
/// ([`VirtualServo::condition`]): 1.0 its bits, 2.0 the Alert bit.
fn with_condition(s: &VirtualServo, protocol: Protocol, error: u8) -> u8 {
    match (
        s.condition.load(std::sync::atomic::Ordering::Relaxed),
        protocol,
    ) {
        (0, _) => error,
        (c, Protocol::V1) => error | c,
        (_, Protocol::V2) => error | 0x80,
    }
}

/// What one instruction needs to reach.
struct Ctx<'a, B: VirtualServoBackend> {
    servos: &'a mut Vec<VirtualServo>,
    backend: &'a mut B,
    marks: &'a mut Vec<ReplyMark>,
    time: f64,
    out: &'a mut Vec<u8>,
}

/// Status Return Level needed for a reply: PING always, READ-type from 1, the rest
/// from 2 (EM-P2; EM-RX28 Status Return Level).
fn level_needed(instruction: u8) -> u8 {
    match Instruction::from_code(instruction) {
        Some(Instruction::Ping) => 0,
        Some(
            Instruction::Read
            | Instruction::SyncRead
            | Instruction::BulkRead
            | Instruction::FastSyncRead
            | Instruction::FastBulkRead,
        ) => 1,
        _ => 2,
    }
}

/// Little-endian parameter reader that knows 1.0 addresses are one byte.
struct Params<'a> {
    bytes: &'a [u8],
    pos: usize,
    protocol: Protocol,
}

impl<'a> Params<'a> {
    fn new(protocol: Protocol, bytes: &'a [u8]) -> Params<'a> {
        Params {
            bytes,
            pos: 0,
            protocol,
        }
    }
    fn u8(&mut self) -> Option<u8> {
        let b = *self.bytes.get(self.pos)?;
        self.pos += 1;
        Some(b)
    }
    fn u16(&mut self) -> Option<u16> {
        let lo = self.u8()?;
        let hi = self.u8()?;
        Some(u16::from_le_bytes([lo, hi]))
    }
    /// An address or length: 1 byte in 1.0, 2 in 2.0.
    fn addr(&mut self) -> Option<u16> {
        match self.protocol {
            Protocol::V1 => self.u8().map(u16::from),
            Protocol::V2 => self.u16(),
        }
    }
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.bytes.get(self.pos..self.pos + n)?;
        self.pos += n;
        Some(s)
    }
    fn rest(&self) -> &'a [u8] {
        &self.bytes[self.pos..]
    }
    fn done(&self) -> bool {
        self.pos == self.bytes.len()
    }
}

impl<B: VirtualServoBackend> Ctx<'_, B> {
    fn find(&self, protocol: Protocol, id: u8) -> Option<usize> {
        self.servos
            .iter()
            .position(|s| s.protocol() == protocol && s.id() == id)
    }

    /// Append a status packet from servo `k` in `protocol` (the instruction's: a
    /// write that switches the servo's protocol is answered in the old one).
    fn status(&mut self, k: usize, protocol: Protocol, error: u8, data: &[u8]) {
        let s = &self.servos[k];
        let error = with_condition(s, protocol, error);
        let mut w = PacketWriter::status(self.out, protocol, s.id(), error);
        w.bytes(data);
        // A status packet of at most 4 + 1 + 65535 bytes always encodes.
        let _ = w.finish();
        self.marks.push(ReplyMark {
            end: self.out.len(),
            delay: s.return_delay(),
        });
    }

    /// Reply to a unicast instruction `f` if the Status Return Level allows.
    fn reply(&mut self, k: usize, f: &Frame<'_>, result: Result<(), Fault>, data: &[u8]) {
        let level = level_needed(f.instruction);
        if f.id == BROADCAST_ID || self.servos[k].status_return_level() < level {
            return;
        }
        match result {
            Ok(()) => self.status(k, f.protocol, 0, data),
            Err(e) => self.status(k, f.protocol, e.error_byte(f.protocol), &[]),
        }
    }

    fn refresh(&mut self, k: usize) {
        refresh(&mut self.servos[k], self.backend, k, self.time);
    }

    fn apply_effects(&mut self, k: usize, fx: WriteEffects) {
        let s = &mut self.servos[k];
        if s.is_board() {
            return;
        }
        if fx.end > fx.start {
            announce_registers(s, self.backend, k, fx.start, fx.end);
        }
        // Present Position is read within one turn again on a change to Position
        // Control Mode and on torque on in it (EM-XM Present Position note).
        let position_mode =
            s.register(Item::OperatingMode).is_some() && s.value(Item::OperatingMode) == 3;
        if position_mode && (fx.operating_mode || (fx.torque_enable && s.torque_enabled())) {
            unwind(s, self.backend, k);
        }
        if fx.torque_enable {
            self.backend.set_torque_enabled(k, s.torque_enabled());
        }
        // Torque on drives the servo to the Goal Position register, written or not.
        if fx.goal_position || (fx.torque_enable && s.torque_enabled()) {
            let r = s
                .register(Item::GoalPosition)
                .expect("every servo table has one");
            let raw = s.value(Item::GoalPosition) as i64 - homing_offset(s) + s.turn_offset;
            let goal = r.to_si(raw.clamp(i32::MIN as i64, i32::MAX as i64) as i32);
            self.backend.set_goal_position(k, goal);
        }
    }

    fn write(&mut self, k: usize, address: u16, data: &[u8]) -> Result<(), Fault> {
        self.servos[k].check_write(address, data)?;
        let fx = self.servos[k].apply_write(address, data);
        self.apply_effects(k, fx);
        Ok(())
    }

    /// Servo indices an instruction to (`protocol`, `id`) reaches.
    fn targets(&self, protocol: Protocol, id: u8, out: &mut [usize; 256]) -> usize {
        let mut n = 0;
        for (k, s) in self.servos.iter().enumerate() {
            if n == out.len() {
                break; // more servos than ids exist: duplicates, ignored
            }
            if s.protocol() == protocol && (id == BROADCAST_ID || s.id() == id) {
                out[n] = k;
                n += 1;
            }
        }
        n
    }

    fn process(&mut self, f: &Frame<'_>) {
        let protocol = f.protocol;
        let code = f.instruction;
        let mut targets = [0usize; 256];
        let n = self.targets(protocol, f.id, &mut targets);
        let targets = &targets[..n];
        let instruction = Instruction::from_code(code).filter(|i| i.in_protocol(protocol));
        let Some(instruction) = instruction else {
            // Undefined here (e.g. SYNC_READ or REBOOT sent to a 1.0 servo).
            for &k in targets {
                self.reply(k, f, Err(Fault::Instruction), &[]);
            }
            return;
        };
        match instruction {
            Instruction::Ping => self.ping(f, targets),
            Instruction::Read => self.read(f, targets),
            Instruction::Write | Instruction::RegWrite => {
                self.write_or_stage(f, instruction, targets)
            }
            Instruction::Action => self.action(f, targets),
            Instruction::FactoryReset => self.factory_reset(f, targets),
            Instruction::Reboot => self.reboot(f, targets),
            Instruction::Clear => self.clear(f, targets),
            Instruction::SyncWrite => self.sync_write(protocol, f.params),
            Instruction::BulkWrite => self.bulk_write(f.params),
            Instruction::SyncRead | Instruction::FastSyncRead => self.sync_read(f, instruction),
            Instruction::BulkRead | Instruction::FastBulkRead => self.bulk_read(f, instruction),
            Instruction::Status => {}
        }
    }

    /// PING: the model number and firmware (2.0), an empty status (1.0).
    fn ping(&mut self, f: &Frame<'_>, targets: &[usize]) {
        let protocol = f.protocol;
        if protocol == Protocol::V1 && f.id == BROADCAST_ID {
            return; // EM-P1: no status for broadcast.
        }
        for &k in targets {
            let s = &self.servos[k];
            let model = s.model_number().to_le_bytes();
            let fw = s.firmware;
            match protocol {
                Protocol::V1 => self.status(k, protocol, 0, &[]),
                Protocol::V2 => self.status(k, protocol, 0, &[model[0], model[1], fw]),
            }
        }
    }

    /// READ: a status with the registers asked for (none to a broadcast).
    fn read(&mut self, f: &Frame<'_>, targets: &[usize]) {
        let mut p = Params::new(f.protocol, f.params);
        let (Some(address), Some(len)) = (p.addr(), p.addr()) else {
            for &k in targets {
                self.reply(k, f, Err(Fault::Instruction), &[]);
            }
            return;
        };
        if f.id != BROADCAST_ID {
            for &k in targets {
                self.read_reply(k, address, len);
            }
        }
    }

    /// WRITE (applied now) or REG_WRITE (staged for ACTION).
    fn write_or_stage(&mut self, f: &Frame<'_>, instruction: Instruction, targets: &[usize]) {
        let mut p = Params::new(f.protocol, f.params);
        let address = p.addr();
        let data = p.rest();
        for &k in targets {
            let r = match address {
                None => Err(Fault::Instruction),
                Some(a) if instruction == Instruction::Write => self.write(k, a, data),
                Some(a) => self.servos[k].check_write(a, data).map(|()| {
                    self.servos[k].stage(a, data);
                }),
            };
            self.reply(k, f, r, &[]);
        }
    }

    /// ACTION: apply the staged REG_WRITE of each target.
    fn action(&mut self, f: &Frame<'_>, targets: &[usize]) {
        for &k in targets {
            let r = match self.servos[k].take_staged() {
                Some(fx) => {
                    self.apply_effects(k, fx);
                    Ok(())
                }
                None => Err(Fault::Instruction),
            };
            self.reply(k, f, r, &[]);
        }
    }

    /// The restart that follows REBOOT and FACTORY_RESET: torque off, then
    /// [`power_on`] (the goal where the servo is, Present Position within one turn).
    fn restart(&mut self, k: usize) {
        if !self.servos[k].is_board() {
            self.backend.set_torque_enabled(k, false);
        }
        power_on(&mut self.servos[k], self.backend, k, self.time);
    }

    /// FACTORY_RESET: answer under the old id (and protocol), reset the control
    /// table, then reboot as the servo does. Its parameter (2.0): 0xFF all, 0x01
    /// all but ID, 0x02 all but ID and Baud Rate (EM-P2 Factory Reset); a 1.0 reset
    /// has none and resets all (EM-P1). An option EM-P2 does not list is refused
    /// with an Instruction Error, resetting nothing (EM-P2 is silent on it).
    fn factory_reset(&mut self, f: &Frame<'_>, targets: &[usize]) {
        let option = match f.protocol {
            Protocol::V1 => 0xFF,
            Protocol::V2 => f.params.first().copied().unwrap_or(0xFF),
        };
        if f.protocol == Protocol::V2 && f.id == BROADCAST_ID && option == 0xFF {
            return; // Ignored since firmware 42 (EM-P2).
        }
        let known = matches!(option, 0xFF | 0x01 | 0x02);
        for &k in targets {
            if !known {
                self.reply(k, f, Err(Fault::Instruction), &[]);
                continue;
            }
            self.reply(k, f, Ok(()), &[]);
            self.servos[k].factory_reset(option);
            self.restart(k);
        }
    }

    /// REBOOT: answer, then restart with RAM at its initial values (torque off),
    /// EEPROM kept, the goal at the present position.
    fn reboot(&mut self, f: &Frame<'_>, targets: &[usize]) {
        for &k in targets {
            self.reply(k, f, Ok(()), &[]);
            self.servos[k].reboot();
            self.restart(k);
        }
    }

    /// CLEAR with P1 0x01 and the fixed P2..P5 0x44 0x58 0x4C 0x22: reset Present
    /// Position to within one full rotation (0..4095, Homing Offset still added),
    /// only while the servo is stopped: moving, it answers Result Fail (EM-P2
    /// Clear, which names no operating mode it is limited to). Goal Position moves
    /// by as much, so the servo holds where it is (EM-P2 does not say what Goal
    /// Position reads after it). Other parameters are reserved: Instruction Error.
    fn clear(&mut self, f: &Frame<'_>, targets: &[usize]) {
        let valid = f.params == [0x01, 0x44, 0x58, 0x4C, 0x22];
        for &k in targets {
            let r = if !valid {
                Err(Fault::Instruction)
            } else if self.servos[k].is_board() {
                Ok(())
            } else if moving(&self.servos[k], self.backend.measure(k).velocity) {
                Err(Fault::ResultFail)
            } else {
                unwind(&mut self.servos[k], self.backend, k);
                Ok(())
            };
            self.reply(k, f, r, &[]);
        }
    }

    /// SYNC_READ (one status per id, in order) or FAST_SYNC_READ (one shared status).
    fn sync_read(&mut self, f: &Frame<'_>, instruction: Instruction) {
        let protocol = f.protocol;
        let mut p = Params::new(protocol, f.params);
        let (Some(address), Some(len)) = (p.u16(), p.u16()) else {
            return;
        };
        let ids = p.rest();
        if instruction == Instruction::SyncRead {
            for &id in ids {
                if let Some(k) = self.find(protocol, id) {
                    self.read_reply(k, address, len);
                }
            }
        } else {
            self.fast_reply(ids.iter().map(|&id| (id, address, len)));
        }
    }

    /// BULK_READ (one status per item, not from RX) or FAST_BULK_READ (one shared status).
    fn bulk_read(&mut self, f: &Frame<'_>, instruction: Instruction) {
        let protocol = f.protocol;
        let mut items = [(0u8, 0u16, 0u16); 256];
        let mut count = 0;
        let mut p = Params::new(protocol, f.params);
        if protocol == Protocol::V1 && p.u8() != Some(0x00) {
            return;
        }
        while !p.done() && count < items.len() {
            let item = match protocol {
                Protocol::V1 => (|| {
                    let len = p.u8()?;
                    let id = p.u8()?;
                    let address = p.u8()?;
                    Some((id, address as u16, len as u16))
                })(),
                Protocol::V2 => (|| Some((p.u8()?, p.u16()?, p.u16()?)))(),
            };
            let Some(item) = item else { return };
            // A repeated id is read once (EM-P1).
            if items[..count].iter().all(|i| i.0 != item.0) {
                items[count] = item;
                count += 1;
            }
        }
        if instruction == Instruction::FastBulkRead {
            self.fast_reply(items[..count].iter().copied());
            return;
        }
        for &(id, address, len) in &items[..count] {
            let Some(k) = self.find(protocol, id) else {
                continue;
            };
            if !self.servos[k].has_bulk_read() {
                continue; // RX: no BULK_READ.
            }
            self.read_reply(k, address, len);
        }
    }

    /// Answer a READ-type request naming servo `k`.
    fn read_reply(&mut self, k: usize, address: u16, len: u16) {
        if self.servos[k].status_return_level() < 1 {
            return;
        }
        let protocol = self.servos[k].protocol();
        match self.servos[k].check_read(address, len) {
            Ok(()) => {
                self.refresh(k);
                self.servos[k].load_indirect(address, len);
                let s = &self.servos[k];
                let error = with_condition(s, protocol, 0);
                let mut w = PacketWriter::status(self.out, protocol, s.id(), error);
                w.bytes(s.read(address, len));
                let _ = w.finish();
                self.marks.push(ReplyMark {
                    end: self.out.len(),
                    delay: s.return_delay(),
                });
            }
            Err(fault) => self.status(k, protocol, fault.error_byte(protocol), &[]),
        }
    }

    /// One FAST_SYNC_READ / FAST_BULK_READ reply (the SDK's fastSyncReadRxPacket): id 0xFE, then
    /// `[ERR ID DATA CRC]` per servo present, each CRC over the packet from its
    /// first byte, the last being the packet's CRC. Not byte-stuffed: the SDK
    /// parses these replies with a fixed stride and removes no stuffing.
    fn fast_reply(&mut self, items: impl Iterator<Item = (u8, u16, u16)>) {
        let start = self.out.len();
        self.out
            .extend_from_slice(&[0xFF, 0xFF, 0xFD, 0x00, BROADCAST_ID, 0, 0, 0x55]);
        let mut any = false;
        let mut delay = Duration::ZERO;
        // Where each block's CRC goes, filled once LENGTH is known.
        let mut crc_slots = [0usize; 256];
        let mut blocks = 0;
        for (id, address, len) in items {
            if blocks == crc_slots.len() {
                break;
            }
            let Some(k) = self.find(Protocol::V2, id) else {
                continue;
            };
            if self.servos[k].status_return_level() < 1 {
                continue;
            }
            if !any {
                delay = self.servos[k].return_delay();
            }
            any = true;
            let check = self.servos[k].check_read(address, len);
            if check.is_ok() {
                self.refresh(k);
                self.servos[k].load_indirect(address, len);
            }
            let s = &self.servos[k];
            match check {
                Ok(()) => {
                    self.out.push(0);
                    self.out.push(id);
                    self.out.extend_from_slice(s.read(address, len));
                }
                Err(fault) => {
                    self.out.push(fault.error_byte(Protocol::V2));
                    self.out.push(id);
                    self.out.extend(std::iter::repeat_n(0u8, len as usize));
                }
            }
            // Each block's CRC covers LENGTH, which is known only at the end.
            crc_slots[blocks] = self.out.len();
            blocks += 1;
            self.out.extend_from_slice(&[0, 0]);
        }
        if !any {
            self.out.truncate(start);
            return;
        }
        let length = self.out.len() - (start + 7);
        self.out[start + 5..start + 7].copy_from_slice(&(length as u16).to_le_bytes());
        // Front to back: each CRC covers every byte before it, earlier CRCs included.
        let mut running = 0u16;
        let mut covered = start;
        for &crc_at in &crc_slots[..blocks] {
            running = crc16_update(running, &self.out[covered..crc_at]);
            covered = crc_at;
            self.out[crc_at..crc_at + 2].copy_from_slice(&running.to_le_bytes());
        }
        self.marks.push(ReplyMark {
            end: self.out.len(),
            delay,
        });
    }

    fn sync_write(&mut self, protocol: Protocol, params: &[u8]) {
        let mut p = Params::new(protocol, params);
        let (Some(address), Some(len)) = (p.addr(), p.addr()) else {
            return;
        };
        while !p.done() {
            let (Some(id), Some(data)) = (p.u8(), p.take(len as usize)) else {
                return;
            };
            if let Some(k) = self.find(protocol, id) {
                let _ = self.write(k, address, data);
            }
        }
    }

    fn bulk_write(&mut self, params: &[u8]) {
        let mut p = Params::new(Protocol::V2, params);
        while !p.done() {
            let (Some(id), Some(address), Some(len)) = (p.u8(), p.u16(), p.u16()) else {
                return;
            };
            let Some(data) = p.take(len as usize) else {
                return;
            };
            if let Some(k) = self.find(Protocol::V2, id) {
                let _ = self.write(k, address, data);
            }
        }
    }
}
