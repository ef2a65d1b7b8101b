//! The tip-over experiment on a robot over its Dynamixel bus, as a [`BusPlan`] says
//! (what `experiment tipover --port`, `adapt --port`, `demo` and Python's
//! `tipover(port=...)` run): the plan checked against the host's model, the person
//! asked on a serial port ([`Operator`]), the port opened, the record written; the
//! protocol itself is `twinloop_ident::tipover_bus`.

use crate::LoopError;
use crate::bus_plan::BusPlan;
use crate::profile::{hinges_only, load_description};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use twinloop_description::Description;
use twinloop_experiments::guarded::{BusRobot, Guarded, hold_standing, is_serial, record_columns};
use twinloop_experiments::tipover::TipoverConfig;
use twinloop_experiments::tipover::{Direction, TipoverResult};
pub use twinloop_ident::tipover_bus::{ANKLE_SLOPE, BusOutcome, BusReport, ONSET_AVERAGE_S};
use twinloop_ident::tipover_bus::{BusTipoverOptions, bus_outcome, run_directions};
use twinloop_ident::tipover_study::{TiltModel, tipover_config};
use twinloop_link::{DynamixelRobot, ReadMethod, RobotMapping};

/// The outcome, the runs behind it (the mapping's joint order), and the port.
pub struct BusRun {
    pub outcome: BusOutcome,
    pub runs: Vec<TipoverResult>,
    pub joint_names: Vec<String>,
    pub port: String,
}

/// The person beside the robot, and where the run's lines go.
pub struct Operator<'a> {
    /// Asked (a question) before the first lean, and before each stand-up after it, on
    /// a serial port when the plan has no `yes`: `Ok` to go on.
    pub ask: &'a mut (dyn FnMut(&str) -> Result<(), LoopError> + Send),
    /// The run's lines (with `verbose`, what is happening; always, where the record
    /// went).
    pub log: &'a mut (dyn FnMut(&str) + Send),
    /// Set to stop the run (the CLI sets it on Ctrl-C); the servos are left holding.
    pub stop: Arc<AtomicBool>,
}

/// What the plan needs of the host's model and the mapping, checked before the
/// robot is asked to move.
struct Prepared {
    model: Description,
    names: Vec<String>,
    cfg: TipoverConfig,
    tilt_model: TiltModel,
}

/// Check `plan` against `model` (the host's model) and its mapping: the lean signs,
/// the IMU board, the servos it stiffens.
fn prepare(plan: &BusPlan, model: Description) -> Result<Prepared, LoopError> {
    hinges_only(&model, &plan.model_spec, "the tip-over experiment")?;
    let mapping = RobotMapping::resolve(&plan.map).map_err(|e| LoopError::from(e).at("map"))?;
    let names = mapping.joint_names();
    let cfg = tipover_config(&model, &names, plan.ramp).map_err(|e| {
        LoopError::from(e).context(format!("{} with {}", plan.model_spec, mapping.source))
    })?;
    let Some(board) = mapping.boards.first() else {
        return Err(LoopError::new(format!(
            "{}: no [[board]]: the tip-over experiment needs the trunk IMU",
            plan.map
        ))
        .at("map"));
    };
    let tilt_model = TiltModel::new(&model, &names, &board.link)?;
    if !plan.soft_servos {
        twinloop_experiments::stiffen::check_stiffenable(&mapping)
            .map_err(|e| LoopError::from(e).at("soft_servos"))?;
    }
    Ok(Prepared {
        model,
        names,
        cfg,
        tilt_model,
    })
}

/// Run the tip-over over the bus (see the module documentation), the host's model
/// read from `plan.model_spec`.
pub fn tipover_on_bus(plan: &BusPlan, operator: &mut Operator<'_>) -> Result<BusRun, LoopError> {
    let (model, _) = load_description(&plan.model_spec)?;
    tipover_on_bus_with(plan, model, operator)
}

