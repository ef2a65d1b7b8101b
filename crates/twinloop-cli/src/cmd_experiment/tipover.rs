//! `twinloop experiment tipover`: the tip-over experiment of seeds 000 and 001 on the
//! simulator, with the CoM from the tip angles beside the model's.

use crate::common::hinges_only;
use crate::common::{JSON_HELP, emit, load_description};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use std::path::PathBuf;
use twinloop_ident::tipover_study::{
    STUDY_RUNS, StudyOptions, StudyReport, run_study_with_progress,
};

/// The slowest first ramp, deg/s: each direction's first run ramps until the robot
/// tips or the ankles reach the 45 deg limit (900 s of robot time at this speed; the
/// 0.001 deg/s once asked for would be 12.5 h per run, eight runs). The first ramp
/// only finds where the robot tips; the creep at --slow-ramp makes the measurement.
const MIN_RAMP: f64 = 0.05;

/// The slowest creep, deg/s: the creep covers the last half degree or so before the
/// tip, 100 s of robot time per direction at this speed.
const MIN_SLOW_RAMP: f64 = 0.005;

/// `--ramp`: a finite speed of at least [`MIN_RAMP`].
fn first_ramp(s: &str) -> Result<f64, String> {
    let x = crate::common::positive(s)?;
    if x < MIN_RAMP {
        return Err(format!(
            "{} deg/s is below {MIN_RAMP}: a ramp to the 45 deg limit would take {} s \
             ({} h) of robot time per run; the first ramp only finds where the \
             robot tips and --slow-ramp (default 0.05) creeps up to it, so use --ramp {MIN_RAMP} \
             or more (default 0.5)",
            crate::common::num(x),
            crate::common::num(45.0 / x),
            crate::common::num(45.0 / x / 3600.0)
        ));
    }
    Ok(x)
}

/// `--slow-ramp`: a finite speed of at least [`MIN_SLOW_RAMP`].
fn creep_ramp(s: &str) -> Result<f64, String> {
    let x = crate::common::positive(s)?;
    if x < MIN_SLOW_RAMP {
        return Err(format!(
            "{} deg/s is below {MIN_SLOW_RAMP}: the creep over the last half degree would \
             take {} s of robot time per direction, and a slower creep no longer shortens \
             the lag of a tip's detection (about 0.2 s of fall: 0.001 deg at 0.005 deg/s); use \
             --slow-ramp {MIN_SLOW_RAMP} or more (default 0.05)",
            crate::common::num(x),
            crate::common::num(0.5 / x)
        ));
    }
    Ok(x)
}

