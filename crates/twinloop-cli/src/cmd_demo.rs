//! `twinloop demo`: the adaptation loop of seed 000 end to end, with no hardware. A
//! simulated robot (a built-in profile, `--robot`: km20, op3 or darwin_op) with a
//! hardware change the adapting side is not told (a random one, `--seed`, or on km20
//! one of seed 000's battery scenarios, `--scenario`) answers on a pseudo-terminal as
//! a real robot does on its USB adapter; the tip-over runs over
//! that bus exactly as on a real robot (faster than real time); the change is found
//! from the four fall angles and the robot's weight; the adapted model is written and
//! checked; then the truth is revealed beside what was found.

use crate::cmd_experiment::tipover_bus::{
    ANKLE_SLOPE, BusOutcome, BusPlan, GoalCounts, ONSET_AVERAGE_S, tipover_on_bus,
};
use crate::cmd_link::{PortArgs, open_client};
use crate::common::{JSON_HELP, emit};
use crate::error::{CliError, CliResult, Outcome};
use crate::protocol_bias::{
    Calibration, Replay, adapt_to_protocol, angles_of as angles, join, protocol_reading,
    replay_options,
};
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;
use twinloop_description::Description;
use twinloop_description::builtin::km20;
use twinloop_experiments::tipover::Direction;
use twinloop_ident::adapt::{AdaptOptions, html_report, standing_com, standing_point};
use twinloop_ident::ann_data::{Change, changed, outlined_links, random_change};
use twinloop_ident::tipover_study::report_for_runs;
use twinloop_link::Item;
use twinloop_link::RobotMapping;
use twinloop_virtual::{PtyServer, VirtualRobot, VirtualRobotOptions};

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// The robot: a built-in profile (its description, servos and IMU board, served
    /// and measured as they are)
    #[arg(long, default_value = "km20", value_name = "NAME", value_parser = RobotMapping::BUILTINS)]
    pub robot: String,
    /// Draw the hidden change from this seed: one mass of 0.05-0.5 kg on a random link
    /// of the robot, at a random point inside its outline
    #[arg(long, default_value_t = 7, conflicts_with = "scenario")]
    pub seed: u64,
    /// Instead of a random change, one of seed 000's battery scenarios on km20 (0.2
    /// kg; km20 only, they name its links): a (both legs: two masses at once), c
    /// (front of the hip), d (left arm), e (right arm), f (shoulders)
    #[arg(long, value_name = "LABEL", value_parser = ["a", "c", "d", "e", "f"])]
    pub scenario: Option<String>,
    /// Simulated seconds per wall-clock second of the robot behind the bus (and the
    /// host's clock rate)
    #[arg(long, default_value_t = 4.0, value_name = "FACTOR", value_parser = crate::common::positive)]
    pub realtime_factor: f64,
    /// How far the simulated robot's weight sinks into its floor, m (the floor's
    /// stiffness, as `serve --ground-sink`)
    #[arg(long, default_value_t = 1e-4, value_name = "M", value_parser = crate::common::positive)]
    pub ground_sink: f64,
    /// The hidden robot's servos run these models (`identify servo --out`; the
    /// grammar of `serve --servo-params`: FILE.toml for every servo of its type,
    /// ID=FILE.toml or JOINT=FILE.toml for one, repeatable): the adapting side knows
    /// only the datasheets, as with a real robot whose servos were never identified
    #[arg(long, value_name = "[ID=]FILE.toml")]
    pub servo_params: Vec<String>,
    /// Creeping approaches per direction (as `experiment tipover --creeps`)
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u64).range(1..=5))]
    pub creeps: u64,
    /// Tell the adapting side which link the change is on, as `adapt --where` (a team
    /// knows where it bolted the part): the position is then fitted inside that
    /// link's outline. One change only (not with --scenario a)
    #[arg(long)]
    pub tell_where: bool,
    /// The goal positions sent to the joints a lean turns. dithered
    /// (sigma-delta: the counts flip around the ramp so that their running mean is
    /// the ramp) lets the robot tip where its lean takes it, between two counts;
    /// staircase (whole counts) tips it on the jolt of a count step, a count early
    /// or late from run to run (as `experiment tipover --goal-counts`)
    #[arg(long, value_enum, default_value_t)]
    pub goal_counts: GoalCounts,
    /// Leave the servos as they are instead of stiffening them (every servo is made
    /// stiff through the servo catalogue, and put back afterwards; a servo model with
    /// no known way to stiffen otherwise stops the run before anything moves). The
    /// output then says the servos were soft: the angles include their give.
    #[arg(long)]
    pub soft_servos: bool,
    /// Read each creep's tip as the mean of the ankle readings over this long up to
    /// the onset, s of robot time (as `experiment tipover --onset-average`; 0: the
    /// onset's sample alone)
    #[arg(long, default_value_t = ONSET_AVERAGE_S, value_parser = crate::common::non_negative)]
    pub onset_average: f64,
    /// Passes of adapting to the protocol (0: off): the tip-over protocol is simulated
    /// on the adapted model, on an in-memory bus stepped in lockstep with the host, and
    /// the static angles the model is fitted to move by that model's protocol bias
    /// (what the protocol reads minus its static angles); the last pass is kept (about
    /// 1 s per pass)
    #[arg(long, default_value_t = 3, value_name = "N", value_parser = clap::value_parser!(u64).range(0..=5))]
    pub protocol_passes: u64,
    /// Check the adapted model as the robot was measured: serve its simulation on a
    /// second pseudo-terminal (datasheet servos: what the adapting side knows) and run
    /// the same protocol over the bus, creeping from 1.5 deg before each of the
    /// robot's tips; prints its fall angles beside the robot's (about 30 s more)
    #[arg(long)]
    pub check: bool,
    /// Folder for the files written: the adapted URDF, the tip-over and adaptation
    /// JSON, the HTML report and the CSV of every cycle read over the bus
    #[arg(long, default_value = "twinloop-demo", value_name = "DIR")]
    pub out: PathBuf,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
}

