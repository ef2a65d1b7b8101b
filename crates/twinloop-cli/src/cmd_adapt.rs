//! `twinloop adapt`: the model adapted to a hardware change from the tip-over angles
//! (seed 000 sections III and V.B); the algorithm is `twinloop_ident::adapt`. With
//! `--method ann` the three-mass LIPM comes from the seed's ANN (section V.C), which
//! `twinloop adapt train` trains (`twinloop_ident::ann_adapt`).

use crate::common::hinges_only;
use crate::common::{JSON_HELP, ROBOT_HELP, emit, load_description};
use crate::error::{CliError, CliResult, Outcome};
use clap::{Args, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};
use twinloop_ident::adapt::{AdaptOptions, check, html_report};
use twinloop_ident::ann::TrainOptions;
use twinloop_ident::ann_adapt::{
    AnnModel, AnnTrainOptions, TrainReport, adapt_ann, train_ann, train_ann_on,
};
use twinloop_ident::ann_data::{Change, DataOptions, check_against_simulation};
use twinloop_ident::tipover_study::{StudyOptions, StudyReport};

#[derive(Args, Debug)]
#[command(
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    override_usage = "twinloop adapt [OPTIONS] --robot <ROBOT> --tipover <TIP.json>\n       \
                      (to train the ANN: adapt train --help)"
)]
pub struct AdaptArgs {
    #[command(subcommand)]
    pub command: Option<AdaptCommand>,
    #[arg(long, value_name = "ROBOT", help = ROBOT_HELP, required = true)]
    pub robot: Option<String>,
    /// The tip-over experiment's JSON (`twinloop experiment tipover --json`). With
    /// --port, where the tip-over measured in place is written.
    #[arg(long, value_name = "TIP.json", required_unless_present = "port")]
    pub tipover: Option<PathBuf>,
    /// Run the tip-over in place on the robot on this bus first (as `experiment
    /// tipover --port`: it asks before moving a robot on a serial port), then adapt
    /// to what it measured; the bus flags mean what they mean for `twinloop link`.
    #[command(flatten)]
    pub bus: crate::bus_args::PortArgs,
    /// With --port: the servo mapping (builtin:km20 or a mapping TOML; it must have the
    /// IMU [[board]]).
    #[arg(long, value_name = "MAP", requires = "port")]
    pub map: Option<String>,
    /// With --port: every cycle read, as a CSV written row by row (an .mcap: ROS 2
    /// messages, as `experiment tipover --record`).
    #[arg(long, value_name = "FILE.csv|FILE.mcap", requires = "port")]
    pub record: Option<PathBuf>,
    /// With --port on a serial device: do not ask before the first lean.
    #[arg(long, requires = "port")]
    pub yes: bool,
    /// Leave the servos as they are instead of stiffening them (every servo is made
    /// stiff through the servo catalogue, and put back afterwards; a servo model with
    /// no known way to stiffen otherwise stops the run before anything moves). The
    /// output then says the servos were soft: the angles include their give.
    #[arg(long, requires = "port")]
    pub soft_servos: bool,
    /// With --port, a simulated robot served faster than real time: its factor.
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = crate::bounds::realtime_factor)]
    pub realtime_factor: f64,
    /// exact: the exact inversion (an added point mass, the adapted URDF); ann: the
    /// three-mass LIPM from the network of `twinloop adapt train` (--net; needs --where).
    #[arg(long, value_enum, default_value_t = Method::Exact)]
    pub method: Method,
    /// The network of `twinloop adapt train --out` (with --method ann).
    #[arg(long, value_name = "NET.json")]
    pub net: Option<PathBuf>,
    /// The changed robot's total mass, kg: the added mass is this minus the prior's.
    #[arg(long, value_name = "KG", value_parser = crate::common::positive)]
    pub total_mass: Option<f64>,
    /// The link the mass was added to (with --total-mass: the host, and the part is
    /// kept within 1 cm of that link's collision outline).
    #[arg(long = "where", value_name = "LINK")]
    pub host: Option<String>,
    /// Merge the mass into the host link's inertial instead of a fixed `added_mass` link.
    #[arg(long)]
    pub merge: bool,
    /// Resolution of the measured angles, deg (default: for a tip-over measured over a
    /// bus, half a count of its mapping's ankle servo and the creep's step in one
    /// host cycle, 0.15 deg on RX and 0.05 on MX and X; else 0.05).
    #[arg(long, value_name = "DEG", value_parser = crate::common::positive)]
    pub resolution: Option<f64>,
    /// The adapted URDF to write.
    #[arg(long, value_name = "ADAPTED.urdf")]
    pub out: Option<PathBuf>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// HTML report to write.
    #[arg(long, value_name = "FILE.html")]
    pub report: Option<PathBuf>,
    /// One MCAP of the result (not written when a check fails, as --out): per direction (forward, backward,
    /// left, right; one a second) the measured fall angle (fall_deg) and the prior's
    /// and the adapted model's static fall angles (prior.fall_deg, adapted.fall_deg),
    /// the adapted URDF attached, the command line, version and inputs' SHA-256.
    #[arg(long, value_name = "RESULT.mcap")]
    pub mcap: Option<PathBuf>,
    /// Run the simulated tip-over study on the adapted model and compare its angles.
    #[arg(long)]
    pub check: bool,
    /// For a tip-over measured over a bus (its JSON keeps the protocol, as
    /// `experiment tipover --port` and `--port` here write it): passes of adapting to
    /// the protocol's bias. Each pass runs the same protocol on the adapted model,
    /// simulated in lockstep with a host at the robot run's cycle, and adapts again
    /// to the measured angles less what that protocol read past the model's static
    /// angles (about 1 s per pass). 0: adapt to the angles as measured. A tip-over
    /// from the simulator has no protocol bias to take off
    #[arg(long, default_value_t = 3, value_name = "N", value_parser = clap::value_parser!(u64).range(0..=5))]
    pub protocol_passes: u64,
    /// The passes replay the protocol on a floor that sinks this far under the
    /// robot's weight, m (`serve --ground-sink`'s meaning). Default: the floor on
    /// which the adapted model tips sideways as the robot did, found by
    /// up to 4 replays (a floor that gives lets a robot tip degrees earlier)
    #[arg(long, value_name = "M", value_parser = crate::common::positive)]
    pub ground_sink: Option<f64>,
    /// The lean the robot did (`twinloop experiment lean --out`): replayed on the prior
    /// and the adapted model, the ankle and knee torques compared (seed 001 section F).
    #[arg(long, value_name = "LEAN.csv")]
    pub lean: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Method {
    Exact,
    Ann,
}

