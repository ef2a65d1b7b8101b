//! A robot on its Dynamixel bus guarded for an experiment: every read recorded as it
//! comes, a silent or faulty servo or a stop request ends the run, the servos left
//! holding the standing pose. Shared by the experiments that move a robot over its
//! bus (`twinloop experiment tipover --port`, `lean --port`, the Python package).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use twinloop_io::CsvWriter;
use twinloop_link::DynamixelRobot;
use twinloop_link::transport::Transport;
use twinloop_robot::{Robot, RobotError, RobotState};

pub type BusRobot = DynamixelRobot<Box<dyn Transport>>;

/// The robot as the experiment sees it, with the safety checks: every read is
/// recorded, any servo that stops answering or reports overload, overheating or
/// input voltage ends the run, and so does Ctrl-C.
pub struct Guarded<'a> {
    pub robot: &'a mut BusRobot,
    pub writer: Option<CsvWriter>,
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
        writer: Option<CsvWriter>,
        standing: &[f64],
        stop: Arc<AtomicBool>,
    ) -> Guarded<'a> {
        Guarded {
            robot,
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

    /// The first servo that did not answer, named by id.
    fn silent_servo(&self) -> Option<String> {
        let joints = &self.robot.mapping().joints;
        self.robot
            .outcomes()
            .zip(joints)
            .find_map(|((name, o), j)| match o {
                Err(e) => Some(format!("servo id {} (joint \"{name}\"): {e}", j.id)),
                _ => None,
            })
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

    fn read(&mut self, state: &mut RobotState) -> Result<(), RobotError> {
        let r = self.robot.read(state);
        let now = self.robot.time();
        if let Some(t) = self.last_read.replace(now) {
            let k = ((now - t).max(0.0) / CYCLE_BIN_S) as usize;
            self.cycles[k.min(CYCLE_BINS - 1)] += 1;
        }
        // Every read reaches the file, a failed one too (NaN where a servo was
        // silent).
        self.record(state)?;
        if let Some(m) = self.silent_servo() {
            return Err(self.fail(m));
        }
        if let Err(e) = r {
            return Err(self.fail(e.to_string()));
        }
        if let Some(m) = self.hardware_fault() {
            return Err(self.fail(m));
        }
        if self.stop.load(Ordering::Relaxed) {
            return Err(self.fail("interrupted (Ctrl-C)".into()));
        }
        Ok(())
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
