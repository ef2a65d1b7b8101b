//! `twinloop experiment servo`: one servo driven through the excitation of
//! docs/servo-models.md, every read logged as it comes: on a pendulum bench (`--id`,
//! `--load`) or moving one limb of a held robot (`--map`, `--joint`; the load from
//! the description, crate::limb).

use super::bus::{confirm, is_serial, resolve};
use crate::bus_args::{PortArgs, interrupt_flag, open_client};
use crate::error::{CliError, CliResult, Outcome};
use crate::limb::Limb;
use clap::Args;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Instant;
use twinloop_actuator::log::LogWriter;
use twinloop_actuator::{Excitation, LoopFamily, Pendulum, ServoType};
use twinloop_link::ModelTable;
use twinloop_link::transport::Transport;
use twinloop_link::{Client, Item, JointMapping, Protocol, Register, RobotMapping, ServoModel};

#[derive(Args, Debug)]
pub struct ServoArgs {
    #[command(flatten)]
    pub bus: PortArgs,
    /// Bench: the servo's id
    #[arg(long, value_name = "N", required_unless_present = "joint", conflicts_with_all = ["map", "joint"], requires = "load", value_parser = crate::common::servo_id)]
    pub id: Option<u8>,
    /// Bench: the pendulum, a TOML file with mass (kg), length (m), arm_inertia (kg m^2)
    #[arg(long, value_name = "LOAD.toml", requires = "id")]
    pub load: Option<PathBuf>,
    /// Limb of a held robot: the servo mapping (builtin:km20 or a mapping TOML)
    #[arg(long, value_name = "MAP", requires = "joint")]
    pub map: Option<String>,
    /// Limb of a held robot: the joint whose servo moves (the mapping's name)
    #[arg(long, value_name = "NAME", requires = "map")]
    pub joint: Option<String>,
    /// Limb of a held robot: the description (default: the mapping's `urdf`)
    #[arg(long, value_name = "ROBOT", requires = "joint")]
    pub robot: Option<String>,
    /// The log (CSV, written row by row)
    #[arg(long, value_name = "LOG.csv")]
    pub out: PathBuf,
    /// Scale of the sequence's angles (1: steps up to 0.8 rad, sinusoids of 0.5 rad)
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = crate::common::positive)]
    pub amplitude: f64,
    /// Servo seconds per host second: F for a bench served with `serve --realtime-factor F`
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = crate::bounds::realtime_factor)]
    pub realtime_factor: f64,
    /// Over a serial port: do not ask before moving the servo
    #[arg(long)]
    pub yes: bool,
}

/// Stop before the factory Temperature Limit (80 C) trips the servo.
const MAX_TEMPERATURE_C: f64 = 75.0;
/// Reads in a row without an answer before the servo is taken for gone.
const MAX_MISSES: usize = 25;

/// The registers read each cycle, as one block.
struct Block {
    start: u16,
    len: usize,
    regs: [Option<&'static Register>; 7],
}

impl Block {
    /// Present Position, Velocity, Load, Current, Voltage, Temperature, and Goal
    /// Position (the goal the servo has: a write whose reply was lost may or may not
    /// have reached it).
    fn new(model: ServoModel) -> Block {
        let t = model.table();
        let regs = [
            Item::PresentPosition,
            Item::PresentVelocity,
            Item::PresentLoad,
            Item::PresentCurrent,
            Item::PresentVoltage,
            Item::PresentTemperature,
            Item::GoalPosition,
        ]
        .map(|i| t.item(i));
        let start = regs.iter().flatten().map(|r| r.address).min().unwrap_or(0);
        let end = regs.iter().flatten().map(|r| r.end()).max().unwrap_or(0);
        Block {
            start,
            len: (end - start) as usize,
            regs,
        }
    }