#[derive(Subcommand, Debug)]
pub enum AdaptCommand {
    /// Train the seed's ANN (seed 000 V.C) on simulated changes of a robot
    ///
    /// Draws --samples random changes (a point mass of 0.05-0.5 kg anywhere in a link's
    /// collision outline), finds each changed robot's fall angles by the static tipping
    /// analysis (its CoM over the sole edge; --check-sim N runs the full simulated
    /// tip-over on N of them to compare), on all cores, splits them 70/15/15 into
    /// training, testing and validation sets, trains a 5-10-5 perceptron (tanh,
    /// back-propagation with Adam) from the forward and backward fall angles, the added
    /// mass and the body part to the three-mass LIPM's positions, and scores it beside the
    /// seed's manual method and the exact inversion on the held-out changes.
    ///
    /// Example:
    ///   twinloop adapt train --robot builtin:km20 --samples 10000 --seed 1 --out net.json \
    ///       --json train.json --report train.html
    ///
    /// Output: NET.json (layers, weights, input and output scalings, the body parts), the
    /// JSON (split, learning curve, errors per method and set: three-mass positions, vCoM
    /// and fall angles, mean / 95th percentile / largest) and the report (seed Tables
    /// VI-VII style).
    #[command(verbatim_doc_comment)]
    Train(Box<TrainArgs>),
}

#[derive(Args, Debug)]
pub struct TrainArgs {
    #[arg(long, value_name = "ROBOT", help = ROBOT_HELP)]
    pub robot: String,
    /// Random changes to draw.
    #[arg(long, default_value_t = 10_000, value_name = "N", value_parser = crate::bounds::count)]
    pub samples: usize,
    /// Seed of every random draw (changes, noise, weights, batch order).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The trained network.
    #[arg(long, value_name = "NET.json")]
    pub out: PathBuf,
    /// One-sigma noise added to each fall angle, deg.
    #[arg(long, default_value_t = 0.05, value_name = "DEG", value_parser = crate::common::non_negative)]
    pub noise: f64,
    /// Smallest and largest added mass, kg.
    #[arg(long, default_value = "0.05,0.5", value_name = "LO,HI")]
    pub mass_range: String,
    /// The seed's inputs only (fall angles and body part): no added mass input.
    #[arg(long)]
    pub seed_inputs: bool,
    /// Most training epochs.
    #[arg(long, default_value_t = 1000, value_name = "N", value_parser = crate::bounds::count)]
    pub epochs: usize,
    /// Worker threads (0: all cores).
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub threads: usize,
    /// Trainings from different initial weights (in parallel); the one whose models
    /// fall at the testing set's angles best is kept.
    #[arg(long, default_value_t = 4, value_name = "N")]
    pub restarts: usize,
    /// Run the full simulated tip-over on the first N validation changes and compare its
    /// angles with the static route's.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub check_sim: usize,
    /// Make the changes' tip-overs as Ray tasks on the cluster at ADDRESS ("auto",
    /// "ray://head:10001", or "local" for a Ray started here) through the Python
    /// package (`python3 -m twinloop.adapt_train`; TWINLOOP_PYTHON names another
    /// interpreter), then train here as without it: the same samples, the same network.
    #[arg(long, value_name = "ADDRESS")]
    pub ray: Option<String>,
    /// With --ray local: the CPUs of the local Ray (default: all).
    #[arg(long, value_name = "N", requires = "ray", value_parser = crate::bounds::count)]
    pub ray_cpus: Option<usize>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// HTML report to write.
    #[arg(long, value_name = "FILE.html")]
    pub report: Option<PathBuf>,
    /// The longest the training may take, s: its time is estimated before it starts
    /// (from a few changes tipped here) and said on stderr; more than this is refused.
    #[arg(long, default_value_t = crate::bounds::MAX_WALL_S, value_name = "S",
          value_parser = crate::bounds::max_time)]
    pub max_time: f64,
}

