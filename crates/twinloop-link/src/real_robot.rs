//! The real-robot backend of [`twinloop_robot::Robot`]: joints are servos on a
//! Dynamixel bus, tied to URDF joints by a [`RobotMapping`]. Reading runs one
//! control-cycle read (positions, velocities, loads of every joint) and, when the
//! mapping has a `[[board]]`, one READ of the board's gyro and accelerometer (the
//! trunk IMU, with the host's tilt estimate); commanding sends one SYNC_WRITE per
//! protocol, and time is the wall clock (times a clock rate for a simulated robot served
//! faster than real time), or a [`HostClock`] of the caller's (a simulation stepped in
//! lockstep with its host).

use crate::board::TiltFilter;
use crate::client::Client;
use crate::control_cycle::{ControlCycle, ReadMethod, ServoReading};
use crate::control_table::ModelTable;
use crate::link_error::{LinkError, Outcome};
use crate::mapping::{BoardMapping, RobotMapping};
use crate::protocol::Protocol;
use crate::register::{Item, Unit};
use crate::transport::Transport;
use std::time::{Duration, Instant};
use twinloop_robot::{Imu, Robot, RobotError, RobotState};

/// The trunk IMU's board as the host reads it: one READ of its inertial block per
/// cycle, decoded into the link frame, and the tilt filter.
struct BoardReader {
    board: BoardMapping,
    /// The inertial registers' span ([`crate::BoardType::imu_span`]), read in one.
    base: u16,
    block: Vec<u8>,
    filter: TiltFilter,
    /// Robot time of the previous good reading, s.
    last: Option<f64>,
    /// The last read's outcome.
    outcome: Outcome,
}

/// The host's clock when it is not the wall clock: a simulated robot on an in-memory
/// bus whose time moves only when the host waits (`twinloop_virtual::Lockstep`), so
/// that the same protocol runs as fast as the simulation can and gives the same
/// result every time.
pub trait HostClock: Send {
    /// Robot time, s.
    fn now(&self) -> f64;
    /// Let `dt` s of robot time pass (one control cycle's wait).
    fn wait(&mut self, dt: f64) -> Result<(), RobotError>;
}

/// A physical robot on a Dynamixel bus.
pub struct DynamixelRobot<T: Transport> {
    pub client: Client<T>,
    mapping: RobotMapping,
    cycle: ControlCycle,
    names: Vec<String>,
    readings: Vec<ServoReading>,
    goals: Vec<i32>,
    /// N m per raw unit of each joint's load/current register, joint direction
    /// included.
    effort_scale: Vec<f64>,
    start: Instant,
    next_tick: Option<Instant>,
    /// Robot seconds per host second (see [`DynamixelRobot::set_clock_rate`]).
    clock_rate: f64,
    /// A clock of the caller's instead of the wall clock (see [`HostClock`]).
    clock: Option<Box<dyn HostClock>>,
    imu: Option<BoardReader>,
    /// Per joint: `Some(residual)` when its goals are dithered (see
    /// [`DynamixelRobot::set_dithered`]), the part of a count not yet sent.
    dither: Vec<Option<f64>>,
}

fn link_to_robot(e: &LinkError, joint: &str) -> RobotError {
    match e.id() {
        Some(_) => RobotError::at_joint(joint, e.to_string()),
        None => RobotError::new(e.to_string()),
    }
}

/// The Model Number a servo answers at address 0 (2 bytes on both protocols: the
/// e-manual control tables of every Dynamixel, EM-RX28 and EM-XM430), if it answers.
fn answered_model<T: Transport>(client: &mut Client<T>, protocol: Protocol, id: u8) -> Option<u16> {
    let mut b = [0u8; 2];
    client.read(protocol, id, 0, &mut b).ok()?;
    Some(u16::from_le_bytes(b))
}

/// Refuse a mapping whose servos are not the models it names: an MX-28 (4096
/// counts per turn) read as an RX-28 (1024 per 300 deg) puts the joint 135 deg off.
/// A servo that does not answer is left to the reads (a silent servo is their
/// business); a mismatch is read twice so that a damaged reply that passed its
/// checksum does not refuse a right mapping.
fn check_models<T: Transport>(
    client: &mut Client<T>,
    mapping: &RobotMapping,
) -> Result<(), RobotError> {
    for j in &mapping.joints {
        let expected = j.model.model_number();
        let Some(got) = answered_model(client, j.protocol, j.id) else {
            continue;
        };
        if got == expected || answered_model(client, j.protocol, j.id) != Some(got) {
            continue;
        }
        let answered = match twinloop_servos::ServoModel::from_model_number(got) {
            Some(m) => format!("{m} (model number {got})"),
            None => format!("model number {got}, not in the catalogue"),
        };
        let line = if j.line > 0 {
            format!(" line {}", j.line)
        } else {
            String::new()
        };
        return Err(RobotError::at_joint(
            &j.name,
            format!(
                "servo id {} answers as {answered}, but the mapping ({}{line}) says {} (model number {expected}): fix the mapping's model",
                j.id, mapping.source, j.model
            ),
        ));
    }
    Ok(())
}

