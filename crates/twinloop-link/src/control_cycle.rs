//! The control cycle a humanoid runs: write every joint's goal position with one
//! SYNC_WRITE per protocol, then read every joint's present position, velocity and
//! load (or current) with the cheapest read its servos have: FAST_SYNC_READ or
//! SYNC_READ on Protocol 2.0, BULK_READ on MX with 1.0 firmware, and one READ per
//! servo on RX, which has nothing else (ROBOTIS e-manual, Protocol 1.0 instruction set).
//!
//! Everything is laid out when the cycle is built; running it allocates nothing.

use crate::client::{BulkRead, Client};
use crate::control_table::ModelTable;
use crate::link_error::{LinkError, Outcome};
use crate::protocol::Protocol;
use crate::register::{Item, Register};
use crate::servo_model::ServoModel;
use crate::status_error::StatusError;
use crate::transport::Transport;
use std::fmt;

/// A servo in the cycle and the protocol it talks (its model's, or 1.0 for an X or
/// MX(2.0) servo whose Protocol Type register selects it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CycleServo {
    pub id: u8,
    pub model: ServoModel,
    pub protocol: Protocol,
}

impl CycleServo {
    /// A servo talking its model's own protocol.
    pub fn new(id: u8, model: ServoModel) -> CycleServo {
        CycleServo {
            id,
            model,
            protocol: model.protocol(),
        }
    }
}

/// How a group of servos is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadMethod {
    /// The cheapest the servos support.
    Auto,
    /// One READ per servo.
    Read,
    BulkRead,
    SyncRead,
    FastSyncRead,
}

impl ReadMethod {
    pub fn name(self) -> &'static str {
        match self {
            ReadMethod::Auto => "auto",
            ReadMethod::Read => "READ per servo",
            ReadMethod::BulkRead => "BULK_READ",
            ReadMethod::SyncRead => "SYNC_READ",
            ReadMethod::FastSyncRead => "FAST_SYNC_READ",
        }
    }

    pub fn parse(text: &str) -> Option<ReadMethod> {
        Some(match text.to_ascii_lowercase().replace('-', "_").as_str() {
            "auto" => ReadMethod::Auto,
            "read" => ReadMethod::Read,
            "bulk" | "bulk_read" => ReadMethod::BulkRead,
            "sync" | "sync_read" => ReadMethod::SyncRead,
            "fast" | "fast_sync_read" => ReadMethod::FastSyncRead,
            _ => return None,
        })
    }
}

/// What one cycle measured for one servo, raw (decoded) register values.
#[derive(Debug, Clone)]
pub struct ServoReading {
    pub position: i32,
    pub velocity: i32,
    /// Present Load (1.0, XL430, MX-28(2.0)) or Present Current (XM430, MX-64/106
    /// (2.0)); [`ControlCycle::effort_register`] says which.
    pub effort: i32,
    /// Whether this cycle's values are valid, and any condition the servo reported.
    pub outcome: Outcome,
}

impl Default for ServoReading {
    fn default() -> ServoReading {
        ServoReading {
            position: 0,
            velocity: 0,
            effort: 0,
            outcome: Err(LinkError::Timeout { id: 0 }),
        }
    }
}

/// Counts of one cycle.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CycleSummary {
    pub ok: usize,
    pub failed: usize,
}

/// A cycle that cannot be built.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CycleError(pub String);

impl fmt::Display for CycleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CycleError {}

/// Servos read and written together: one protocol and one register layout (a 1.0
/// group of X servos set to Protocol 1.0 keeps the X addresses).
struct Group {
    protocol: Protocol,
    method: ReadMethod,
    /// Indices into the cycle's servo list.
    members: Vec<usize>,
    ids: Vec<u8>,
    goal_address: u16,
    goal_size: u16,
    block_address: u16,
    block_len: u16,
}

/// Per-servo registers within the read block.
struct Layout {
    position: Register,
    velocity: Register,
    effort: Register,
}

