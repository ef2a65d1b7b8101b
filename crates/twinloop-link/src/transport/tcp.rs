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
}

impl TcpTransport {
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
        })
    }
}

impl Transport for TcpTransport {
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.stream.write_all(bytes)
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        // A zero timeout means "block forever" to the socket API.
        let timeout = timeout.max(Duration::from_micros(1));
        if self.timeout != Some(timeout) {
            self.stream.set_read_timeout(Some(timeout))?;
            self.timeout = Some(timeout);
        }
        match self.stream.read(buf) {
            Ok(0) => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!("tcp peer {} closed the connection", self.peer),
            )),
            Ok(n) => Ok(n),
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

    fn discard_input(&mut self) -> io::Result<()> {
        self.stream.set_nonblocking(true)?;
        let mut scratch = [0u8; 256];
        let result = loop {
            match self.stream.read(&mut scratch) {
                Ok(0) => break Ok(()),
                Ok(_) => continue,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break Ok(()),
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
