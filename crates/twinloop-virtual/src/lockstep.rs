//! A simulated robot stepped by its host: the bus in memory (no pty, no thread),
//! simulated time moving only while the host waits for its next cycle. The same
//! protocol a host runs over a real bus then runs as fast as the simulation can,
//! and gives the same result every time: what `twinloop demo` uses to simulate how
//! its own tip-over protocol measures a model (docs/adaptation.md, "the protocol's
//! bias").

use crate::VirtualRobot;
use crate::backend::SimServoBackend;
use crate::error::VirtualError;
use twinloop_link::VirtualBus;
use twinloop_link::transport::{LoopbackTransport, Transport};
use twinloop_link::{Client, ClientConfig, HostClock};
use twinloop_robot::RobotError;

/// The clock of a [`VirtualRobot`] stepped in lockstep with its host: each wait
/// steps the simulation by the wait, or by `cycle_s` if longer (a bus cycle takes
/// its own time on the wire and in the host, which a wait cannot shorten).
pub struct Lockstep {
    robot: VirtualRobot,
    cycle_s: f64,
}

impl Lockstep {
    /// `robot` stepped `cycle_s` s (at least) per control cycle, and the client of
    /// its bus in memory. `cycle_s` must be positive and finite.
    pub fn new(
        robot: VirtualRobot,
        cycle_s: f64,
    ) -> Result<(Lockstep, Client<Box<dyn Transport>>), VirtualError> {
        if !(cycle_s.is_finite() && cycle_s > 0.0) {
            return Err(VirtualError::new(format!(
                "lockstep cycle {cycle_s} s: must be positive and finite"
            )));
        }
        let bus: VirtualBus<SimServoBackend> = robot.bus();
        let t: Box<dyn Transport> = Box::new(LoopbackTransport::new(bus));
        let client = Client::with_config(
            t,
            ClientConfig {
                retries: 0,
                ..ClientConfig::default()
            },
        );
        Ok((Lockstep { robot, cycle_s }, client))
    }
}

impl HostClock for Lockstep {
    fn now(&self) -> f64 {
        self.robot.time()
    }

    fn wait(&mut self, dt: f64) -> Result<(), RobotError> {
        self.robot
            .step_for(dt.max(self.cycle_s))
            .map_err(|e| RobotError::new(format!("the simulated robot stopped: {e}")))
    }
}
