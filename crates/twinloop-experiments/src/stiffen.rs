//! Every servo stiff for an experiment, and back as it was afterwards: the static
//! methods (tip-over, lean) treat the robot as rigid, so each servo holds its pose as
//! stiffly as its family allows. What to write comes from the servo catalogue
//! (`twinloop_servos`: RX compliance margin and slope, MX P Gain, MX(2.0)/X Position
//! P Gain, [`ServoModel::stiff_values`]); the host reads those registers first and
//! writes back what it found when the experiment ends.
//!
//! A servo model the catalogue knows no way to stiffen stops the experiment before
//! anything moves ([`check_stiffenable`]) unless the caller runs with the servos as
//! they are (`--soft-servos`), and then says so in its output.

use crate::guarded::BusRobot;
use std::time::{Duration, Instant};
use twinloop_link::servos::{LoopFamily, LoopRegister};
use twinloop_link::{Protocol, RobotMapping, ServoModel};
use twinloop_robot::RobotError;

/// The loop registers as the experiment found them, per servo: what
/// [`restore_loops`] writes back.
#[derive(Debug, Clone, Default)]
pub struct SavedLoops {
    entries: Vec<Saved>,
}

#[derive(Debug, Clone, Copy)]
struct Saved {
    id: u8,
    protocol: Protocol,
    reg: LoopRegister,
    value: i32,
}