#[derive(Args, Debug)]
pub struct TipoverArgs {
    /// Robot description: builtin:km20, builtin:lab17, builtin:op3, builtin:darwin_op, a
    /// robot profile (.toml: its description, its [roles] naming the ankle and hip roll
    /// joints), or a URDF/MJCF file whose joints are named like l_ank_pitch / r_ank_roll /
    /// l_hip_roll (guessed, said on stderr); the feet need collision boxes. Sideways, the
    /// hip rolls turn with the ankle rolls (the legs lean as a parallelogram, feet flat,
    /// pelvis level). With --port, the model for the lean signs (default: the --map
    /// profile's description, with its roles).
    #[arg(long, value_name = "ROBOT")]
    pub robot: Option<String>,
    /// With --port (needs --map), the experiment runs on a robot over its bus instead
    /// of the simulator; the bus flags mean what they mean for `twinloop link`.
    #[command(flatten)]
    pub bus: crate::bus_args::PortArgs,
    /// Servo mapping of the robot on --port: builtin:km20 or a mapping TOML.
    #[arg(long, value_name = "MAP")]
    pub map: Option<String>,
    /// Over the bus: every cycle read as a CSV row (t, q:<joint>, goal:<joint>,
    /// imu:gyro_x..imu:accel_z, tilt:pitch, tilt:roll), flushed row by row; an .mcap
    /// is written as ROS 2 messages (/joint_states, the rest on /twinloop/columns),
    /// complete when the run ends (a failed run's is closed and kept).
    #[arg(long, value_name = "FILE.csv|FILE.mcap")]
    pub record: Option<PathBuf>,
    /// Over the bus, when the robot is a simulation served faster than real time
    /// (`twinloop serve --realtime-factor F`): F, so the protocol's ramps, waits and
    /// tilt filter count the robot's seconds. 1 for a real robot.
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = crate::bounds::realtime_factor)]
    pub realtime_factor: f64,
    /// Over a serial port: do not ask for confirmation before the first ramp.
    #[arg(long)]
    pub yes: bool,
    /// Over the bus: the directions to run, in order (comma list of forward,
    /// backward, left, right; default all four). A robot that fell is stood up again
    /// by a person between directions.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub directions: Vec<String>,
    #[command(flatten)]
    pub added: crate::units::AddMassArgs,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// Ankle ramp speed, deg/s, 0.05 or more (the first run of each direction: slower
    /// would take hours and measure no better, the creep at --slow-ramp measures).
    #[arg(long, default_value_t = 0.5, value_parser = first_ramp)]
    pub ramp: f64,
    /// Servo compliance slope during the experiment, Dynamixel RX units (2 = stiffest,
    /// the default). The CoM methods assume a rigid robot; stiffer servos bend less.
    /// Over a bus every servo family is made as stiff through the servo catalogue: MX
    /// and X by their P gain (slope 2: the register's top, 254 or 16383).
    #[arg(long, default_value_t = 2.0, value_parser = crate::common::positive)]
    pub compliance_slope: f64,
    /// Over a bus (--port), the slope of the two RX ankles a direction ramps, RX units
    /// (default 32, the factory value): goal positions are whole counts, and a stiff
    /// ankle takes each count as a jolt that tips the robot early. The other servos,
    /// and MX and X ankles (counts a third as large), hold at --compliance-slope.
    #[arg(long, default_value_t = twinloop_loop::tipover_bus::ANKLE_SLOPE as f64, value_parser = crate::common::positive)]
    pub ankle_slope: f64,
    /// Ramp speed of the second run's slow final approach, deg/s: each direction is run
    /// twice, the second time up to half a degree before the first tip and then at this
    /// speed, so the tip is seen with less lag. 0.005 or more.
    #[arg(long, default_value_t = 0.05, value_parser = creep_ramp)]
    pub slow_ramp: f64,
    /// Over a bus: creeping approaches per direction. With 2 (the default) the two are
    /// averaged when they tip within 0.2 deg of each other (0.6 with --onset-average
    /// 0), and a third is made when they do not (a jolt or a stalled cycle spoils a
    /// creep now and then); the closest two count. 1: a single creep.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=5))]
    pub creeps: u32,
    /// Over a bus: the goal positions sent to the joints a lean turns. dithered
    /// (sigma-delta: the counts flip around the ramp so that their running mean is
    /// the ramp) lets the robot tip where its lean takes it, between two counts;
    /// staircase (whole counts) tips it on the jolt of a count step, a count early
    /// or late from run to run (docs/adaptation.md)
    #[arg(long, value_enum, default_value_t)]
    pub goal_counts: crate::bus_args::GoalCounts,
    /// Leave the servos as they are instead of stiffening them (every servo is made
    /// stiff through the servo catalogue, and put back afterwards; a servo model with
    /// no known way to stiffen otherwise stops the run before anything moves). The
    /// output then says the servos were soft: the angles include their give.
    #[arg(long)]
    pub soft_servos: bool,
    /// Over a bus: read each creep's tip as the mean of the ankle readings (and the
    /// posture, the feet's roll and the lean) over this long up to the onset, s of
    /// robot time. The ankles flip between two counts as the robot rocks on its sole
    /// edges, and one sample reads a count early or late from run to run; 0: the
    /// onset's sample alone
    #[arg(long, default_value_t = twinloop_loop::tipover_bus::ONSET_AVERAGE_S, value_parser = crate::common::non_negative)]
    pub onset_average: f64,
    /// Quantise the ankle readings like Dynamixel RX encoders (1024 counts over 300 deg).
    #[arg(long)]
    pub encoders: bool,
    /// In the simulator: servo model parameters (`identify servo --out`;
    /// docs/servo-models.md) in place of the datasheet servos: FILE.toml for every
    /// joint whose servo is of its type, or JOINT=FILE.toml for one, repeatable
    #[arg(long, value_name = "[JOINT=]FILE.toml")]
    pub servo_params: Vec<String>,
}