fn read_tip(path: &Path) -> Result<StudyReport, CliError> {
    let text = twinloop_io::input::read_to_string(path)
        .map_err(|e| CliError::io(path, e).context("--tipover"))?;
    let tip: StudyReport = serde_json::from_str(&text).map_err(|e| {
        CliError::new(twinloop_io::input::wrong_kind(
            &path.display().to_string(),
            &text,
            "a tip-over JSON (what `twinloop experiment tipover --json FILE` writes)",
            &e.to_string(),
        ))
        .context("--tipover")
    })?;
    tip.check_measured()
        .map_err(|e| CliError::from(e.in_file(path)).context("--tipover"))?;
    Ok(tip)
}

/// Refuse a tip-over measured on another robot: its angles say nothing of this
/// one's centre of mass (the file's `robot` is the description's name).
fn same_robot(tip: &StudyReport, name: &str, spec: &str, path: &Path) -> Result<(), CliError> {
    if tip.robot.is_empty() || tip.robot == name {
        return Ok(());
    }
    Err(CliError::new(format!(
        "{}: field `robot`: this tip-over was measured on {:?}, not on {spec} ({name:?}); \
         adapt a robot with its own tip-over",
        path.display(),
        tip.robot
    ))
    .context("--tipover"))
}

/// The tip-over run in place over the bus (`--port`), written to `out` if given.
fn tip_in_place(a: &AdaptArgs, robot: &str, out: Option<&Path>) -> Result<StudyReport, CliError> {
    use twinloop_loop::tipover_bus::BusOutcome;
    let Some(map) = a.map.clone() else {
        return Err(CliError::new(
            "--port needs --map MAP (the robot's servos and IMU board)",
        ));
    };
    let plan = twinloop_loop::BusPlan {
        record: a.record.clone(),
        yes: a.yes,
        soft_servos: a.soft_servos,
        clock_rate: a.realtime_factor,
        ..twinloop_loop::BusPlan::standard(robot, &map, a.bus.bus_port())
    };
    let run = crate::bus_args::tipover_on_bus(&plan)?;
    let BusOutcome::Study(study) = run.outcome else {
        return Err(CliError::new(
            "the tip-over did not run all four directions",
        ));
    };
    if let Some(path) = out {
        let text =
            serde_json::to_string_pretty(&*study).map_err(|e| CliError::new(e.to_string()))?;
        twinloop_io::output::write_atomic(path, text + "\n")
            .map_err(|e| CliError::from(e).context("--tipover"))?;
    }
    Ok(*study)
}

/// With --record and --report: the tip-over in 3D (`replay.html` beside the report),
/// the recording with the adapted (--out) and prior models as ghosts. A replay that
/// cannot be made is a warning.
fn replay_3d(
    a: &AdaptArgs,
    report: &Path,
    adapted: bool,
    files: &mut Vec<String>,
) -> Option<PathBuf> {
    let (Some(record), Some(robot)) = (&a.record, &a.robot) else {
        return None;
    };
    let urdf = a.out.as_deref().filter(|_| adapted);
    let out = report.with_file_name("replay.html");
    crate::replay3d::replay_for_report(record, robot, urdf, &out, files)
}

