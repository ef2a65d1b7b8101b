//! An in-memory transport whose far end is a function: what the host writes goes
//! to a [`Responder`] (a virtual bus) at once, and its reply is what the host reads.
//! No threads, no clock: a read with nothing queued returns "timed out"
//! immediately, which makes 100 000-cycle tests take seconds.

use super::Transport;
use std::io;
use std::time::Duration;

/// The far end of a [`LoopbackTransport`].
pub trait Responder: Send {
    /// React to bytes the host sent, appending reply bytes to `reply`.
    fn respond(&mut self, input: &[u8], reply: &mut Vec<u8>);
}

pub struct LoopbackTransport<R: Responder> {
    pub responder: R,
    queue: Vec<u8>,
    read_pos: usize,
    /// Bytes written by the host and read back so far (wire-time accounting).
    pub bytes_written: u64,
    pub bytes_read: u64,
}

impl<R: Responder> LoopbackTransport<R> {
    pub fn new(responder: R) -> LoopbackTransport<R> {
        LoopbackTransport {
            responder,
            queue: Vec::with_capacity(4096),
            read_pos: 0,
            bytes_written: 0,
            bytes_read: 0,
        }
    }
}

impl<R: Responder> Transport for LoopbackTransport<R> {
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.bytes_written += bytes.len() as u64;
        if self.read_pos == self.queue.len() {
            self.queue.clear();
            self.read_pos = 0;
        }
        self.responder.respond(bytes, &mut self.queue);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], _timeout: Duration) -> io::Result<usize> {
        let n = (self.queue.len() - self.read_pos).min(buf.len());
        buf[..n].copy_from_slice(&self.queue[self.read_pos..self.read_pos + n]);
        self.read_pos += n;
        self.bytes_read += n as u64;
        Ok(n)
    }

    fn discard_input(&mut self) -> io::Result<usize> {
        let n = self.queue.len() - self.read_pos;
        self.queue.clear();
        self.read_pos = 0;
        Ok(n)
    }

    fn describe(&self) -> String {
        "in-memory loopback".into()
    }
}