/// [`tipover_on_bus`] with the host's model given (Python's `robot=` Description).
pub fn tipover_on_bus_with(
    plan: &BusPlan,
    model: Description,
    operator: &mut Operator<'_>,
) -> Result<BusRun, LoopError> {
    let mapping = RobotMapping::resolve(&plan.map).map_err(|e| LoopError::from(e).at("map"))?;
    let port = plan
        .port
        .port
        .clone()
        .or_else(|| mapping.port.clone())
        .ok_or_else(|| {
            LoopError::new("--map needs --port PORT (or the mapping's port)").at("port")
        })?;
    let mut prepared = prepare(plan, model)?;
    if is_serial(&port) && !plan.yes {
        (operator.ask)(
            "the robot will lean until it tips in four directions; hold a hand ready; continue?",
        )?;
    }
    let client = plan.port.open(Some(&port))?;
    let mut robot = DynamixelRobot::new(client, mapping, ReadMethod::Auto)
        .map_err(|e| LoopError::io(e.to_string()))?;
    robot
        .set_clock_rate(plan.clock_rate)
        .map_err(|e| LoopError::from(e).at("realtime_factor"))?;
    run_prepared(plan, &mut prepared, robot, port, operator)
}

/// The same protocol on a simulated `model` stepped in lockstep with the host
/// (`twinloop_virtual::Lockstep`, `cycle_s` of robot time per control cycle, the bus
/// in memory): how the protocol measures that model, the same every time and as fast
/// as the simulation runs. `plan`'s port, record and clock rate are not used; the
/// host's model is read from `plan.model_spec`.
pub fn tipover_in_lockstep(
    plan: &BusPlan,
    model: &Description,
    options: &twinloop_virtual::VirtualRobotOptions,
    cycle_s: f64,
) -> Result<BusRun, LoopError> {
    let (host, _) = load_description(&plan.model_spec)?;
    tipover_in_lockstep_with(plan, host, model, options, cycle_s)
}

/// [`tipover_in_lockstep`] with the host's model given.
pub fn tipover_in_lockstep_with(
    plan: &BusPlan,
    host: Description,
    model: &Description,
    options: &twinloop_virtual::VirtualRobotOptions,
    cycle_s: f64,
) -> Result<BusRun, LoopError> {
    let mapping = RobotMapping::resolve(&plan.map)?;
    let vr = twinloop_virtual::VirtualRobot::new(model, &mapping, options)
        .map_err(|e| LoopError::new(format!("the simulated {}: {e}", model.name)))?;
    let (clock, client) = twinloop_virtual::Lockstep::new(vr, cycle_s)?;
    let mut robot = DynamixelRobot::new(client, mapping, ReadMethod::Auto)?;
    robot.set_clock(Box::new(clock));
    let plan = BusPlan {
        record: None,
        yes: true,
        ..plan.clone()
    };
    let mut prepared = prepare(&plan, host)?;
    let (mut ask, mut log) = (|_: &str| Ok(()), |_: &str| {});
    let mut operator = Operator {
        ask: &mut ask,
        log: &mut log,
        stop: Arc::new(AtomicBool::new(false)),
    };
    run_prepared(
        &plan,
        &mut prepared,
        robot,
        "in-memory lockstep bus".into(),
        &mut operator,
    )
}

/// The directions as the protocol runs them, from the plan.
fn bus_options(plan: &BusPlan) -> BusTipoverOptions {
    BusTipoverOptions {
        directions: plan.directions.clone(),
        slow_ramp: plan.slow_ramp,
        compliance_slope: plan.compliance_slope,
        ankle_slope: plan.ankle_slope,
        soft_servos: plan.soft_servos,
        creeps: plan.creeps,
        first_tips: plan.first_tips.clone(),
        dither: plan.dither,
        onset_average_s: plan.onset_average_s,
    }
}

