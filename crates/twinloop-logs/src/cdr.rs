//! CDR, the byte layout of ROS 2 messages, for exactly the types twinloop reads and
//! writes (see `msgs`).
//!
//! Facts, from the OMG CORBA 3.4 spec (part 2, 9.3 "CDR Transfer Syntax") and the
//! DDS-RTPS 2.5 spec (10.2 "serialized payload"): a 4-byte encapsulation header,
//! whose second byte is the representation (0 = big-endian CDR, 1 = little-endian;
//! 2 and 3 are parameter lists, which ROS 2 does not use), then the fields in declaration order,
//! each primitive aligned to its own size counted from the end of that header; a
//! string is a `u32` length that counts its terminating NUL, the bytes and the NUL;
//! a sequence is a `u32` count and the elements; a fixed array has no count. ROS 2
//! (rmw_fastrtps, rosbag2) writes little-endian.
use crate::error::LogError;

fn short() -> LogError {
    LogError::new("the message ends before its last field (truncated CDR)")
}

/// Reads one CDR message; borrows its bytes, allocates nothing.
pub struct CdrReader<'a> {
    buf: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> CdrReader<'a> {
    pub fn new(data: &'a [u8]) -> Result<Self, LogError> {
        if data.len() < 4 {
            return Err(short());
        }
        let little = match data[1] {
            0 => false,
            1 => true,
            r => {
                return Err(LogError::new(format!(
                    "CDR representation {r} is not plain CDR (0 or 1)"
                )));
            }
        };
        Ok(CdrReader {
            buf: &data[4..],
            pos: 0,
            little,
        })
    }

    fn take(&mut self, n: usize, align: usize) -> Result<&'a [u8], LogError> {
        let start = self.pos.next_multiple_of(align);
        let end = start.checked_add(n).ok_or_else(short)?;
        let s = self.buf.get(start..end).ok_or_else(short)?;
        self.pos = end;
        Ok(s)
    }

    pub fn u32(&mut self) -> Result<u32, LogError> {
        let b: [u8; 4] = self.take(4, 4)?.try_into().expect("4 bytes");
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    pub fn i32(&mut self) -> Result<i32, LogError> {
        Ok(self.u32()? as i32)
    }

    pub fn f64(&mut self) -> Result<f64, LogError> {
        let b: [u8; 8] = self.take(8, 8)?.try_into().expect("8 bytes");
        Ok(if self.little {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        })
    }

    /// A string without its NUL.
    pub fn string(&mut self) -> Result<&'a str, LogError> {
        let bytes = self.string_bytes()?;
        std::str::from_utf8(bytes).map_err(|_| LogError::new("a string is not UTF-8"))
    }

    /// A string's bytes without its NUL, not checked as UTF-8 (for comparing with a
    /// string already checked: a JointState's names repeat in every message).
    pub fn string_bytes(&mut self) -> Result<&'a [u8], LogError> {
        let n = self.u32()? as usize;
        let bytes = self.take(n, 1)?;
        Ok(bytes.strip_suffix(&[0]).unwrap_or(bytes))
    }

    /// A sequence's element count, checked against the bytes left (each element is at
    /// least `min_size` bytes), so a damaged count is an error, not a huge allocation.
    pub fn count(&mut self, min_size: usize) -> Result<usize, LogError> {
        let n = self.u32()? as usize;
        if n.saturating_mul(min_size) > self.buf.len().saturating_sub(self.pos) {
            return Err(short());
        }
        Ok(n)
    }

    /// A `float64[]` into `out` (cleared first; its capacity is reused).
    pub fn f64_seq(&mut self, out: &mut Vec<f64>) -> Result<(), LogError> {
        let n = self.count(8)?;
        out.clear();
        if n == 0 {
            return Ok(());
        }
        let bytes = self.take(8 * n, 8)?;
        let little = self.little;
        out.extend(bytes.chunks_exact(8).map(|c| {
            let b: [u8; 8] = c.try_into().expect("8 bytes");
            if little {
                f64::from_le_bytes(b)
            } else {
                f64::from_be_bytes(b)
            }
        }));
        Ok(())
    }

    /// `N` consecutive doubles (a fixed array or a small struct of doubles).
    pub fn f64s<const N: usize>(&mut self) -> Result<[f64; N], LogError> {
        let mut v = [0.0; N];
        for x in &mut v {
            *x = self.f64()?;
        }
        Ok(v)
    }
}

/// Writes one little-endian CDR message.
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    pub fn new() -> Self {
        CdrWriter {
            buf: vec![0, 1, 0, 0],
        }
    }

    /// Start a new message in the same buffer (keeps its capacity).
    pub fn reset(&mut self) {
        self.buf.clear();
        self.buf.extend_from_slice(&[0, 1, 0, 0]);
    }

    fn align(&mut self, n: usize) {
        let len = (self.buf.len() - 4).next_multiple_of(n) + 4;
        self.buf.resize(len, 0);
    }

    pub fn u32(&mut self, x: u32) {
        self.align(4);
        self.buf.extend_from_slice(&x.to_le_bytes());
    }

    pub fn i32(&mut self, x: i32) {
        self.u32(x as u32);
    }

    pub fn f64(&mut self, x: f64) {
        self.align(8);
        self.buf.extend_from_slice(&x.to_le_bytes());
    }

    pub fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    pub fn f64_seq(&mut self, xs: &[f64]) {
        self.u32(xs.len() as u32);
        for &x in xs {
            self.f64(x);
        }
    }

    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_double_after_a_string_is_aligned_from_the_end_of_the_header() {
        let mut w = CdrWriter::new();
        w.string("ab");
        w.f64(1.5);
        // header 4 + len 4 + "ab\0" 3 = offset 7 from the header's end -> pad to 8.
        assert_eq!(w.bytes().len(), 4 + 8 + 8);
        let mut r = CdrReader::new(w.bytes()).unwrap();
        assert_eq!(r.string().unwrap(), "ab");
        assert_eq!(r.f64().unwrap(), 1.5);
        assert!(r.f64().is_err());
    }

    #[test]
    fn a_sequence_count_larger_than_the_message_is_an_error() {
        let mut w = CdrWriter::new();
        w.u32(1_000_000);
        let mut v = Vec::new();
        let e = CdrReader::new(w.bytes())
            .unwrap()
            .f64_seq(&mut v)
            .unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
    }
}
