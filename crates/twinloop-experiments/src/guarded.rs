//! A robot on its Dynamixel bus guarded for an experiment: every read recorded as it
//! comes, a servo silent for longer than the silence window, a faulty servo or a
//! stop request ends the run, the servos left holding the standing pose. Shared by
//! the experiments that move a robot over its bus (`twinloop experiment tipover
//! --port`, `lean --port`, the Python package).
//!
//! A bus degrades before it breaks: a reply lost to noise, or a host or server
//! descheduled for a few hundred milliseconds on a loaded machine, costs a read, not
//! the run. A read in which a servo (or the IMU board) did not answer is recorded
//! (NaN where it was silent) and taken again, until every servo answers or one has
//! been silent for the whole window of wall time.

use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use twinloop_io::RowSink;
use twinloop_link::transport::Transport;
use twinloop_link::{ClientStats, DynamixelRobot};
use twinloop_robot::{Robot, RobotError, RobotState};

/// How long a servo may stay silent (wall time) before it is declared lost, by
/// default: long enough to ride out a host or server descheduled on a busy machine
/// (a served robot stalled 0.2 s at a time on a 2-core machine at load 8, at worst
/// 2.2 s; at load 14-21, 2.0-2.7 s, which stopped 13 of 21 two-process tip-overs
/// when the window was 2 s), short enough that a robot whose bus is gone is left
/// holding within about 5.6 s (the window plus one read of every servo with its
/// retries). The servos hold their last goal meanwhile.
pub const SILENCE_WINDOW_S: f64 = 5.0;

/// How a bus held up over a run: the client's retries and discarded packets, and
/// the reads taken again within the silence window.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct BusHealth {
    /// Requests sent, retries included.
    pub requests: u64,
    /// Requests sent again after a lost or damaged reply.
    pub retries: u64,
    pub timeouts: u64,
    pub corrupt: u64,
    pub wrong_replies: u64,
    /// Packets that answered no request waited for (late replies, another servo's).
    pub discarded_packets: u64,
    /// Bytes dropped from the input before a request (late replies).
    pub stale_bytes: u64,
    /// Reads of the whole robot, kept ones and repeated ones.
    pub reads: u64,
    /// Reads in which a servo was silent: recorded (NaN where it was), and taken
    /// again by an experiment.
    pub reads_missed: u64,
    /// The longest time a servo went without answering, s of wall time.
    pub longest_silence_s: f64,
    /// The silence window the run had, s.
    pub silence_window_s: f64,
}

impl BusHealth {
    /// One line for the terminal.
    pub fn line(&self) -> String {
        format!(
            "bus: {} requests, {} retries ({} timeouts, {} corrupt, {} wrong replies), {} \
             packets discarded, {} stale bytes dropped; {} of {} reads missed a servo (kept, NaN \
             where silent), longest silence {:.3} s (window {} s)",
            self.requests,
            self.retries,
            self.timeouts,
            self.corrupt,
            self.wrong_replies,
            self.discarded_packets,
            self.stale_bytes,
            self.reads_missed,
            self.reads,
            self.longest_silence_s,
            self.silence_window_s
        )
    }

    /// The client's counters into `self`.
    pub fn with_client(mut self, c: &ClientStats) -> BusHealth {
        self.requests = c.requests;
        self.retries = c.retries;
        self.timeouts = c.timeouts;
        self.corrupt = c.corrupt;
        self.wrong_replies = c.wrong_replies;
        self.discarded_packets = c.discarded;
        self.stale_bytes = c.stale_bytes;
        self
    }
}

pub type BusRobot = DynamixelRobot<Box<dyn Transport>>;

/// The robot as the experiment sees it, with the safety checks: every read is
/// recorded, any servo that stops answering or reports overload, overheating or
/// input voltage ends the run, and so does Ctrl-C.
pub struct Guarded<'a> {
    pub robot: &'a mut BusRobot,
    /// How long a servo may stay silent before the run stops ([`SILENCE_WINDOW_S`]
    /// by default).
    pub silence_window: Duration,
    /// Since when each servo has not answered (joints in order, then the IMU
    /// board): the start of the first read it missed since it last answered. Counted
    /// from there, not from its last answer, a servo is not blamed for the time the
    /// host spent waiting on the others.
    silent_since: Vec<Option<Instant>>,
    reads: u64,
    reads_missed: u64,
    longest_silence: Duration,
    /// The record (a CSV, or another format the program registered: MCAP).
    pub writer: Option<Box<dyn RowSink>>,
    goals: Vec<f64>,
    row: Vec<f64>,
    stop: Arc<AtomicBool>,
    /// Why the run stopped, once it did: the first failure, servo named.
    pub abort: Option<String>,
    /// Rows written to the record.
    pub rows: usize,
    /// The time between reads, in [`CYCLE_BIN_S`] bins (the last bin takes the
    /// rest), and the previous read's time: the host's control cycle, allocation-free.
    cycles: [u32; CYCLE_BINS],
    last_read: Option<f64>,
}

