//! `twinloop experiment servo`: one servo on a pendulum bench driven through the
//! excitation of docs/servo-models.md, every read logged as it comes.

use super::bus::{confirm, is_serial};
use crate::cmd_link::{PortArgs, interrupt_flag, open_client};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Instant;
use twinloop_actuator::log::LogWriter;
use twinloop_actuator::{Excitation, LoopFamily, Pendulum, ServoType};
use twinloop_link::transport::Transport;
use twinloop_link::{Client, Item, Protocol, Register, ServoModel};

#[derive(Args, Debug)]
pub struct ServoArgs {
    #[command(flatten)]
    pub bus: PortArgs,
    /// The servo's id on the bench
    #[arg(long, value_name = "N")]
    pub id: u8,
    /// The pendulum: a TOML file with mass (kg), length (m), arm_inertia (kg m^2)
    #[arg(long, value_name = "LOAD.toml")]
    pub load: PathBuf,
    /// The log (CSV, written row by row)
    #[arg(long, value_name = "LOG.csv")]
    pub out: PathBuf,
    /// Scale of the sequence's angles (1: steps up to 0.8 rad, sinusoids of 0.5 rad)
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = crate::common::positive)]
    pub amplitude: f64,
    /// Servo seconds per host second: F for a bench served with `serve --realtime-factor F`
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = crate::common::positive)]
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

pub fn run(a: &ServoArgs) -> CliResult {
    let load = Pendulum::read(&a.load)?;
    let mut client = open_client(&a.bus, None)?;
    let port = a.bus.port.clone().unwrap_or_default();
    let model = find(&mut client, a.id)?;
    let servo = twinloop_virtual::servo_type(model).ok_or_else(|| {
        CliError::new(format!(
            "servo id {}: {model} has no servo model (known: {})",
            a.id,
            ServoType::known_names()
        ))
    })?;
    let stall = servo.rating().stall_torque;
    let gravity = load.mass * twinloop_actuator::bench::GRAVITY * load.length;
    if gravity > twinloop_actuator::load_rule::MAX_RATIO * stall {
        return Err(CliError::new(format!(
            "{}: the pendulum's weight takes {gravity:.2} N m at the horizontal, over 60 % of the {servo}'s {stall} N m stall torque: lighter or shorter",
            a.load.display()
        )));
    }
    if let Some(w) = twinloop_actuator::load_rule::too_light(servo, &load) {
        eprintln!("warning: {}: {w}", a.load.display());
    }
    let exc = Excitation::standard(servo, a.amplitude);
    if is_serial(&port) && !a.yes {
        confirm(&format!(
            "swing the pendulum on servo id {} ({servo}) on {port} for {:.0} s, up to {:.2} rad from hanging",
            a.id,
            exc.duration(),
            0.8 * a.amplitude
        ))?;
    }
    let block = Block::new(model);
    let goal_reg = model
        .table()
        .item(Item::GoalPosition)
        .ok_or("no Goal Position")?;
    let mut log = LogWriter::create(&a.out, servo, &format!("id {} on {port}", a.id))
        .map_err(|e| CliError::new(format!("{}: {e}", a.out.display())))?;
    let stop = interrupt_flag();
    let protocol = model.protocol();
    let (goal, mut regs) = exc.at(0.0).ok_or("the excitation is empty")?;
    write_firmware(&mut client, model, servo, a.id, regs)?;
    write_item(
        &mut client,
        model,
        a.id,
        Item::GoalPosition,
        goal_reg.from_si(goal),
    )?;
    write_item(&mut client, model, a.id, Item::TorqueEnable, 1)?;
    let mut t_goal = 0.0;
    let mut buf = vec![0u8; block.len];
    // Time 0: the first goal was just written.
    let t0 = Instant::now();
    let mut abort = None;
    let mut last_q = 0.0;
    // The goal the servo reports and when it was sent; the last write's time.
    let mut row_goal = f64::NAN;
    let mut last_write = 0.0;
    let mut misses = 0;
    loop {
        let t = t0.elapsed().as_secs_f64() * a.realtime_factor;
        let status = match client.read(protocol, a.id, block.start, &mut buf) {
            Ok(s) => s,
            Err(e) => {
                // A lost reply now and then is the bus's way; a servo gone is not.
                misses += 1;
                if misses > MAX_MISSES {
                    abort = Some(format!("servo id {}: {e} ({misses} times in a row)", a.id));
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
        log.write(&row, &regs)
            .map_err(|e| CliError::new(format!("{}: {e}", a.out.display())))?;
        if status.hardware_fault() {
            abort = Some(format!("servo id {}: {status}", a.id));
            break;
        }
        if m[5] >= MAX_TEMPERATURE_C {
            abort = Some(format!(
                "servo id {}: {} C, stopping before its 80 C limit",
                a.id, m[5]
            ));
            break;
        }
        if stop.load(Ordering::Relaxed) {
            abort = Some("interrupted (Ctrl-C)".into());
            break;
        }
        let Some((g, r)) = exc.at(t) else { break };
        if r != regs {
            write_firmware(&mut client, model, servo, a.id, r)?;
            regs = r;
        }
        let raw = goal_reg.from_si(g);
        last_write = t0.elapsed().as_secs_f64() * a.realtime_factor;
        // A lost reply: the next read tells whether the goal arrived.
        let _ = write_item(&mut client, model, a.id, Item::GoalPosition, raw);
    }
    let rows = log.rows;
    log.finish()
        .map_err(|e| CliError::new(format!("{}: {e}", a.out.display())))?;
    let took = t0.elapsed().as_secs_f64();
    if let Some(why) = abort {
        // Left safe: torque on, holding where it is.
        let hold = goal_reg.from_si(last_q);
        let _ = write_item(&mut client, model, a.id, Item::GoalPosition, hold);
        return Err(CliError::new(format!(
            "{why}; the servo holds where it was ({rows} rows in {})",
            a.out.display()
        )));
    }
    let hang = goal_reg.from_si(0.0);
    write_item(&mut client, model, a.id, Item::GoalPosition, hang)?;
    crate::common::print(&format!(
        "{rows} rows in {took:.1} s ({:.0} Hz) of servo id {} ({servo}) -> {}\n",
        rows as f64 / took,
        a.id,
        a.out.display()
    ));
    Ok(Outcome::Ok)
}
