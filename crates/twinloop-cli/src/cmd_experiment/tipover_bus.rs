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
use twinloop_experiments::guarded::BusRobot;
use twinloop_experiments::tipover::{Direction, TipoverResult};
pub use twinloop_ident::tipover_bus::{ANKLE_SLOPE, BusOutcome, BusReport, ONSET_AVERAGE_S};
use twinloop_ident::tipover_bus::{BusTipoverOptions, bus_outcome, run_directions};
use twinloop_ident::tipover_study::{BusProtocol, TiltModel, tipover_config};
use twinloop_link::{DynamixelRobot, ReadMethod, RobotMapping};

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
    /// How stiff the servos that hold the pose are made, as an RX Compliance Slope
    /// (2: stiffest; every servo family through the catalogue).
    pub compliance_slope: i32,
    /// The same for the joints a direction ramps (see [`ANKLE_SLOPE`]).
    pub ankle_slope: i32,
    /// Leave the servos as they are (`--soft-servos`; see
    /// `BusTipoverOptions::soft_servos`).
    pub soft_servos: bool,
    /// Creeping approaches per direction (see `BusTipoverOptions::creeps`).
    pub creeps: usize,
    /// Commanded tip angles known beforehand, one per direction: creeps only (see
    /// `BusTipoverOptions::first_tips`).
    pub first_tips: Option<Vec<f64>>,
    /// Dither the turned joints' goal counts (see `BusTipoverOptions::dither`).
    pub dither: bool,
    /// A creep's tip is the mean reading over this long up to its onset, s of robot
    /// time (see `BusTipoverOptions::onset_average_s`).
    pub onset_average_s: f64,
    /// Robot seconds per host second (a simulated robot served faster than real time).
    pub clock_rate: f64,
    /// Say on stderr what is happening.
    pub verbose: bool,
}

impl BusPlan {
    /// The plan that runs `protocol` again, creeping from `first_tips` (commanded,
    /// deg, one per direction in `Direction::ALL`'s order), with `model_spec` as the
    /// host's model; no port, no record (for [`tipover_in_lockstep`]).
    pub fn replaying(protocol: &BusProtocol, model_spec: &str, first_tips: Vec<f64>) -> BusPlan {
        BusPlan {
            model_spec: model_spec.to_string(),
            map: protocol.map.clone(),
            port: PortArgs::quick(None, 10.0, 0),
            record: None,
            yes: true,
            directions: Direction::ALL.to_vec(),
            ramp: protocol.ramp_deg_per_s,
            slow_ramp: protocol.slow_ramp_deg_per_s,
            compliance_slope: protocol.compliance_slope,
            ankle_slope: protocol.ankle_slope,
            soft_servos: protocol.soft_servos,
            creeps: protocol.creeps,
            first_tips: Some(first_tips),
            dither: protocol.dither,
            onset_average_s: protocol.onset_average_s,
            clock_rate: 1.0,
            verbose: false,
        }
    }
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
    let port_args = PortArgs {
        port: Some(port.clone()),
        ..plan.port.clone()
    };
    let client = open_client(&port_args, None)?;
    let mut robot = DynamixelRobot::new(client, mapping, ReadMethod::Auto)?;
    robot.set_clock_rate(plan.clock_rate)?;
    tipover_with(plan, robot, port)
}

/// The same protocol on a simulated `model` stepped in lockstep with the host
/// (`twinloop_virtual::Lockstep`, `cycle_s` of robot time per control cycle, the bus
/// in memory): how the protocol measures that model, the same every time and as fast
/// as the simulation runs. `plan`'s port, record and clock rate are not used.
pub fn tipover_in_lockstep(
    plan: &BusPlan,
    model: &twinloop_description::Description,
    options: &twinloop_virtual::VirtualRobotOptions,
    cycle_s: f64,
) -> Result<BusRun, CliError> {
    let mapping = RobotMapping::resolve(&plan.map)?;
    let vr = twinloop_virtual::VirtualRobot::new(model, &mapping, options)
        .map_err(|e| CliError::new(format!("the simulated {}: {e}", model.name)))?;
    let (clock, client) = twinloop_virtual::Lockstep::new(vr, cycle_s).map_err(CliError::new)?;
    let mut robot = DynamixelRobot::new(client, mapping, ReadMethod::Auto)?;
    robot.set_clock(Box::new(clock));
    let plan = BusPlan {
        record: None,
        yes: true,
        ..plan.clone()
    };
    tipover_with(&plan, robot, "in-memory lockstep bus".into())
}

