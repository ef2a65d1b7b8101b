//! The host side: ping and scan, read and write registers, the group instructions,
//! reboot; every exchange checked (checksum, id, length, plausibility) and retried
//! within a bound when bytes were lost or damaged.
//!
//! One request is encoded into a reusable buffer, replies are decoded from the
//! transport straight into the decoder's fixed buffer, and data is copied into
//! slices the caller owns: no exchange allocates once the client is warm.

use crate::crc16::crc16_update;
use crate::decoder::{Accept, Decoder, Frame};
use crate::instruction::Instruction;
use crate::link_error::{LinkError, Outcome};
use crate::packet::PacketWriter;
use crate::protocol::{BROADCAST_ID, Protocol};
use crate::servo_model::ServoModel;
use crate::status_error::StatusError;
use crate::transport::Transport;
use std::ops::RangeInclusive;
use std::time::{Duration, Instant};

/// How patient and how persistent the client is.
#[derive(Debug, Clone)]
pub struct ClientConfig {
    /// Allowance per reply on top of its wire time: USB adapter latency, the
    /// servo's Return Delay Time (500 us by default) and processing.
    pub latency: Duration,
    /// Extra attempts after a lost or damaged reply (0 = no retry).
    pub retries: u32,
    /// Bit rate used for wire-time allowances when the transport has none.
    pub baud: u32,
    /// Whether servos answer WRITE / REG_WRITE / ACTION / REBOOT (Status Return
    /// Level 2, the factory setting). With level 0 or 1 set this to false.
    pub write_replies: bool,
}

impl Default for ClientConfig {
    fn default() -> ClientConfig {
        ClientConfig {
            latency: Duration::from_millis(10),
            retries: 2,
            baud: 1_000_000,
            write_replies: true,
        }
    }
}

/// Counters over the client's life.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ClientStats {
    /// Requests sent (retries included).
    pub requests: u64,
    pub retries: u64,
    pub timeouts: u64,
    pub corrupt: u64,
    pub wrong_replies: u64,
    pub implausible: u64,
    pub rejected: u64,
    /// Valid packets that answered no request being waited for (another servo's,
    /// the wrong length, a late reply to a request given up): dropped.
    pub discarded: u64,
    /// Bytes dropped from the input before a request (late replies of an earlier,
    /// failed exchange), so that none is taken for the new request's reply.
    pub stale_bytes: u64,
}

/// A servo found by ping or scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FoundServo {
    pub protocol: Protocol,
    pub id: u8,
    pub model_number: u16,
    pub firmware: u8,
    /// The model, when twinloop knows the number.
    pub model: Option<ServoModel>,
}

/// One servo's part of a BULK_READ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BulkRead {
    pub id: u8,
    pub address: u16,
    pub len: u16,
}

/// What a reply must look like to be accepted.
#[derive(Clone, Copy)]
enum Expect {
    /// A normal status packet from `id` with exactly `len` data bytes.
    Status { id: u8, len: usize },
    /// A FAST_SYNC_READ reply (id 0xFE) of `total` bytes on the wire.
    Fast { total: usize },
}

/// The host-side client over any [`Transport`].
pub struct Client<T: Transport> {
    transport: T,
    tx: Vec<u8>,
    /// Data of the last accepted reply (or the raw packet of a fast reply).
    rx: Vec<u8>,
    decoder: Decoder,
    pub config: ClientConfig,
    pub stats: ClientStats,
    /// An exchange failed or a packet was dropped since the last request: the input
    /// may hold late replies, so it is emptied before the next request goes out.
    dirty: bool,
    /// The address and length the request being exchanged names (READ, WRITE),
    /// for the message of a servo that rejects it.
    register: Option<(u16, u16)>,
}

impl<T: Transport> Client<T> {
    pub fn new(transport: T) -> Client<T> {
        Client::with_config(transport, ClientConfig::default())
    }

    pub fn with_config(transport: T, config: ClientConfig) -> Client<T> {
        Client {
            transport,
            tx: Vec::with_capacity(1024),
            rx: Vec::with_capacity(8192),
            decoder: Decoder::new(Accept::Both),
            config,
            stats: ClientStats::default(),
            dirty: false,
            register: None,
        }
    }