impl<T: Transport> DynamixelRobot<T> {
    /// Build the backend; `method` picks how servos are read (`Auto`: the cheapest
    /// each protocol's servos support).
    pub fn new(
        client: Client<T>,
        mapping: RobotMapping,
        method: ReadMethod,
    ) -> Result<DynamixelRobot<T>, RobotError> {
        let mut client = client;
        check_models(&mut client, &mapping)?;
        let servos = mapping.cycle_servos();
        let cycle = ControlCycle::new(&servos, method)
            .map_err(|e| RobotError::new(format!("{}: {e}", mapping.source)))?;
        let effort_scale = mapping
            .joints
            .iter()
            .enumerate()
            .map(|(k, j)| {
                let reg = cycle.effort_register(k);
                let spec = j.model.spec();
                let per_unit = match reg.unit {
                    Unit::LoadRatio { per_unit } => per_unit * spec.stall_torque,
                    Unit::Current { amps_per_unit, .. } => {
                        amps_per_unit * spec.torque_per_amp().unwrap_or(0.0)
                    }
                    _ => 0.0,
                };
                per_unit * j.direction
            })
            .collect();
        let n = mapping.joints.len();
        // The first board is the trunk IMU.
        let imu = mapping.boards.first().map(|b| BoardReader {
            board: b.clone(),
            base: b.kind.imu_span().0,
            block: vec![0; b.kind.imu_span().1 as usize],
            filter: TiltFilter::default(),
            last: None,
            outcome: Err(LinkError::Timeout { id: b.id }),
        });
        Ok(DynamixelRobot {
            client,
            names: mapping.joint_names(),
            mapping,
            cycle,
            readings: vec![ServoReading::default(); n],
            goals: vec![0; n],
            effort_scale,
            start: Instant::now(),
            next_tick: None,
            clock_rate: 1.0,
            clock: None,
            imu,
            dither: vec![None; n],
        })
    }

