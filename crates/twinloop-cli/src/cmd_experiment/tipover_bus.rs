//! The tip-over experiment on a robot over its Dynamixel bus (`experiment tipover
//! --port --map`, and what `adapt --port` and `demo` run): the study's protocol (each
//! direction twice, the second time creeping up to the tip) through nothing but the
//! servos' registers and the IMU board, with the safety checks; four directions give
//! the same JSON as the simulator's study.

use super::bus::{BusRobot, Guarded, confirm, hold_standing, is_serial, record_writer};
use crate::cmd_link::{PortArgs, open_client};
use crate::common::hinges_only;
use crate::common::load_description;
use crate::error::CliError;
use serde::Serialize;
use std::path::PathBuf;
use twinloop_experiments::tipover::{Direction, TipoverConfig, TipoverResult, run_direction, tilt};
use twinloop_ident::tipover_study::{StudyReport, TiltModel, report_for_runs, tipover_config};
use twinloop_link::{DynamixelRobot, Item, ReadMethod, RobotMapping};
use twinloop_robot::{Robot, RobotError, RobotState};

/// How the experiment runs over the bus.
#[derive(Debug, Clone)]
pub struct BusPlan {
    /// The model: lean signs, the tilt reference and the static references.
    pub model_spec: String,
    pub map: String,
    pub port: PortArgs,
    pub record: Option<PathBuf>,
    /// Do not ask before moving a robot on a serial port.
    pub yes: bool,
    pub directions: Vec<Direction>,
    /// First ramp of each direction, deg/s of robot time.
    pub ramp: f64,
    /// The second run's creep over the last half degree, deg/s.
    pub slow_ramp: f64,
    /// RX Compliance Slope written to the servos that hold the pose (2: stiffest).
    pub compliance_slope: i32,
    /// RX Compliance Slope of the joints a direction ramps (see [`ANKLE_SLOPE`]).
    pub ankle_slope: i32,
    /// Robot seconds per host second (a simulated robot served faster than real time).
    pub clock_rate: f64,
    /// Say on stderr what is happening.
    pub verbose: bool,
}

/// One direction over the bus.
#[derive(Debug, Clone, Serialize)]
pub struct BusDirection {
    pub commanded_deg: f64,
    pub measured_deg: f64,
    pub time_s: f64,
    pub excess_deg: f64,
    pub lean_deg: f64,
}

/// The directions run when not all four were asked for.
#[derive(Debug, Clone, Serialize)]
pub struct BusReport {
    pub robot: String,
    pub port: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forward: Option<BusDirection>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub backward: Option<BusDirection>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub left: Option<BusDirection>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub right: Option<BusDirection>,
}

/// What a run over the bus gave.
pub enum BusOutcome {
    /// All four directions: the study's report (static references and CoM from the
    /// model, `com.true` being the model's CoM).
    Study(Box<StudyReport>),
    Partial(Box<BusReport>),
}

/// The outcome, the runs behind it (the mapping's joint order), and the port.
pub struct BusRun {
    pub outcome: BusOutcome,
    pub runs: Vec<TipoverResult>,
    pub joint_names: Vec<String>,
    pub port: String,
}

/// Trunk tilt within which the robot counts as standing again, deg, and for how long
/// it must stay there, s of robot time.
const UPRIGHT_DEG: f64 = 3.0;
const UPRIGHT_HOLD_S: f64 = 1.0;
/// How far before the first run's tip the second run starts to creep, deg: more than
/// the simulator's half degree, because over a bus the first run's detection lags by a
/// cycle or more and the robot must not tip before the creep begins.
const SLOW_MARGIN_DEG: f64 = 1.5;
/// How long a person (or the virtual robot's operator) has to stand the robot up, s.
const STAND_UP_TIMEOUT_S: f64 = 120.0;

pub fn parse_directions(list: &[String]) -> Result<Vec<Direction>, CliError> {
    if list.is_empty() {
        return Ok(Direction::ALL.to_vec());
    }
    list.iter()
        .map(|s| {
            Direction::ALL
                .into_iter()
                .find(|d| d.name() == s.trim())
                .ok_or_else(|| {
                    CliError::new(format!(
                        "--directions: \"{s}\" is not forward, backward, left or right"
                    ))
                })
        })
        .collect()
}

/// The trunk's (pitch, roll) from the IMU, rad.
fn trunk_tilt(st: &RobotState) -> Option<(f64, f64)> {
    st.imu.and_then(|i| i.orientation).map(tilt)
}

