//! `twinloop identify servo`: a servo model fitted to `experiment servo` logs.

use crate::common::{JSON_HELP, emit};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use serde_json::json;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;
use twinloop_actuator::identify::{Identification, IdentifyOptions, identify_with};
use twinloop_actuator::log::ServoLog;
use twinloop_actuator::params::{NONSMOOTH, PARAM_NAMES};
use twinloop_actuator::{Load, ModelLevel, Pendulum, ServoParams, ServoType, datasheet};

#[derive(Args, Debug)]
pub struct ServoIdArgs {
    /// Logs to fit (`experiment servo --out`); with no --holdout, the last
    /// --holdout-fraction of each is kept out of the fit and scored
    #[arg(long, value_name = "LOG.csv", num_args = 1.., required_unless_present = "defaults")]
    pub data: Vec<PathBuf>,
    /// Logs scored but not fitted
    #[arg(long, value_name = "LOG.csv", num_args = 1..)]
    pub holdout: Vec<PathBuf>,
    /// The pendulum the logs were recorded with (mass, length, arm_inertia); without
    /// it, the logs of a limb (`experiment servo --map --joint`) rebuild their load
    /// from the robot, joint and held pose they record
    #[arg(long, value_name = "LOAD.toml")]
    pub load: Option<PathBuf>,
    /// Limb logs: compute the load from this description instead of the one the log
    /// names (a file moved, or a corrected model)
    #[arg(long, value_name = "ROBOT", conflicts_with = "load")]
    pub robot: Option<String>,
    /// The model ladder's rung: m1 (Coulomb + viscous), m2 (+ Stribeck), m3 (+ load-dependent), m4 (both)
    #[arg(long, default_value = "m1", value_name = "NAME")]
    pub model: String,
    /// The servo type, where the logs' first line does not name it
    #[arg(long, value_name = "MODEL")]
    pub servo: Option<String>,
    /// Start from these parameters (default: the datasheet's)
    #[arg(long, value_name = "FILE.toml")]
    pub start: Option<PathBuf>,
    /// Share of each log held out when no --holdout is given
    #[arg(long, default_value_t = 0.25, value_parser = crate::common::positive)]
    pub holdout_fraction: f64,
    /// Also fit these (comma list): backlash (by CMA-ES, alternating with LM: the dead
    /// band is not smooth), sensing_delay, bus_delay (by LM with the rest). Needs the
    /// excitation's slow back-and-forth through zero load (backlash) and its steps
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub fit: Vec<String>,
    /// Write the datasheet parameters of MODEL to --out and stop
    #[arg(long, value_name = "MODEL")]
    pub defaults: Option<String>,
    /// The parameter file written (`serve --servo-params` reads it)
    #[arg(long, value_name = "FILE.toml")]
    pub out: Option<PathBuf>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
}

fn parse_servo(text: &str, option: &str) -> Result<ServoType, CliError> {
    ServoType::parse(text).ok_or_else(|| {
        CliError::new(format!(
            "{option} {text:?}: no servo model (known: {})",
            ServoType::known_names()
        ))
    })
}

pub fn run(a: &ServoIdArgs) -> CliResult {
    let level = ModelLevel::parse(&a.model)
        .ok_or_else(|| CliError::new(format!("--model {:?}: m1, m2, m3 or m4", a.model)))?;
    if let Some(m) = &a.defaults {
        let p = datasheet::defaults(parse_servo(m, "--defaults")?, level);
        let out = a.out.as_ref().ok_or("--defaults needs --out FILE.toml")?;
        let text = p.to_toml("datasheet values (twinloop identify servo --defaults): docs/servo-models.md says where each comes from");
        std::fs::write(out, text).map_err(|e| CliError::io(out, e))?;
        return Ok(Outcome::Ok);
    }
    let mut options = IdentifyOptions::default();
    for name in &a.fit {
        let i = NONSMOOTH
            .into_iter()
            .find(|&i| PARAM_NAMES[i] == name.trim())
            .ok_or_else(|| {
                CliError::new(format!(
                    "--fit {name:?}: backlash, sensing_delay or bus_delay"
                ))
            })?;
        options.nonsmooth.push(i);
    }
    if a.holdout_fraction >= 1.0 {
        return Err(CliError::new("--holdout-fraction must be below 1"));
    }
    let servo = a
        .servo
        .as_deref()
        .map(|s| parse_servo(s, "--servo"))
        .transpose()?;
    let read = |paths: &[PathBuf]| -> Result<Vec<ServoLog>, CliError> {
        paths
            .iter()
            .map(|p| ServoLog::read(p, servo).map_err(CliError::from))
            .collect()
    };
    // The pendulum is read first: a bad LOAD.toml is named before any log.
    let pendulum = a.load.as_deref().map(Pendulum::read).transpose()?;
    let logs = read(&a.data)?;
    let holdout = read(&a.holdout)?;
    let load = match pendulum {
        Some(p) => Load::from(p),
        None => limb_load(a.data.iter().chain(&a.holdout), a.robot.as_deref())?,
    };
    let servo = logs
        .first()
        .and_then(|l| l.servo)
        .ok_or("identify servo needs --data LOG.csv naming its servo (or --servo MODEL)")?;
    let start = match &a.start {
        Some(p) => ServoParams::read(p)?.with_level(level),
        None => datasheet::defaults(servo, level),
    };
    let t0 = Instant::now();
    let id = identify_with(&logs, &holdout, &load, &start, a.holdout_fraction, &options)?;
    let seconds = t0.elapsed().as_secs_f64();
    if let Some(out) = &a.out {
        let comment = format!(
            "fitted by twinloop identify servo ({} rows in {} logs); held-out error {:.3} mrad RMS",
            logs.iter().map(ServoLog::len).sum::<usize>(),
            logs.len(),
            id.heldout_rms_mrad
        );
        std::fs::write(out, id.params.to_toml(&comment)).map_err(|e| CliError::io(out, e))?;
    }
    emit(&text(&id, seconds), a.json.as_ref(), &to_json(&id, seconds))?;
    Ok(Outcome::Ok)
}