/// The protocol on `robot`, whose bus is `port`.
fn tipover_with(plan: &BusPlan, mut robot: BusRobot, port: String) -> Result<BusRun, CliError> {
    let mapping = robot.mapping().clone();
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
    if !plan.soft_servos {
        twinloop_experiments::stiffen::check_stiffenable(&mapping)?;
    }
    let serial = is_serial(&port);
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
    g.silence_window = plan.port.silence_window();
    let opts = BusTipoverOptions {
        directions: plan.directions.clone(),
        slow_ramp: plan.slow_ramp,
        compliance_slope: plan.compliance_slope,
        ankle_slope: plan.ankle_slope,
        soft_servos: plan.soft_servos,
        creeps: plan.creeps,
        first_tips: plan.first_tips.clone(),
        dither: plan.dither,
        onset_average_s: plan.onset_average_s,
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
    let health = g.health();
    let cycle_s = g.median_cycle_s();
    let writer = g.writer.take();
    let abort = g.abort.take();
    hold_standing(&mut robot, &standing);
    if plan.verbose {
        eprintln!("{}", health.line());
    }
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
    let mut outcome = bus_outcome(
        &model,
        &plan.model_spec,
        &port,
        &runs,
        &names,
        plan.soft_servos,
    )?;
    match &mut outcome {
        BusOutcome::Study(study) => study.bus = Some(health),
        BusOutcome::Partial(partial) => partial.bus = Some(health),
    }
    if let (BusOutcome::Study(study), Some(cycle_s)) = (&mut outcome, cycle_s) {
        study.protocol = Some(BusProtocol {
            map: plan.map.clone(),
            ramp_deg_per_s: plan.ramp,
            slow_ramp_deg_per_s: plan.slow_ramp,
            compliance_slope: plan.compliance_slope,
            ankle_slope: plan.ankle_slope,
            creeps: plan.creeps,
            dither: plan.dither,
            onset_average_s: plan.onset_average_s,
            cycle_s,
            soft_servos: plan.soft_servos,
        });
    }
    Ok(BusRun {
        outcome,
        runs,
        joint_names: names,
        port,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The demo's protocol, from the first ramp (no known tips), one creep.
    fn plan() -> BusPlan {
        let protocol = BusProtocol {
            map: "builtin:km20".into(),
            ramp_deg_per_s: 2.0,
            slow_ramp_deg_per_s: 0.15,
            compliance_slope: 2,
            ankle_slope: ANKLE_SLOPE,
            creeps: 1,
            dither: false,
            onset_average_s: ONSET_AVERAGE_S,
            cycle_s: 0.029,
            soft_servos: false,
        };
        BusPlan {
            first_tips: None,
            ..BusPlan::replaying(&protocol, "builtin:km20", Vec::new())
        }
    }

    #[test]
    fn soft_servos_run_as_they_are_and_the_output_says_so() {
        let model = twinloop_description::builtin::km20::build().unwrap();
        let options = crate::protocol_bias::replay_options(1e-4);
        let soft = BusPlan {
            soft_servos: true,
            directions: vec![Direction::Forward],
            ..plan()
        };
        let run = tipover_in_lockstep(&soft, &model, &options, 0.029).unwrap();
        let BusOutcome::Partial(r) = run.outcome else {
            panic!("one direction ran, no partial report")
        };
        let json = serde_json::to_value(&*r).unwrap();
        assert_eq!(json["soft_servos"], serde_json::Value::Bool(true));
        // Soft (factory slope 32, margin 1 on every RX) the robot tips earlier than
        // stiffened: the servos give under the lean.
        let stiff = BusPlan {
            directions: vec![Direction::Forward],
            ..plan()
        };
        let BusOutcome::Partial(s) = tipover_in_lockstep(&stiff, &model, &options, 0.029)
            .unwrap()
            .outcome
        else {
            panic!("one direction ran, no partial report")
        };
        assert!(!s.soft_servos);
        let (soft_deg, stiff_deg) = (
            r.forward.as_ref().unwrap().measured_deg,
            s.forward.as_ref().unwrap().measured_deg,
        );
        // Measured: 8.64 soft, 8.82 stiff.
        assert!(
            soft_deg < stiff_deg - 0.1,
            "soft {soft_deg} deg, stiff {stiff_deg}"
        );
    }

    /// The protocol on km20 in lockstep, at the pty demo's host cycle (29 ms of robot
    /// time): the four angles it reads and the model's static angles at its onsets.
    fn lockstep_km20() -> ([f64; 4], [f64; 4]) {
        let model = twinloop_description::builtin::km20::build().unwrap();
        let options = crate::protocol_bias::replay_options(1e-4);
        let run = tipover_in_lockstep(&plan(), &model, &options, 0.029).unwrap();
        let BusOutcome::Study(s) = run.outcome else {
            panic!("four directions ran, no study")
        };
        let d = [&s.forward, &s.backward, &s.left, &s.right];
        (d.map(|d| d.measured_deg), d.map(|d| d.static_deg))
    }

    #[test]
    fn the_protocol_in_lockstep_reads_the_same_every_time_and_near_the_statics() {
        let (a, statics) = lockstep_km20();
        let (b, _) = lockstep_km20();
        // No wall clock, no threads: the same result to the bit.
        assert_eq!(a, b);
        // Whole ankle counts (0.29 deg, two ankles averaged) and each count step a
        // jolt to soft ankles on the edge of their soles: the protocol reads within
        // about a degree of the statics (docs/adaptation.md measured +1.0 deg forward
        // on a changed km20), not exactly.
        for k in 0..4 {
            assert!(
                (a[k] - statics[k]).abs() < 1.5,
                "direction {k}: read {:.2} deg, static {:.2}",
                a[k],
                statics[k]
            );
        }
    }
}
