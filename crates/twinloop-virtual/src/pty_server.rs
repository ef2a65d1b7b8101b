//! A virtual robot served on a new pseudo-terminal from threads of its own: what
//! `twinloop serve` does, for a program (`twinloop demo`) or a test that drives the
//! robot in-process through the real packet path.

use crate::backend::SimServoBackend;
use crate::virtual_robot::{SimHandle, VirtualRobot};
use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use twinloop_link::VirtualBus;
use twinloop_link::servo::{ServeOptions, serve};
use twinloop_link::transport::PtyTransport;

/// The robot on its pty; dropping it stops serving and the simulation.
pub struct PtyServer {
    path: String,
    sim: SimHandle,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<io::Result<()>>>,
}

impl PtyServer {
    /// Serve `vr` on a new pty, its wire time emulated at `emulate_baud` (`None`:
    /// answers at once). `configure` sets up the bus first (registers a host would
    /// find already set, such as a Return Delay Time).
    pub fn start(
        vr: VirtualRobot,
        emulate_baud: Option<u32>,
        configure: impl FnOnce(&mut VirtualBus<SimServoBackend>),
    ) -> io::Result<PtyServer> {
        let mut bus = vr.bus();
        configure(&mut bus);
        let mut pty = PtyTransport::open()?;
        let path = pty.path().display().to_string();
        let sim = vr.spawn();
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("twinloop-pty-server".into())
            .spawn(move || {
                // The host waits for these replies; the simulation may slow down.
                let _ = twinloop_link::servo::favour_reply_thread();
                let options = ServeOptions {
                    emulate_baud,
                    stop_on_eof: false,
                    warn_stalls: false,
                };
                serve(&mut bus, &mut pty, &options, &flag)
            })?;
        Ok(PtyServer {
            path,
            sim,
            stop,
            thread: Some(thread),
        })
    }

    /// The pty's path, for a client to open.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The running simulation (snapshots, status).
    pub fn sim(&self) -> &SimHandle {
        &self.sim
    }

    /// Stop serving; what the serve loop ended with.
    pub fn stop(mut self) -> io::Result<()> {
        self.stop.store(true, Ordering::Relaxed);
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(r)) => r,
            Some(Err(_)) => Err(io::Error::other("the serve thread panicked")),
            None => Ok(()),
        }
    }
}

impl Drop for PtyServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