/// Bins of the control-cycle histogram: 0.25 ms each, up to 100 ms.
const CYCLE_BINS: usize = 400;
const CYCLE_BIN_S: f64 = 2.5e-4;

impl Guarded<'_> {
    /// Guard `robot`, recording to `writer` (columns [`record_columns`]), stopping
    /// once `stop` is set (the CLI sets it on Ctrl-C); the goals start at `standing`.
    pub fn new<'a>(
        robot: &'a mut BusRobot,
        writer: Option<Box<dyn RowSink>>,
        standing: &[f64],
        stop: Arc<AtomicBool>,
    ) -> Guarded<'a> {
        let n = robot.mapping().joints.len() + 1;
        Guarded {
            robot,
            silence_window: Duration::from_secs_f64(SILENCE_WINDOW_S),
            silent_since: vec![None; n],
            reads: 0,
            reads_missed: 0,
            longest_silence: Duration::ZERO,
            writer,
            goals: standing.to_vec(),
            row: Vec::new(),
            stop,
            abort: None,
            rows: 0,
            cycles: [0; CYCLE_BINS],
            last_read: None,
        }
    }

    /// The median time between two reads so far, s of robot time (the centre of its
    /// 0.25 ms bin); `None` before two reads.
    pub fn median_cycle_s(&self) -> Option<f64> {
        let n: u64 = self.cycles.iter().map(|&c| u64::from(c)).sum();
        if n == 0 {
            return None;
        }
        let mut seen = 0;
        for (k, &c) in self.cycles.iter().enumerate() {
            seen += u64::from(c);
            if 2 * seen >= n {
                return Some((k as f64 + 0.5) * CYCLE_BIN_S);
            }
        }
        None
    }

    /// Stop the run with `message` (the first failure is the one reported).
    pub fn fail(&mut self, message: String) -> RobotError {
        if self.abort.is_none() {
            self.abort = Some(message.clone());
        }
        RobotError::new(message)
    }

    /// A servo that reports a hardware condition (1.0 overload, overheating,
    /// input voltage; 2.0 Alert), named by id.
    fn hardware_fault(&self) -> Option<String> {
        let joints = &self.robot.mapping().joints;
        self.robot
            .outcomes()
            .zip(joints)
            .find_map(|((name, o), j)| match o {
                Ok(status) if status.hardware_fault() => {
                    Some(format!("servo id {} (joint \"{name}\"): {status}", j.id))
                }
                _ => None,
            })
    }

    /// How the bus held up so far.
    pub fn health(&self) -> BusHealth {
        BusHealth {
            reads: self.reads,
            reads_missed: self.reads_missed,
            longest_silence_s: self.longest_silence.as_secs_f64(),
            silence_window_s: self.silence_window.as_secs_f64(),
            ..BusHealth::default()
        }
        .with_client(&self.robot.client.stats)
    }

    /// Note who answered the read started at `asked`; the servo (or board) silent
    /// the longest, named, with how long, if any is silent. Allocates only then.
    fn silences(&mut self, asked: Instant, now: Instant) -> Option<(String, Duration)> {
        let mut worst: Option<(usize, Duration)> = None;
        let outcomes = self
            .robot
            .outcomes()
            .map(|(_, o)| o)
            .chain(self.robot.imu_outcome());
        for (k, o) in outcomes.enumerate() {
            if o.is_ok() {
                self.silent_since[k] = None;
                continue;
            }
            let silent = now.duration_since(*self.silent_since[k].get_or_insert(asked));
            if worst.is_none_or(|w| silent > w.1) {
                worst = Some((k, silent));
            }
        }
        let (k, silent) = worst?;
        let joints = &self.robot.mapping().joints;
        let who = match (joints.get(k), self.robot.imu_board()) {
            (Some(j), _) => format!("servo id {} (joint \"{}\")", j.id, j.name),
            (None, Some(b)) => format!("servo id {} (board \"{}\")", b.id, b.name),
            (None, None) => format!("servo {k}"),
        };
        let outcome = self
            .robot
            .outcomes()
            .map(|(_, o)| o)
            .chain(self.robot.imu_outcome())
            .nth(k);
        let why = match outcome {
            Some(Err(e)) => e.to_string(),
            _ => String::new(),
        };
        Some((format!("{who}: {why}"), silent))
    }

    /// Read until every servo answered, recording each read; a servo silent for
    /// longer than the window, a link error, a fault or a stop request ends it.
    fn read_within_window(&mut self, state: &mut RobotState) -> Result<(), RobotError> {
        loop {
            let asked = Instant::now();
            let r = self.robot.read(state);
            let now = self.robot.time();
            if let Some(t) = self.last_read.replace(now) {
                let k = ((now - t).max(0.0) / CYCLE_BIN_S) as usize;
                self.cycles[k.min(CYCLE_BINS - 1)] += 1;
            }
            self.reads += 1;
            // Every read reaches the file, a failed one too (NaN where a servo was
            // silent).
            self.record(state)?;
            if let Err(e) = &r
                && e.joint.is_none()
            {
                // The link itself failed (port gone): nothing to wait for.
                return Err(self.fail(e.to_string()));
            }
            if let Some(m) = self.hardware_fault() {
                return Err(self.fail(m));
            }
            if self.stop.load(Ordering::Relaxed) {
                return Err(self.fail("interrupted (Ctrl-C)".into()));
            }
            let Some((who, silent)) = self.silences(asked, Instant::now()) else {
                return r;
            };
            self.longest_silence = self.longest_silence.max(silent);
            self.reads_missed += 1;
            if silent >= self.silence_window {
                return Err(self.fail(format!(
                    "{who}; silent for {:.2} s, longer than the silence window ({} s)",
                    silent.as_secs_f64(),
                    self.silence_window.as_secs_f64()
                )));
            }
        }
    }

    fn record(&mut self, st: &RobotState) -> Result<(), RobotError> {
        let Some(w) = self.writer.as_mut() else {
            return Ok(());
        };
        self.row.clear();
        self.row.push(st.time);
        self.row.extend_from_slice(&st.positions);
        self.row.extend_from_slice(&self.goals);
        match st.imu {
            Some(imu) => {
                self.row.extend_from_slice(&[
                    imu.gyro[0],
                    imu.gyro[1],
                    imu.gyro[2],
                    imu.accel[0],
                    imu.accel[1],
                    imu.accel[2],
                ]);
                let (p, r) = imu
                    .orientation
                    .map(crate::tipover::tilt)
                    .unwrap_or((f64::NAN, f64::NAN));
                self.row.extend_from_slice(&[p, r]);
            }
            None => self.row.extend_from_slice(&[f64::NAN; 8]),
        }
        w.write_row(&self.row)
            .map_err(|e| RobotError::new(format!("the record: {e}")))?;
        self.rows += 1;
        Ok(())
    }
}