/// Hold the standing pose until the robot stands again: its trunk within
/// [`UPRIGHT_DEG`] of `upright` for [`UPRIGHT_HOLD_S`]. A person stands a fallen
/// robot up (the virtual robot's operator does it by itself); a robot caught before
/// it fell is standing already.
fn wait_upright(
    g: &mut Guarded,
    standing: &[f64],
    upright: (f64, f64),
    period: f64,
) -> Result<(), RobotError> {
    let mut st = RobotState::default();
    let t0 = g.time();
    let mut since: Option<f64> = None;
    loop {
        g.command_positions(standing)?;
        g.advance(period)?;
        g.read(&mut st)?;
        let now = g.time();
        let ok = trunk_tilt(&st).is_some_and(|(p, r)| {
            (p - upright.0).abs().max((r - upright.1).abs()) < UPRIGHT_DEG.to_radians()
        });
        since = if ok { since.or(Some(now)) } else { None };
        if since.is_some_and(|s| now - s >= UPRIGHT_HOLD_S) {
            return Ok(());
        }
        if now - t0 > STAND_UP_TIMEOUT_S {
            let (p, r) = trunk_tilt(&st).unwrap_or((f64::NAN, f64::NAN));
            return Err(g.fail(format!(
                "the robot did not stand up again within {STAND_UP_TIMEOUT_S} s (trunk pitch {:.1} deg, roll {:.1} deg)",
                p.to_degrees(),
                r.to_degrees()
            )));
        }
    }
}

/// Stiffen every servo as the study does (RX compliance margin 0, slope
/// `slope`): the CoM methods treat the robot as rigid. Servos without these
/// registers are left as they are.
fn stiffen(
    robot: &mut BusRobot,
    slope: i32,
    pick: impl Fn(usize) -> bool + Copy,
) -> Result<(), RobotError> {
    for (item, v) in [
        (Item::CwComplianceMargin, 0),
        (Item::CcwComplianceMargin, 0),
        (Item::CwComplianceSlope, slope),
        (Item::CcwComplianceSlope, slope),
    ] {
        robot.set_register_of(item, v, pick)?;
    }
    Ok(())
}

/// The ramped ankles' RX Compliance Slope over the bus: the factory value. Goal
/// positions are whole counts (0.29 deg), so the ramp is a staircase; a servo at the
/// stiffest slope takes each count as a jolt, and a robot on the edge of its soles
/// tips up to a degree early (measured over the pty: forward and backward 1.1 deg
/// early at slope 2, within the count at 32). The hip rolls that turn with the ankle
/// rolls sideways stay stiff: soft, they let the legs' parallelogram shear and the
/// robot tips 3-4 deg early.
pub const ANKLE_SLOPE: i32 = 32;

/// The ankle joints a lean in `d` ramps.
fn ramped_ankles(cfg: &TipoverConfig, d: Direction) -> [usize; 2] {
    if d.is_pitch() {
        cfg.ankle_pitch
    } else {
        cfg.ankle_roll
    }
}

/// Run the tip-over over the bus (see the module documentation).
pub fn tipover_on_bus(plan: &BusPlan) -> Result<BusRun, CliError> {
    tipover_on_bus_timed(plan, None)
}

