//! The bus flags every command that talks to a robot shares (`link`, `serve`,
//! `experiment ... --port`, `adapt --port`, `bench link`), the goal-count choice of
//! the tip-over, and the Ctrl-C flag: argument mapping onto `twinloop_loop::BusPort`.

use crate::error::CliError;
use clap::Args;
use std::io::{BufRead, IsTerminal, Write};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;
use twinloop_link::Client;
use twinloop_link::transport::Transport;
use twinloop_loop::tipover_bus::{BusRun, Operator};
use twinloop_loop::{BusPlan, BusPort, LoopError};

#[derive(Args, Clone, Debug)]
pub struct PortArgs {
    /// The bus: a serial device (/dev/ttyUSB0), a pty path from `twinloop serve`, or tcp:HOST:PORT
    #[arg(long, value_name = "PORT")]
    pub port: Option<String>,
    /// Bit rate
    #[arg(long, default_value_t = 1_000_000, value_parser = crate::common::baud)]
    pub baud: u32,
    /// Allowance per reply on top of its wire time, ms (USB latency, return delay)
    #[arg(long, default_value_t = 10.0, value_parser = crate::bounds::wall_millis)]
    pub timeout_ms: f64,
    /// Extra attempts after a lost or damaged reply
    #[arg(long, default_value_t = 2, value_parser = crate::bounds::retries)]
    pub retries: u32,
    /// Set the USB adapter's latency timer to 1 ms (FTDI, via sysfs)
    #[arg(long)]
    pub low_latency: bool,
    /// Busy-check the port for up to this many microseconds before sleeping while
    /// waiting for a reply: shorter round trips, one busy core meanwhile
    #[arg(long, default_value_t = 0, value_name = "US")]
    pub spin_us: u64,
    /// How long a servo may stay silent, s of wall time, before it is declared lost:
    /// a read it misses is recorded (NaN) and taken again until it answers or this
    /// window has passed. Experiments then stop naming it (servos left holding);
    /// `link record` stops when every servo has been silent this long
    #[arg(long, default_value_t = twinloop_experiments::guarded::SILENCE_WINDOW_S, value_name = "S", value_parser = crate::bounds::wall_seconds)]
    pub silence_window: f64,
}

impl PortArgs {
    /// The options of a port opened by a program rather than a person: the
    /// defaults but `port`, `timeout_ms` and `retries`.
    pub fn quick(port: Option<String>, timeout_ms: f64, retries: u32) -> PortArgs {
        PortArgs {
            port,
            baud: 1_000_000,
            timeout_ms,
            retries,
            low_latency: false,
            spin_us: 0,
            silence_window: twinloop_experiments::guarded::SILENCE_WINDOW_S,
        }
    }

    /// The bus as a plan opens it.
    pub fn bus_port(&self) -> BusPort {
        BusPort {
            port: self.port.clone(),
            baud: self.baud,
            timeout_ms: self.timeout_ms,
            retries: self.retries,
            low_latency: self.low_latency,
            spin_us: self.spin_us,
            silence_window: self.silence_window,
        }
    }

    pub fn silence_window(&self) -> Duration {
        Duration::from_secs_f64(self.silence_window)
    }
}

/// Open the bus --port names (or the mapping's port).
pub fn open_client(
    p: &PortArgs,
    default_port: Option<&str>,
) -> Result<Client<Box<dyn Transport>>, CliError> {
    Ok(p.bus_port().open(default_port)?)
}

/// The goal positions a lean sends the joints it turns (`--goal-counts`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum GoalCounts {
    /// First-order sigma-delta counts: the counts sent flip around the ramp so that
    /// their running mean is the ramp, and the lean grows smoothly. The default
    /// everywhere a tip-over runs over a bus.
    #[default]
    Dithered,
    /// Whole counts, the ramp rounded: a staircase of 0.29 deg steps on an RX, each a
    /// jolt to a robot on the edge of its soles.
    Staircase,
}

impl GoalCounts {
    pub fn dithered(self) -> bool {
        self == GoalCounts::Dithered
    }
}

/// Set by SIGINT/SIGTERM; a second Ctrl-C ends the process at once.
pub fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // Order matters: the conditional shutdown fires only if the flag is already set.
        let _ = signal_hook::flag::register_conditional_shutdown(sig, 130, flag.clone());
        let _ = signal_hook::flag::register(sig, flag.clone());
    }
    flag
}

/// Ask the person at the terminal; anything but yes is a refusal, and no terminal
/// is one too (pass --yes).
pub fn confirm(question: &str) -> Result<(), CliError> {
    let stdin = std::io::stdin();
    if !stdin.is_terminal() {
        return Err(CliError::new(format!(
            "{question}: no terminal to ask on; pass --yes to run without asking"
        )));
    }
    eprint!("{question} [y/N] ");
    let _ = std::io::stderr().flush();
    let mut line = String::new();
    stdin
        .lock()
        .read_line(&mut line)
        .map_err(|e| CliError::new(format!("reading the answer: {e}")))?;
    if matches!(line.trim(), "y" | "Y" | "yes") {
        Ok(())
    } else {
        Err(CliError::new("not confirmed; the robot was not moved"))
    }
}

/// Run `plan` over its bus as the CLI does: the person asked at the terminal, the
/// run's lines on stderr, Ctrl-C stopping it with the servos holding.
pub fn tipover_on_bus(plan: &BusPlan) -> Result<BusRun, CliError> {
    let mut ask = |q: &str| confirm(q).map_err(|e| LoopError::new(e.message));
    let mut log = |line: &str| eprintln!("{line}");
    let mut operator = Operator {
        ask: &mut ask,
        log: &mut log,
        stop: interrupt_flag(),
    };
    Ok(twinloop_loop::tipover_bus::tipover_on_bus(
        plan,
        &mut operator,
    )?)
}