/// The first ramp's and the creeps' speeds, deg/s of robot time.
const RAMP: f64 = 2.0;
const SLOW_RAMP: f64 = 0.15;

/// What the demo found, beside the truth (`--json`).
#[derive(Debug, Serialize)]
struct DemoReport {
    /// The built-in profile measured (`--robot`).
    robot: String,
    /// The hidden change(s).
    truth: Vec<Change>,
    /// The tip-over ran with the servos as they were (`--soft-servos`).
    soft_servos: bool,
    /// `[forward, backward, left, right]`, deg: the robot measured over the bus (the
    /// report's "robot (measured)"), the prior, adapted and true models' static tipping
    /// angles at the measured onsets (the report's "adapted model (static, at the
    /// robot's onsets)"; the true model's are what a perfect measurement would read).
    measured_deg: [f64; 4],
    prior_model_deg: [f64; 4],
    adapted_model_deg: [f64; 4],
    true_model_deg: [f64; 4],
    /// With `--protocol-passes`: the protocol simulated in lockstep on the true model
    /// (what the robot's measurement would read with no bus noise), deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    true_protocol_deg: Option<[f64; 4]>,
    /// With `--check`: the adapted model's simulation measured over the bus by the
    /// same protocol, deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    adapted_simulation_deg: Option<[f64; 4]>,
    /// With `--protocol-passes`: the protocol simulated on the adapted model, per pass.
    #[serde(skip_serializing_if = "Option::is_none")]
    calibration: Option<Calibration>,
    found: Option<twinloop_ident::adapt::AddedMass>,
    true_com: [f64; 3],
    adapted_com: Option<[f64; 3]>,
    /// Distance of the adapted model's CoM from the true one, m.
    com_error: Option<f64>,
    /// Distance of the found mass from the true one (one change), m, in the standing
    /// frame.
    position_error: Option<f64>,
    /// What `adapt` held the answer against (`adapt.json`'s `checks`).
    checks: Vec<twinloop_ident::adapt_checks::AdaptCheck>,
    files: Vec<String>,
    wall_s: f64,
}

/// The hidden change: a battery scenario's masses, or one random mass.
fn hidden_change(a: &DemoArgs, prior: &Description) -> Result<(Vec<Change>, String), CliError> {
    if let Some(label) = &a.scenario {
        if a.robot != km20::NAME {
            return Err(CliError::new(format!(
                "--scenario {label}: seed 000's battery scenarios are km20's (they name its links); on {} the change is drawn from --seed",
                a.robot
            )));
        }
        let s = km20::BATTERY_SCENARIOS
            .iter()
            .find(|s| s.label == label)
            .ok_or_else(|| CliError::new(format!("--scenario {label}: no such scenario")))?;
        let changes = s
            .masses
            .iter()
            .map(|m| Change {
                link: m.link.to_string(),
                mass: m.mass,
                xyz: m.xyz,
            })
            .collect();
        return Ok((
            changes,
            format!("seed 000 battery scenario {label} ({})", s.name),
        ));
    }
    let mut rng = twinloop_random::SplitMix64(a.seed);
    let links = outlined_links(prior);
    let c = random_change(prior, &links, (0.05, 0.5), &mut rng);
    Ok((vec![c], format!("drawn from seed {}", a.seed)))
}

