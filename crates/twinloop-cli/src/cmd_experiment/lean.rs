//! `twinloop experiment lean`: seed 001's lean (centre -> forward -> backward -> centre
//! over the ankles) on the simulator or on a robot over its bus, the ankle and knee
//! angles and torques written row by row.

use super::bus::{Guarded, confirm, hold_standing, is_serial, record_writer, resolve};
use crate::bus_args::{PortArgs, open_client};
use crate::common::hinges_only;
use crate::common::{JSON_HELP, emit, load_description, num};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use twinloop_description::Description;
use twinloop_experiments::lean::{
    LeanConfig, LeanJointNames, LeanJointSummary, LeanRecord, LeanRow, lean_config, lean_simulator,
    run_lean, sagittal_tip_angles, summarize,
};
use twinloop_experiments::stiffen;
use twinloop_link::{DynamixelRobot, ReadMethod};
use twinloop_robot::RobotError;

#[derive(Args, Debug)]
pub struct LeanArgs {
    /// Robot description (builtin:km20, a URDF or MJCF file) to lean in the simulator.
    /// With --port, the model that gives the lean's signs and amplitude (default: the
    /// mapping's `urdf`).
    #[arg(long, value_name = "ROBOT")]
    pub robot: Option<String>,
    /// With --port (needs --map), the lean runs on a robot over its bus; the bus flags
    /// mean what they mean for `twinloop link`.
    #[command(flatten)]
    pub bus: PortArgs,
    /// Servo mapping of the robot on --port: builtin:km20 or a mapping TOML.
    #[arg(long, value_name = "MAP")]
    pub map: Option<String>,
    /// The lean, one row per control period, written (and flushed) as it comes.
    /// (`.mcap`: ROS 2 messages; `NAME/`: a rosbag2 folder, docs/logs.md.)
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
    /// Over the bus: every cycle read, all joints and the IMU (as `experiment
    /// tipover`; an .mcap as ROS 2 messages).
    #[arg(long, value_name = "FILE.csv|FILE.mcap")]
    pub record: Option<PathBuf>,
    /// Over a serial port: do not ask for confirmation before the lean.
    #[arg(long)]
    pub yes: bool,
    /// Over the bus: leave the servos as they are instead of stiffening them (every
    /// servo is made stiff through the servo catalogue and put back afterwards; a
    /// servo model with no known way to stiffen otherwise stops the lean before
    /// anything moves). The output then says the servos were soft.
    #[arg(long)]
    pub soft_servos: bool,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// Lean amplitude, deg of ankle (default: --fraction of the model's static tip angle).
    #[arg(long, value_name = "DEG", value_parser = crate::common::positive)]
    pub amplitude: Option<f64>,
    /// Amplitude as a fraction of the smaller of the model's static forward and backward
    /// tip angles (rigid model, feet flat). The servos' give adds to it: on km20 with
    /// factory RX settings the trunk leans 1.6-2.1 times the ankle command.
    #[arg(long, default_value_t = 0.3, value_parser = crate::common::positive)]
    pub fraction: f64,
    /// Ankle speed during the ramps, deg/s.
    #[arg(long, default_value_t = 2.0, value_name = "DEG/S", value_parser = crate::common::positive)]
    pub ramp: f64,
    /// Hold after each ramp, s.
    #[arg(long, default_value_t = 1.5, value_name = "S", value_parser = crate::common::non_negative)]
    pub hold: f64,
    /// Standing still before the lean, s.
    #[arg(long, default_value_t = 1.0, value_name = "S", value_parser = crate::common::non_negative)]
    pub settle: f64,
    /// Control (and row) period, s.
    #[arg(long, default_value_t = 0.005, value_name = "S", value_parser = crate::units::time_step)]
    pub dt: f64,
    /// Ankle pitch joints, left,right.
    #[arg(long, value_delimiter = ',', num_args = 2, value_names = ["LEFT", "RIGHT"],
          default_values_t = ["l_ank_pitch".to_string(), "r_ank_pitch".to_string()])]
    pub ankles: Vec<String>,
    /// Knee joints, left,right.
    #[arg(long, value_delimiter = ',', num_args = 2, value_names = ["LEFT", "RIGHT"],
          default_values_t = ["l_knee".to_string(), "r_knee".to_string()])]
    pub knees: Vec<String>,
    #[command(flatten)]
    pub added: crate::units::AddMassArgs,
    /// In the simulator: every servo's compliance slope, Dynamixel RX units (2 =
    /// stiffest), margin 0; default the factory settings `twinloop serve` runs with.
    #[arg(long, value_name = "UNITS", value_parser = crate::common::positive)]
    pub compliance_slope: Option<f64>,
}

