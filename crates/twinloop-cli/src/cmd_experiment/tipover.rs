//! `twinloop experiment tipover`: the tip-over experiment of seeds 000 and 001 on the
//! simulator, with the CoM from the tip angles beside the model's.

use crate::common::{JSON_HELP, emit, load_description};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use std::path::PathBuf;
use twinloop_ident::tipover_study::{StudyOptions, StudyReport, run_study};

#[derive(Args, Debug)]
pub struct TipoverArgs {
    /// Robot description: builtin:km20, builtin:lab17, or a URDF/MJCF file whose ankle and hip roll
    /// joints are named like l_ank_pitch / r_ank_roll / l_hip_roll and whose feet have
    /// collision boxes. Sideways, the hip rolls turn with the ankle rolls (the legs lean
    /// as a parallelogram, feet flat, pelvis level).
    /// With --port, the model for the lean signs (default: the mapping's `urdf`).
    #[arg(long, value_name = "ROBOT")]
    pub robot: Option<String>,
    /// With --port (needs --map), the experiment runs on a robot over its bus instead
    /// of the simulator; the bus flags mean what they mean for `twinloop link`.
    #[command(flatten)]
    pub bus: crate::cmd_link::PortArgs,
    /// Servo mapping of the robot on --port: builtin:km20 or a mapping TOML.
    #[arg(long, value_name = "MAP")]
    pub map: Option<String>,
    /// Over the bus: every cycle read as a CSV row (t, q:<joint>, goal:<joint>,
    /// imu:gyro_x..imu:accel_z, tilt:pitch, tilt:roll), flushed row by row.
    #[arg(long, value_name = "FILE.csv")]
    pub record: Option<PathBuf>,
    /// Over a serial port: do not ask for confirmation before the first ramp.
    #[arg(long)]
    pub yes: bool,
    /// Over the bus: the directions to run, in order (comma list of forward,
    /// backward, left, right; default all four). A robot that fell is stood up again
    /// by a person between directions.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub directions: Vec<String>,
    /// Add a point mass before the experiment (seed 000's batteries), repeatable:
    /// KG@LINK:X,Y,Z with X,Y,Z in metres in the link frame, e.g. 0.2@torso:0.05,0,0.
    #[arg(long = "add-mass", value_name = "KG@LINK:X,Y,Z")]
    pub add_mass: Vec<String>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// Ankle ramp speed, deg/s.
    #[arg(long, default_value_t = 0.5)]
    pub ramp: f64,
    /// Servo compliance slope during the experiment, Dynamixel RX units (2 = stiffest,
    /// the default). The CoM methods assume a rigid robot; stiffer servos bend less.
    #[arg(long, default_value_t = 2.0)]
    pub compliance_slope: f64,
    /// Ramp speed of the second run's slow final approach, deg/s: each direction is run
    /// twice, the second time up to half a degree before the first tip and then at this
    /// speed, so the tip is seen with less lag.
    #[arg(long, default_value_t = 0.05)]
    pub slow_ramp: f64,
    /// Quantise the ankle readings like Dynamixel RX encoders (1024 counts over 300 deg).
    #[arg(long)]
    pub encoders: bool,
}

/// Parse `KG@LINK:X,Y,Z`.
pub(super) fn parse_mass(s: &str) -> Result<(f64, String, [f64; 3]), String> {
    let bad = |why: &str| format!("--add-mass \"{s}\": {why} (expected KG@LINK:X,Y,Z)");
    let (kg, rest) = s.split_once('@').ok_or_else(|| bad("no '@'"))?;
    let (link, xyz) = rest
        .rsplit_once(':')
        .ok_or_else(|| bad("no ':' before the position"))?;
    let kg: f64 = kg
        .trim()
        .parse()
        .map_err(|_| bad("the mass is not a number"))?;
    let v: Vec<f64> = xyz
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad("the position is not three numbers"))?;
    if v.len() != 3 {
        return Err(bad("the position needs three numbers"));
    }
    Ok((kg, link.to_string(), [v[0], v[1], v[2]]))
}

pub fn run(a: &TipoverArgs) -> CliResult {
    if a.bus.port.is_some() || a.map.is_some() {
        return bus::run(a);
    }
    let Some(spec) = a.robot.as_deref() else {
        return Err(CliError::new(
            "give --robot ROBOT (the simulator) or --port PORT --map MAP (a robot over its bus)",
        ));
    };
    let (mut robot, _) = load_description(spec)?;
    for m in &a.add_mass {
        let (kg, link, xyz) = parse_mass(m)?;
        twinloop_description::builtin::add_point_mass(&mut robot, &link, kg, xyz)
            .map_err(|e| CliError::from(e).context(format!("--add-mass \"{m}\"")))?;
    }
    let opts = StudyOptions {
        ramp_deg_per_s: a.ramp,
        dynamixel_encoders: a.encoders,
        slow_ramp_deg_per_s: a.slow_ramp,
        compliance_units: Some((a.compliance_slope, 0.0)),
        ..Default::default()
    };
    eprintln!("running the four tip-overs in the simulator ...");
    let r = run_study(&robot, &opts)?;
    emit(&summary(&r), a.json.as_ref(), &r)?;
    Ok(Outcome::Ok)
}