    pub fn transport(&self) -> &T {
        &self.transport
    }

    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    pub fn into_transport(self) -> T {
        self.transport
    }

    fn baud(&self) -> u32 {
        self.transport.baud().unwrap_or(self.config.baud).max(1)
    }

    /// Time `bytes` take on the wire (8N1: 10 bits per byte).
    pub fn wire_time(&self, bytes: usize) -> Duration {
        Duration::from_nanos((bytes as u64 * 10 * 1_000_000_000) / self.baud() as u64)
    }

    fn reply_timeout(&self, reply_bytes: usize) -> Duration {
        self.config.latency + self.wire_time(self.tx.len() + reply_bytes)
    }

    /// Send `self.tx`, first dropping whatever a failed exchange may have left in
    /// the input (as the ROBOTIS SDK's txPacket clears the port before every
    /// request, protocol1_packet_handler.py): a late reply to a request given up
    /// is never taken for this request's.
    fn send(&mut self) -> Result<(), LinkError> {
        if self.dirty {
            self.recover()?;
        }
        self.stats.requests += 1;
        self.transport.write_all(&self.tx)?;
        Ok(())
    }

    /// Drop what is buffered, counting it.
    fn recover(&mut self) -> Result<(), LinkError> {
        let buffered = self.decoder.buffered();
        self.decoder.clear();
        let dropped = self.transport.discard_input()?;
        self.stats.stale_bytes += (buffered + dropped) as u64;
        self.dirty = false;
        Ok(())
    }

    fn count(&mut self, e: &LinkError) {
        if e.is_transient() {
            self.dirty = true;
        }
        match e {
            LinkError::Timeout { .. } => self.stats.timeouts += 1,
            LinkError::Corrupt { .. } => self.stats.corrupt += 1,
            LinkError::WrongReply { .. } => self.stats.wrong_replies += 1,
            LinkError::Implausible { .. } => self.stats.implausible += 1,
            LinkError::Rejected { .. } => self.stats.rejected += 1,
            _ => {}
        }
    }

    /// Wait for the reply `expect` describes; its data (or raw packet, for a fast
    /// reply) lands in `self.rx`.
    fn receive(&mut self, protocol: Protocol, expect: Expect, timeout: Duration) -> Outcome {
        let id = match expect {
            Expect::Status { id, .. } => id,
            Expect::Fast { .. } => BROADCAST_ID,
        };
        let deadline = Instant::now() + timeout;
        let damage_before = self.damage_seen();
        let mut wrong: Option<LinkError> = None;
        let mut flushing = false;
        loop {
            loop {
                let frame = if flushing {
                    self.decoder.next_frame_flushing()
                } else {
                    self.decoder.next_frame()
                };
                let Some(f) = frame else { break };
                if f.raw == &self.tx[..] {
                    // Our own request echoed by the adapter.
                    continue;
                }
                match judge(&f, protocol, expect, id) {
                    Verdict::Foreign => {
                        self.stats.discarded += 1;
                        self.dirty = true;
                        continue;
                    }
                    Verdict::Wrong(e) => {
                        self.stats.discarded += 1;
                        wrong = Some(e);
                        continue;
                    }
                    Verdict::Rejected(status) => {
                        // A refusal carries no data, whatever length was asked.
                        return Err(LinkError::Rejected {
                            id,
                            error: status,
                            register: self.register,
                        });
                    }
                    Verdict::Accept(status, bytes) => {
                        self.rx.clear();
                        self.rx.extend_from_slice(bytes);
                        if wrong.is_some() {
                            // Something that did not belong came first: drop the rest
                            // before the next request.
                            self.dirty = true;
                        }
                        return Ok(status);
                    }
                }
            }
            if flushing {
                let err = wrong.unwrap_or(if self.damage_seen() != damage_before {
                    LinkError::Corrupt { id }
                } else {
                    LinkError::Timeout { id }
                });
                return Err(err);
            }
            // Past the deadline this is a zero wait: one last look at what already
            // arrived. (A host descheduled past its deadline must still read the
            // reply sitting in the buffer rather than call it lost.)
            let now = Instant::now();
            let late = now >= deadline;
            let spare = self.decoder.spare();
            let n = self
                .transport
                .read(spare, deadline.saturating_duration_since(now))?;
            self.decoder.commit(n);
            if n == 0 || late {
                // Transports return 0 only when the wait ran out; late, the look
                // was the last one.
                flushing = true;
            }
        }
    }

