//! A streaming packet decoder for both protocols that resynchronises after garbage,
//! a truncated packet or a bad checksum.
//!
//! Bytes go in as they arrive ([`Decoder::push`], or [`Decoder::spare`] +
//! [`Decoder::commit`] to read straight into its buffer); whole, checked frames come
//! out ([`Decoder::next_frame`]). A candidate header whose packet fails its checksum
//! costs one byte: scanning resumes at the next byte, so a real packet that started
//! inside the garbage is still found. The buffer is allocated once, at twice the
//! largest packet accepted; a LENGTH field above that limit rejects the header
//! instead of allocating.

use crate::crc16::{checksum_v1, crc16};
use crate::packet::{has_stuffing, unstuff_into};
use crate::protocol::Protocol;

/// Which protocols a decoder recognises. A bus may carry both: a 2.0 header
/// (`FF FF FD 00`) is never a valid 1.0 packet (id 0xFD with LENGTH 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Accept {
    V1,
    V2,
    Both,
}

impl Accept {
    pub fn only(protocol: Protocol) -> Accept {
        match protocol {
            Protocol::V1 => Accept::V1,
            Protocol::V2 => Accept::V2,
        }
    }

    fn v1(self) -> bool {
        matches!(self, Accept::V1 | Accept::Both)
    }

    fn v2(self) -> bool {
        matches!(self, Accept::V2 | Accept::Both)
    }
}

/// Default limit on one packet, in bytes on the wire. The SDK refuses LENGTH above
/// 1024; a fast sync read of 253 servos x 16 bytes needs about 5 kB.
pub const DEFAULT_MAX_PACKET: usize = 8192;

/// One checked packet. For a 2.0 status packet `instruction` is 0x55 and
/// `params[0]` the error byte; for a 1.0 packet `instruction` is the byte after
/// LENGTH, which is the error byte when a servo sent it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frame<'a> {
    pub protocol: Protocol,
    pub id: u8,
    pub instruction: u8,
    /// Parameters after un-stuffing.
    pub params: &'a [u8],
    /// The packet exactly as received (stuffed, with header and checksum).
    pub raw: &'a [u8],
}

/// What the decoder found next: a checked frame, or a candidate packet whose
/// checksum failed (a servo answers that with a checksum/CRC error status).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecodeEvent<'a> {
    Frame(Frame<'a>),
    BadChecksum {
        protocol: Protocol,
        id: u8,
        instruction: u8,
    },
}

/// Counters of what the decoder saw besides good frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DecoderStats {
    pub frames: u64,
    /// Bytes dropped while looking for a header.
    pub skipped_bytes: u64,
    /// Candidate packets whose checksum or CRC did not match.
    pub bad_checksums: u64,
    /// Headers rejected because LENGTH exceeded the limit.
    pub oversized: u64,
}

enum Candidate {
    NeedMore,
    Invalid,
    Packet { protocol: Protocol, total: usize },
}

/// The streaming decoder. See the module documentation.
pub struct Decoder {
    buf: Box<[u8]>,
    start: usize,
    end: usize,
    /// Bytes of the frame last returned, dropped on the next call.
    consumed: usize,
    accept: Accept,
    max_packet: usize,
    unstuffed: Vec<u8>,
    stats: DecoderStats,
}

impl Decoder {
    pub fn new(accept: Accept) -> Decoder {
        Decoder::with_max_packet(accept, DEFAULT_MAX_PACKET)
    }

    /// A decoder that rejects packets longer than `max_packet` bytes (at least 16).
    pub fn with_max_packet(accept: Accept, max_packet: usize) -> Decoder {
        let max_packet = max_packet.max(16);
        Decoder {
            buf: vec![0; 2 * max_packet].into_boxed_slice(),
            start: 0,
            end: 0,
            consumed: 0,
            accept,
            max_packet,
            unstuffed: Vec::with_capacity(max_packet),
            stats: DecoderStats::default(),
        }
    }

