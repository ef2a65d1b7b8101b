//! `tipover(port=...)`: the tip-over experiment on a robot over its Dynamixel bus, as
//! `twinloop experiment tipover --port --map --json` runs it (the protocol is
//! `twinloop_ident::tipover_bus`; here the port is opened, Ctrl-C is watched and the
//! servos are left holding).

use crate::errors::value_error;
use crate::experiments::to_py;
use crate::model::load_description;
use crate::sim::description_arg;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;
use twinloop_description::{Description, JointKind};
use twinloop_experiments::guarded::{Guarded, hold_standing, is_serial, record_columns};
use twinloop_ident::tipover_bus::{
    BusOutcome, BusTipoverOptions, ONSET_AVERAGE_S, bus_outcome, parse_directions, run_directions,
};
use twinloop_ident::tipover_study::{BusProtocol, TiltModel, tipover_config};
use twinloop_io::CsvWriter;
use twinloop_link::transport::{self, SerialOptions};
use twinloop_link::{Client, ClientConfig, DynamixelRobot, ReadMethod, RobotMapping};

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

fn os_error(e: impl std::fmt::Display) -> PyErr {
    PyOSError::new_err(e.to_string())
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

pub fn run<'py>(
    py: Python<'py>,
    robot: Option<&Bound<'py, PyAny>>,
    plan: Plan,
) -> PyResult<Bound<'py, PyAny>> {
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
    let (model, model_spec): (Arc<Description>, String) = match robot {
        Some(r) => {
            let d = description_arg(r)?;
            let spec = r.extract::<String>().unwrap_or_else(|_| d.name.clone());
            (d, spec)
        }
        None => {
            let Some(urdf) = &mapping.urdf else {
                return Err(value_error(format!(
                    "robot: {}: no `urdf` in [robot]; give robot= for the lean signs",
                    mapping.source
                )));
            };
            let spec = urdf.to_string_lossy().into_owned();
            (Arc::new(load_description(&spec)?), spec)
        }
    };
    if let Some(j) = model.joints.iter().find(|j| j.kind == JointKind::Spherical) {
        return Err(value_error(format!(
            "robot: {model_spec}: joint \"{}\" is a ball joint; the tip-over experiment \
             handles hinge and slide joints only",
            j.name
        )));
    }
    let directions =
        parse_directions(&plan.directions).map_err(|e| value_error(format!("directions: {e}")))?;
    let names = mapping.joint_names();
    let cfg = tipover_config(&model, &names, plan.ramp)
        .map_err(|e| value_error(format!("{model_spec} with {}: {e}", mapping.source)))?;
    let Some(board) = mapping.boards.first() else {
        return Err(value_error(format!(
            "map: {map}: no [[board]]: the tip-over experiment needs the trunk IMU"
        )));
    };
    let mut tilt_model =
        TiltModel::new(&model, &names, &board.link).map_err(|e| value_error(e.to_string()))?;
    if !plan.soft_servos {
        twinloop_experiments::stiffen::check_stiffenable(&mapping)
            .map_err(|e| value_error(format!("{e}; or pass soft_servos=True")))?;
    }
    if is_serial(&port) && !plan.yes {
        return Err(value_error(format!(
            "yes: {port} is a serial port: the robot will lean until it tips in each \
             direction, and a person stands it up in between; pass yes=True to run"
        )));
    }
    let t = transport::open(&port, plan.baud, &SerialOptions::default())
        .map_err(|e| os_error(format!("{port}: {e}")))?;
    let config = ClientConfig {
        latency: Duration::from_secs_f64(plan.timeout_ms / 1000.0),
        retries: plan.retries,
        baud: plan.baud,
        write_replies: true,
    };
    let mut bot = DynamixelRobot::new(Client::with_config(t, config), mapping, ReadMethod::Auto)
        .map_err(os_error)?;
    bot.set_clock_rate(plan.realtime_factor)
        .map_err(|e| value_error(format!("realtime_factor: {e}")))?;
    let writer = match &plan.record {
        Some(path) => Some(
            CsvWriter::recording(path, &record_columns(&names))
                .map_err(|e| os_error(format!("record: {e}")))?,
        ),
        None => None,
    };
    let opts = BusTipoverOptions {
        directions,
        slow_ramp: plan.slow_ramp,
        compliance_slope: plan.compliance_slope.round() as i32,
        ankle_slope: plan.ankle_slope.round() as i32,
        soft_servos: plan.soft_servos,
        creeps: plan.creeps,
        first_tips: None,
        dither: plan.dither,
        onset_average_s: ONSET_AVERAGE_S,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let watch = InterruptWatch::new(&stop);
    let standing = vec![0.0; names.len()];
    let (runs, abort, finished, cycle_s, health) = py.detach(|| {
        let mut g = Guarded::new(&mut bot, writer, &standing, stop.clone());
        let runs = run_directions(
            &mut g,
            &opts,
            &cfg,
            &mut tilt_model,
            &mut |_, _| Ok(()),
            &mut |_| {},
        );
        let cycle_s = g.median_cycle_s();
        let health = g.health();
        let writer = g.writer.take();
        let abort = g.abort.take();
        hold_standing(&mut bot, &standing);
        (
            runs,
            abort,
            writer.map(CsvWriter::finish).transpose(),
            cycle_s,
            health,
        )
    });
    drop(watch);
    finished.map_err(|e| os_error(format!("record: {e}")))?;
    // A Ctrl-C is Python's KeyboardInterrupt (its handler ran too).
    py.check_signals()?;
    let runs = runs.map_err(|e| {
        os_error(format!(
            "{}; stopped, the servos hold the standing pose",
            abort.unwrap_or(e)
        ))
    })?;
    // How the bus held up, as the CLI's JSON has it.
    let mut outcome = bus_outcome(&model, &model_spec, &port, &runs, &names, plan.soft_servos)
        .map_err(|e| value_error(e.to_string()))?;
    match &mut outcome {
        BusOutcome::Study(study) => study.bus = Some(health),
        BusOutcome::Partial(partial) => partial.bus = Some(health),
    }
    match outcome {
        BusOutcome::Study(mut r) => {
            // How it was measured, as the CLI keeps it (`adapt --protocol-passes`).
            r.protocol = cycle_s.map(|cycle_s| BusProtocol {
                map: map.to_string(),
                ramp_deg_per_s: plan.ramp,
                slow_ramp_deg_per_s: plan.slow_ramp,
                compliance_slope: opts.compliance_slope,
                ankle_slope: opts.ankle_slope,
                creeps: opts.creeps,
                dither: opts.dither,
                onset_average_s: opts.onset_average_s,
                cycle_s,
                soft_servos: opts.soft_servos,
            });
            to_py(py, &*r)
        }
        BusOutcome::Partial(r) => to_py(py, &*r),
    }
}