pub struct ControlCycle {
    servos: Vec<CycleServo>,
    layouts: Vec<Layout>,
    groups: Vec<Group>,
    goal_buf: Vec<u8>,
    read_buf: Vec<u8>,
    /// The second copy of a verified read.
    verify_buf: Vec<u8>,
    outcomes: Vec<Outcome>,
    bulk: Vec<BulkRead>,
    /// Discard values outside their register's range (one re-read first). On by
    /// default; off only to measure what the checksum alone lets through.
    pub range_checks: bool,
    /// Protocol 1.0 verified reads: read each 1.0 servo again and accept only when
    /// two consecutive replies agree byte for byte (up to `retries` extra reads).
    /// The 8-bit checksum passes every damage whose byte sum is a multiple of 256
    /// (a data bit and the same checksum bit flipped the opposite way, or two
    /// bytes' bit 7 flipped alike); two independent replies damaged identically
    /// are what is left. It costs a second round trip per servo, and a servo moving
    /// between the two reads fails verification until it agrees. Off by default.
    pub verify_v1: bool,
}

/// The register block every cycle reads, by the protocol of the model's table: 1.0
/// Present Position..Present Load (36..42), 2.0 Present Current/Load..Present
/// Position (126..136, within a 1.0 packet's one-byte addresses too).
fn block(table: Protocol) -> (u16, u16) {
    match table {
        Protocol::V1 => (36, 6),
        Protocol::V2 => (126, 10),
    }
}

impl ControlCycle {
    /// Lay out the cycle for `servos` (in joint order). `method` applies to every
    /// group it suits; an explicit method a servo lacks is an error naming it.
    pub fn new(servos: &[CycleServo], method: ReadMethod) -> Result<ControlCycle, CycleError> {
        let mut layouts = Vec::with_capacity(servos.len());
        for s in servos {
            let t = s.model.table();
            let get = |item| {
                t.item(item).copied().ok_or_else(|| {
                    CycleError(format!("servo id {}: {} has no {item:?}", s.id, s.model))
                })
            };
            let effort = t
                .item(Item::PresentLoad)
                .filter(|r| r.address >= block(s.model.protocol()).0)
                .or_else(|| t.item(Item::PresentCurrent))
                .copied()
                .ok_or_else(|| CycleError(format!("servo id {}: no load register", s.id)))?;
            layouts.push(Layout {
                position: get(Item::PresentPosition)?,
                velocity: get(Item::PresentVelocity)?,
                effort,
            });
        }
        for (k, a) in servos.iter().enumerate() {
            if !a.model.speaks(a.protocol) {
                return Err(CycleError(format!(
                    "servo id {}: {} cannot talk {}",
                    a.id, a.model, a.protocol
                )));
            }
            if let Some(b) = servos[..k]
                .iter()
                .find(|b| b.id == a.id && b.protocol == a.protocol)
            {
                return Err(CycleError(format!(
                    "servo id {} appears twice ({} and {}) on {}",
                    a.id, b.model, a.model, a.protocol
                )));
            }
        }
        let mut groups = Vec::new();
        let kinds = [
            (Protocol::V1, Protocol::V1),
            (Protocol::V1, Protocol::V2),
            (Protocol::V2, Protocol::V2),
        ];
        for (protocol, table) in kinds {
            let members: Vec<usize> = (0..servos.len())
                .filter(|&i| servos[i].protocol == protocol && servos[i].model.protocol() == table)
                .collect();
            if members.is_empty() {
                continue;
            }
            let models: Vec<&CycleServo> = members.iter().map(|&i| &servos[i]).collect();
            let lacking =
                |has: fn(ServoModel) -> bool| models.iter().find(|s| !has(s.model)).copied();
            let chosen = match method {
                ReadMethod::Auto => match protocol {
                    Protocol::V2 if lacking(ServoModel::has_fast_sync_read).is_none() => {
                        ReadMethod::FastSyncRead
                    }
                    Protocol::V2 => ReadMethod::SyncRead,
                    Protocol::V1
                        if lacking(ServoModel::has_bulk_read).is_none() && models.len() > 1 =>
                    {
                        ReadMethod::BulkRead
                    }
                    Protocol::V1 => ReadMethod::Read,
                },
                m => {
                    // SYNC_READ and FAST_SYNC_READ are 2.0 instructions (EM-P1 has
                    // neither), whatever the model.
                    let never = |_: ServoModel| false;
                    let v2 = protocol == Protocol::V2;
                    let check: Option<fn(ServoModel) -> bool> = match m {
                        ReadMethod::BulkRead => Some(ServoModel::has_bulk_read),
                        ReadMethod::SyncRead if v2 => Some(ServoModel::has_sync_read),
                        ReadMethod::FastSyncRead if v2 => Some(ServoModel::has_fast_sync_read),
                        ReadMethod::SyncRead | ReadMethod::FastSyncRead => Some(never),
                        _ => None,
                    };
                    if let Some(has) = check
                        && let Some(s) = lacking(has)
                    {
                        return Err(CycleError(format!(
                            "servo id {} ({}, {}) has no {}",
                            s.id,
                            s.model,
                            protocol,
                            m.name()
                        )));
                    }
                    m
                }
            };
            let goal = servos[members[0]]
                .model
                .table()
                .item(Item::GoalPosition)
                .copied()
                .ok_or_else(|| CycleError("no goal position register".into()))?;
            let (block_address, block_len) = block(table);
            groups.push(Group {
                protocol,
                method: chosen,
                ids: members.iter().map(|&i| servos[i].id).collect(),
                members,
                goal_address: goal.address,
                goal_size: goal.size as u16,
                block_address,
                block_len,
            });
        }
        let n = servos.len();
        Ok(ControlCycle {
            servos: servos.to_vec(),
            layouts,
            groups,
            goal_buf: Vec::with_capacity(n * 4),
            read_buf: vec![0; n * 10],
            verify_buf: vec![0; 10],
            range_checks: true,
            verify_v1: false,
            outcomes: vec![Err(LinkError::Timeout { id: 0 }); n],
            bulk: Vec::with_capacity(n),
        })
    }