/// Serve `truth` on a new pty, as `twinloop serve --catch-falls` does: the simulation
/// runs `factor` times faster than real time, tethered to its host (a host held up by
/// the scheduler finds the robot where it left it), and the servos answer without a
/// return delay (a tuned robot; the bus cycle is then a third as long).
fn serve_truth(
    truth: &Description,
    mapping: &RobotMapping,
    a: &DemoArgs,
    servo_params: &[String],
) -> Result<PtyServer, CliError> {
    let options = VirtualRobotOptions {
        realtime_factor: a.realtime_factor,
        tether_s: Some(0.02),
        servo_params: twinloop_actuator::params_set::ServoParamsSet::read(
            servo_params,
            "--servo-params",
        )?,
        ..replay_options(a.ground_sink)
    };
    let vr = VirtualRobot::new(truth, mapping, &options)?;
    let devices = mapping.joints.len() + mapping.boards.len();
    PtyServer::start(vr, Some(1_000_000), |bus| {
        for k in 0..devices {
            // Return Delay Time 0 is within every table's range.
            let _ = bus.host_write(k, Item::ReturnDelayTime, 0);
        }
    })
    .map_err(|e| CliError::new(format!("cannot serve the robot on a pseudo-terminal: {e}")))
}

/// `--check`: the adapted `model` simulated behind a second pty as the robot was
/// (datasheet servos, the same floor and clock) and measured over the bus by the
/// same protocol, each direction creeping from 1.5 deg before the robot's own
/// commanded tip (`commanded`, in `Direction::ALL`'s order); its fall angles, deg.
fn check_on_bus(
    model: &Description,
    mapping: &RobotMapping,
    a: &DemoArgs,
    commanded: Vec<f64>,
    record: &Path,
) -> Result<[f64; 4], CliError> {
    eprintln!("checking: the adapted model's simulation, over the bus, from near each tip");
    let robot = serve_truth(model, mapping, a, &[])?;
    let plan = plan(robot.path(), record, a, Some(commanded));
    let run = tipover_on_bus(&plan)
        .map_err(|e| e.context("checking the adapted model (its simulation over the bus)"))?;
    let BusOutcome::Study(study) = run.outcome else {
        return Err(CliError::new(
            "checking the adapted model: the tip-over did not run all four directions",
        ));
    };
    Ok(angles(&study, |d| d.measured_deg))
}

/// The demo's protocol on the robot at `port`, every read recorded to `record`; with
/// `first_tips`, creeps only (the check).
fn plan(port: &str, record: &Path, a: &DemoArgs, first_tips: Option<Vec<f64>>) -> BusPlan {
    BusPlan {
        model_spec: spec(a),
        map: spec(a),
        port: demo_port(port),
        record: Some(record.to_path_buf()),
        yes: true,
        directions: Direction::ALL.to_vec(),
        ramp: RAMP,
        slow_ramp: SLOW_RAMP,
        compliance_slope: 2,
        ankle_slope: ANKLE_SLOPE,
        soft_servos: a.soft_servos,
        creeps: a.creeps as usize,
        first_tips,
        dither: a.goal_counts.dithered(),
        onset_average_s: a.onset_average,
        clock_rate: a.realtime_factor,
        verbose: true,
    }
}

/// The robot's built-in description and profile: `builtin:NAME`.
fn spec(a: &DemoArgs) -> String {
    format!("builtin:{}", a.robot)
}

/// The measured fall angles' resolution, deg: half a count of the left ankle pitch's
/// servo (the tip is read on both ankles, averaged; every built-in's ankles are one
/// model): RX 0.29 deg (EM-RX28 Goal Position: 300 deg / 1024), MX and X 0.088 deg
/// (EM-MX28, EM-XM430: 360 deg / 4096).
fn ankle_resolution_deg(mapping: &RobotMapping) -> Result<f64, CliError> {
    let ankle = mapping
        .role("left_ankle_pitch")
        .and_then(|joint| mapping.joints.iter().find(|j| j.name == joint))
        .ok_or_else(|| {
            CliError::new(format!(
                "{}: no [[joint]] for roles.left_ankle_pitch",
                mapping.source
            ))
        })?;
    Ok(0.5 * ankle.model.resolution().to_degrees())
}