/// The JSON of a lean.
#[derive(Serialize)]
struct LeanReport {
    robot: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    port: Option<String>,
    /// Over the bus with `--soft-servos`: the servos were left as they were.
    soft_servos: bool,
    out: String,
    amplitude_deg: f64,
    /// The model's static tip angles, deg (forward, backward).
    tip_forward_deg: f64,
    tip_backward_deg: f64,
    ramp_deg_per_s: f64,
    hold_s: f64,
    rows: usize,
    duration_s: f64,
    /// Per joint: mean angle (rad) and torque (N m) in the forward, backward and
    /// centre holds, and the torque's range.
    joints: Vec<LeanJointSummary>,
}

pub fn run(a: &LeanArgs) -> CliResult {
    let names = LeanJointNames {
        ankles: [a.ankles[0].clone(), a.ankles[1].clone()],
        knees: [a.knees[0].clone(), a.knees[1].clone()],
    };
    if !(a.fraction > 0.0 && a.fraction <= 0.8) {
        return Err(CliError::new(format!(
            "--fraction {}: must be in (0, 0.8] of the tip angle (the lean must not tip)",
            a.fraction
        )));
    }
    if a.bus.port.is_some() || a.map.is_some() {
        if !a.added.add_mass.is_empty() || a.compliance_slope.is_some() {
            return Err(CliError::new(
                "--add-mass and --compliance-slope change the simulated robot; over --port the robot is what it is",
            ));
        }
        return over_bus(a, &names);
    }
    let Some(spec) = a.robot.as_deref() else {
        return Err(CliError::new(
            "give --robot ROBOT (the simulator) or --port PORT --map MAP (a robot over its bus)",
        ));
    };
    let (mut robot, _) = load_description(spec)?;
    hinges_only(&robot, spec, "the lean experiment")?;
    a.added.apply(&mut robot)?;
    let (mut sim, standing) = lean_simulator(&robot, a.compliance_slope)?;
    if a.dt < sim.config.dt {
        // The simulator cannot advance less than its step: rows at one time forever.
        return Err(CliError::new(format!(
            "--dt {} s is shorter than the simulator's step, {} s: give --dt {} or more",
            a.dt, sim.config.dt, sim.config.dt
        )));
    }
    let tips = sagittal_tip_angles(&mut sim, &standing, &names)?;
    let order = sim.model.joint_names.clone();
    let cfg = configure(a, &sim.model, &order, &names, tips)?;
    let mut writer = lean_writer(a, &cfg)?;
    let mut buf = Vec::new();
    eprintln!(
        "leaning {spec} +-{:.2} deg in the simulator ({:.1} s) ...",
        cfg.amplitude_deg,
        cfg.duration_s()
    );
    let record = run_lean(&mut sim, &standing, &cfg, &mut |row| {
        write_row(&mut writer, row, &mut buf)
    });
    // A lean stopped by a fall is still a record of the run up to it: keep its rows.
    writer.finish()?;
    report(a, spec.to_string(), None, &cfg, tips, &record?)
}