    pub fn servos(&self) -> &[CycleServo] {
        &self.servos
    }

    /// The read method chosen for the servos of `protocol`, if any are present.
    pub fn method(&self, protocol: Protocol) -> Option<ReadMethod> {
        self.groups
            .iter()
            .find(|g| g.protocol == protocol)
            .map(|g| g.method)
    }

    /// The registers the readings of servo `index` decode with (for SI units).
    pub fn position_register(&self, index: usize) -> &Register {
        &self.layouts[index].position
    }

    pub fn velocity_register(&self, index: usize) -> &Register {
        &self.layouts[index].velocity
    }

    pub fn effort_register(&self, index: usize) -> &Register {
        &self.layouts[index].effort
    }

    /// The goal position register of servo `index`.
    pub fn goal_register(&self, index: usize) -> Register {
        *self.servos[index]
            .model
            .table()
            .item(Item::GoalPosition)
            .expect("checked in new")
    }

    /// One cycle: SYNC_WRITE `goals` (raw, servo order; `None` writes nothing), then
    /// read every servo into `readings`. Only a dead link is an `Err`; each servo's
    /// own trouble is in its reading's outcome.
    pub fn run<T: Transport>(
        &mut self,
        client: &mut Client<T>,
        goals: Option<&[i32]>,
        readings: &mut [ServoReading],
    ) -> Result<CycleSummary, LinkError> {
        if let Some(goals) = goals {
            self.write_goals(client, goals)?;
        }
        self.read(client, readings)
    }

    /// SYNC_WRITE raw goal positions (servo order), one packet per protocol; each
    /// value is clamped to its register's range.
    pub fn write_goals<T: Transport>(
        &mut self,
        client: &mut Client<T>,
        goals: &[i32],
    ) -> Result<(), LinkError> {
        assert_eq!(goals.len(), self.servos.len());
        for g in &self.groups {
            self.goal_buf.clear();
            for &i in &g.members {
                let reg = self.servos[i]
                    .model
                    .table()
                    .item(Item::GoalPosition)
                    .expect("checked in new");
                let mut b = [0u8; 4];
                reg.encode(goals[i].clamp(reg.min, reg.max), &mut b);
                self.goal_buf.extend_from_slice(&b[..g.goal_size as usize]);
            }
            client.sync_write(
                g.protocol,
                g.goal_address,
                g.goal_size,
                &g.ids,
                &self.goal_buf,
            )?;
        }
        Ok(())
    }