pub fn run(a: AdaptArgs) -> CliResult {
    if let Some(AdaptCommand::Train(t)) = a.command {
        return run_train(*t);
    }
    let Some(robot) = &a.robot else {
        return Err(CliError::new("adapt needs --robot"));
    };
    let (prior, _) = load_description(robot)?;
    hinges_only(&prior, robot, "adaptation")?;
    if let Some(kg) = a.total_mass {
        crate::units::total_mass("--total-mass", kg, &prior)?;
    }
    let tip = the_tipover(&a, robot, &prior)?;
    if a.method == Method::Ann {
        return run_ann(&a, &prior, &tip);
    }
    if a.total_mass.is_none()
        && a.host.is_none()
        && (a.out.is_some() || a.mcap.is_some() || a.check)
    {
        return Err(CliError::new(
            "the tip-over angles fix only m_a (p - c_meas) = M0 (c_meas - c0): give --total-mass KG or --where LINK to place the mass",
        ));
    }
    let opts = AdaptOptions {
        total_mass: a.total_mass,
        host: a.host.clone(),
        merge: a.merge,
        angle_resolution_deg: Some(twinloop_loop::bus_plan::tipover_resolution_deg(
            a.resolution,
            &tip,
        )?),
        protocol_bias_deg: None,
    };
    use twinloop_loop::adapt_to_protocol;
    use twinloop_loop::protocol_bias::{REPLAY_GROUND_SINK, Replay};
    let replay_options =
        twinloop_loop::protocol_bias::replay_options(a.ground_sink.unwrap_or(REPLAY_GROUND_SINK));
    let replay = Replay {
        model_spec: robot,
        host: &prior,
        passes: a.protocol_passes as usize,
        options: &replay_options,
        fit_floor: a.ground_sink.is_none(),
        other_places: true,
    };
    let (mut adapted, _) = adapt_to_protocol(
        &prior,
        &tip,
        &opts,
        &replay,
        &mut |line| eprintln!("{line}"),
        &|e| twinloop_loop::LoopError::from(where_option(e)),
    )?;
    if a.check {
        check(&mut adapted, &StudyOptions::default()).map_err(where_flag)?;
    }
    let lean = match &a.lean {
        Some(path) => {
            let table = crate::common::read_table(path).map_err(|e| e.context("--lean"))?;
            Some(
                twinloop_ident::adapt::lean_check(&mut adapted, &prior, &table)
                    .map_err(|e| CliError::from(e).context(format!("--lean {}", path.display())))?,
            )
        }
        None => None,
    };
    let failed = adapted.report.failed_checks().next().is_some();
    if !failed {
        write_model_outputs(&a, &mut adapted, &prior, &tip, lean.as_ref())?;
    }
    if let Some(p) = &a.report {
        let replay = replay_3d(&a, p, adapted.robot.is_some(), &mut adapted.report.files);
        adapted.report.files.push(p.display().to_string());
        let mut page = html_report(&adapted.report);
        if let Some(replay) = &replay {
            crate::replay3d::link_replay(&mut page, replay);
        }
        page.write(p)
            .map_err(|e| CliError::new(e.to_string()).context("--report"))?;
    }
    let r = &adapted.report;
    let t = summary_text(r, a.out.as_deref());
    emit(&t, a.json.as_ref(), r)?;
    Ok(if failed {
        Outcome::Problems
    } else {
        Outcome::Ok
    })
}

/// The tip-over to adapt to: measured now over `--port`, or read from `--tipover`
/// (checked to be this robot's, its onset joints the description's).
fn the_tipover(
    a: &AdaptArgs,
    robot: &str,
    prior: &twinloop_description::Description,
) -> Result<StudyReport, CliError> {
    match (&a.bus.port, &a.tipover) {
        (Some(_), out) => tip_in_place(a, robot, out.as_deref()),
        (None, Some(path)) => {
            let tip = read_tip(path)?;
            same_robot(&tip, &prior.name, robot, path)?;
            tip.check_onset_joints(prior)
                .map_err(|e| CliError::from(e.in_file(path)).context("--tipover"))?;
            Ok(tip)
        }
        (None, None) => Err(CliError::new("adapt needs --tipover or --port")),
    }
}

/// `--out` (the adapted URDF) and `--mcap`, written only when every check passed.
fn write_model_outputs(
    a: &AdaptArgs,
    adapted: &mut twinloop_ident::adapt::Adapted,
    prior: &twinloop_description::Description,
    tip: &StudyReport,
    lean: Option<&twinloop_experiments::LeanAdaptationCheck>,
) -> Result<(), CliError> {
    if let (Some(out), Some(robot)) = (&a.out, &adapted.robot) {
        twinloop_description::urdf::write_file(robot, out)
            .map_err(|e| CliError::new(format!("{}: {e}", out.display())).context("--out"))?;
        adapted.report.files.push(out.display().to_string());
    }
    if let (Some(path), Some(robot)) = (&a.mcap, &adapted.robot) {
        write_result_mcap(path, a, (prior, robot), tip, lean)?;
        adapted.report.files.push(path.display().to_string());
    }
    Ok(())
}

/// `--mcap`: the measured fall angles (less no bias: as the tip-over file gives them)
/// beside each model's static fall angles, one direction a second; with `--lean`,
/// then the lean ([`lean_part`]).
fn write_result_mcap(
    path: &Path,
    a: &AdaptArgs,
    (prior, adapted): (
        &twinloop_description::Description,
        &twinloop_description::Description,
    ),
    tip: &StudyReport,
    lean: Option<&twinloop_experiments::LeanAdaptationCheck>,
) -> Result<(), CliError> {
    let before = twinloop_ident::adapt::static_fall_angles(prior, tip)?;
    let after = twinloop_ident::adapt::static_fall_angles(adapted, tip)?;
    let cols = ["fall_deg", "prior.fall_deg", "adapted.fall_deg"].map(str::to_string);
    let mut table = twinloop_io::Table::new(
        std::iter::once("t".to_string())
            .chain(cols.iter().cloned())
            .collect(),
    );
    for (k, d) in twinloop_experiments::tipover::Direction::ALL
        .into_iter()
        .enumerate()
    {
        table.rows.push(vec![
            k as f64,
            tip.direction(d).measured_deg,
            before[k],
            after[k],
        ]);
    }
    let mut inputs = vec![a.robot.clone().unwrap_or_default()];
    inputs.extend(a.tipover.iter().map(|p| p.display().to_string()));
    inputs.extend(a.lean.iter().map(|p| p.display().to_string()));
    let [m, p, d] = cols;
    let result = crate::result_mcap::ResultLog {
        table,
        measured: vec![m],
        predicted: crate::result_mcap::prior_and_adapted(vec![p], vec![d]),
        robot: Some(adapted),
        robot_file: "adapted.urdf",
        inputs,
        files: Vec::new(),
        parts: lean.map(lean_part).into_iter().collect(),
    };
    crate::result_mcap::write(path, "adapt", &result)
}