/// The bus as the demo's host opens it: a reply may wait 500 ms beyond its wire time
/// (a real adapter needs 10; the simulated robot shares the machine with the host, and
/// on a loaded two-core machine its threads wait their turn: at load 12, 50 ms lost
/// most runs to a timeout). The simulation holds while its host waits (the tether),
/// so a late reply costs time, not accuracy.
fn demo_port(path: &str) -> PortArgs {
    PortArgs::quick(Some(path.to_string()), 500.0, 3)
}

/// Ping every id of the mapping: how many servos and boards answer.
fn find_robot(port: &str, mapping: &RobotMapping) -> Result<(usize, usize), CliError> {
    let mut client = open_client(&demo_port(port), None)?;
    let servos = mapping
        .joints
        .iter()
        .filter(|j| client.ping(j.protocol, j.id).is_ok())
        .count();
    let boards = mapping
        .boards
        .iter()
        .filter(|b| client.ping(b.protocol, b.id).is_ok())
        .count();
    Ok((servos, boards))
}

fn mm(v: [f64; 3]) -> String {
    format!(
        "({:+.1}, {:+.1}, {:+.1}) mm",
        v[0] * 1e3,
        v[1] * 1e3,
        v[2] * 1e3
    )
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(v).map_err(|e| CliError::new(e.to_string()))?;
    Ok(twinloop_io::output::write_atomic(path, text + "\n")?)
}

/// The tip-over in 3D (`replay.html` in `dir`, beside the report): the robot's
/// recording with the adapted and prior models as ghosts. A replay that cannot be
/// made is a warning: the demo's result does not depend on it.
fn replay_3d(
    a: &DemoArgs,
    record: &Path,
    adapted: Option<&Path>,
    files: &mut Vec<String>,
) -> Option<PathBuf> {
    let out = a.out.join("replay.html");
    crate::replay3d::replay_for_report(record, &spec(a), adapted, &out, files)
}

/// The robot with its hidden change, served and measured over the bus: what the
/// adapting side has (the tip-over and the scale's reading) and what it is not told.
struct Measured {
    prior: Description,
    mapping: RobotMapping,
    truth: Description,
    truth_changes: Vec<Change>,
    run: crate::cmd_experiment::tipover_bus::BusRun,
    study: Box<twinloop_ident::tipover_study::StudyReport>,
    scale: f64,
    record: PathBuf,
}

/// Serve the robot with its hidden change and run the tip-over on it over the bus.
fn measure(a: &DemoArgs) -> Result<Measured, CliError> {
    let (prior, _) = crate::common::load_description(&spec(a))?;
    let mapping = RobotMapping::builtin(&a.robot)
        .ok_or_else(|| CliError::new(format!("no built-in profile {}", a.robot)))?;
    let (truth_changes, how) = hidden_change(a, &prior)?;
    if a.tell_where
        && truth_changes
            .iter()
            .any(|c| c.link != truth_changes[0].link)
    {
        return Err(CliError::new(
            "--tell-where: the change is on more than one link (adapt --where takes one)",
        ));
    }
    let mut truth = prior.clone();
    for c in &truth_changes {
        truth = changed(&truth, c)?;
    }
    let robot = serve_truth(&truth, &mapping, a, &a.servo_params)?;
    let mut text = format!(
        "robot {} with a hidden change ({how}) answers on {} (simulated, x{} real time)\n",
        a.robot,
        robot.path(),
        a.realtime_factor
    );
    let (servos, boards) = find_robot(robot.path(), &mapping)?;
    text += &format!(
        "found on the bus: {servos} of {} servos, {boards} IMU board(s) at id {}\n",
        mapping.joints.len(),
        mapping.boards.first().map(|b| b.id).unwrap_or(0)
    );
    let scale = truth.total_mass();
    text += &format!(
        "the scale says {scale:.3} kg (the model: {:.3} kg)\n",
        prior.total_mass()
    );
    eprint!("{text}");
    let record = a.out.join("tipover.csv");
    let plan = plan(robot.path(), &record, a, None);
    // A simulation that stopped (it diverged, or its operator could not stand the
    // robot up) leaves the bus answering with its last state: say so rather than
    // what the host made of the frozen robot.
    let run = tipover_on_bus(&plan).map_err(|e| match robot.sim().status().error {
        Some(why) => CliError::new(format!(
            "the simulated robot stopped: {why} (the host saw: {})",
            e.message
        )),
        None => e,
    })?;
    drop(robot);
    let BusOutcome::Study(study) = &run.outcome else {
        return Err(CliError::new(
            "the tip-over did not run all four directions",
        ));
    };
    let study = study.clone();
    Ok(Measured {
        prior,
        mapping,
        truth,
        truth_changes,
        run,
        study,
        scale,
        record,
    })
}