    pub fn accept(&self) -> Accept {
        self.accept
    }

    pub fn set_accept(&mut self, accept: Accept) {
        self.accept = accept;
    }

    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Bytes held that are not yet part of a returned frame.
    pub fn buffered(&self) -> usize {
        self.end - self.start - self.consumed.min(self.end - self.start)
    }

    /// Forget everything buffered.
    pub fn clear(&mut self) {
        self.start = 0;
        self.end = 0;
        self.consumed = 0;
    }

    fn drop_consumed(&mut self) {
        self.start += self.consumed;
        self.consumed = 0;
        if self.start == self.end {
            self.start = 0;
            self.end = 0;
        }
    }

    /// Free space to read into (compacting first); follow with [`Decoder::commit`].
    pub fn spare(&mut self) -> &mut [u8] {
        self.drop_consumed();
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        &mut self.buf[self.end..]
    }

    /// Mark `n` bytes written into [`Decoder::spare`] as received.
    pub fn commit(&mut self, n: usize) {
        self.end = (self.end + n).min(self.buf.len());
    }

    /// Copy in as many of `bytes` as fit; returns how many were taken. Call
    /// [`Decoder::next_frame`] until it returns `None`, then push the rest.
    pub fn push(&mut self, bytes: &[u8]) -> usize {
        let spare = self.spare();
        let n = spare.len().min(bytes.len());
        spare[..n].copy_from_slice(&bytes[..n]);
        self.commit(n);
        n
    }