    /// How many seconds pass on the robot per second of the host's clock: 1 for a
    /// real robot; for a simulated one served faster than real time (`twinloop
    /// serve --realtime-factor F`), F, so that [`Robot::time`], [`Robot::advance`]
    /// and the tilt filter count the robot's seconds and an experiment runs the same
    /// protocol F times faster. Rates that are not positive and finite are refused.
    pub fn set_clock_rate(&mut self, rate: f64) -> Result<(), RobotError> {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(RobotError::new(format!(
                "clock rate {rate}: robot seconds per host second must be positive"
            )));
        }
        self.clock_rate = rate;
        Ok(())
    }

    /// Count time on `clock` instead of the wall clock: [`Robot::time`] is its
    /// `now`, [`Robot::advance`] its `wait` (see [`HostClock`]).
    pub fn set_clock(&mut self, clock: Box<dyn HostClock>) {
        self.clock = Some(clock);
    }

    /// The board the trunk IMU is read from, if the mapping has one.
    pub fn imu_board(&self) -> Option<&BoardMapping> {
        self.imu.as_ref().map(|b| &b.board)
    }

    /// The IMU board's outcome in the last read, if the mapping has a board.
    pub fn imu_outcome(&self) -> Option<&Outcome> {
        self.imu.as_ref().map(|b| &b.outcome)
    }

    /// The host's tilt estimate (its time constant can be changed).
    pub fn tilt_filter_mut(&mut self) -> Option<&mut TiltFilter> {
        self.imu.as_mut().map(|b| &mut b.filter)
    }

    /// Read the board into `state.imu` (None if it failed).
    fn read_imu(&mut self, state: &mut RobotState) -> Result<(), RobotError> {
        let now = self.time();
        let Some(b) = self.imu.as_mut() else {
            return Ok(());
        };
        let base = b.base;
        let outcome = self
            .client
            .read(b.board.protocol, b.board.id, base, &mut b.block);
        // A board that does not answer is named like a joint (the link itself is
        // alive): `board "trunk_imu": ...`; only a dead port is a link error.
        let who = format!("board {:?}", b.board.name);
        b.outcome = outcome.clone();
        if let Err(e) = outcome {
            state.imu = None;
            return Err(link_to_robot(&e, &who));
        }
        let Some(sample) = b.board.kind.decode_imu(base, &b.block) else {
            state.imu = None;
            b.outcome = Err(LinkError::Implausible {
                id: b.board.id,
                register: "gyro or accelerometer",
            });
            return Err(RobotError::at_joint(
                who,
                format!(
                    "id {}: gyro or accelerometer value outside its register's range ({})",
                    b.board.id, b.board.kind.name
                ),
            ));
        };
        let link = crate::board::ImuSample {
            gyro: b.board.axes.board_to_link(sample.gyro),
            accel: b.board.axes.board_to_link(sample.accel),
        };
        let dt = b.last.map(|t| now - t).unwrap_or(0.0);
        b.last = Some(now);
        b.filter.update(&link, dt);
        state.imu = Some(Imu {
            gyro: link.gyro,
            accel: link.accel,
            orientation: b.filter.orientation(),
        });
        Ok(())
    }

    pub fn mapping(&self) -> &RobotMapping {
        &self.mapping
    }

    pub fn cycle(&self) -> &ControlCycle {
        &self.cycle
    }

    /// The read settings (range checks, Protocol 1.0 verified reads).
    pub fn cycle_mut(&mut self) -> &mut ControlCycle {
        &mut self.cycle
    }

    /// Each joint's outcome in the last read (joint order).
    pub fn outcomes(&self) -> impl Iterator<Item = (&str, &Outcome)> {
        self.names
            .iter()
            .map(|s| s.as_str())
            .zip(self.readings.iter().map(|r| &r.outcome))
    }

    /// Torque on or off for every joint (one SYNC_WRITE per protocol).
    pub fn set_torque(&mut self, on: bool) -> Result<(), RobotError> {
        self.set_register(Item::TorqueEnable, on as i32).map(|_| ())
    }

    /// Write `value` (raw) to `item` of every joint whose servo has that register
    /// (one SYNC_WRITE per protocol and register layout); returns how many servos
    /// were written. For RAM settings an experiment needs, such as the RX compliance
    /// slopes and margins.
    pub fn set_register(&mut self, item: Item, value: i32) -> Result<usize, RobotError> {
        self.set_register_of(item, value, |_| true)
    }

    /// Dither the goals of the joints `pick` selects (indices in
    /// [`Robot::joint_names`] order), and round the others' as before.
    ///
    /// A Goal Position is a whole count (0.29 deg on an RX), so a slow ramp sent
    /// rounded is a staircase, and each step jolts the robot. Dithered, each goal
    /// goes out as first-order sigma-delta modulation (error feedback, as in a
    /// delta-sigma converter): the part of a count that rounding drops is carried
    /// to the next command, so the counts sent flip between the two around the
    /// goal and their running mean is the goal itself, finer than a count. Joints
    /// whose goals change together by the same amount flip together. Selecting
    /// again starts every residual from zero.
    pub fn set_dithered(&mut self, pick: impl Fn(usize) -> bool) {
        for (k, d) in self.dither.iter_mut().enumerate() {
            *d = pick(k).then_some(0.0);
        }
    }

    /// [`DynamixelRobot::set_register`] for the joints (indices in
    /// [`Robot::joint_names`] order) that `pick` selects.
    pub fn set_register_of(
        &mut self,
        item: Item,
        value: i32,
        pick: impl Fn(usize) -> bool,
    ) -> Result<usize, RobotError> {
        use crate::register::Register;
        // Servos of one protocol whose register sits at the same address and size.
        let mut groups: Vec<(Protocol, &'static Register, Vec<u8>)> = Vec::new();
        for (k, j) in self.mapping.joints.iter().enumerate() {
            if !pick(k) {
                continue;
            }
            let Some(reg) = j.model.table().item(item) else {
                continue;
            };
            let same = |g: &&mut (Protocol, &Register, Vec<u8>)| {
                g.0 == j.protocol && g.1.address == reg.address && g.1.size == reg.size
            };
            match groups.iter_mut().find(same) {
                Some(g) => g.2.push(j.id),
                None => groups.push((j.protocol, reg, vec![j.id])),
            }
        }
        let mut written = 0;
        for (protocol, reg, ids) in groups {
            let size = reg.size as usize;
            let mut data = vec![0u8; size * ids.len()];
            for chunk in data.chunks_mut(size) {
                reg.encode(value, chunk);
            }
            self.client
                .sync_write(protocol, reg.address, reg.size as u16, &ids, &data)
                .map_err(|e| RobotError::new(e.to_string()))?;
            written += ids.len();
        }
        Ok(written)
    }
}