/// The lean in `adapt --mcap`, its clock moved so that its first row would be a
/// second after the last fall angle (t = 4 s): at each of the robot's samples both
/// replays cover, the robot's torques (and angles where the replays have them too)
/// on `/lean/measured` (`tau.<joint>`, `q.<joint>`), and each model's replay,
/// shifted and interpolated there as the comparison does, on `/lean/prior` and
/// `/lean/adapted` (`prior.` and `adapted.` + the names): so each joint's RMS of a
/// model's torques from the robot's is the lean check's `before_rms`/`after_rms`.
fn lean_part(c: &twinloop_experiments::LeanAdaptationCheck) -> crate::result_mcap::ResultPart {
    use twinloop_experiments::lean_validation::resample_at;
    let robot = &c.robot;
    let (range_b, before) = resample_at(&c.replays[0], c.before.shift_s, &robot.t);
    let (range_a, after) = resample_at(&c.replays[1], c.after.shift_s, &robot.t);
    let (start, end) = (
        range_b.start.max(range_a.start),
        range_b.end.min(range_a.end),
    );
    // Both replays record the robot's joints in its order (simulate_replay).
    let n = robot.joints.len();
    let angles: Vec<usize> = (0..n)
        .filter(|&k| !robot.q[k].is_empty() && !before.q[k].is_empty() && !after.q[k].is_empty())
        .collect();
    let mut measured: Vec<String> = robot.joints.iter().map(|j| format!("tau.{j}")).collect();
    measured.extend(angles.iter().map(|&k| format!("q.{}", robot.joints[k])));
    let (prior, adapted, mut table) = crate::result_mcap::comparison_columns(&measured, &measured);
    let t0 = robot.t.first().copied().unwrap_or(0.0);
    for i in start..end.max(start) {
        let mut row = vec![4.0 + robot.t[i] - t0];
        row.extend(robot.tau.iter().map(|y| y[i]));
        row.extend(angles.iter().map(|&k| robot.q[k][i]));
        for (sim, range) in [(&before, &range_b), (&after, &range_a)] {
            let r = i - range.start;
            row.extend(sim.tau.iter().map(|y| y[r]));
            row.extend(angles.iter().map(|&k| sim.q[k][r]));
        }
        table.rows.push(row);
    }
    let topic = |t: &str, columns: Vec<String>| twinloop_logs::ArrayTopic {
        topic: t.into(),
        columns,
    };
    crate::result_mcap::ResultPart {
        table,
        topics: vec![
            topic("/lean/measured", measured),
            topic("/lean/prior", prior),
            topic("/lean/adapted", adapted),
        ],
    }
}