/// The lean's configuration for a robot ordering its joints as `order`: the amplitude
/// given, or the fraction of the model's tip angle; refused at or beyond the tip.
fn configure(
    a: &LeanArgs,
    model: &twinloop_dynamics::Model,
    order: &[String],
    names: &LeanJointNames,
    (forward, backward): (f64, f64),
) -> Result<LeanConfig, CliError> {
    let tip = forward.min(backward).to_degrees();
    let amplitude = a.amplitude.unwrap_or(a.fraction * tip);
    if !(amplitude.is_finite() && amplitude > 0.0 && amplitude < tip) {
        return Err(CliError::new(format!(
            "--amplitude {amplitude} deg: must be > 0 and below the model's static tip angle, {tip:.2} deg"
        )));
    }
    let mut cfg = lean_config(model, order, names, amplitude)?;
    cfg.ramp_deg_per_s = a.ramp;
    cfg.hold_s = a.hold;
    cfg.settle_s = a.settle;
    cfg.period_s = a.dt;
    cfg.max_tilt_deg = Some(tip);
    // The settle is simulated (or waited on the bus) too: bound the whole run.
    crate::bounds::steps(
        cfg.settle_s + cfg.duration_s(),
        a.dt,
        &format!(
            "--settle {} s and the lean of {} s at --dt {} s",
            num(cfg.settle_s),
            num(cfg.duration_s()),
            num(a.dt)
        ),
    )?;
    Ok(cfg)
}

/// The lean's rows: a CSV, or an MCAP (`.mcap`) or rosbag2 folder (`run/`) of ROS 2
/// messages, as every recording (`twinloop_io::open_recording`).
fn lean_writer(a: &LeanArgs, cfg: &LeanConfig) -> Result<Box<dyn twinloop_io::RowSink>, CliError> {
    Ok(twinloop_io::open_recording(
        &a.out,
        &LeanRecord::columns(&cfg.recorded_names),
    )?)
}

fn write_row(
    w: &mut Box<dyn twinloop_io::RowSink>,
    row: &LeanRow<'_>,
    buf: &mut Vec<f64>,
) -> Result<(), RobotError> {
    LeanRecord::row_values(row, buf);
    w.write_row(buf)
        .map_err(|e| RobotError::new(format!("--out: {e}")))
}

fn report(
    a: &LeanArgs,
    robot: String,
    port: Option<String>,
    cfg: &LeanConfig,
    (forward, backward): (f64, f64),
    record: &LeanRecord,
) -> CliResult {
    let r = LeanReport {
        robot,
        soft_servos: port.is_some() && a.soft_servos,
        port,
        out: a.out.display().to_string(),
        amplitude_deg: cfg.amplitude_deg,
        tip_forward_deg: forward.to_degrees(),
        tip_backward_deg: backward.to_degrees(),
        ramp_deg_per_s: cfg.ramp_deg_per_s,
        hold_s: cfg.hold_s,
        rows: record.t.len(),
        duration_s: record.t.last().copied().unwrap_or(0.0),
        joints: summarize(record, cfg),
    };
    let mut text = String::new();
    if r.soft_servos {
        text += &format!("{}\n", twinloop_ident::adapt::SOFT_SERVOS_NOTE);
    }
    text += &format!(
        "{}{}: lean +-{:.2} deg of ankle (static tip {:.2} forward, {:.2} backward), {} rows over {:.1} s to {}\n\
         mean torque in the holds, N m:\n  joint          forward  backward    centre   (angle, deg)\n",
        r.robot,
        r.port
            .as_deref()
            .map(|p| format!(" over {p}"))
            .unwrap_or_default(),
        r.amplitude_deg,
        r.tip_forward_deg,
        r.tip_backward_deg,
        r.rows,
        r.duration_s,
        r.out
    );
    for j in &r.joints {
        text.push_str(&format!(
            "  {:<12} {:>9.4} {:>9.4} {:>9.4}   ({:+.2} {:+.2} {:+.2})\n",
            j.joint,
            j.tau_hold[0],
            j.tau_hold[1],
            j.tau_hold[2],
            j.q_hold[0].to_degrees(),
            j.q_hold[1].to_degrees(),
            j.q_hold[2].to_degrees()
        ));
    }
    emit(&text, a.json.as_ref(), &r)?;
    Ok(Outcome::Ok)
}