    /// Read every servo's position, velocity and load or current into `readings`
    /// (servo order).
    pub fn read<T: Transport>(
        &mut self,
        client: &mut Client<T>,
        readings: &mut [ServoReading],
    ) -> Result<CycleSummary, LinkError> {
        assert_eq!(readings.len(), self.servos.len());
        let mut summary = CycleSummary::default();
        for g in &self.groups {
            let l = g.block_len as usize;
            let n = g.members.len();
            let buf = &mut self.read_buf[..n * l];
            let outcomes = &mut self.outcomes[..n];
            match g.method {
                ReadMethod::FastSyncRead => {
                    client.fast_sync_read(g.block_address, g.block_len, &g.ids, buf, outcomes)?
                }
                ReadMethod::SyncRead => {
                    client.sync_read(g.block_address, g.block_len, &g.ids, buf, outcomes)?
                }
                ReadMethod::BulkRead => {
                    self.bulk.clear();
                    self.bulk.extend(g.ids.iter().map(|&id| BulkRead {
                        id,
                        address: g.block_address,
                        len: g.block_len,
                    }));
                    client.bulk_read(g.protocol, &self.bulk, buf, outcomes)?
                }
                ReadMethod::Read | ReadMethod::Auto => {
                    for (k, &id) in g.ids.iter().enumerate() {
                        outcomes[k] = client.read(
                            g.protocol,
                            id,
                            g.block_address,
                            &mut buf[k * l..(k + 1) * l],
                        );
                        if let Err(LinkError::Io(e)) = &outcomes[k] {
                            return Err(LinkError::Io(e.clone()));
                        }
                    }
                }
            }
            for (k, &i) in g.members.iter().enumerate() {
                let id = g.ids[k];
                let lay = &self.layouts[i];
                let mut outcome =
                    std::mem::replace(&mut self.outcomes[k], Ok(StatusError::new(g.protocol, 0)));
                // Plausibility: a value outside its register's range passed the
                // checksum by chance; re-read it once rather than accept it.
                for attempt in 0..2 {
                    if outcome.is_err() || !self.range_checks {
                        break;
                    }
                    let data = &self.read_buf[k * l..(k + 1) * l];
                    let Some(bad) = implausible(lay, g.block_address, data) else {
                        break;
                    };
                    outcome = Err(LinkError::Implausible { id, register: bad });
                    client.stats.implausible += 1;
                    if attempt == 0 && client.config.retries > 0 {
                        outcome = client.read(
                            g.protocol,
                            id,
                            g.block_address,
                            &mut self.read_buf[k * l..(k + 1) * l],
                        );
                    }
                }
                if self.verify_v1 && g.protocol == Protocol::V1 && outcome.is_ok() {
                    outcome = verify(
                        client,
                        id,
                        g.block_address,
                        &mut self.read_buf[k * l..(k + 1) * l],
                        &mut self.verify_buf[..l],
                        outcome,
                    );
                    if self.range_checks
                        && outcome.is_ok()
                        && let Some(bad) =
                            implausible(lay, g.block_address, &self.read_buf[k * l..(k + 1) * l])
                    {
                        client.stats.implausible += 1;
                        outcome = Err(LinkError::Implausible { id, register: bad });
                    }
                }
                let data = &self.read_buf[k * l..(k + 1) * l];
                let r = &mut readings[i];
                if outcome.is_ok() {
                    let field = |reg: &Register| {
                        let o = (reg.address - g.block_address) as usize;
                        reg.decode(&data[o..o + reg.size as usize])
                    };
                    r.position = field(&lay.position);
                    r.velocity = field(&lay.velocity);
                    r.effort = field(&lay.effort);
                    summary.ok += 1;
                } else {
                    summary.failed += 1;
                }
                r.outcome = outcome;
            }
        }
        Ok(summary)
    }
}

/// Verified read of a 1.0 servo whose block `data` was just read (`first` its
/// outcome): read again into `spare` until two consecutive replies agree, at most
/// 1 + `retries` more reads. The agreed copy ends in `data`.
fn verify<T: Transport>(
    client: &mut Client<T>,
    id: u8,
    address: u16,
    data: &mut [u8],
    spare: &mut [u8],
    first: Outcome,
) -> Outcome {
    let mut last = first;
    let mut have = true;
    for _ in 0..=client.config.retries {
        let r = client.read(Protocol::V1, id, address, spare);
        if let Err(LinkError::Io(_)) = &r {
            return r;
        }
        match r {
            Ok(status) if have && spare == &*data => return Ok(status),
            Ok(status) => {
                data.copy_from_slice(spare);
                last = Ok(status);
                have = true;
            }
            Err(e) => {
                last = Err(e);
                have = false;
            }
        }
    }
    match last {
        Err(LinkError::Io(e)) => Err(LinkError::Io(e)),
        _ => Err(LinkError::Unverified { id }),
    }
}

/// The name of the first register in `data` (the read block at `base`) whose value
/// no healthy servo reports.
fn implausible(lay: &Layout, base: u16, data: &[u8]) -> Option<&'static str> {
    [&lay.position, &lay.velocity, &lay.effort]
        .into_iter()
        .find(|r| {
            let o = (r.address - base) as usize;
            !r.plausible(&data[o..o + r.size as usize])
        })
        .map(|r| r.name)
}