/// What the terminal says of an adaptation: the angles, the CoMs, the part, the
/// checks and the files written.
fn summary_text(r: &twinloop_ident::adapt::AdaptReport, out: Option<&Path>) -> String {
    let mm = |v: [f64; 3]| {
        format!(
            "[{:.1}, {:.1}, {:.1}] mm",
            v[0] * 1e3,
            v[1] * 1e3,
            v[2] * 1e3
        )
    };
    let mut t = String::new();
    if r.soft_servos {
        t += &format!("{}\n", twinloop_ident::adapt::SOFT_SERVOS_NOTE);
    }
    t += &format!(
        "measured fall angles {} deg (forward, backward, left, right)\n\
         prior CoM {}, measured CoM {} (sigma {})\n",
        r.measured_deg
            .iter()
            .map(|a| format!("{a:.2}"))
            .collect::<Vec<_>>()
            .join(" / "),
        mm(r.prior_com),
        mm(r.measured_com),
        mm(r.measured_com_sigma)
    );
    if let Some(c) = &r.com_resolution {
        t += &format!(
            "CoM resolution {} ({:.1} mm at worst): how far the CoM moves with every angle \
             within {:.3} deg of its reading{}\n",
            mm(c.axes_m),
            c.worst_m * 1e3,
            r.angle_resolution_deg,
            match (&c.angles, &c.floor) {
                (Some(a), Some(f)) => format!(
                    " and the floor fitted from them with it (angles {:.1} mm, floor {:.1} mm: \
                     the floor known to {:.3} mm)",
                    a.worst_m * 1e3,
                    f.share.worst_m * 1e3,
                    f.resolution_m * 1e3
                ),
                _ => String::new(),
            }
        );
    }
    match &r.added {
        Some(m) => {
            t += &format!(
                "{} {:.3} kg on {} at {} in its frame ({} standing; sigma {}); {} iterations\n",
                if m.mass >= 0.0 { "added" } else { "taken off:" },
                m.mass.abs(),
                m.host,
                mm(m.position_host),
                mm(m.position),
                mm(m.position_sigma),
                r.iterations
            );
        }
        None => {
            t += &format!(
                "m_a (p - c_meas) = [{:.1}, {:.1}, {:.1}] kg mm: give --total-mass or --where to place it\n",
                r.family_moment[0] * 1e3,
                r.family_moment[1] * 1e3,
                r.family_moment[2] * 1e3
            );
        }
    }
    if let Some(c) = r.check_deg {
        t += &crate::adapt_text::check_angles_text(&c, &r.measured_deg);
    }
    for l in &r.lean {
        t += &format!(
            "lean, {}: robot - model torque RMS {:.4} N m before, {:.4} after\n",
            l.joint, l.before_rms, l.after_rms
        );
    }
    t += &crate::adapt_text::checks_text(r, out);
    for f in &r.files {
        t += &format!("wrote {f}\n");
    }
    t
}

/// `adapt --method ann`.
fn run_ann(
    a: &AdaptArgs,
    prior: &twinloop_description::Description,
    tip: &StudyReport,
) -> CliResult {
    if a.out.is_some() || a.check || a.merge || a.report.is_some() {
        return Err(CliError::new(
            "--method ann gives the three-mass LIPM, not a URDF: --out, --merge, --check and --report are for --method exact",
        ));
    }
    let net = a
        .net
        .as_ref()
        .ok_or_else(|| CliError::new("--method ann needs the network: --net NET.json"))?;
    let host = a.host.as_ref().ok_or_else(|| {
        CliError::new("--method ann needs --where LINK: the general location of the change is the network's input")
    })?;
    let text = twinloop_io::input::read_to_string(net)
        .map_err(|e| CliError::io(net, e).context("--net"))?;
    let model = AnnModel::from_json(&text)
        .map_err(|e| CliError::new(format!("{}: {e}", net.display())).context("--net"))?;
    let r = adapt_ann(prior, tip, &model, host, a.total_mass).map_err(where_flag)?;
    let mm = |v: [f64; 3]| {
        format!(
            "[{:.1}, {:.1}, {:.1}] mm",
            v[0] * 1e3,
            v[1] * 1e3,
            v[2] * 1e3
        )
    };
    let mut t = format!(
        "measured fall angles {:.2} / {:.2} deg (forward, backward), change on {} (part {})
",
        r.measured_deg[0], r.measured_deg[1], r.host, r.part
    );
    for (k, name) in ["left leg", "right leg", "hip"].iter().enumerate() {
        t += &format!(
            "{name:9} {:.3} kg at {} (prior {:.3} kg at {})
",
            r.adapted.masses[k],
            mm(r.adapted.positions[k]),
            r.prior.masses[k],
            mm(r.prior.positions[k])
        );
    }
    t += &format!(
        "vCoM {}; the three-mass model's fall angles {:.2} / {:.2} deg
",
        mm(r.adapted_com),
        r.adapted_fall_deg[0],
        r.adapted_fall_deg[1]
    );
    emit(&t, a.json.as_ref(), &r)?;
    Ok(Outcome::Ok)
}

/// `--mass-range LO,HI` in kg: positive, rising, and not grams on `prior`.
fn mass_range(s: &str, prior: &twinloop_description::Description) -> Result<(f64, f64), CliError> {
    let bad = |why: &str| CliError::new(format!("--mass-range {s}: {why}"));
    let expected = "expected LO,HI in kg, e.g. 0.05,0.5";
    let (lo, hi) = s.split_once(',').ok_or_else(|| bad(expected))?;
    let lo: f64 = lo.trim().parse().map_err(|_| bad(expected))?;
    let hi: f64 = hi.trim().parse().map_err(|_| bad(expected))?;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0) {
        return Err(bad("the masses must be finite numbers > 0 kg"));
    }
    if lo > hi {
        return Err(bad(&format!(
            "LO is above HI; write {},{}",
            crate::common::num(hi),
            crate::common::num(lo)
        )));
    }
    crate::units::added_mass(hi, prior.total_mass()).map_err(|why| bad(&why))?;
    Ok((lo, hi))
}