    fn value(&self, k: usize, buf: &[u8]) -> f64 {
        match self.regs[k] {
            Some(r) => {
                let a = (r.address - self.start) as usize;
                r.to_si(r.decode(&buf[a..a + r.size as usize]))
            }
            None => f64::NAN,
        }
    }
}

/// Find the servo: --id on either protocol.
fn find(client: &mut Client<Box<dyn Transport>>, id: u8) -> Result<ServoModel, CliError> {
    for protocol in [Protocol::V1, Protocol::V2] {
        if let Ok(found) = client.ping(protocol, id) {
            return found.model.ok_or_else(|| {
                CliError::new(format!(
                    "servo id {id}: model number {} is not one twinloop knows",
                    found.model_number
                ))
            });
        }
    }
    Err(CliError::new(format!(
        "servo id {id}: no answer on either protocol"
    )))
}

fn write_item(
    client: &mut Client<Box<dyn Transport>>,
    model: ServoModel,
    id: u8,
    item: Item,
    value: i32,
) -> Result<(), CliError> {
    let r = model
        .table()
        .item(item)
        .ok_or_else(|| CliError::new(format!("servo id {id}: {model} has no {item:?} register")))?;
    let mut b = [0u8; 4];
    r.encode(value, &mut b[..r.size as usize]);
    client
        .write(model.protocol(), id, r.address, &b[..r.size as usize])
        .map_err(|e| CliError::new(format!("servo id {id}: writing {}: {e}", r.name)))?;
    Ok(())
}

/// Write the loop's registers: RX compliance slope (both directions), margin and
/// punch; MX/X Position P, I, D gains.
fn write_firmware(
    client: &mut Client<Box<dyn Transport>>,
    model: ServoModel,
    servo: ServoType,
    id: u8,
    regs: [f64; 3],
) -> Result<(), CliError> {
    let items: &[(Item, usize)] = match servo.family() {
        LoopFamily::Compliance => &[
            (Item::CwComplianceSlope, 0),
            (Item::CcwComplianceSlope, 0),
            (Item::CwComplianceMargin, 1),
            (Item::CcwComplianceMargin, 1),
            (Item::Punch, 2),
        ],
        LoopFamily::Pid => &[
            (Item::PositionPGain, 0),
            (Item::PositionIGain, 1),
            (Item::PositionDGain, 2),
        ],
    };
    // A gain the log records must have arrived: a lost reply is tried again.
    for &(item, k) in items {
        let mut tries = 0;
        while let Err(e) = write_item(client, model, id, item, regs[k] as i32) {
            tries += 1;
            if tries >= 5 {
                return Err(e);
            }
        }
    }
    Ok(())
}

/// The bus's client.
type BusClient = Client<Box<dyn Transport>>;

/// Where the limb's sequence stays away from the joint's limits, rad.
const LIMIT_MARGIN: f64 = 0.1;
/// How far beyond its goal a servo may swing (a step's overshoot), as a share of
/// the goal's excursion, in choosing the limb's amplitude.
const OVERSHOOT: f64 = 1.2;
/// The standard sequence's excursions at amplitude 1, rad: its largest step and the
/// farthest it goes the other way (the sinusoids).
const REACH_FAR: f64 = 0.8;
const REACH_NEAR: f64 = 0.5;

/// What the run moves: the servo, where the sequence is centred and which way its
/// largest step goes, the goals' bounds, and the log's extra comment lines.
struct Target {
    id: u8,
    model: ServoModel,
    servo: ServoType,
    /// Servo angle the sequence is centred on and returns to, rad.
    centre: f64,
    /// +1 or -1: the sequence's sign (its 0.8 step toward the wider side).
    sign: f64,
    amplitude: f64,
    /// Goals are clamped into these (servo angles, rad), and a position beyond them
    /// by more than [`LIMIT_MARGIN`] stops the run.
    bounds: (f64, f64),
    comments: String,
    what: String,
}

pub fn run(a: &ServoArgs) -> CliResult {
    let (mut client, port, target) = match (&a.joint, a.id) {
        (Some(joint), _) => limb_target(a, joint)?,
        (None, Some(id)) => bench_target(a, id)?,
        (None, None) => {
            return Err(CliError::new(
                "give --id N --load LOAD.toml (a bench) or --map MAP --joint NAME (a limb of a held robot)",
            ));
        }
    };
    let exc = Excitation::standard(target.servo, target.amplitude);
    if is_serial(&port) && !a.yes {
        confirm(&format!(
            "{} on {port} for {:.0} s",
            target.what,
            exc.duration(),
        ))?;
    }
    drive(a, &mut client, &port, &target, &exc)
}

/// The bench: --id swinging the pendulum of --load, hanging at 0.
fn bench_target(a: &ServoArgs, id: u8) -> Result<(BusClient, String, Target), CliError> {
    let path = a
        .load
        .as_ref()
        .ok_or("--id needs --load LOAD.toml (the pendulum)")?;
    let load = Pendulum::read(path)?;
    let mut client = open_client(&a.bus, None)?;
    let port = a.bus.port.clone().unwrap_or_default();
    let model = find(&mut client, id)?;
    let servo = servo_type(model, id)?;
    let stall = servo.rating().stall_torque;
    let gravity = load.mass * twinloop_actuator::bench::GRAVITY * load.length;
    if gravity > twinloop_actuator::load_rule::MAX_RATIO * stall {
        return Err(CliError::new(format!(
            "{}: the pendulum's weight takes {gravity:.2} N m at the horizontal, over 60 % of the {servo}'s {stall} N m stall torque: lighter or shorter",
            path.display()
        )));
    }
    if let Some(w) = twinloop_actuator::load_rule::too_light(servo, &load) {
        eprintln!("warning: {}: {w}", path.display());
    }
    let target = Target {
        id,
        model,
        servo,
        centre: 0.0,
        sign: 1.0,
        amplitude: a.amplitude,
        bounds: (f64::NEG_INFINITY, f64::INFINITY),
        comments: String::new(),
        what: format!(
            "swing the pendulum on servo id {id} ({servo}), up to {:.2} rad from hanging",
            REACH_FAR * a.amplitude
        ),
    };
    Ok((client, port, target))
}

/// The mapping's entry for `--joint`.
fn mapped_joint<'m>(mapping: &'m RobotMapping, joint: &str) -> Result<&'m JointMapping, CliError> {
    mapping
        .joints
        .iter()
        .find(|j| j.name == joint)
        .ok_or_else(|| {
            CliError::new(format!(
                "--joint {joint:?}: not a joint of {} (its joints: {})",
                mapping.source,
                mapping
                    .joints
                    .iter()
                    .map(|j| j.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
}

/// The held pose: every mapped servo's position now; joints without a servo at 0
/// (within their limits), as the virtual robot holds them. With `joint`'s servo
/// angle.
fn held_pose(
    client: &mut BusClient,
    mapping: &RobotMapping,
    model: &twinloop_dynamics::Model,
    joint: &str,
) -> Result<(Vec<(String, f64)>, f64), CliError> {
    let mut pose: Vec<(String, f64)> = model
        .joint_names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            (
                n.clone(),
                0f64.clamp(model.lower_limits[i], model.upper_limits[i]),
            )
        })
        .collect();
    let mut here = 0.0;
    for j in &mapping.joints {
        let Some(i) = model.joint_index(&j.name) else {
            continue;
        };
        let s = read_position(client, j.model, j.id)?;
        pose[i].1 = j.joint_angle(s);
        if j.name == joint {
            here = s;
        }
    }
    Ok((pose, here))
}

/// Refuse a limb too heavy for the servo; warn when it is too light to determine
/// friction and armature (docs/servo-models.md, "Which load").
fn check_load(joint: &str, servo: ServoType, gravity: f64) -> Result<(), CliError> {
    let stall = servo.rating().stall_torque;
    let rule = twinloop_actuator::load_rule::MAX_RATIO;
    if gravity > rule * stall {
        return Err(CliError::new(format!(
            "--joint {joint}: the limb's weight takes up to {gravity:.2} N m, over {:.0} % of the {servo}'s {stall} N m stall torque",
            100.0 * rule
        )));
    }
    let min = twinloop_actuator::load_rule::min_ratio(servo);
    if gravity < min * stall {
        eprintln!(
            "warning: --joint {joint}: the limb's weight takes up to {gravity:.2} N m, {:.0} % of the {servo}'s {stall} N m stall torque; {}friction and armature are poorly determined below {:.0} % (docs/servo-models.md, \"Which load\"): a bench with a heavier pendulum determines them better",
            100.0 * gravity / stall,
            if servo.current_unit().is_none() {
                "it senses no current, so "
            } else {
                ""
            },
            100.0 * min
        );
    }
    Ok(())
}

/// The joint's range as servo angles (the description's limits within the
/// mapping's, narrowed by the margin), the side with more room and the amplitude
/// that keeps the sequence inside it.
fn sequence_range(
    a: &ServoArgs,
    jm: &JointMapping,
    model: &twinloop_dynamics::Model,
    k: usize,
    here: f64,
    joint: &str,
) -> Result<(f64, f64, f64, f64), CliError> {
    let (jlo, jhi) = (
        model.lower_limits[k].max(jm.min),
        model.upper_limits[k].min(jm.max),
    );
    let (s1, s2) = (jm.servo_angle(jlo), jm.servo_angle(jhi));
    let (lo, hi) = (s1.min(s2), s1.max(s2));
    let (room_up, room_down) = (hi - LIMIT_MARGIN - here, here - lo - LIMIT_MARGIN);
    let (sign, far, near) = if room_up >= room_down {
        (1.0, room_up, room_down)
    } else {
        (-1.0, room_down, room_up)
    };
    let amplitude = a
        .amplitude
        .min(far / (OVERSHOOT * REACH_FAR))
        .min(near / (OVERSHOOT * REACH_NEAR));
    if amplitude < 0.1 {
        return Err(CliError::new(format!(
            "--joint {joint}: at {here:.3} rad (servo angle) it is too near its limits ({lo:.3} to {hi:.3} rad) for the sequence: move it towards the middle of its range first"
        )));
    }
    Ok((lo, hi, sign, amplitude))
}

/// The limb of a held robot: --joint's servo from --map, its load the subtree beyond
/// the joint at the pose the other servos hold (read now), the sequence centred
/// where the joint is and scaled to stay inside its limits.
fn limb_target(a: &ServoArgs, joint: &str) -> Result<(BusClient, String, Target), CliError> {
    let (mapping, port, spec) = resolve(
        a.map.as_deref(),
        &a.bus,
        a.robot.as_deref(),
        "the limb's load",
    )?;
    let spec = recorded_spec(&spec, &mapping);
    let (robot, _) = crate::common::load_description(&spec)?;
    crate::common::hinges_only(&robot, &spec, "a limb load")?;
    let jm = mapped_joint(&mapping, joint)?;
    let model = twinloop_dynamics::Model::from_description_with_base(
        &robot,
        twinloop_dynamics::BaseKind::Fixed,
    )
    .map_err(|e| CliError::new(format!("{spec}: {e}")))?;
    let k = model
        .joint_index(joint)
        .ok_or_else(|| CliError::new(format!("--joint {joint:?}: not a joint of {spec}")))?;
    let bus = PortArgs {
        port: Some(port.clone()),
        ..a.bus.clone()
    };
    let mut client = open_client(&bus, None)?;
    let found = find(&mut client, jm.id)?;
    if found != jm.model {
        return Err(CliError::new(format!(
            "servo id {} ({joint}): answers as {found}, {} says {}",
            jm.id, mapping.source, jm.model
        )));
    }
    let servo = servo_type(found, jm.id)?;
    let (pose, here) = held_pose(&mut client, &mapping, &model, joint)?;
    let (gravity, trunk) = match mapping.boards.first() {
        Some(b) => (
            trunk_gravity(&mut client, b, &model, &pose)?,
            format!("from board \"{}\" (id {})", b.name, b.id),
        ),
        None => (
            crate::limb::UPRIGHT,
            "trunk assumed upright: no IMU board in the mapping".to_string(),
        ),
    };
    let limb = Limb {
        robot: spec.clone(),
        joint: joint.to_string(),
        zero: jm.zero,
        direction: jm.direction,
        pose,
        gravity,
        trunk,
    };
    let (load, _) = limb.load(&robot)?;
    check_load(joint, servo, load.max_gravity_torque())?;
    let (lo, hi, sign, amplitude) = sequence_range(a, jm, &model, k, here, joint)?;
    let what = format!(
        "move {joint} (servo id {}, {servo}) of the held robot (trunk fixed, every other servo holding) by up to {:.2} rad from {here:.3} rad (range {lo:.3} to {hi:.3})",
        jm.id,
        REACH_FAR * amplitude
    );
    let target = Target {
        id: jm.id,
        model: found,
        servo,
        centre: here,
        sign,
        amplitude,
        bounds: (lo, hi),
        comments: limb.header(&load),
        what,
    };
    hold_others(&mut client, &mapping, jm.id)?;
    Ok((client, port, target))
}

/// Readings of the trunk's accelerometer averaged for gravity's direction.
const GRAVITY_READS: usize = 20;

/// Gravity in the base frame, m/s^2: the board's accelerometer (averaged; the robot
/// held still reads +g along up) turned from its link into the base frame at the
/// held pose, scaled to the description's g.
fn trunk_gravity(
    client: &mut BusClient,
    board: &twinloop_link::mapping::BoardMapping,
    model: &twinloop_dynamics::Model,
    pose: &[(String, f64)],
) -> Result<[f64; 3], CliError> {
    let who = format!("board \"{}\" (id {})", board.name, board.id);
    let (base, len) = board.kind.imu_span();
    let mut block = vec![0u8; len as usize];
    let mut sum = nalgebra::Vector3::zeros();
    let mut n = 0;
    let mut misses = 0;
    while n < GRAVITY_READS {
        let sample = client
            .read(board.protocol, board.id, base, &mut block)
            .ok()
            .and_then(|_| board.kind.decode_imu(base, &block));
        match sample {
            Some(s) => {
                sum += nalgebra::Vector3::from(board.axes.board_to_link(s.accel));
                n += 1;
            }
            None => {
                misses += 1;
                if misses > MAX_MISSES {
                    return Err(CliError::new(format!(
                        "{who}: no accelerometer reading ({misses} tries)"
                    )));
                }
            }
        }
    }
    let up = sum / n as f64;
    let g = twinloop_description::GRAVITY;
    if (up.norm() / g - 1.0).abs() > 0.2 {
        return Err(CliError::new(format!(
            "{who}: the accelerometer reads {:.2} m/s^2, not gravity's {g}: is the robot held still?",
            up.norm()
        )));
    }
    let link = model
        .links
        .iter()
        .find(|l| l.name == board.link)
        .ok_or_else(|| {
            CliError::new(format!(
                "{who}: link \"{}\" is not a link of the robot",
                board.link
            ))
        })?;
    let mut q = vec![0.0; model.nq];
    for (name, angle) in pose {
        if let Some(k) = model.joint_index(name) {
            q[model.idx_q[k]] = *angle;
        }
    }
    let mut data = twinloop_dynamics::Data::new(model);
    twinloop_dynamics::forward_kinematics(model, &mut data, &q);
    let body = if link.body == twinloop_dynamics::BASE {
        nalgebra::Matrix3::identity()
    } else {
        data.o_m_i[link.body].rotation
    };
    let in_base = body * link.placement.rotation * up;
    let gravity = -g * in_base / in_base.norm();
    Ok([gravity.x, gravity.y, gravity.z])
}

/// The description as the log records it: a file given relative to the mapping
/// file, or to here, made absolute so `identify servo` finds it from anywhere.
fn recorded_spec(spec: &str, mapping: &RobotMapping) -> String {
    if spec.starts_with("builtin:") {
        return spec.to_string();
    }
    let p = std::path::Path::new(spec);
    let candidate = match std::path::Path::new(&mapping.source).parent() {
        Some(d) if p.is_relative() && !p.exists() => d.join(p),
        _ => p.to_path_buf(),
    };
    std::fs::canonicalize(&candidate)
        .map(|c| c.display().to_string())
        .unwrap_or_else(|_| spec.to_string())
}

/// Every other mapped servo holds where it is, torque on, its loop as it was: the
/// robot held still. (Stiffened to RX slope 2, margin 0, the fit on the simulated
/// km20 did no better: friction_base 7-8 % high against 2.6-6.4 %,
/// docs/servo-models.md.)
fn hold_others(
    client: &mut Client<Box<dyn Transport>>,
    mapping: &RobotMapping,
    moving: u8,
) -> Result<(), CliError> {
    for j in mapping.joints.iter().filter(|j| j.id != moving) {
        let s = read_position(client, j.model, j.id)?;
        let reg = j
            .model
            .table()
            .item(Item::GoalPosition)
            .ok_or("no Goal Position")?;
        write_item(client, j.model, j.id, Item::GoalPosition, reg.from_si(s))?;
        write_item(client, j.model, j.id, Item::TorqueEnable, 1)?;
    }
    Ok(())
}

/// Present Position of one servo, rad (a few tries: a lost reply is no reason to stop).
fn read_position(
    client: &mut Client<Box<dyn Transport>>,
    model: ServoModel,
    id: u8,
) -> Result<f64, CliError> {
    let r = model
        .table()
        .item(Item::PresentPosition)
        .ok_or_else(|| CliError::new(format!("servo id {id}: {model} has no Present Position")))?;
    let mut buf = [0u8; 4];
    let n = r.size as usize;
    let mut last = String::new();
    for _ in 0..5 {
        match client.read(model.protocol(), id, r.address, &mut buf[..n]) {
            Ok(_) => return Ok(r.to_si(r.decode(&buf[..n]))),
            Err(e) => last = e.to_string(),
        }
    }
    Err(CliError::new(format!(
        "servo id {id}: reading Present Position: {last}"
    )))
}

fn servo_type(model: ServoModel, id: u8) -> Result<ServoType, CliError> {
    twinloop_virtual::servo_type(model).ok_or_else(|| {
        CliError::new(format!(
            "servo id {id}: {model} has no servo model (known: {})",
            ServoType::known_names()
        ))
    })
}

/// The first sign of trouble in a cycle: a hardware fault, heat, the servo past
/// its range, or Ctrl-C.
fn trouble(
    id: u8,
    status: twinloop_link::StatusError,
    m: &[f64; 7],
    (lo, hi): (f64, f64),
    stop: &std::sync::atomic::AtomicBool,
) -> Option<String> {
    if status.hardware_fault() {
        return Some(format!("servo id {id}: {status}"));
    }
    if m[5] >= MAX_TEMPERATURE_C {
        return Some(format!(
            "servo id {id}: {} C, stopping before its 80 C limit",
            m[5]
        ));
    }
    if m[0] < lo - LIMIT_MARGIN || m[0] > hi + LIMIT_MARGIN {
        return Some(format!(
            "servo id {id}: at {:.3} rad, past the joint's range {lo:.3} to {hi:.3} rad",
            m[0]
        ));
    }
    if stop.load(Ordering::Relaxed) {
        return Some("interrupted (Ctrl-C)".into());
    }
    None
}

/// The first goal and the firmware's registers written, then the torque on.
fn start(
    client: &mut Client<Box<dyn Transport>>,
    target: &Target,
    regs: [f64; 3],
    goal_raw: i32,
) -> Result<(), CliError> {
    let (id, model, servo) = (target.id, target.model, target.servo);
    write_firmware(client, model, servo, id, regs)?;
    write_item(client, model, id, Item::GoalPosition, goal_raw)?;
    write_item(client, model, id, Item::TorqueEnable, 1)?;
    Ok(())
}

/// The run: the sequence written goal by goal, every read logged as it comes.
fn drive(
    a: &ServoArgs,
    client: &mut Client<Box<dyn Transport>>,
    port: &str,
    target: &Target,
    exc: &Excitation,
) -> CliResult {
    let (id, model, servo) = (target.id, target.model, target.servo);
    let block = Block::new(model);
    let goal_reg = model
        .table()
        .item(Item::GoalPosition)
        .ok_or("no Goal Position")?;
    let goal_at = |t: f64| -> Option<(f64, [f64; 3])> {
        exc.at(t).map(|(g, r)| {
            let (lo, hi) = target.bounds;
            ((target.centre + target.sign * g).clamp(lo, hi), r)
        })
    };
    let mut log = LogWriter::create_with(
        &a.out,
        servo,
        &format!("id {id} on {port}"),
        &target.comments,
    )
    .map_err(|e| out_error(a, e))?;
    let stop = interrupt_flag();
    let protocol = model.protocol();
    let (goal, mut regs) = goal_at(0.0).ok_or("the excitation is empty")?;
    start(client, target, regs, goal_reg.from_si(goal))?;
    let mut t_goal = 0.0;
    let mut buf = vec![0u8; block.len];
    // Time 0: the first goal was just written.
    let t0 = Instant::now();
    // Every way out of the loop says why (None: the sequence ended).
    let mut abort: Option<String>;
    let mut last_q = target.centre;
    // The goal the servo reports and when it was sent; the last write's time.
    let mut row_goal = f64::NAN;
    let mut last_write = 0.0;
    let mut misses = 0;
    loop {
        let t = t0.elapsed().as_secs_f64() * a.realtime_factor;
        let status = match client.read(protocol, id, block.start, &mut buf) {
            Ok(s) => s,
            Err(e) => {
                // A lost reply now and then is the bus's way; a servo gone is not.
                misses += 1;
                if misses > MAX_MISSES {
                    abort = Some(format!("servo id {id}: {e} ({misses} times in a row)"));
                    break;
                }
                continue;
            }
        };
        misses = 0;
        let m: [f64; 7] = std::array::from_fn(|k| block.value(k, &buf));
        last_q = m[0];
        if m[6] != row_goal {
            row_goal = m[6];
            t_goal = last_write;
        }
        let row = [t, m[6], t_goal, m[0], m[1], m[2], m[3], m[4], m[5]];
        log.write(&row, &regs).map_err(|e| out_error(a, e))?;
        abort = trouble(id, status, &m, target.bounds, &stop);
        if abort.is_some() {
            break;
        }
        let Some((g, r)) = goal_at(t) else { break };
        if r != regs {
            write_firmware(client, model, servo, id, r)?;
            regs = r;
        }
        let raw = goal_reg.from_si(g);
        last_write = t0.elapsed().as_secs_f64() * a.realtime_factor;
        // A lost reply: the next read tells whether the goal arrived.
        let _ = write_item(client, model, id, Item::GoalPosition, raw);
    }
    let rows = log.rows;
    log.finish().map_err(|e| out_error(a, e))?;
    let took = t0.elapsed().as_secs_f64();
    end_run(
        a,
        client,
        target,
        goal_reg,
        abort.map(|why| (why, last_q)),
        rows,
        took,
    )
}

/// The log's file named in its error.
fn out_error(a: &ServoArgs, e: impl std::fmt::Display) -> CliError {
    CliError::new(format!("{}: {e}", a.out.display()))
}

/// The servo after the run: back to the centre and the rows reported, or, when the
/// run was stopped (why, and the last position read), left safe: torque on, holding
/// where it is.
fn end_run(
    a: &ServoArgs,
    client: &mut Client<Box<dyn Transport>>,
    target: &Target,
    goal_reg: &Register,
    abort: Option<(String, f64)>,
    rows: usize,
    took: f64,
) -> CliResult {
    let (id, model, servo) = (target.id, target.model, target.servo);
    let (lo, hi) = target.bounds;
    if let Some((why, last_q)) = abort {
        // Left safe: torque on, holding where it is.
        let hold = goal_reg.from_si(last_q.clamp(lo, hi));
        let _ = write_item(client, model, id, Item::GoalPosition, hold);
        return Err(CliError::new(format!(
            "{why}; the servo holds where it was ({rows} rows in {})",
            a.out.display()
        )));
    }
    let back = goal_reg.from_si(target.centre);
    write_item(client, model, id, Item::GoalPosition, back)?;
    crate::common::print(&format!(
        "{rows} rows in {took:.1} s ({:.0} Hz) of servo id {id} ({servo}) -> {}\n",
        rows as f64 / took,
        a.out.display()
    ));
    Ok(Outcome::Ok)
}