/// The load of limb logs: each rebuilt from the robot (or `robot`), joint and held
/// pose it records; all must be the same load (within 1e-6 relative).
fn limb_load<'a>(
    paths: impl Iterator<Item = &'a PathBuf>,
    robot: Option<&str>,
) -> Result<Load, CliError> {
    let mut load: Option<(Load, String)> = None;
    for p in paths {
        let file = p.display().to_string();
        let text = std::fs::read_to_string(p).map_err(|e| CliError::io(p, e))?;
        let limb = crate::limb::Limb::from_log(&text, &file)?.ok_or_else(|| {
            CliError::new(format!(
                "{file}: a bench log (no \"# limb:\" lines): give --load LOAD.toml"
            ))
        })?;
        let (l, _) = limb.load_from(robot)?;
        match &load {
            None => load = Some((l, file)),
            Some((first, name)) => {
                let same = |x: f64, y: f64| (x - y).abs() <= 1e-6 * (x.abs() + y.abs()).max(1e-9);
                if !(same(l.inertia, first.inertia)
                    && same(l.gravity_sin, first.gravity_sin)
                    && same(l.gravity_cos, first.gravity_cos)
                    && same(l.gravity_const, first.gravity_const))
                {
                    return Err(CliError::new(format!(
                        "{file}: its limb load differs from {name}'s (another joint or pose): fit them separately"
                    )));
                }
            }
        }
    }
    load.map(|l| l.0)
        .ok_or_else(|| CliError::new("identify servo needs --data LOG.csv"))
}

fn text(id: &Identification, seconds: f64) -> String {
    let p = &id.params;
    let sd = p
        .uncertainty
        .unwrap_or([f64::NAN; twinloop_actuator::params::N_PARAMS]);
    let mut s = format!(
        "{} model {} at {:.2} V, fitted in {seconds:.2} s ({} iterations)\n",
        p.servo,
        p.level.name(),
        p.voltage,
        id.iterations
    );
    for &i in id.fitted.iter().chain(&id.nonsmooth) {
        let _ = writeln!(
            s,
            "  {:18} {:>12.6} +- {:.2e}",
            PARAM_NAMES[i], p.values[i], sd[i]
        );
    }
    for (name, v, sd) in &id.combinations {
        let _ = writeln!(s, "  {name:34} {v:.6} +- {sd:.2e}");
    }
    let _ = writeln!(
        s,
        "position error: fitted {:.3} mrad RMS; held out {:.3} mrad RMS, {:.3} mrad mean absolute ({} rows)",
        id.fit_rms_mrad, id.heldout_rms_mrad, id.heldout_mae_mrad, id.heldout_rows
    );
    let _ = writeln!(
        s,
        "condition number {:.3e}; not determined by these logs: {}",
        id.condition,
        if id.undetermined.is_empty() {
            "nothing".to_string()
        } else {
            id.undetermined.join(", ")
        }
    );
    s
}

fn to_json(id: &Identification, seconds: f64) -> serde_json::Value {
    let p = &id.params;
    let sd = p
        .uncertainty
        .unwrap_or([f64::NAN; twinloop_actuator::params::N_PARAMS]);
    let params: serde_json::Map<String, serde_json::Value> = id
        .fitted
        .iter()
        .chain(&id.nonsmooth)
        .map(|&i| {
            (
                PARAM_NAMES[i].to_string(),
                json!({"value": p.values[i], "sd": sd[i]}),
            )
        })
        .collect();
    json!({
        "servo": p.servo.name(),
        "model": p.level.name(),
        "voltage": p.voltage,
        "params": params,
        "fitted": id.fitted.iter().map(|&i| PARAM_NAMES[i]).collect::<Vec<_>>(),
        "correlation": id.correlation,
        "combinations": id.combinations.iter().map(|(n, v, s)| json!({"name": n, "value": v, "sd": s})).collect::<Vec<_>>(),
        "fit_rms_mrad": id.fit_rms_mrad,
        "heldout_rms_mrad": id.heldout_rms_mrad,
        "heldout_mae_mrad": id.heldout_mae_mrad,
        "heldout_rows": id.heldout_rows,
        "singular_values": id.singular_values,
        "condition": id.condition,
        "undetermined": id.undetermined,
        "weakest_direction": id.weakest_direction.iter().map(|(n, w)| json!({"name": n, "weight": w})).collect::<Vec<_>>(),
        "iterations": id.iterations,
        "evaluations": id.evaluations,
        "cmaes_evaluations": id.nonsmooth_evaluations,
        "seconds": seconds,
    })
}