impl SavedLoops {
    /// `(id, register name, value found)` for every register read.
    pub fn values(&self) -> impl Iterator<Item = (u8, &'static str, i32)> + '_ {
        self.entries.iter().map(|e| (e.id, e.reg.name, e.value))
    }
}

/// The joints whose servo model has no known way to stiffen, `(id, model)`.
pub fn unstiffenable(mapping: &RobotMapping) -> Vec<(u8, ServoModel)> {
    mapping
        .joints
        .iter()
        .filter(|j| j.model.stiff_values(2).is_none())
        .map(|j| (j.id, j.model))
        .collect()
}

/// Refuse a robot with a servo no known way stiffens (before anything moves): the
/// error names each such servo's id and model and the way out.
pub fn check_stiffenable(mapping: &RobotMapping) -> Result<(), RobotError> {
    let soft = unstiffenable(mapping);
    if soft.is_empty() {
        return Ok(());
    }
    let list: Vec<String> = soft
        .iter()
        .map(|(id, m)| format!("servo id {id} ({m})"))
        .collect();
    Err(RobotError::new(format!(
        "{}: no known way to stiffen {}: the experiment treats the robot as rigid; \
         run with --soft-servos to measure with the servos as they are",
        mapping.source,
        list.join(", ")
    )))
}

/// Read every joint's loop registers (one READ per servo and register), each read
/// taken again while the servo stays silent for less than `window` (wall time: a
/// host or served robot descheduled on a busy machine, as [`crate::guarded`] rides
/// out in the experiment's reads).
pub fn save_loops(robot: &mut BusRobot, window: Duration) -> Result<SavedLoops, RobotError> {
    let joints: Vec<(u8, Protocol, ServoModel)> = robot
        .mapping()
        .joints
        .iter()
        .map(|j| (j.id, j.protocol, j.model))
        .collect();
    let mut entries = Vec::new();
    for (id, protocol, model) in joints {
        for &reg in model.loop_registers() {
            let mut buf = [0u8; 4];
            let bytes = &mut buf[..reg.size as usize];
            read_within(robot, protocol, id, reg.address, bytes, window).map_err(|e| {
                RobotError::new(format!(
                    "reading {} of servo id {id} ({model}): {e}",
                    reg.name
                ))
            })?;
            let value = bytes
                .iter()
                .rev()
                .fold(0i32, |v, &b| (v << 8) | i32::from(b));
            entries.push(Saved {
                id,
                protocol,
                reg,
                value,
            });
        }
    }
    Ok(SavedLoops { entries })
}

/// One READ, taken again on a transient failure (no reply, a damaged one) until it
/// succeeds or the servo has been silent for `window`.
fn read_within(
    robot: &mut BusRobot,
    protocol: Protocol,
    id: u8,
    address: u16,
    out: &mut [u8],
    window: Duration,
) -> Result<(), twinloop_link::LinkError> {
    let start = Instant::now();
    loop {
        match robot.client.read(protocol, id, address, out) {
            Ok(_) => return Ok(()),
            Err(e) if e.is_transient() && start.elapsed() < window => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Write the stiff values for Compliance Slope `rx_slope` (RX units: 2 the
/// stiffest, 32 the factory's; the other families as stiff, see
/// [`ServoModel::stiff_values`]) to the joints `pick` selects (indices in the
/// mapping's joint order). Servos with no known way are left as they are.
pub fn stiffen(
    robot: &mut BusRobot,
    rx_slope: u8,
    pick: impl Fn(usize) -> bool,
) -> Result<(), RobotError> {
    let mut writes: Vec<(u8, Protocol, LoopRegister, i32)> = Vec::new();
    for (k, j) in robot.mapping().joints.iter().enumerate() {
        let Some(values) = j.model.stiff_values(rx_slope).filter(|_| pick(k)) else {
            continue;
        };
        for (&reg, v) in j.model.loop_registers().iter().zip(values) {
            writes.push((j.id, j.protocol, reg, v));
        }
    }
    write_grouped(robot, &writes)
}

/// The stiffness of a servo a lean ramps, as an RX Compliance Slope: `ankle` on an
/// RX (whole goal counts of 0.29 deg jolt a stiff RX ankle and tip the robot early:
/// `twinloop_ident::tipover_bus::ANKLE_SLOPE`), `hold` on MX and X, whose counts are
/// 0.088 deg. Measured on the served OP3 (XM430-W350, dithered goals, ramp 2 deg/s,
/// creep 0.15 deg/s, docs/adaptation.md): ramped ankles at the RX-32 equivalent (P
/// 1062) tipped 2.4 deg (forward) to 1.4 deg (sideways) behind their goals and read
/// sideways 21.2 deg; as stiff as the rest (P 16383), 23.9 deg, 2.7 deg nearer the
/// simulator's 28.9, backward 0.3 deg nearer, forward 0.4 deg farther, the CoM as far
/// off (16.7 and 17.2 mm).
pub fn ramped_slope(model: ServoModel, hold: u8, ankle: u8) -> u8 {
    match model.family() {
        Some(LoopFamily::Compliance) => ankle,
        _ => hold,
    }
}

/// [`stiffen`] for a lean: the joints `ramped` selects at [`ramped_slope`], the
/// others at `hold`.
pub fn stiffen_for_lean(
    robot: &mut BusRobot,
    hold: u8,
    ankle: u8,
    ramped: impl Fn(usize) -> bool,
) -> Result<(), RobotError> {
    let models: Vec<ServoModel> = robot.mapping().joints.iter().map(|j| j.model).collect();
    let soft_ankle = |k: usize| ramped(k) && ramped_slope(models[k], hold, ankle) != hold;
    stiffen(robot, hold, |k| !soft_ankle(k))?;
    stiffen(robot, ankle, soft_ankle)
}

/// Write back what [`save_loops`] read.
pub fn restore_loops(robot: &mut BusRobot, saved: &SavedLoops) -> Result<(), RobotError> {
    let writes: Vec<(u8, Protocol, LoopRegister, i32)> = saved
        .entries
        .iter()
        .map(|e| (e.id, e.protocol, e.reg, e.value))
        .collect();
    write_grouped(robot, &writes)
}

/// One SYNC_WRITE per protocol and register (address and size), each servo its own
/// value.
fn write_grouped(
    robot: &mut BusRobot,
    writes: &[(u8, Protocol, LoopRegister, i32)],
) -> Result<(), RobotError> {
    let mut done = vec![false; writes.len()];
    for k in 0..writes.len() {
        if done[k] {
            continue;
        }
        let (_, protocol, reg, _) = writes[k];
        let size = reg.size as usize;
        let (mut ids, mut data) = (Vec::new(), Vec::new());
        for (m, &(id, p, r, v)) in writes.iter().enumerate().skip(k) {
            if !done[m] && p == protocol && r.address == reg.address && r.size == reg.size {
                done[m] = true;
                ids.push(id);
                data.extend_from_slice(&(v as u32).to_le_bytes()[..size]);
            }
        }
        robot
            .client
            .sync_write(protocol, reg.address, reg.size as u16, &ids, &data)
            .map_err(|e| RobotError::new(format!("writing {}: {e}", reg.name)))?;
    }
    Ok(())
}