/// `twinloop demo`.
pub fn run(a: DemoArgs) -> CliResult {
    let t0 = Instant::now();
    std::fs::create_dir_all(&a.out).map_err(|e| CliError::io(&a.out, e).context("--out"))?;
    let m = measure(&a)?;
    let (prior, study, run) = (&m.prior, &m.study, &m.run);
    let tip_json = a.out.join("tipover.json");
    write_json(&tip_json, &**study)?;
    let opts = AdaptOptions {
        total_mass: Some(m.scale),
        host: a.tell_where.then(|| m.truth_changes[0].link.clone()),
        angle_resolution_deg: Some(ankle_resolution_deg(&m.mapping)?),
        ..Default::default()
    };
    let measured = angles(study, |d| d.measured_deg);
    // The check's floor and servos (datasheet): what the adapting side knows.
    let replay_options = replay_options(a.ground_sink);
    let model_spec = spec(&a);
    let replay = Replay {
        model_spec: &model_spec,
        passes: a.protocol_passes as usize,
        options: &replay_options,
    };
    let (mut adapted, calibration) = adapt_to_protocol(
        prior,
        study,
        &opts,
        &replay,
        &mut |line| eprintln!("{line}"),
        &|e| CliError::from(e),
    )?;
    let prior_deg = angles(study, |d| d.static_deg);
    let mut files = vec![
        m.record.display().to_string(),
        tip_json.display().to_string(),
    ];
    let mut adapted_deg = [f64::NAN; 4];
    let mut urdf = None;
    if let Some(model) = &adapted.robot {
        let after = report_for_runs(model, &run.runs, &run.joint_names)?;
        adapted_deg = angles(&after, |d| d.static_deg);
        let path = a.out.join(format!("{}_adapted.urdf", a.robot));
        twinloop_description::urdf::write_file(model, &path)
            .map_err(|e| CliError::new(format!("{}: {e}", path.display())))?;
        files.push(path.display().to_string());
        urdf = Some(path);
    }
    let simulated_deg = match (&adapted.robot, a.check) {
        (Some(model), true) => {
            let commanded: Vec<f64> = run.runs.iter().map(|r| r.commanded_deg).collect();
            let check_csv = a.out.join("check.csv");
            let deg = check_on_bus(model, &m.mapping, &a, commanded, &check_csv)?;
            files.push(check_csv.display().to_string());
            Some(deg)
        }
        _ => None,
    };
    let html = a.out.join("report.html");
    let replay = replay_3d(&a, &m.record, urdf.as_deref(), &mut files);
    adapted.report.files = files.clone();
    let mut page = html_report(&adapted.report);
    if let Some(replay) = &replay {
        crate::replay3d::link_replay(&mut page, replay);
    }
    page.write(&html)
        .map_err(|e| CliError::new(format!("{}: {e}", html.display())))?;
    files.push(html.display().to_string());
    let adapt_json = a.out.join("adapt.json");
    write_json(&adapt_json, &adapted.report)?;
    files.push(adapt_json.display().to_string());

    let true_com = standing_com(&m.truth)?;
    // The truth's static angles at the robot's onsets: what a perfect measurement reads.
    let truth_deg = angles(
        &report_for_runs(&m.truth, &run.runs, &run.joint_names)?,
        |d| d.static_deg,
    );
    // The protocol on the truth, in lockstep: the pty measurement less its noise.
    let true_protocol_deg = match calibration {
        Some(_) => Some(
            protocol_reading(study, &model_spec, &m.truth, &replay_options)
                .map_err(|e| e.context("simulating the protocol on the true model"))?,
        ),
        None => None,
    };
    let r = &adapted.report;
    // One change: where it is in the standing frame (the found one's frame).
    let position_error = match (&r.added, m.truth_changes.as_slice()) {
        (Some(found), [one]) => Some(dist(
            found.position,
            standing_point(prior, &one.link, one.xyz)?,
        )),
        _ => None,
    };
    let mut report = DemoReport {
        robot: a.robot.clone(),
        truth: m.truth_changes.clone(),
        soft_servos: a.soft_servos,
        measured_deg: measured,
        prior_model_deg: prior_deg,
        adapted_model_deg: adapted_deg,
        true_model_deg: truth_deg,
        true_protocol_deg,
        adapted_simulation_deg: simulated_deg,
        calibration,
        found: r.added.clone(),
        true_com,
        adapted_com: r.adapted_com,
        com_error: r.adapted_com.map(|c| dist(c, true_com)),
        position_error,
        checks: r.checks.clone(),
        files,
        wall_s: 0.0,
    };
    report.wall_s = t0.elapsed().as_secs_f64();
    let t = terminal_text(&a, &report, r, &m.record);
    emit(&t, a.json.as_ref(), &report)?;
    Ok(Outcome::Ok)
}