/// `adapt train`.
fn run_train(a: TrainArgs) -> CliResult {
    let (prior, _) = load_description(&a.robot)?;
    hinges_only(&prior, &a.robot, "adaptation")?;
    let opts = AnnTrainOptions {
        data: DataOptions {
            samples: a.samples,
            seed: a.seed,
            mass_range: mass_range(&a.mass_range, &prior)?,
            noise_deg: a.noise,
            threads: a.threads,
        },
        train: TrainOptions {
            max_epochs: a.epochs,
            seed: a.seed,
            ..Default::default()
        },
        mass_input: !a.seed_inputs,
        restarts: a.restarts,
    };
    if a.ray.is_none() {
        train_time(&prior, &opts, a.check_sim, a.max_time)?;
    }
    let (model, mut report) = match &a.ray {
        Some(address) => {
            let started = std::time::Instant::now();
            let samples = ray_training_set(&a, address)?;
            train_ann_on(&prior, &opts, samples, started.elapsed().as_secs_f64())
                .map_err(train_flags)?
        }
        None => {
            let bar = crate::progress::steps(a.samples);
            bar.set_message("changes tipped (static route)");
            let r = train_ann(&prior, &opts, &|done| bar.set_position(done as u64))
                .map_err(train_flags)?;
            bar.finish_and_clear();
            r
        }
    };
    if a.check_sim > 0 {
        let changes: Vec<Change> = validation_changes(&prior, &opts, a.check_sim)?;
        let bar = crate::progress::steps(changes.len());
        bar.set_message("simulated tip-over studies");
        report.sim_check = check_against_simulation(
            &prior,
            &changes,
            &StudyOptions::default(),
            a.threads,
            &|done| bar.set_position(done as u64),
        )?;
        bar.finish_and_clear();
    }
    twinloop_io::output::write_atomic(&a.out, model.to_json())
        .map_err(|e| CliError::from(e).context("--out"))?;
    report.files.push(a.out.display().to_string());
    if let Some(p) = &a.report {
        report.files.push(p.display().to_string());
        twinloop_ident::ann_report::train_html_report(&report)
            .write(p)
            .map_err(|e| CliError::new(e.to_string()).context("--report"))?;
    }
    emit(&train_text(&report), a.json.as_ref(), &report)?;
    Ok(Outcome::Ok)
}

/// CPU time of one training epoch of one sample, in units of one change tipped by the
/// static route: 7.6 us against 1.3 ms, measured on km20 (`adapt train --samples 1000`:
/// data 0.66 s, training 5.66 s for 700 x 533 epochs x 4 restarts, on 2 threads).
const EPOCH_PER_TIP: f64 = 0.0058;

/// One simulated tip-over study (`--check-sim`) in changes tipped by the static route
/// (about 2 s against 1.3 ms on km20).
const STUDY_PER_TIP: f64 = 1500.0;

/// `adapt train`'s time estimated before it starts, from a few changes tipped here
/// (the machine's speed and load included), and refused past `max_time`: a million
/// samples were hours of work with nothing said (issue 29). An upper bound: the
/// training may stop early.
fn train_time(
    prior: &twinloop_description::Description,
    opts: &AnnTrainOptions,
    check_sim: usize,
    max_time: f64,
) -> Result<(), CliError> {
    let threads = twinloop_ident::ann_data::worker_threads(opts.data.threads) as f64;
    let probe = opts.data.samples.min(8 * threads as usize);
    let started = std::time::Instant::now();
    twinloop_ident::ann_data::generate_range(prior, &opts.data, 0..probe, &|_| {})
        .map_err(train_flags)?;
    // CPU seconds of one change tipped.
    let tip = started.elapsed().as_secs_f64() * threads / probe as f64;
    let n = opts.data.samples as f64;
    let restarts = opts.restarts.max(1) as f64;
    let data = tip * n * 1.3 / threads;
    let training = tip * EPOCH_PER_TIP * 0.7 * n * opts.train.max_epochs as f64 * restarts
        / restarts.min(threads);
    let studies = tip * STUDY_PER_TIP * check_sim as f64 / threads;
    let made_of = format!(
        "{} changes at {} ms each on {} threads, up to {} epochs x {} restarts of training{}",
        opts.data.samples,
        crate::common::num((tip * 1e4).round() / 10.0),
        threads,
        opts.train.max_epochs,
        opts.restarts.max(1),
        if check_sim > 0 {
            format!(", {check_sim} simulated tip-overs")
        } else {
            String::new()
        }
    );
    let per_sample = (data + training) / n;
    let fit = ((max_time - studies) / per_sample).max(0.0);
    // Two significant digits, rounded down: a count to write, not a promise.
    let unit = 10f64.powf(fit.log10().floor() - 1.0).max(1.0);
    let fit = (fit / unit).floor() * unit;
    crate::bounds::within_time(
        "adapt train",
        data + training + studies,
        &made_of,
        max_time,
        &format!(
            "lower --samples (about {} fit), --epochs or --restarts",
            crate::common::num(fit)
        ),
    )
}