impl<T: Transport> Robot for DynamixelRobot<T> {
    fn joint_names(&self) -> &[String] {
        &self.names
    }

    fn time(&self) -> f64 {
        match &self.clock {
            Some(c) => c.now(),
            None => self.start.elapsed().as_secs_f64() * self.clock_rate,
        }
    }

    /// One read of every joint. Joints whose servo failed read NaN; the first such
    /// joint is named in the error (the others are in [`DynamixelRobot::outcomes`]),
    /// and the state is filled either way.
    fn read(&mut self, state: &mut RobotState) -> Result<(), RobotError> {
        let n = self.names.len();
        let read = self.cycle.read(&mut self.client, &mut self.readings);
        state.time = self.time();
        let summary = match read {
            Ok(s) => s,
            Err(e) => {
                // The link failed: nothing was read, and the state says so (NaN),
                // never the previous cycle's values as if read again.
                state.positions.clear();
                state.positions.resize(n, f64::NAN);
                for v in [&mut state.velocities, &mut state.efforts] {
                    let v = v.get_or_insert_with(Vec::new);
                    v.clear();
                    v.resize(n, f64::NAN);
                }
                return Err(RobotError::new(e.to_string()));
            }
        };
        state.positions.resize(n, f64::NAN);
        let velocities = state.velocities.get_or_insert_with(Vec::new);
        velocities.resize(n, f64::NAN);
        let efforts = state.efforts.get_or_insert_with(Vec::new);
        efforts.resize(n, f64::NAN);
        let mut first_error = None;
        for (k, (j, r)) in self.mapping.joints.iter().zip(&self.readings).enumerate() {
            match &r.outcome {
                Ok(_) => {
                    state.positions[k] = j.position(r.position);
                    velocities[k] = j.direction * self.cycle.velocity_register(k).to_si(r.velocity);
                    efforts[k] = self.effort_scale[k]
                        * (r.effort
                            - match self.cycle.effort_register(k).unit {
                                Unit::Current { zero, .. } => zero,
                                _ => 0,
                            }) as f64;
                }
                Err(e) => {
                    state.positions[k] = f64::NAN;
                    velocities[k] = f64::NAN;
                    efforts[k] = f64::NAN;
                    if first_error.is_none() {
                        first_error = Some(link_to_robot(e, &j.name));
                    }
                }
            }
        }
        let imu = self.read_imu(state);
        match first_error {
            None => imu,
            Some(mut e) => {
                if summary.failed > 1 {
                    e.message =
                        format!("{} ({} joints failed this read)", e.message, summary.failed);
                }
                Err(e)
            }
        }
    }

    /// Goal positions (rad, clamped to each joint's limits) to every servo.
    fn command_positions(&mut self, goals: &[f64]) -> Result<(), RobotError> {
        if goals.len() != self.names.len() {
            return Err(RobotError::new(format!(
                "{} goals for {} joints",
                goals.len(),
                self.names.len()
            )));
        }
        for (k, j) in self.mapping.joints.iter().enumerate() {
            self.goals[k] = match self.dither[k].as_mut() {
                None => j.goal_raw(goals[k]),
                Some(residual) => j.goal_raw_carrying(goals[k], residual),
            };
        }
        self.cycle
            .write_goals(&mut self.client, &self.goals)
            .map_err(|e| RobotError::new(e.to_string()))
    }

    /// Wait until `dt` after the previous call's target time, so a loop calling
    /// read / command / advance(dt) runs at a steady rate; if the loop fell behind
    /// it starts counting again from now.
    fn advance(&mut self, dt: f64) -> Result<(), RobotError> {
        if dt.is_nan() || dt < 0.0 {
            return Err(RobotError::new(format!("advance by {dt} s")));
        }
        if let Some(c) = self.clock.as_mut() {
            return c.wait(dt);
        }
        let now = Instant::now();
        let step = Duration::from_secs_f64(dt / self.clock_rate);
        let target = match self.next_tick {
            Some(t) if t + step > now => t + step,
            _ => now + step,
        };
        if target > now {
            std::thread::sleep(target - now);
        }
        self.next_tick = Some(target);
        Ok(())
    }
}
