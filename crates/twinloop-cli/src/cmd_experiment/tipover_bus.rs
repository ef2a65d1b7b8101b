//! The tip-over experiment on a robot over its Dynamixel bus (`experiment tipover
//! --port --map`, and what `adapt --port` and `demo` run): the port opened, the
//! person asked on a serial port, the record written; the protocol itself is
//! `twinloop_ident::tipover_bus`.

use super::bus::{Guarded, confirm, hold_standing, is_serial, record_writer};
use crate::cmd_link::{PortArgs, open_client};
use crate::common::hinges_only;
use crate::common::load_description;
use crate::error::CliError;
use std::path::PathBuf;
use twinloop_experiments::tipover::{Direction, TipoverResult};
pub use twinloop_ident::tipover_bus::{ANKLE_SLOPE, BusOutcome, BusReport};
use twinloop_ident::tipover_bus::{BusTipoverOptions, bus_outcome, run_directions};
use twinloop_ident::tipover_study::{TiltModel, tipover_config};
use twinloop_link::{DynamixelRobot, ReadMethod, RobotMapping};

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
    /// Creeping approaches per direction (see `BusTipoverOptions::creeps`).
    pub creeps: usize,
    /// Commanded tip angles known beforehand, one per direction: creeps only (see
    /// `BusTipoverOptions::first_tips`).
    pub first_tips: Option<Vec<f64>>,
    /// Dither the turned joints' goal counts (see `BusTipoverOptions::dither`).
    pub dither: bool,
    /// Robot seconds per host second (a simulated robot served faster than real time).
    pub clock_rate: f64,
    /// Say on stderr what is happening.
    pub verbose: bool,
}

/// The outcome, the runs behind it (the mapping's joint order), and the port.
pub struct BusRun {
    pub outcome: BusOutcome,
    pub runs: Vec<TipoverResult>,
    pub joint_names: Vec<String>,
    pub port: String,
}

pub fn parse_directions(list: &[String]) -> Result<Vec<Direction>, CliError> {
    twinloop_ident::tipover_bus::parse_directions(list)
        .map_err(|e| CliError::new(format!("--directions: {e}")))
}

/// Run the tip-over over the bus (see the module documentation).
pub fn tipover_on_bus(plan: &BusPlan) -> Result<BusRun, CliError> {
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
    let mut g = Guarded::new(
        &mut robot,
        writer,
        &standing,
        crate::cmd_link::interrupt_flag(),
    );
    let opts = BusTipoverOptions {
        directions: plan.directions.clone(),
        slow_ramp: plan.slow_ramp,
        compliance_slope: plan.compliance_slope,
        ankle_slope: plan.ankle_slope,
        creeps: plan.creeps,
        first_tips: plan.first_tips.clone(),
        dither: plan.dither,
    };
    let mut before = |d: Direction, k: usize| {
        if k > 0 && serial && !plan.yes {
            confirm(&format!(
                "stand the robot up again for the {} lean; continue?",
                d.name()
            ))
            .map_err(|e| e.message)?;
        }
        Ok(())
    };
    let mut log = |line: &str| {
        if plan.verbose {
            eprintln!("{line}");
        }
    };
    let runs = run_directions(&mut g, &opts, &cfg, &mut tilt_model, &mut before, &mut log);
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
            abort.unwrap_or(e)
        ))
    })?;
    let outcome = bus_outcome(&model, &plan.model_spec, &port, &runs, &names)?;
    Ok(BusRun {
        outcome,
        runs,
        joint_names: names,
        port,
    })
}
