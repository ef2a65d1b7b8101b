//! A bus behind TCP: a virtual robot served with `twinloop serve --port tcp:ADDR`, or a
//! serial-to-network bridge. Bytes pass through unchanged.

use super::Transport;
use std::io::{self, Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;

pub struct TcpTransport {
    stream: TcpStream,
    peer: String,
    timeout: Option<Duration>,
    /// Bytes received so far (a refusal comes first or not at all).
    received: u64,
    /// When the connection was made (see [`FRESH`]).
    opened: std::time::Instant,
}

/// How long a fresh connection's first reply may take. A server accepts a
/// connection and starts reading it some time after the client's connect returns
/// (`twinloop serve` hands it to its serving thread): the first requests sit unread
/// meanwhile, a client waiting only a reply's allowance (10 ms) gives them up, and
/// the server, finding them piled up, answers only the last (a scan's first servos
/// "not found"). Until the first byte arrives, a read waits until the connection is
/// this old: once per connection, at most this long.
pub const FRESH: Duration = Duration::from_millis(300);

/// What `twinloop serve` sends a client it cannot serve (another one has the bus)
/// before it closes the connection: this, then the reason, then a newline.
pub const REFUSAL: &[u8] = b"twinloop serve: busy: ";

/// Refuse a connection: send [`REFUSAL`] and `why`, close our side, and read until
/// the client leaves (closing with its request unread would reset the connection
/// and could drop the refusal before the client reads it).
pub fn refuse(mut stream: TcpStream, why: &str) -> io::Result<()> {
    stream.set_nonblocking(false)?;
    // One write: the client reads the line whole when it arrives in one segment.
    let mut line = REFUSAL.to_vec();
    line.extend_from_slice(why.as_bytes());
    line.push(b'\n');
    stream.write_all(&line)?;
    stream.shutdown(std::net::Shutdown::Write)?;
    stream.set_read_timeout(Some(Duration::from_secs(2)))?;
    let mut scratch = [0u8; 256];
    while matches!(stream.read(&mut scratch), Ok(n) if n > 0) {}
    Ok(())
}

/// `buf`, the first bytes from the server, as the error of a refusal, if it is one.
fn refusal(buf: &[u8], peer: &str) -> Option<io::Error> {
    let rest = buf.strip_prefix(REFUSAL)?;
    let line = rest.split(|&b| b == b'\n').next().unwrap_or(rest);
    Some(io::Error::new(
        io::ErrorKind::ResourceBusy,
        format!(
            "tcp:{peer} is busy: {} (one program at a time talks to a bus)",
            String::from_utf8_lossy(line)
        ),
    ))
}

impl TcpTransport {
    /// `first` and what follows it up to the newline (a refusal split over two
    /// segments), waiting at most half a second for the rest.
    fn rest_of_line(&mut self, first: &[u8]) -> Vec<u8> {
        let mut line = first.to_vec();
        let until = std::time::Instant::now() + Duration::from_millis(500);
        let mut more = [0u8; 256];
        while !line.contains(&b'\n') && std::time::Instant::now() < until {
            let _ = self
                .stream
                .set_read_timeout(Some(Duration::from_millis(50)));
            match self.stream.read(&mut more) {
                Ok(0) => break,
                Ok(k) => line.extend_from_slice(&more[..k]),
                // A read timeout: the loop's deadline decides.
                Err(_) => continue,
            }
        }
        self.timeout = None;
        line
    }

    pub fn connect(addr: &str) -> io::Result<TcpTransport> {
        let mut last = None;
        for a in addr.to_socket_addrs()? {
            match TcpStream::connect_timeout(&a, Duration::from_secs(5)) {
                Ok(s) => return TcpTransport::from_stream(s),
                Err(e) => last = Some(e),
            }
        }
        Err(last.unwrap_or_else(|| {
            io::Error::new(io::ErrorKind::NotFound, format!("{addr}: no address"))
        }))
    }

    /// Wrap an accepted connection (the server side of `twinloop serve --port tcp:ADDR`).
    pub fn from_stream(stream: TcpStream) -> io::Result<TcpTransport> {
        // Packets are small and latency is the point: no Nagle delay.
        stream.set_nodelay(true)?;
        let peer = stream
            .peer_addr()
            .map(|a| a.to_string())
            .unwrap_or_else(|_| "?".into());
        Ok(TcpTransport {
            stream,
            peer,
            timeout: None,
            received: 0,
            opened: std::time::Instant::now(),
        })
    }
}

impl Transport for TcpTransport {
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.stream.write_all(bytes)
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        // A zero timeout means "block forever" to the socket API.
        let mut timeout = timeout.max(Duration::from_micros(1));
        if self.received == 0 {
            let fresh_until = self.opened + FRESH;
            timeout = timeout.max(fresh_until.saturating_duration_since(std::time::Instant::now()));
        }
        if self.timeout != Some(timeout) {
            self.stream.set_read_timeout(Some(timeout))?;
            self.timeout = Some(timeout);
        }
        match self.stream.read(buf) {
            Ok(0) => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!("tcp peer {} closed the connection", self.peer),
            )),
            Ok(n) => {
                if self.received == 0 && buf[..n].starts_with(REFUSAL) {
                    let line = self.rest_of_line(&buf[..n]);
                    if let Some(e) = refusal(&line, &self.peer) {
                        return Err(e);
                    }
                }
                self.received += n as u64;
                Ok(n)
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock
                        | io::ErrorKind::TimedOut
                        | io::ErrorKind::Interrupted
                ) =>
            {
                Ok(0)
            }
            Err(e) => Err(e),
        }
    }

    fn discard_input(&mut self) -> io::Result<usize> {
        self.stream.set_nonblocking(true)?;
        let mut scratch = [0u8; 256];
        let mut dropped = 0;
        let result = loop {
            match self.stream.read(&mut scratch) {
                Ok(0) => break Ok(dropped),
                Ok(n) => dropped += n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break Ok(dropped),
                Err(e) => break Err(e),
            }
        };
        self.stream.set_nonblocking(false)?;
        result
    }

    fn describe(&self) -> String {
        format!("tcp {}", self.peer)
    }
}