/// The demo's result as the terminal says it: the fall angles in the adapt report's
/// names (`html_report`'s columns, the JSON's fields), what was found beside the
/// truth, and the checks `adapt` would hold the answer against.
fn terminal_text(
    a: &DemoArgs,
    d: &DemoReport,
    r: &twinloop_ident::adapt::AdaptReport,
    record: &Path,
) -> String {
    let mut t = String::new();
    if a.soft_servos {
        t += &format!("{}\n", twinloop_ident::adapt::SOFT_SERVOS_NOTE);
    }
    // Each row in the adapt report's words (`html_report`'s columns).
    let row = |label: &str, v: [f64; 4]| format!("  {label:46}{}", join(v));
    t += &format!("{:48}forward backward  left right\n", "fall angles, deg");
    t += &(row("robot (measured)", d.measured_deg) + "\n");
    for (label, v) in [
        (
            "prior model (static, at the robot's onsets)",
            d.prior_model_deg,
        ),
        (
            "adapted model (static, at the robot's onsets)",
            d.adapted_model_deg,
        ),
        (
            "true model (static, at the robot's onsets)",
            d.true_model_deg,
        ),
    ] {
        t += &(row(label, v) + "\n");
    }
    if let Some(p) = d.true_protocol_deg {
        t += &(row("true model (protocol, simulated)", p) + "\n");
    }
    if let Some(c) = &d.calibration {
        t += &row("protocol's bias", c.passes[c.kept].bias_deg);
        t += " (read past the statics, simulated on the adapted model; the adapted model is the robot less it)\n";
    }
    if let Some(sim) = d.adapted_simulation_deg {
        t += &(row("adapted model (simulated, over the bus)", sim) + "\n");
        let (k, worst) = (0..4).fold((0, 0.0_f64), |b, k| {
            let e = sim[k] - d.measured_deg[k];
            if e.abs() > b.1.abs() { (k, e) } else { b }
        });
        t += &format!(
            "the adapted simulation tips within {:.2} deg of the robot (largest {}: {:+.2})\n",
            worst.abs(),
            ["forward", "backward", "left", "right"][k],
            worst
        );
    }
    t += &found_text(d, r);
    t += &crate::adapt_text::checks_text(r, None);
    t += &format!("wrote {} ({:.0} s)\n", d.files.join(", "), d.wall_s);
    t += &format!(
        "see the robot's run in 3D: twinloop view {} {}\n",
        spec(a),
        record.display()
    );
    t
}

/// What was found beside the truth: the part, the CoM, the part's distance.
fn found_text(d: &DemoReport, r: &twinloop_ident::adapt::AdaptReport) -> String {
    let mut t = String::new();
    match &r.added {
        Some(m) => {
            t += &format!(
                "found: {:.3} kg on {} at {} in its frame\n",
                m.mass,
                m.host,
                mm(m.position_host)
            );
        }
        None => t += "found: no placement (see the report)\n",
    }
    for c in &d.truth {
        t += &format!(
            "truth: {:.3} kg on {} at {} in its frame\n",
            c.mass,
            c.link,
            mm(c.xyz)
        );
    }
    if d.truth.len() > 1 {
        t += "  (two changes at once are found as the one equivalent change)\n";
    }
    t += &format!(
        "CoM: prior {} -> adapted model {}, true {}: off by {:.1} mm\n",
        mm(r.prior_com),
        r.adapted_com.map(mm).unwrap_or_else(|| "-".into()),
        mm(d.true_com),
        d.com_error.unwrap_or(f64::NAN) * 1e3
    );
    if let Some(e) = d.position_error {
        t += &format!(
            "the mass is {:.1} mm from where it really is (CoM sigma x mass ratio: {})\n",
            e * 1e3,
            r.added
                .as_ref()
                .map(|m| mm(m.position_sigma))
                .unwrap_or_default()
        );
    }
    t
}