impl Robot for Guarded<'_> {
    fn joint_names(&self) -> &[String] {
        self.robot.joint_names()
    }

    fn time(&self) -> f64 {
        self.robot.time()
    }

    /// One read of every servo; a servo that missed it is read again (each read
    /// recorded) until it answers or its silence passes the window.
    fn read(&mut self, state: &mut RobotState) -> Result<(), RobotError> {
        self.read_within_window(state)
    }

    fn command_positions(&mut self, goals: &[f64]) -> Result<(), RobotError> {
        self.goals.clear();
        self.goals.extend_from_slice(goals);
        if self.stop.load(Ordering::Relaxed) {
            return Err(self.fail("interrupted (Ctrl-C)".into()));
        }
        self.robot
            .command_positions(goals)
            .map_err(|e| self.fail(e.to_string()))
    }

    fn advance(&mut self, dt: f64) -> Result<(), RobotError> {
        self.robot.advance(dt)
    }
}

/// Whether `port` is a serial device (not a pty from `serve`, not tcp).
pub fn is_serial(port: &str) -> bool {
    if port.starts_with("tcp:") {
        return false;
    }
    let real = std::fs::canonicalize(port).unwrap_or_else(|_| port.into());
    !real.starts_with("/dev/pts")
}

/// Leave the robot holding the standing pose: torque on, goal = standing, rounded
/// (an experiment stopped while dithering must not leave a goal flipping).
pub fn hold_standing(robot: &mut BusRobot, standing: &[f64]) {
    robot.set_dithered(|_| false);
    let _ = robot.set_torque(true);
    let _ = robot.command_positions(standing);
}

/// The columns of the raw record a [`Guarded`] robot writes, one row per cycle read:
/// `t`, `q:<joint>`, `goal:<joint>`, `imu:gyro_x .. imu:accel_z`, `tilt:pitch`,
/// `tilt:roll`.
pub fn record_columns(names: &[String]) -> Vec<String> {
    let mut cols = vec!["t".to_string()];
    for prefix in ["q", "goal"] {
        cols.extend(names.iter().map(|n| format!("{prefix}:{n}")));
    }
    for c in [
        "imu:gyro_x",
        "imu:gyro_y",
        "imu:gyro_z",
        "imu:accel_x",
        "imu:accel_y",
        "imu:accel_z",
        "tilt:pitch",
        "tilt:roll",
    ] {
        cols.push(c.to_string());
    }
    cols
}