/// [`tipover_on_bus`] counting the robot's seconds by `clock` (a simulated robot
/// served in this process: see `DynamixelRobot::set_clock`) instead of the host's
/// clock times `plan.clock_rate`.
pub fn tipover_on_bus_timed(
    plan: &BusPlan,
    clock: Option<twinloop_link::RobotClock>,
) -> Result<BusRun, CliError> {
    let mapping = RobotMapping::resolve(&plan.map)?;
    let port = plan
        .port
        .port
        .clone()
        .or_else(|| mapping.port.clone())
        .ok_or_else(|| CliError::new("--map needs --port PORT (or the mapping's port)"))?;
    let (model, _) = load_description(&plan.model_spec)?;
    hinges_only(&model, &plan.model_spec, "the tip-over experiment")?;
    let names = mapping.joint_names();
    let cfg = tipover_config(&model, &names, plan.ramp).map_err(|e| {
        CliError::from(e).context(format!("{} with {}", plan.model_spec, mapping.source))
    })?;
    let Some(board) = mapping.boards.first() else {
        return Err(CliError::new(format!(
            "{}: no [[board]]: the tip-over experiment needs the trunk IMU",
            plan.map
        )));
    };
    let mut tilt_model = TiltModel::new(&model, &names, &board.link)?;
    let serial = is_serial(&port);
    let port_args = PortArgs {
        port: Some(port.clone()),
        ..plan.port.clone()
    };
    let client = open_client(&port_args, None)?;
    let mut robot = DynamixelRobot::new(client, mapping, ReadMethod::Auto)?;
    robot.set_clock_rate(plan.clock_rate)?;
    if let Some(c) = clock {
        robot.set_clock(c);
    }
    let writer = match &plan.record {
        Some(path) => Some(record_writer(path, &names)?),
        None => None,
    };
    if serial && !plan.yes {
        confirm(
            "the robot will lean until it tips in four directions; hold a hand ready; continue?",
        )?;
    }
    let standing = vec![0.0; names.len()];
    let mut g = Guarded::new(&mut robot, writer, &standing);
    let runs = run_directions(
        &mut g,
        plan,
        &cfg,
        &standing,
        &mut tilt_model,
        serial,
        &port,
    );
    let rows = g.rows;
    let writer = g.writer.take();
    let abort = g.abort.take();
    hold_standing(&mut robot, &standing);
    if let Some(w) = writer {
        w.finish()?;
        if let Some(p) = &plan.record {
            eprintln!("{rows} rows written to {}", p.display());
        }
    }
    let runs = runs.map_err(|e| {
        CliError::new(format!(
            "{}; stopped, the servos hold the standing pose",
            abort.unwrap_or(e.message)
        ))
    })?;
    let kept = runs.clone();
    let outcome = if runs.len() == 4 {
        BusOutcome::Study(Box::new(report_for_runs(&model, &runs, &names)?))
    } else {
        let mut r = BusReport {
            robot: plan.model_spec.clone(),
            port: port.clone(),
            forward: None,
            backward: None,
            left: None,
            right: None,
        };
        for run in runs {
            let d = Some(BusDirection {
                commanded_deg: run.commanded_deg,
                measured_deg: run.measured_deg,
                time_s: run.time_s,
                excess_deg: run.excess_deg,
                lean_deg: run.lean_deg,
            });
            match run.direction {
                Direction::Forward => r.forward = d,
                Direction::Backward => r.backward = d,
                Direction::Left => r.left = d,
                Direction::Right => r.right = d,
            }
        }
        BusOutcome::Partial(Box::new(r))
    };
    Ok(BusRun {
        outcome,
        runs: kept,
        joint_names: names,
        port,
    })
}

/// Each direction twice, as the study: a first ramp finds the tip, a second comes up
/// to [`SLOW_MARGIN_DEG`] before it and creeps; the robot stood up before each run.
fn run_directions(
    g: &mut Guarded,
    plan: &BusPlan,
    cfg: &TipoverConfig,
    standing: &[f64],
    tilt_model: &mut TiltModel,
    serial: bool,
    port: &str,
) -> Result<Vec<TipoverResult>, CliError> {
    // Upright is the trunk's tilt the model gives standing with the feet flat (the
    // robot's first readings may still rock from the stiffening).
    // (`tilt` counts roll the other way: positive leaning right.)
    let t = tilt_model.predict(Direction::Forward, standing);
    let upright = (t[0], -t[1]);
    let mut out = Vec::with_capacity(plan.directions.len());
    for (k, &d) in plan.directions.iter().enumerate() {
        if k > 0 && serial && !plan.yes {
            confirm(&format!(
                "stand the robot up again for the {} lean; continue?",
                d.name()
            ))?;
        }
        if plan.verbose {
            eprintln!("leaning {} over {port} ...", d.name());
        }
        // Every servo stiff but the two ankles this direction ramps.
        let ankles = ramped_ankles(cfg, d);
        stiffen(g.robot, plan.compliance_slope, |k| !ankles.contains(&k))
            .and_then(|()| stiffen(g.robot, plan.ankle_slope, |k| ankles.contains(&k)))
            .map_err(|e| CliError::new(e.to_string()))?;
        let mut run = |cfg: &TipoverConfig, g: &mut Guarded| -> Result<TipoverResult, RobotError> {
            wait_upright(g, standing, upright, cfg.period_s)?;
            let mut predict = |q: &[f64]| tilt_model.predict(d, q);
            let r = run_direction(g, standing, d, cfg, Some(&mut predict));
            // The ramp ends at the first sign of tipping (or a fault): the ankles go
            // back to the standing pose at once.
            let _ = g.robot.command_positions(standing);
            r
        };
        let first = run(cfg, g)?;
        let mut slow = cfg.clone();
        slow.slow_from_deg = Some((first.commanded_deg - SLOW_MARGIN_DEG).max(0.0));
        slow.slow_ramp_deg_per_s = plan.slow_ramp;
        let mut r = run(&slow, g)?;
        r.time_s = first.time_s;
        if plan.verbose {
            eprintln!(
                "  {}: tipped at {:.2} deg (first ramp {:.2} deg)",
                d.name(),
                r.measured_deg,
                first.measured_deg
            );
        }
        out.push(r);
    }
    wait_upright(g, standing, upright, cfg.period_s)?;
    Ok(out)
}