    fn damage_seen(&self) -> u64 {
        let s = self.decoder.stats();
        s.bad_checksums + s.skipped_bytes
    }

    /// Send `self.tx` and wait for one status packet, retrying transient failures.
    fn exchange(&mut self, protocol: Protocol, id: u8, len: usize) -> Outcome {
        let mut attempt = 0;
        loop {
            self.send()?;
            let timeout = self.reply_timeout(protocol.status_overhead() + len);
            let r = self.receive(protocol, Expect::Status { id, len }, timeout);
            match &r {
                Err(e) => {
                    // `count` marks the input for emptying before the next request.
                    self.count(e);
                    if e.is_transient() && attempt < self.config.retries {
                        attempt += 1;
                        self.stats.retries += 1;
                        continue;
                    }
                    return r;
                }
                Ok(_) => {
                    // After a retry the reply to the attempt given up may still be
                    // on its way: the next request starts from an empty input.
                    self.dirty |= attempt > 0 || self.decoder.buffered() > 0;
                    return r;
                }
            }
        }
    }

    fn begin(&mut self, protocol: Protocol, id: u8, instruction: Instruction) -> PacketWriter<'_> {
        self.tx.clear();
        self.register = None;
        PacketWriter::instruction(&mut self.tx, protocol, id, instruction)
    }

    /// PING one servo; 1.0 servos then get a READ of model number and firmware
    /// (a 1.0 ping reply carries no data).
    pub fn ping(&mut self, protocol: Protocol, id: u8) -> Result<FoundServo, LinkError> {
        self.begin(protocol, id, Instruction::Ping).finish()?;
        let (model_number, firmware) = match protocol {
            Protocol::V2 => {
                self.exchange(protocol, id, 3)?;
                (u16::from_le_bytes([self.rx[0], self.rx[1]]), self.rx[2])
            }
            Protocol::V1 => {
                self.exchange(protocol, id, 0)?;
                let mut b = [0u8; 3];
                self.read(protocol, id, 0, &mut b)?;
                (u16::from_le_bytes([b[0], b[1]]), b[2])
            }
        };
        Ok(FoundServo {
            protocol,
            id,
            model_number,
            firmware,
            model: ServoModel::from_model_number(model_number),
        })
    }

    /// Protocol 2.0 broadcast PING: every servo answers in turn; listen for
    /// `listen` and return who answered, in id order.
    pub fn broadcast_ping(&mut self, listen: Duration) -> Result<Vec<FoundServo>, LinkError> {
        self.begin(Protocol::V2, BROADCAST_ID, Instruction::Ping)
            .finish()?;
        self.send()?;
        let deadline = Instant::now() + listen;
        let mut found = Vec::new();
        loop {
            while let Some(f) = self.decoder.next_frame() {
                if f.protocol == Protocol::V2
                    && f.instruction == Instruction::Status.code()
                    && f.params.len() == 4
                    && f.id <= Protocol::V2.max_id()
                {
                    let model_number = u16::from_le_bytes([f.params[1], f.params[2]]);
                    found.push(FoundServo {
                        protocol: Protocol::V2,
                        id: f.id,
                        model_number,
                        firmware: f.params[3],
                        model: ServoModel::from_model_number(model_number),
                    });
                }
            }
            let now = Instant::now();
            if now >= deadline {
                break;
            }
            let spare = self.decoder.spare();
            let n = self.transport.read(spare, deadline - now)?;
            self.decoder.commit(n);
            if n == 0 {
                break;
            }
        }
        while let Some(f) = self.decoder.next_frame_flushing() {
            let _ = f;
        }
        found.sort_by_key(|s| s.id);
        found.dedup_by_key(|s| s.id);
        Ok(found)
    }

    /// Find the servos on the bus: for 2.0 a broadcast ping (then single pings of
    /// the ids in range if nobody answered it), for 1.0 a ping per id. Returns
    /// what answered, in id order.
    pub fn scan(
        &mut self,
        protocol: Protocol,
        ids: RangeInclusive<u8>,
    ) -> Result<Vec<FoundServo>, LinkError> {
        self.scan_with_progress(protocol, ids, |_| {})
    }

    /// [`Client::scan`], calling `progress(id)` before each single ping (a 1.0
    /// scan pings 254 ids one by one: seconds with nothing to show otherwise).
    pub fn scan_with_progress(
        &mut self,
        protocol: Protocol,
        ids: RangeInclusive<u8>,
        progress: impl FnMut(u8),
    ) -> Result<Vec<FoundServo>, LinkError> {
        let ids: Vec<u8> = (*ids.start()..=(*ids.end()).min(protocol.max_id())).collect();
        self.scan_ids_with_progress(protocol, &ids, progress)
    }

    /// [`Client::scan_with_progress`] of exactly the ids in `ids` (a list such as
    /// `1,200` pings those two, not the span between them); ids past the
    /// protocol's last are skipped.
    pub fn scan_ids_with_progress(
        &mut self,
        protocol: Protocol,
        ids: &[u8],
        mut progress: impl FnMut(u8),
    ) -> Result<Vec<FoundServo>, LinkError> {
        let ids: Vec<u8> = ids
            .iter()
            .copied()
            .filter(|&id| id <= protocol.max_id())
            .collect();
        if protocol == Protocol::V2 {
            // The SDK's window: 14 bytes per possible servo plus 3 ms each, + 16 ms.
            let listen = self.wire_time(14 * 253)
                + Duration::from_millis(3 * 253 + 16).min(self.config.latency * 80);
            let found = self.broadcast_ping(listen)?;
            let found: Vec<FoundServo> =
                found.into_iter().filter(|s| ids.contains(&s.id)).collect();
            if !found.is_empty() {
                return Ok(found);
            }
        }
        let retries = std::mem::replace(&mut self.config.retries, 0);
        let late = |s: &ClientStats| s.discarded + s.stale_bytes + s.corrupt + s.wrong_replies;
        let before = late(&self.stats);
        let mut found = Vec::new();
        let mut result = self.ping_each(protocol, &ids, &mut found, &mut progress);
        // A reply that came too late (a busy bus or a loaded served robot) is dropped
        // as stale and its servo looks absent: when the pass saw any, the ids that did
        // not answer are asked once more. Without that sign, only a lone gap between
        // two ids that answered is (a humanoid numbers its servos in a row, and a
        // reply lost whole leaves no stale bytes). A quiet bus with absent ids costs
        // nothing.
        if result.is_ok() {
            let any_late = late(&self.stats) > before;
            let answered = |id: u8| found.iter().any(|s| s.id == id);
            let missing: Vec<u8> = ids
                .iter()
                .copied()
                .filter(|&id| !answered(id))
                .filter(|&id| {
                    any_late || (id > 0 && answered(id - 1) && id < u8::MAX && answered(id + 1))
                })
                .collect();
            if !missing.is_empty() {
                result = self.ping_each(protocol, &missing, &mut found, &mut progress);
                found.sort_by_key(|s| s.id);
            }
        }
        self.config.retries = retries;
        result.map(|_| found)
    }

    /// Ping each of `ids` once, adding who answers to `found`; only a failing port
    /// stops the pass.
    fn ping_each(
        &mut self,
        protocol: Protocol,
        ids: &[u8],
        found: &mut Vec<FoundServo>,
        progress: &mut impl FnMut(u8),
    ) -> Result<(), LinkError> {
        for &id in ids {
            progress(id);
            match self.ping(protocol, id) {
                Ok(s) => found.push(s),
                Err(LinkError::Io(e)) => return Err(LinkError::Io(e)),
                Err(_) => {}
            }
        }
        Ok(())
    }

    /// READ `out.len()` bytes from `address`.
    pub fn read(&mut self, protocol: Protocol, id: u8, address: u16, out: &mut [u8]) -> Outcome {
        let mut w = self.begin(protocol, id, Instruction::Read);
        w.address(address).address(out.len() as u16);
        w.finish()?;
        self.register = Some((address, out.len() as u16));
        let status = self.exchange(protocol, id, out.len())?;
        out.copy_from_slice(&self.rx);
        Ok(status)
    }

    fn write_like(
        &mut self,
        protocol: Protocol,
        instruction: Instruction,
        id: u8,
        address: u16,
        data: &[u8],
    ) -> Outcome {
        let mut w = self.begin(protocol, id, instruction);
        w.address(address).bytes(data);
        w.finish()?;
        self.register = Some((address, data.len() as u16));
        self.finish_command(protocol, id)
    }

    /// Send the encoded command; wait for its status unless broadcast or the
    /// servos are set not to answer.
    fn finish_command(&mut self, protocol: Protocol, id: u8) -> Outcome {
        if id == BROADCAST_ID || !self.config.write_replies {
            self.send()?;
            return Ok(StatusError::new(protocol, 0));
        }
        self.exchange(protocol, id, 0)
    }

    /// WRITE `data` at `address`.
    pub fn write(&mut self, protocol: Protocol, id: u8, address: u16, data: &[u8]) -> Outcome {
        self.write_like(protocol, Instruction::Write, id, address, data)
    }

    /// REG_WRITE: stage a write, executed at the next ACTION.
    pub fn reg_write(&mut self, protocol: Protocol, id: u8, address: u16, data: &[u8]) -> Outcome {
        self.write_like(protocol, Instruction::RegWrite, id, address, data)
    }

    /// ACTION: execute staged REG_WRITEs (usually broadcast).
    pub fn action(&mut self, protocol: Protocol, id: u8) -> Outcome {
        self.begin(protocol, id, Instruction::Action).finish()?;
        self.finish_command(protocol, id)
    }

    /// REBOOT (Protocol 2.0 only; 1.0 servos have no such instruction).
    pub fn reboot(&mut self, protocol: Protocol, id: u8) -> Outcome {
        self.begin(protocol, id, Instruction::Reboot).finish()?;
        self.finish_command(protocol, id)
    }

    /// CLEAR (Protocol 2.0): reset the multi-turn count of Present Position to within
    /// one turn; refused with Result Fail while the servo moves (EM-P2 "Clear").
    pub fn clear_multi_turn(&mut self, id: u8) -> Outcome {
        let mut w = self.begin(Protocol::V2, id, Instruction::Clear);
        w.bytes(&[0x01, 0x44, 0x58, 0x4C, 0x22]);
        w.finish()?;
        self.finish_command(Protocol::V2, id)
    }

    /// FACTORY_RESET. `option` (2.0 only): 0xFF all, 0x01 all but id, 0x02 all but
    /// id and baud rate.
    pub fn factory_reset(&mut self, protocol: Protocol, id: u8, option: u8) -> Outcome {
        let mut w = self.begin(protocol, id, Instruction::FactoryReset);
        if protocol == Protocol::V2 {
            w.u8(option);
        }
        w.finish()?;
        self.finish_command(protocol, id)
    }

    /// SYNC_WRITE `len` bytes at `address` to each of `ids`; `data` holds
    /// `ids.len() * len` bytes in id order. No servo answers.
    pub fn sync_write(
        &mut self,
        protocol: Protocol,
        address: u16,
        len: u16,
        ids: &[u8],
        data: &[u8],
    ) -> Result<(), LinkError> {
        debug_assert_eq!(data.len(), ids.len() * len as usize);
        let mut w = self.begin(protocol, BROADCAST_ID, Instruction::SyncWrite);
        w.address(address).address(len);
        for (k, &id) in ids.iter().enumerate() {
            w.u8(id)
                .bytes(&data[k * len as usize..(k + 1) * len as usize]);
        }
        w.finish()?;
        self.send()
    }

    /// BULK_WRITE (Protocol 2.0): each item its own address and data.
    pub fn bulk_write(&mut self, items: &[(u8, u16, &[u8])]) -> Result<(), LinkError> {
        let mut w = self.begin(Protocol::V2, BROADCAST_ID, Instruction::BulkWrite);
        for (id, address, data) in items {
            w.u8(*id).u16(*address).u16(data.len() as u16).bytes(data);
        }
        w.finish()?;
        self.send()
    }

    /// SYNC_READ (Protocol 2.0): `len` bytes at `address` from each of `ids`, into
    /// `out` (`ids.len() * len` bytes, id order); one outcome per id. Servos whose
    /// reply was lost are re-read one by one (bounded retries).
    pub fn sync_read(
        &mut self,
        address: u16,
        len: u16,
        ids: &[u8],
        out: &mut [u8],
        outcomes: &mut [Outcome],
    ) -> Result<(), LinkError> {
        let mut w = self.begin(Protocol::V2, BROADCAST_ID, Instruction::SyncRead);
        w.u16(address).u16(len).bytes(ids);
        w.finish()?;
        self.send()?;
        let l = len as usize;
        for (k, &id) in ids.iter().enumerate() {
            let timeout = self.reply_timeout(Protocol::V2.status_overhead() + l);
            let r = self.receive(Protocol::V2, Expect::Status { id, len: l }, timeout);
            if let Err(e) = &r {
                self.count(e);
            } else {
                out[k * l..(k + 1) * l].copy_from_slice(&self.rx);
            }
            outcomes[k] = r;
        }
        self.reread_failed(Protocol::V2, address, len, ids, out, outcomes)
    }

    /// FAST_SYNC_READ (Protocol 2.0): like [`Client::sync_read`] but all servos
    /// answer in one packet (`[ERR ID DATA CRC]` per servo, the SDK's fastSyncReadRxPacket). Each
    /// block's CRC is checked (cumulative from the packet's start), then its id.
    pub fn fast_sync_read(
        &mut self,
        address: u16,
        len: u16,
        ids: &[u8],
        out: &mut [u8],
        outcomes: &mut [Outcome],
    ) -> Result<(), LinkError> {
        let mut w = self.begin(Protocol::V2, BROADCAST_ID, Instruction::FastSyncRead);
        w.u16(address).u16(len).bytes(ids);
        w.finish()?;
        self.send()?;
        let l = len as usize;
        let total = 8 + ids.len() * (l + 4);
        let timeout = self.reply_timeout(total);
        match self.receive(Protocol::V2, Expect::Fast { total }, timeout) {
            Ok(_) => {
                let raw = &self.rx;
                let mut pos = 8;
                let mut broken = false;
                // Each block's CRC covers the packet up to it: one running CRC.
                let mut running = 0u16;
                let mut covered = 0;
                for (k, &id) in ids.iter().enumerate() {
                    let err = raw[pos];
                    let block_id = raw[pos + 1];
                    let crc_at = pos + 2 + l;
                    let crc = u16::from_le_bytes([raw[crc_at], raw[crc_at + 1]]);
                    running = crc16_update(running, &raw[covered..crc_at]);
                    covered = crc_at;
                    broken = broken || block_id != id || running != crc;
                    outcomes[k] = if broken {
                        Err(LinkError::Corrupt { id })
                    } else {
                        let status = StatusError::new(Protocol::V2, err);
                        if status.rejected_instruction() {
                            Err(LinkError::Rejected {
                                id,
                                error: status,
                                register: None,
                            })
                        } else {
                            out[k * l..(k + 1) * l].copy_from_slice(&raw[pos + 2..crc_at]);
                            Ok(status)
                        }
                    };
                    pos = crc_at + 2;
                }
                for o in outcomes.iter() {
                    if let Err(e) = o {
                        let e = e.clone();
                        self.count(&e);
                    }
                }
            }
            Err(e) => {
                self.count(&e);
                if let LinkError::Io(_) = e {
                    return Err(e);
                }
                for (k, &id) in ids.iter().enumerate() {
                    outcomes[k] = Err(match &e {
                        LinkError::Corrupt { .. } => LinkError::Corrupt { id },
                        LinkError::WrongReply { .. } => LinkError::Corrupt { id },
                        _ => LinkError::Timeout { id },
                    });
                }
            }
        }
        self.reread_failed(Protocol::V2, address, len, ids, out, outcomes)
    }

    /// BULK_READ: each item its own address and length; `out` holds the items'
    /// data back to back. In 1.0 only MX servos have it.
    pub fn bulk_read(
        &mut self,
        protocol: Protocol,
        items: &[BulkRead],
        out: &mut [u8],
        outcomes: &mut [Outcome],
    ) -> Result<(), LinkError> {
        let mut w = self.begin(protocol, BROADCAST_ID, Instruction::BulkRead);
        match protocol {
            Protocol::V1 => {
                w.u8(0x00);
                for it in items {
                    w.u8(it.len as u8).u8(it.id).u8(it.address as u8);
                }
            }
            Protocol::V2 => {
                for it in items {
                    w.u8(it.id).u16(it.address).u16(it.len);
                }
            }
        }
        w.finish()?;
        self.send()?;
        let mut offset = 0;
        for (k, it) in items.iter().enumerate() {
            let l = it.len as usize;
            let timeout = self.reply_timeout(protocol.status_overhead() + l);
            let r = self.receive(protocol, Expect::Status { id: it.id, len: l }, timeout);
            match &r {
                Err(e) => self.count(e),
                Ok(_) => out[offset..offset + l].copy_from_slice(&self.rx),
            }
            outcomes[k] = r;
            offset += l;
        }
        // Lost replies: one READ each (the input emptied before it).
        let mut offset = 0;
        for (k, it) in items.iter().enumerate() {
            let l = it.len as usize;
            if outcomes[k].as_ref().is_err_and(|e| e.is_transient()) {
                self.stats.retries += 1;
                outcomes[k] = self.read(protocol, it.id, it.address, &mut out[offset..offset + l]);
            }
            offset += l;
        }
        Ok(())
    }

    fn reread_failed(
        &mut self,
        protocol: Protocol,
        address: u16,
        len: u16,
        ids: &[u8],
        out: &mut [u8],
        outcomes: &mut [Outcome],
    ) -> Result<(), LinkError> {
        let l = len as usize;
        for (k, &id) in ids.iter().enumerate() {
            if outcomes[k].as_ref().is_err_and(|e| e.is_transient()) && self.config.retries > 0 {
                self.stats.retries += 1;
                outcomes[k] = self.read(protocol, id, address, &mut out[k * l..(k + 1) * l]);
                if let Err(LinkError::Io(e)) = &outcomes[k] {
                    return Err(LinkError::Io(e.clone()));
                }
            }
        }
        Ok(())
    }
}