/// What the guarded run left: the runs (or why it stopped), the bus's health, the
/// median host cycle.
struct Guard {
    runs: Result<Vec<TipoverResult>, String>,
    health: twinloop_experiments::guarded::BusHealth,
    cycle_s: Option<f64>,
}

/// The protocol on `robot`, whose bus is `port`, every cycle recorded; the servos
/// left holding the standing pose however it ends.
fn guarded_run(
    plan: &BusPlan,
    p: &mut Prepared,
    robot: &mut BusRobot,
    serial: bool,
    operator: &mut Operator<'_>,
) -> Result<Guard, LoopError> {
    let writer = match &plan.record {
        Some(path) => {
            let fail = |e: twinloop_io::IoError| LoopError::io(e.to_string()).at("record");
            let mut w =
                twinloop_io::open_recording(path, &record_columns(&p.names)).map_err(fail)?;
            // The robot on an MCAP's /robot_description, as `link record` writes it.
            w.describe(&twinloop_description::urdf::to_string(&p.model))
                .map_err(fail)?;
            Some(w)
        }
        None => None,
    };
    let standing = vec![0.0; p.names.len()];
    let mut g = Guarded::new(robot, writer, &standing, operator.stop.clone());
    g.silence_window = plan.port.silence_window();
    let opts = bus_options(plan);
    let ask = &mut *operator.ask;
    let mut before = |d: Direction, k: usize| {
        if k > 0 && serial && !plan.yes {
            ask(&format!(
                "stand the robot up again for the {} lean; continue?",
                d.name()
            ))
            .map_err(|e| twinloop_ident::IdentError::new(e.to_string()))?;
        }
        Ok(())
    };
    let log = &mut *operator.log;
    let mut progress = |line: &str| {
        if plan.verbose {
            log(line);
        }
    };
    let runs = run_directions(
        &mut g,
        &opts,
        &p.cfg,
        &mut p.tilt_model,
        &mut before,
        &mut progress,
    );
    let rows = g.rows;
    let health = g.health();
    let cycle_s = g.median_cycle_s();
    let writer = g.writer.take();
    let abort = g.abort.take();
    hold_standing(robot, &standing);
    if plan.verbose {
        log(&health.line());
    }
    if let Some(w) = writer {
        w.finish()
            .map_err(|e| LoopError::io(e.to_string()).at("record"))?;
        if let Some(path) = &plan.record {
            log(&format!("{rows} rows written to {}", path.display()));
        }
    }
    let runs = runs.map_err(|e| {
        format!(
            "{}; stopped, the servos hold the standing pose",
            abort.unwrap_or_else(|| e.to_string())
        )
    });
    Ok(Guard {
        runs,
        health,
        cycle_s,
    })
}

/// The protocol on `robot`, whose bus is `port`, checked by [`prepare`].
fn run_prepared(
    plan: &BusPlan,
    p: &mut Prepared,
    mut robot: BusRobot,
    port: String,
    operator: &mut Operator<'_>,
) -> Result<BusRun, LoopError> {
    let serial = is_serial(&port);
    let guard = guarded_run(plan, p, &mut robot, serial, operator)?;
    let runs = guard.runs.map_err(LoopError::io)?;
    let mut outcome = bus_outcome(
        &p.model,
        &plan.model_spec,
        &port,
        &runs,
        &p.names,
        plan.soft_servos,
    )?;
    match &mut outcome {
        BusOutcome::Study(study) => study.bus = Some(guard.health),
        BusOutcome::Partial(partial) => partial.bus = Some(guard.health),
    }
    if let (BusOutcome::Study(study), Some(cycle_s)) = (&mut outcome, guard.cycle_s) {
        study.protocol = Some(plan.protocol(cycle_s));
    }
    Ok(BusRun {
        outcome,
        runs,
        joint_names: p.names.clone(),
        port,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use twinloop_ident::tipover_study::BusProtocol;

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