/// `--ray`: the training set made as Ray tasks by the Python package (its progress bar
/// on stderr), read back from the JSON it writes. Python is a subprocess, not linked
/// in: the command works without Python unless --ray is given.
fn ray_training_set(
    a: &TrainArgs,
    address: &str,
) -> Result<Vec<twinloop_ident::ann_data::Sample>, CliError> {
    let python = std::env::var("TWINLOOP_PYTHON").unwrap_or_else(|_| "python3".into());
    let out = std::env::temp_dir().join(format!("twinloop-train-{}.json", std::process::id()));
    let mut cmd = std::process::Command::new(&python);
    cmd.args(["-m", "twinloop.adapt_train", "--robot", &a.robot])
        .args([
            "--samples",
            &a.samples.to_string(),
            "--seed",
            &a.seed.to_string(),
        ])
        .args([
            "--mass-range",
            &a.mass_range,
            "--noise",
            &a.noise.to_string(),
        ])
        .args(["--ray", address])
        .arg("--out")
        .arg(&out);
    if let Some(n) = a.ray_cpus {
        cmd.args(["--ray-cpus", &n.to_string()]);
    }
    eprintln!(
        "making {} changes' tip-overs on Ray ({address}) ...",
        a.samples
    );
    let status = cmd.status().map_err(|e| {
        CliError::new(format!(
            "--ray: cannot run {python}: {e} (set TWINLOOP_PYTHON to a Python with the twinloop \
             package and ray: pip install ./python \"ray>=2.9\")"
        ))
    })?;
    let text = std::fs::read_to_string(&out);
    let _ = std::fs::remove_file(&out);
    if !status.success() {
        return Err(CliError::new(format!(
            "--ray: {python} -m twinloop.adapt_train failed ({status}); its message is above"
        )));
    }
    let text = text.map_err(|e| CliError::io(&out, e).context("--ray"))?;
    serde_json::from_str(&text).map_err(|e| {
        CliError::new(format!(
            "--ray: the samples from {python} -m twinloop.adapt_train: {e}"
        ))
    })
}

/// The validation set's first `n` changes (drawn again: each sample's draw depends
/// only on the seed and its index).
fn validation_changes(
    prior: &twinloop_description::Description,
    opts: &AnnTrainOptions,
    n: usize,
) -> Result<Vec<Change>, CliError> {
    let total = opts.data.samples;
    let first = total * 70 / 100 + total * 15 / 100;
    let range = first..(first + n).min(total);
    let (_, samples) = twinloop_ident::ann_data::generate_range(prior, &opts.data, range, &|_| {})?;
    Ok(samples.into_iter().map(|s| s.change).collect())
}

fn train_text(r: &TrainReport) -> String {
    let mut t = format!(
        "{} changes of {} ({}-{} kg, {} deg noise): training {}, testing {}, validation {}\n\
         data {:.2} s on {} threads, training {:.2} s (layout {:?}, {} restarts, kept {} at epoch {} of {}), evaluation {:.2} s\n",
        r.samples,
        r.robot,
        r.mass_range[0],
        r.mass_range[1],
        r.noise_deg,
        r.split[0],
        r.split[1],
        r.split[2],
        r.seconds[0],
        r.threads,
        r.seconds[1],
        r.layout,
        r.restart_fall_deg.len(),
        r.restart_kept + 1,
        r.log.best_epoch,
        r.log.train_mse.len(),
        r.seconds[2]
    );
    for set in [&r.testing, &r.validation] {
        t += &format!(
            "{} set: vCoM mm, fall angle deg, three-mass positions mm (mean / 95th percentile)\n",
            set.set
        );
        for m in &set.methods {
            t += &format!(
                "  {:44} vCoM {:6.2} / {:6.2}  fall {:6.3} / {:6.3}  positions {:6.2} / {:6.2}\n",
                m.method,
                m.com_mm[0],
                m.com_mm[1],
                m.fall_deg[0],
                m.fall_deg[1],
                m.position_mm[0],
                m.position_mm[1]
            );
        }
    }
    for c in &r.sim_check {
        let d = c.max_difference();
        t += &format!(
            "static vs simulated tip-over, {:.3} kg on {}: fw/bw {:.3} deg, left/right {:.3} deg\n",
            c.change.mass, c.change.link, d[0], d[1]
        );
    }
    for f in &r.files {
        t += &format!("wrote {f}\n");
    }
    t
}

/// The library's option names in `adapt train`'s flags.
fn train_flags(mut e: twinloop_ident::IdentError) -> CliError {
    e.option = e.option.map(|o| match o.as_str() {
        "noise_deg" => "noise".into(),
        _ => o,
    });
    CliError::from(e)
}

/// The library's `host` option is the `--where` flag (the seed's word for the general
/// location of the change; `where` cannot name a field).
fn where_flag(e: twinloop_ident::IdentError) -> CliError {
    CliError::from(where_option(e))
}

/// The adaptation's `host` option is `--where` here.
fn where_option(mut e: twinloop_ident::IdentError) -> twinloop_ident::IdentError {
    if e.option.as_deref() == Some("host") {
        e.option = Some("where".into());
    }
    e
}