/// The lean on a robot over its bus: the signs and the amplitude from the model, the
/// torque from the servos' Present Load (N m by the datasheet stall torque), the same
/// guard as the tip-over.
fn over_bus(a: &LeanArgs, names: &LeanJointNames) -> CliResult {
    let (mapping, port, model_spec) = resolve(
        a.map.as_deref(),
        &a.bus,
        a.robot.as_deref(),
        "the lean's signs",
    )?;
    let (model, _) = load_description(&model_spec)?;
    hinges_only(&model, &model_spec, "the lean experiment")?;
    let (tips, cfg) = model_config(a, &model, &mapping.joint_names(), names)?;
    if !a.soft_servos {
        twinloop_experiments::stiffen::check_stiffenable(&mapping)?;
    }
    let serial = is_serial(&port);
    let port_args = PortArgs {
        port: Some(port.clone()),
        ..a.bus.clone()
    };
    let client = open_client(&port_args, None)?;
    let joints = mapping.joint_names();
    let mut robot = DynamixelRobot::new(client, mapping, ReadMethod::Auto)?;
    if robot.imu_board().is_none() {
        eprintln!(
            "warning: {}: no [[board]] with an IMU: tilt:pitch is NaN and nothing watches for a fall",
            robot.mapping().source
        );
    }
    let raw = match &a.record {
        Some(path) => Some(record_writer(path, &joints, &model)?),
        None => None,
    };
    let mut writer = lean_writer(a, &cfg)?;
    if serial && !a.yes {
        confirm(&format!(
            "the robot will lean +-{:.1} deg over its ankles; hold a hand ready; continue?",
            cfg.amplitude_deg
        ))?;
    }
    let standing = vec![0.0; joints.len()];
    // Every servo stiff (the lean's torques are read on a robot holding its pose),
    // the loop registers found written back after.
    let saved = match a.soft_servos {
        true => None,
        false => {
            let saved = stiffen::save_loops(&mut robot, a.bus.silence_window())?;
            stiffen::stiffen(&mut robot, 2, |_| true)?;
            Some(saved)
        }
    };
    let mut g = Guarded::new(
        &mut robot,
        raw,
        &standing,
        crate::bus_args::interrupt_flag(),
    );
    g.silence_window = a.bus.silence_window();
    eprintln!(
        "leaning +-{:.2} deg over {port} ({:.1} s) ...",
        cfg.amplitude_deg,
        cfg.duration_s()
    );
    let mut buf = Vec::new();
    let result = run_lean(&mut g, &standing, &cfg, &mut |row| {
        write_row(&mut writer, row, &mut buf)
    });
    let (rows, abort, health) = (g.rows, g.abort.clone(), g.health());
    let raw = g.writer.take();
    hold_standing(&mut robot, &standing);
    let restored = saved.map(|s| stiffen::restore_loops(&mut robot, &s));
    eprintln!("{}", health.line());
    writer.finish()?;
    if let Some(w) = raw {
        w.finish()?;
        if let Some(p) = &a.record {
            eprintln!("{rows} rows written to {}", p.display());
        }
    }
    if let Some(Err(e)) = restored {
        let what = format!("restoring the servos' loop registers: {}", e.message);
        if result.is_ok() {
            return Err(CliError::new(what));
        }
        eprintln!("warning: {what}");
    }
    match result {
        Ok(record) => report(a, model_spec, Some(port), &cfg, tips, &record),
        Err(e) => Err(CliError::new(format!(
            "{}; stopped, the servos hold the standing pose",
            abort.unwrap_or_else(|| e.to_string())
        ))),
    }
}

/// The model's static tip angles and the lean's configuration in the mapping's joint
/// order.
fn model_config(
    a: &LeanArgs,
    model: &Description,
    order: &[String],
    names: &LeanJointNames,
) -> Result<((f64, f64), LeanConfig), CliError> {
    let (mut sim, standing) = lean_simulator(model, None)?;
    let tips = sagittal_tip_angles(&mut sim, &standing, names)?;
    let cfg = configure(a, &sim.model, order, names, tips)?;
    Ok((tips, cfg))
}