    /// The next complete, checked frame, or `None` until more bytes arrive.
    pub fn next_frame(&mut self) -> Option<Frame<'_>> {
        match self.scan(false, false)? {
            DecodeEvent::Frame(f) => Some(f),
            DecodeEvent::BadChecksum { .. } => None,
        }
    }

    /// Like [`Decoder::next_frame`], but also stops at each candidate whose
    /// checksum failed, reporting its header fields (scanning then resumes one byte
    /// after its start).
    pub fn next_event(&mut self) -> Option<DecodeEvent<'_>> {
        self.scan(false, true)
    }

    /// Like [`Decoder::next_frame`], but for when the line has gone quiet: a packet
    /// still waiting for bytes is given up as truncated, and scanning continues
    /// after its first byte (a complete packet may start inside it). Repeat until
    /// `None`; the buffer is then empty.
    pub fn next_frame_flushing(&mut self) -> Option<Frame<'_>> {
        match self.scan(true, false)? {
            DecodeEvent::Frame(f) => Some(f),
            DecodeEvent::BadChecksum { .. } => None,
        }
    }

    fn classify(&mut self, s: &[u8]) -> Candidate {
        // s[0] == s[1] == 0xFF here.
        if s.len() < 3 {
            return Candidate::NeedMore;
        }
        if self.accept.v2() && s[2] == 0xFD {
            if s.len() < 4 {
                return Candidate::NeedMore;
            }
            if s[3] == 0x00 {
                if s.len() < 7 {
                    return Candidate::NeedMore;
                }
                let id = s[4];
                if id == 0xFD || id == 0xFF {
                    return Candidate::Invalid;
                }
                let length = u16::from_le_bytes([s[5], s[6]]) as usize;
                if length < 3 {
                    return Candidate::Invalid;
                }
                let total = 7 + length;
                if total > self.max_packet {
                    self.stats.oversized += 1;
                    return Candidate::Invalid;
                }
                return Candidate::Packet {
                    protocol: Protocol::V2,
                    total,
                };
            }
            // `FF FF FD FD` is stuffing, `FF FF FD xx` no 2.0 header; 1.0 may still
            // own it (id 0xFD).
        }
        if self.accept.v1() {
            if s.len() < 4 {
                return Candidate::NeedMore;
            }
            let id = s[2];
            let length = s[3] as usize;
            if id == 0xFF || length < 2 {
                return Candidate::Invalid;
            }
            let total = 4 + length;
            if total > self.max_packet {
                self.stats.oversized += 1;
                return Candidate::Invalid;
            }
            return Candidate::Packet {
                protocol: Protocol::V1,
                total,
            };
        }
        Candidate::Invalid
    }

    fn scan(&mut self, flushing: bool, report_bad: bool) -> Option<DecodeEvent<'_>> {
        self.drop_consumed();
        loop {
            let avail = self.end - self.start;
            let base = self.start;
            // Find the next 0xFF 0xFF.
            let Some(i) = self.buf[base..self.end].iter().position(|&b| b == 0xFF) else {
                self.stats.skipped_bytes += avail as u64;
                self.start = 0;
                self.end = 0;
                return None;
            };
            if i + 1 == avail {
                // A lone trailing 0xFF may begin a header.
                self.skip(i);
                if flushing {
                    self.skip(1);
                }
                return None;
            }
            if self.buf[base + i + 1] != 0xFF {
                self.skip(i + 1);
                continue;
            }
            // Copy out the window to classify without holding a borrow of self.
            let window_end = self.end.min(base + i + 7);
            let mut head = [0u8; 7];
            let head_len = window_end - (base + i);
            head[..head_len].copy_from_slice(&self.buf[base + i..window_end]);
            let candidate = self.classify(&head[..head_len]);
            let (protocol, total) = match candidate {
                Candidate::Invalid => {
                    self.skip(i + 1);
                    continue;
                }
                Candidate::NeedMore => {
                    self.skip(i);
                    if flushing {
                        self.skip(1);
                        continue;
                    }
                    return None;
                }
                Candidate::Packet { protocol, total } => (protocol, total),
            };
            if i + total > avail {
                self.skip(i);
                if flushing {
                    self.skip(1);
                    continue;
                }
                return None;
            }
            let p = base + i;
            let packet = &self.buf[p..p + total];
            let ok = match protocol {
                Protocol::V1 => checksum_v1(&packet[2..total - 1]) == packet[total - 1],
                Protocol::V2 => {
                    crc16(&packet[..total - 2])
                        == u16::from_le_bytes([packet[total - 2], packet[total - 1]])
                }
            };
            if !ok {
                self.stats.bad_checksums += 1;
                let (id, instruction) = match protocol {
                    Protocol::V1 => (packet[2], packet[4]),
                    Protocol::V2 => (packet[4], packet[7]),
                };
                self.skip(i + 1);
                if report_bad {
                    return Some(DecodeEvent::BadChecksum {
                        protocol,
                        id,
                        instruction,
                    });
                }
                continue;
            }
            self.stats.skipped_bytes += i as u64;
            self.stats.frames += 1;
            self.start = p;
            self.consumed = total;
            return Some(DecodeEvent::Frame(self.frame_at(p, total, protocol)));
        }
    }

    fn skip(&mut self, n: usize) {
        self.stats.skipped_bytes += n as u64;
        self.start += n;
        if self.start >= self.end {
            self.start = 0;
            self.end = 0;
        }
    }

    fn frame_at(&mut self, p: usize, total: usize, protocol: Protocol) -> Frame<'_> {
        match protocol {
            Protocol::V1 => {
                let packet = &self.buf[p..p + total];
                Frame {
                    protocol,
                    id: packet[2],
                    instruction: packet[4],
                    params: &packet[5..total - 1],
                    raw: packet,
                }
            }
            Protocol::V2 => {
                let region = p + 7..p + total - 2;
                let stuffed = has_stuffing(&self.buf[region.clone()]);
                if stuffed {
                    self.unstuffed.clear();
                    unstuff_into(&self.buf[region], &mut self.unstuffed);
                }
                let packet = &self.buf[p..p + total];
                let body: &[u8] = if stuffed {
                    &self.unstuffed
                } else {
                    &packet[7..total - 2]
                };
                Frame {
                    protocol,
                    id: packet[4],
                    instruction: body[0],
                    params: &body[1..],
                    raw: packet,
                }
            }
        }
    }
}
