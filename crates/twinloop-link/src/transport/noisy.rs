//! A transport wrapper that damages bytes in both directions: bit flips, dropped
//! bytes and inserted bytes, each byte hit with a given probability. It tests that
//! nothing corrupted is accepted and that the client recovers.

use super::Transport;
use std::io;
use std::time::Duration;
use twinloop_random::SplitMix64;

/// What the noise did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoiseStats {
    pub bytes: u64,
    pub flipped: u64,
    pub dropped: u64,
    pub inserted: u64,
}

pub struct NoisyTransport<T: Transport> {
    pub inner: T,
    rng: SplitMix64,
    /// Probability that a byte is damaged (one of flip, drop, insert, equally likely).
    pub rate: f64,
    pub stats: NoiseStats,
    scratch: Vec<u8>,
    pending: Vec<u8>,
    pending_pos: usize,
}

impl<T: Transport> NoisyTransport<T> {
    pub fn new(inner: T, rate: f64, seed: u64) -> NoisyTransport<T> {
        NoisyTransport {
            inner,
            rng: SplitMix64(seed),
            rate,
            stats: NoiseStats::default(),
            scratch: Vec::with_capacity(4096),
            pending: Vec::with_capacity(4096),
            pending_pos: 0,
        }
    }

    fn damage(&mut self, input: &[u8], out: &mut Vec<u8>) {
        for &b in input {
            self.stats.bytes += 1;
            if self.rng.next_f64() >= self.rate {
                out.push(b);
                continue;
            }
            match self.rng.below(3) {
                0 => {
                    self.stats.flipped += 1;
                    out.push(b ^ (1 << self.rng.below(8)));
                }
                1 => self.stats.dropped += 1,
                _ => {
                    self.stats.inserted += 1;
                    out.push(b);
                    out.push(self.rng.next_u64() as u8);
                }
            }
        }
    }
}

impl<T: Transport> Transport for NoisyTransport<T> {
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.clear();
        self.damage(bytes, &mut scratch);
        let r = self.inner.write_all(&scratch);
        self.scratch = scratch;
        r
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        if self.pending_pos == self.pending.len() {
            self.pending.clear();
            self.pending_pos = 0;
            let mut raw = [0u8; 512];
            let n = self.inner.read(&mut raw, timeout)?;
            if n == 0 {
                return Ok(0);
            }
            let mut pending = std::mem::take(&mut self.pending);
            self.damage(&raw[..n], &mut pending);
            self.pending = pending;
        }
        let n = (self.pending.len() - self.pending_pos).min(buf.len());
        buf[..n].copy_from_slice(&self.pending[self.pending_pos..self.pending_pos + n]);
        self.pending_pos += n;
        Ok(n)
    }

    fn discard_input(&mut self) -> io::Result<usize> {
        let n = self.pending.len() - self.pending_pos;
        self.pending.clear();
        self.pending_pos = 0;
        Ok(n + self.inner.discard_input()?)
    }

    fn baud(&self) -> Option<u32> {
        self.inner.baud()
    }

    fn describe(&self) -> String {
        format!(
            "{} with {} % noise",
            self.inner.describe(),
            self.rate * 100.0
        )
    }
}