/// The table of tip angles and the CoM by each method.
fn summary(r: &StudyReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: tip-over (ankle angles from the standing pose, deg)",
        r.robot
    );
    let _ = writeln!(
        s,
        "  direction  commanded  measured  static(model)  feet-roll  time(s)"
    );
    for (name, d) in [
        ("forward", &r.forward),
        ("backward", &r.backward),
        ("left", &r.left),
        ("right", &r.right),
    ] {
        let _ = writeln!(
            s,
            "  {name:<9}  {:>9.3}  {:>8.3}  {:>13.3}  {:>9.3}  {:>7.2}",
            d.commanded_deg, d.measured_deg, d.static_deg, d.excess_deg, d.time_s
        );
    }
    let f = |c: [f64; 3]| format!("[{:+.4}, {:+.4}, {:+.4}]", c[0], c[1], c[2]);
    let _ = writeln!(
        s,
        "CoM relative to the ankle midpoint (m; x forward, y left, z up):"
    );
    let _ = writeln!(s, "  true          {}", f(r.com.truth));
    let _ = writeln!(
        s,
        "  exact method  {}  (off by {:.1} mm)",
        f(r.com.exact_method),
        r.com.exact_error * 1e3
    );
    let _ = writeln!(
        s,
        "  seed method   {}  (off by {:.1} mm; constants: {})",
        f(r.com.seed_method),
        r.com.seed_error * 1e3,
        r.seed_constants
    );
    let _ = writeln!(
        s,
        "  sideways lever  {:.4} m (model {:.4} m)",
        r.com.frontal_lever_exact, r.com.frontal_lever_true
    );
    s
}

/// The tip-over experiment on a robot over its Dynamixel bus (`--port`, `--map`).
mod bus {
    use super::TipoverArgs;
    use crate::cmd_experiment::bus::{
        Guarded, confirm, hold_standing, is_serial, record_writer, resolve,
    };
    use crate::cmd_link::{PortArgs, open_client};
    use crate::common::{emit, load_description};
    use crate::error::{CliError, CliResult, Outcome};
    use nalgebra::Vector3;
    use serde::Serialize;
    use twinloop_experiments::tipover::{Direction, TipoverConfig, TipoverResult, run_direction};
    use twinloop_link::{DynamixelRobot, ReadMethod, RobotMapping};
    use twinloop_robot::{Robot, RobotError};

    #[derive(Serialize)]
    struct BusDirection {
        commanded_deg: f64,
        measured_deg: f64,
        time_s: f64,
        excess_deg: f64,
        lean_deg: f64,
    }

    #[derive(Serialize)]
    struct BusReport {
        robot: String,
        port: String,
        #[serde(skip_serializing_if = "Option::is_none")]
        forward: Option<BusDirection>,
        #[serde(skip_serializing_if = "Option::is_none")]
        backward: Option<BusDirection>,
        #[serde(skip_serializing_if = "Option::is_none")]
        left: Option<BusDirection>,
        #[serde(skip_serializing_if = "Option::is_none")]
        right: Option<BusDirection>,
    }