/// What a frame that is not our own echo is to the request waiting for `id`.
enum Verdict<'a> {
    /// Another protocol's traffic, another servo's late reply, or not a status.
    Foreign,
    /// The right servo, but not the reply asked for.
    Wrong(LinkError),
    /// The servo refused the instruction.
    Rejected(StatusError),
    /// The reply: its status and the bytes kept (the data, or the whole packet for
    /// a FAST_SYNC_READ).
    Accept(StatusError, &'a [u8]),
}

/// Judge a received frame against what was asked.
fn judge<'a>(f: &Frame<'a>, protocol: Protocol, expect: Expect, id: u8) -> Verdict<'a> {
    if f.protocol != protocol || f.id != id {
        return Verdict::Foreign;
    }
    let (error, data): (u8, &[u8]) = match protocol {
        Protocol::V1 => (f.instruction, f.params),
        Protocol::V2 => {
            if f.instruction != Instruction::Status.code() || f.params.is_empty() {
                return Verdict::Foreign;
            }
            (f.params[0], &f.params[1..])
        }
    };
    if protocol == Protocol::V1 && error & 0x80 != 0 {
        // Bit 7 is always 0 in a real 1.0 status (EM-P1).
        return Verdict::Wrong(LinkError::Corrupt { id });
    }
    let status = StatusError::new(protocol, error);
    if status.rejected_instruction() && matches!(expect, Expect::Status { .. }) {
        return Verdict::Rejected(status);
    }
    let (kept, expected_len) = match expect {
        Expect::Status { len, .. } => (data, len),
        Expect::Fast { total } => (f.raw, total),
    };
    if kept.len() != expected_len {
        return Verdict::Wrong(LinkError::WrongReply {
            id,
            expected_len,
            got_len: kept.len(),
        });
    }
    Verdict::Accept(status, kept)
}