/// Parse `KG@LINK:X,Y,Z`.
pub fn run(a: &TipoverArgs) -> CliResult {
    if a.bus.port.is_some() || a.map.is_some() {
        if !a.servo_params.is_empty() {
            return Err(CliError::new(
                "--servo-params sets the simulator's servos: over a bus, give it to `twinloop serve`",
            ));
        }
        if !a.added.add_mass.is_empty() {
            return Err(CliError::new(
                "--add-mass changes the simulated robot; over a bus the robot is what it is (give it to `twinloop serve`)",
            ));
        }
        return bus::run(a);
    }
    let Some(spec) = a.robot.as_deref() else {
        return Err(CliError::new(
            "give --robot ROBOT (the simulator) or --port PORT --map MAP (a robot over its bus)",
        ));
    };
    let (mut robot, _) = load_description(spec)?;
    hinges_only(&robot, spec, "the tip-over experiment")?;
    a.added.apply(&mut robot)?;
    let opts = StudyOptions {
        ramp_deg_per_s: a.ramp,
        dynamixel_encoders: a.encoders,
        slow_ramp_deg_per_s: a.slow_ramp,
        compliance_units: Some((a.compliance_slope, 0.0)),
        servo_params: twinloop_sim::servo_params::ServoParamsSet::read(
            &a.servo_params,
            "--servo-params",
        )?,
        ..Default::default()
    };
    eprintln!("running the four tip-overs in the simulator ...");
    // One step per simulated tip-over (each direction's ramp, then its creep).
    let bar = crate::progress::steps(STUDY_RUNS);
    let mut started = 0;
    let r = run_study_with_progress(&robot, &opts, &mut |what| {
        if started > 0 {
            bar.inc(1);
        }
        started += 1;
        bar.set_message(what.to_string());
    });
    bar.finish_and_clear();
    let r = r?;
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
    for (name, d) in [
        ("forward", &r.forward),
        ("backward", &r.backward),
        ("left", &r.left),
        ("right", &r.right),
    ] {
        for note in [&d.static_note, &d.rigid_static_note].into_iter().flatten() {
            let _ = writeln!(s, "  {name}: {note}");
        }
    }
    let f = |c: [f64; 3]| format!("[{:+.4}, {:+.4}, {:+.4}]", c[0], c[1], c[2]);
    let _ = writeln!(
        s,
        "CoM relative to the ankle midpoint (m; x forward, y left, z up):"
    );
    // Over a bus there is no truth: the reference is the model the robot was
    // described by, and the distances say how far the robot is from it.
    let (reference, apart) = match r.protocol {
        None => ("true        ", "off by"),
        Some(_) => ("model (prior)", "from the model by"),
    };
    let _ = writeln!(s, "  {reference} {}", f(r.com.truth));
    let _ = writeln!(
        s,
        "  exact method  {}  ({apart} {:.1} mm)",
        f(r.com.exact_method),
        r.com.exact_error * 1e3
    );
    let _ = writeln!(
        s,
        "  seed method   {}  ({apart} {:.1} mm; constants: {})",
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

/// `experiment tipover --port --map`: the experiment over the bus, printed like the
/// simulator's when all four directions ran.
mod bus {
    use super::{TipoverArgs, summary};
    use crate::bus_args::tipover_on_bus;
    use crate::cmd_experiment::bus::resolve;
    use crate::common::emit;
    use crate::error::CliError;
    use crate::error::{CliResult, Outcome};
    use twinloop_loop::BusPlan;
    use twinloop_loop::tipover_bus::{BusOutcome, BusReport};

    pub fn run(a: &TipoverArgs) -> CliResult {
        let (_, _, model_spec) = resolve(
            a.map.as_deref(),
            &a.bus,
            a.robot.as_deref(),
            "the lean signs",
        )?;
        let map = a.map.clone().unwrap_or_default();
        let plan = BusPlan {
            model_spec,
            map,
            port: a.bus.bus_port(),
            record: a.record.clone(),
            yes: a.yes,
            directions: twinloop_ident::tipover_bus::parse_directions(&a.directions)
                .map_err(|e| CliError::new(format!("--directions: {e}")))?,
            ramp: a.ramp,
            slow_ramp: a.slow_ramp,
            compliance_slope: a.compliance_slope.round() as i32,
            ankle_slope: a.ankle_slope.round() as i32,
            soft_servos: a.soft_servos,
            creeps: a.creeps as usize,
            first_tips: None,
            dither: a.goal_counts.dithered(),
            onset_average_s: a.onset_average,
            clock_rate: a.realtime_factor,
            verbose: true,
        };
        let run = tipover_on_bus(&plan)?;
        match run.outcome {
            BusOutcome::Study(r) => emit(
                &format!(
                    "over {}\n{}{}",
                    run.port,
                    soft_line(plan.soft_servos),
                    summary(&r)
                ),
                a.json.as_ref(),
                &*r,
            )?,
            BusOutcome::Partial(r) => emit(
                &format!("{}{}", soft_line(r.soft_servos), partial_summary(&r)),
                a.json.as_ref(),
                &*r,
            )?,
        }
        Ok(Outcome::Ok)
    }

    /// The first line of the output when the servos were left soft.
    fn soft_line(soft: bool) -> String {
        if soft {
            format!("{}\n", twinloop_ident::adapt::SOFT_SERVOS_NOTE)
        } else {
            String::new()
        }
    }

    fn partial_summary(r: &BusReport) -> String {
        let mut text = format!(
            "{}: tip-over over {} (ankle angles from the standing pose, deg)\n  direction  commanded  measured  time(s)\n",
            r.robot, r.port
        );
        for (name, d) in [
            ("forward", &r.forward),
            ("backward", &r.backward),
            ("left", &r.left),
            ("right", &r.right),
        ] {
            if let Some(d) = d {
                text.push_str(&format!(
                    "  {name:<9}  {:>9.3}  {:>8.3}  {:>7.2}\n",
                    d.commanded_deg, d.measured_deg, d.time_s
                ));
            }
        }
        text
    }
}