    fn parse_directions(list: &[String]) -> Result<Vec<Direction>, CliError> {
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

    /// The experiment's joints and lean signs from the model, in the mapping's order.
    fn config(
        model_spec: &str,
        mapping: &RobotMapping,
        a: &TipoverArgs,
    ) -> Result<TipoverConfig, CliError> {
        let (robot, _) = load_description(model_spec)?;
        let sim = twinloop_sim::Simulator::new(&robot, twinloop_sim::SimConfig::default())
            .map_err(|e| CliError::new(format!("{model_spec}: {e}")))?;
        let m = &sim.model;
        let mut data = twinloop_dynamics::Data::new(m);
        let q0 = m.neutral_configuration();
        let names = twinloop_description::builtin::foot_geometry(&robot.name)
            .map(|f| {
                [
                    f.left_ankle_pitch,
                    f.right_ankle_pitch,
                    f.left_ankle_roll,
                    f.right_ankle_roll,
                ]
            })
            .unwrap_or_else(|| {
                [
                    "l_ank_pitch".into(),
                    "r_ank_pitch".into(),
                    "l_ank_roll".into(),
                    "r_ank_roll".into(),
                ]
            });
        let hips = ["l_hip_roll".to_string(), "r_hip_roll".to_string()];
        let sim_index = |n: &str| {
            sim.joint_index(n).ok_or_else(|| {
                CliError::new(format!(
                    "{model_spec}: no joint \"{n}\" (the tip-over turns it)"
                ))
            })
        };
        let map_index = |n: &str| {
            mapping
                .joints
                .iter()
                .position(|j| j.name == n)
                .ok_or_else(|| {
                    CliError::new(format!(
                        "{}: no servo drives joint \"{n}\" (the tip-over turns it)",
                        mapping.source
                    ))
                })
        };
        let s2 = |a: &str, b: &str| -> Result<[usize; 2], CliError> {
            Ok([sim_index(a)?, sim_index(b)?])
        };
        let m2 = |a: &str, b: &str| -> Result<[usize; 2], CliError> {
            Ok([map_index(a)?, map_index(b)?])
        };
        let fs = twinloop_sim::statics::lean_signs(
            m,
            &mut data,
            &q0,
            s2(&names[0], &names[1])?,
            Vector3::x(),
        );
        let ls = twinloop_sim::statics::lean_signs(
            m,
            &mut data,
            &q0,
            s2(&names[2], &names[3])?,
            Vector3::y(),
        );
        let hs = twinloop_sim::statics::hip_lean_signs(
            m,
            &mut data,
            &q0,
            s2(&hips[0], &hips[1])?,
            Vector3::y(),
        );
        let mut cfg =
            TipoverConfig::new(m2(&names[0], &names[1])?, m2(&names[2], &names[3])?, fs, ls);
        cfg.hip_roll = Some(m2(&hips[0], &hips[1])?);
        cfg.hip_left_sign = hs;
        cfg.ramp_deg_per_s = a.ramp;
        Ok(cfg)
    }

    pub fn run(a: &TipoverArgs) -> CliResult {
        let (mapping, port, model_spec) = resolve(
            a.map.as_deref(),
            &a.bus,
            a.robot.as_deref(),
            "the lean signs",
        )?;
        let map = mapping.source.clone();
        let directions = parse_directions(&a.directions)?;
        let cfg = config(&model_spec, &mapping, a)?;
        let serial = is_serial(&port);
        let port_args = PortArgs {
            port: Some(port.clone()),
            ..a.bus.clone()
        };
        let client = open_client(&port_args, None)?;
        let names = mapping.joint_names();
        let mut robot = DynamixelRobot::new(client, mapping, ReadMethod::Auto)?;
        if robot.imu_board().is_none() {
            return Err(CliError::new(format!(
                "{map}: no [[board]]: the tip-over experiment needs the trunk IMU"
            )));
        }
        let writer = match &a.record {
            Some(path) => Some(record_writer(path, &names)?),
            None => None,
        };
        if serial && !a.yes {
            confirm(
                "the robot will lean until it tips in four directions; hold a hand ready; continue?",
            )?;
        }
        let standing = vec![0.0; names.len()];
        let mut g = Guarded::new(&mut robot, writer, &standing);
        let mut report = BusReport {
            robot: model_spec.clone(),
            port: port.clone(),
            forward: None,
            backward: None,
            left: None,
            right: None,
        };
        let mut outcome: Result<(), String> = Ok(());
        for (k, &d) in directions.iter().enumerate() {
            if k > 0
                && serial
                && !a.yes
                && let Err(e) = confirm(&format!(
                    "stand the robot up again for the {} lean; continue?",
                    d.name()
                ))
            {
                outcome = Err(e.message);
                break;
            }
            eprintln!("leaning {} over {port} ...", d.name());
            let r: Result<TipoverResult, RobotError> =
                run_direction(&mut g, &standing, d, &cfg, None);
            // The ramp ends at the first sign of tipping (or a fault): the ankles
            // go back to the standing pose at once.
            let _ = g.robot.command_positions(&standing);
            match r {
                Ok(r) => {
                    let out = BusDirection {
                        commanded_deg: r.commanded_deg,
                        measured_deg: r.measured_deg,
                        time_s: r.time_s,
                        excess_deg: r.excess_deg,
                        lean_deg: r.lean_deg,
                    };
                    match d {
                        Direction::Forward => report.forward = Some(out),
                        Direction::Backward => report.backward = Some(out),
                        Direction::Left => report.left = Some(out),
                        Direction::Right => report.right = Some(out),
                    }
                }
                Err(e) => {
                    outcome = Err(g.abort.clone().unwrap_or_else(|| e.to_string()));
                    break;
                }
            }
        }
        let rows = g.rows;
        let writer = g.writer.take();
        hold_standing(&mut robot, &standing);
        if let Some(w) = writer {
            w.finish()?;
            if let Some(p) = &a.record {
                eprintln!("{rows} rows written to {}", p.display());
            }
        }
        if let Err(m) = outcome {
            return Err(CliError::new(format!(
                "{m}; stopped, the servos hold the standing pose"
            )));
        }
        let mut text = format!(
            "{}: tip-over over {port} (ankle angles from the standing pose, deg)\n  direction  commanded  measured  time(s)\n",
            model_spec
        );
        for (name, d) in [
            ("forward", &report.forward),
            ("backward", &report.backward),
            ("left", &report.left),
            ("right", &report.right),
        ] {
            if let Some(d) = d {
                text.push_str(&format!(
                    "  {name:<9}  {:>9.3}  {:>8.3}  {:>7.2}\n",
                    d.commanded_deg, d.measured_deg, d.time_s
                ));
            }
        }
        emit(&text, a.json.as_ref(), &report)?;
        Ok(Outcome::Ok)
    }
}
