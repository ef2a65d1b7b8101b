//! `tipover(port=...)`: the tip-over experiment on a robot over its Dynamixel bus, as
//! `twinloop experiment tipover --port --map --json` runs it: the keywords checked and
//! mapped onto the one plan (`twinloop_loop::BusPlan`) the CLI fills too, run with
//! the GIL released while Ctrl-C is watched; the run itself is
//! `twinloop_loop::tipover_bus`.

use crate::errors::value_error;
use crate::sim::description_arg;
use crate::values::to_py;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use twinloop_description::{Description, JointKind};
use twinloop_ident::tipover_bus::{BusOutcome, ONSET_AVERAGE_S, parse_directions};
use twinloop_link::RobotMapping;
use twinloop_loop::tipover_bus::{Operator, tipover_on_bus_with};
use twinloop_loop::{BusPlan, BusPort, ErrorKind, LoopError};

/// The arguments of `tipover` over a bus.
pub struct Plan {
    pub port: Option<String>,
    pub map: Option<String>,
    pub directions: Vec<String>,
    pub record: Option<PathBuf>,
    pub yes: bool,
    pub ramp: f64,
    pub slow_ramp: f64,
    pub compliance_slope: f64,
    pub ankle_slope: f64,
    pub creeps: usize,
    pub dither: bool,
    pub realtime_factor: f64,
    pub baud: u32,
    pub timeout_ms: f64,
    pub retries: u32,
    /// Leave the servos as they are (`--soft-servos`).
    pub soft_servos: bool,
}

/// A plan's error as Python raises it: the keyword at fault first, OSError for a
/// port or a file, ValueError for the rest.
pub fn loop_error(e: LoopError) -> PyErr {
    let message = e.to_string();
    let message = match e.setting {
        Some("soft_servos") => format!("{message}; or pass soft_servos=True"),
        Some(setting) => format!("{setting}: {message}"),
        None => message,
    };
    match e.kind {
        ErrorKind::Io => PyOSError::new_err(message),
        ErrorKind::Input => value_error(message),
    }
}

/// SIGINT sets `flag` while the experiment runs (Python's own handler still runs, so
/// KeyboardInterrupt follows once the servos hold); restored on drop.
struct InterruptWatch(Option<signal_hook::SigId>);

impl InterruptWatch {
    fn new(flag: &Arc<AtomicBool>) -> InterruptWatch {
        InterruptWatch(signal_hook::flag::register(signal_hook::consts::SIGINT, flag.clone()).ok())
    }
}

impl Drop for InterruptWatch {
    fn drop(&mut self) {
        if let Some(id) = self.0.take() {
            signal_hook::low_level::unregister(id);
        }
    }
}

/// Every number of the plan positive and finite.
fn check_numbers(plan: &Plan) -> PyResult<()> {
    for (x, name) in [
        (plan.ramp, "ramp"),
        (plan.slow_ramp, "slow_ramp"),
        (plan.compliance_slope, "compliance_slope"),
        (plan.ankle_slope, "ankle_slope"),
        (plan.realtime_factor, "realtime_factor"),
        (plan.creeps as f64, "creeps"),
        (plan.timeout_ms, "timeout_ms"),
    ] {
        if !(x > 0.0 && x.is_finite()) {
            return Err(value_error(format!("{name}: must be positive, got {x}")));
        }
    }
    Ok(())
}

/// The host's model and its spec: `robot` (a Description or a spec), else the
/// mapping's description with its roles, as the CLI reads `--map` without `--robot`.
fn host_model(
    robot: Option<&Bound<'_, PyAny>>,
    map: &str,
    mapping: &RobotMapping,
) -> PyResult<(Description, String)> {
    let (model, spec) = match robot {
        Some(r) => {
            let d = description_arg(r)?;
            let spec = r.extract::<String>().unwrap_or_else(|_| d.name.clone());
            ((*d).clone(), spec)
        }
        None if mapping.urdf.is_some() => {
            let (d, _) = twinloop_loop::profile::load_description(map).map_err(loop_error)?;
            (d, map.to_string())
        }
        None => {
            return Err(value_error(format!(
                "robot: {}: no `urdf` in [robot]; give robot= for the lean signs",
                mapping.source
            )));
        }
    };
    if let Some(j) = model.joints.iter().find(|j| j.kind == JointKind::Spherical) {
        return Err(value_error(format!(
            "robot: {spec}: joint \"{}\" is a ball joint; the tip-over experiment \
             handles hinge and slide joints only",
            j.name
        )));
    }
    Ok((model, spec))
}

/// The plan the keywords say, with the host's model.
fn bus_plan(robot: Option<&Bound<'_, PyAny>>, plan: Plan) -> PyResult<(BusPlan, Description)> {
    check_numbers(&plan)?;
    let Some(map) = plan.map.as_deref() else {
        return Err(value_error(
            "map: port= needs map= (builtin:km20 or a mapping TOML)",
        ));
    };
    let mapping = RobotMapping::resolve(map).map_err(|e| value_error(format!("map: {e}")))?;
    let port = plan
        .port
        .clone()
        .or_else(|| mapping.port.clone())
        .ok_or_else(|| value_error("port: map= needs port= (or the mapping's port)"))?;
    let (model, model_spec) = host_model(robot, map, &mapping)?;
    let directions =
        parse_directions(&plan.directions).map_err(|e| value_error(format!("directions: {e}")))?;
    let bus = BusPlan {
        record: plan.record,
        yes: plan.yes,
        directions,
        ramp: plan.ramp,
        slow_ramp: plan.slow_ramp,
        compliance_slope: plan.compliance_slope.round() as i32,
        ankle_slope: plan.ankle_slope.round() as i32,
        soft_servos: plan.soft_servos,
        creeps: plan.creeps,
        first_tips: None,
        dither: plan.dither,
        onset_average_s: ONSET_AVERAGE_S,
        clock_rate: plan.realtime_factor,
        verbose: false,
        ..BusPlan::standard(
            &model_spec,
            map,
            BusPort {
                baud: plan.baud,
                ..BusPort::quick(Some(port), plan.timeout_ms, plan.retries)
            },
        )
    };
    Ok((bus, model))
}

pub fn run<'py>(
    py: Python<'py>,
    robot: Option<&Bound<'py, PyAny>>,
    plan: Plan,
) -> PyResult<Bound<'py, PyAny>> {
    let (plan, model) = bus_plan(robot, plan)?;
    let port = plan.port.port.clone().unwrap_or_default();
    let stop = Arc::new(AtomicBool::new(false));
    let watch = InterruptWatch::new(&stop);
    let run = py.detach(|| {
        // Nobody to ask: on a serial port the robot moves only with yes=True.
        let mut ask = |_: &str| {
            Err(LoopError::new(format!(
                "{port} is a serial port: the robot will lean until it tips in each \
                 direction, and a person stands it up in between; pass yes=True to run"
            ))
            .at("yes"))
        };
        let mut log = |_: &str| {};
        let mut operator = Operator {
            ask: &mut ask,
            log: &mut log,
            stop: stop.clone(),
        };
        tipover_on_bus_with(&plan, model, &mut operator)
    });
    drop(watch);
    // A Ctrl-C is Python's KeyboardInterrupt (its handler ran too).
    py.check_signals()?;
    let run = run.map_err(loop_error)?;
    match run.outcome {
        // How it was measured is kept (`StudyReport::protocol`), as the CLI keeps it.
        BusOutcome::Study(r) => to_py(py, &*r),
        BusOutcome::Partial(r) => to_py(py, &*r),
    }
}
