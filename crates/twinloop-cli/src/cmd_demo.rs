//! `twinloop demo`: the adaptation loop of seed 000 end to end, with no hardware. A
//! simulated robot (a built-in profile, `--robot`: km20, op3 or darwin_op) with a
//! hardware change the adapting side is not told (a random one, `--seed`, or on km20
//! one of seed 000's battery scenarios, `--scenario`) answers on a pseudo-terminal as
//! a real robot does on its USB adapter; the tip-over runs over
//! that bus exactly as on a real robot (faster than real time); the change is found
//! from the four fall angles and the robot's weight; the adapted model is written and
//! checked; then the truth is revealed beside what was found. The scenario is
//! `twinloop_loop::demo`; here the flags are mapped and the result written and printed.

use crate::bus_args::GoalCounts;
use crate::common::{JSON_HELP, emit};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;
use twinloop_ident::adapt::html_report;
use twinloop_link::RobotMapping;
use twinloop_loop::demo::{self, DemoReport, DemoSettings};
use twinloop_loop::protocol_bias::join;
use twinloop_loop::tipover_bus::ONSET_AVERAGE_S;

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
    #[arg(long, default_value_t = 4.0, value_name = "FACTOR", value_parser = crate::bounds::realtime_factor)]
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

/// The scenario's settings from the flags.
fn settings(a: &DemoArgs) -> DemoSettings {
    DemoSettings {
        robot: a.robot.clone(),
        seed: a.seed,
        scenario: a.scenario.clone(),
        realtime_factor: a.realtime_factor,
        ground_sink: a.ground_sink,
        servo_params: a.servo_params.clone(),
        creeps: a.creeps as usize,
        tell_where: a.tell_where,
        dither: a.goal_counts.dithered(),
        soft_servos: a.soft_servos,
        onset_average_s: a.onset_average,
        protocol_passes: a.protocol_passes as usize,
        check: a.check,
        out: a.out.clone(),
    }
}

/// The scenario's lines on stderr.
fn log(line: &str) {
    eprintln!("{line}");
}

/// `twinloop demo`.
pub fn run(a: DemoArgs) -> CliResult {
    let t0 = Instant::now();
    let s = settings(&a);
    std::fs::create_dir_all(&a.out).map_err(|e| CliError::io(&a.out, e).context("--out"))?;
    let m = demo::measure(&s, &mut log)?;
    let tip_json = a.out.join("tipover.json");
    write_json(&tip_json, &*m.study)?;
    let found = demo::adapt_measured(&s, &m, &mut log)?;
    let mut files = vec![
        m.record.display().to_string(),
        tip_json.display().to_string(),
    ];
    let mut urdf = None;
    if let Some(model) = &found.adapted.robot {
        let path = a.out.join(format!("{}_adapted.urdf", a.robot));
        twinloop_description::urdf::write_file(model, &path)
            .map_err(|e| CliError::new(format!("{}: {e}", path.display())))?;
        files.push(path.display().to_string());
        urdf = Some(path);
    }
    let simulated_deg = match (&found.adapted.robot, a.check) {
        (Some(model), true) => {
            let commanded: Vec<f64> = m.run.runs.iter().map(|r| r.commanded_deg).collect();
            let check_csv = a.out.join("check.csv");
            let deg = demo::check_on_bus(model, &m.mapping, &s, commanded, &check_csv, &mut log)?;
            files.push(check_csv.display().to_string());
            Some(deg)
        }
        _ => None,
    };
    let replay = replay_3d(&s, &m.record, urdf.as_deref(), &mut files);
    let (mut report, mut adapted) = demo::reveal(&s, &m, found, simulated_deg, files)?;
    let html = a.out.join("report.html");
    adapted.report.files = report.files.clone();
    let mut page = html_report(&adapted.report);
    if let Some(replay) = &replay {
        crate::replay3d::link_replay(&mut page, replay);
    }
    page.write(&html)?;
    report.files.push(html.display().to_string());
    let adapt_json = a.out.join("adapt.json");
    write_json(&adapt_json, &adapted.report)?;
    report.files.push(adapt_json.display().to_string());
    report.wall_s = t0.elapsed().as_secs_f64();
    let t = terminal_text(&a, &report, &adapted.report, &m.record);
    emit(&t, a.json.as_ref(), &report)?;
    // A check that failed is a doubt about the answer: exit 1, as `adapt` does
    // (issue 27: never a confident wrong answer), the files all written.
    Ok(if report.checks.iter().any(|c| !c.passed) {
        Outcome::Problems
    } else {
        Outcome::Ok
    })
}

fn mm(v: [f64; 3]) -> String {
    format!(
        "({:+.1}, {:+.1}, {:+.1}) mm",
        v[0] * 1e3,
        v[1] * 1e3,
        v[2] * 1e3
    )
}

fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(v).map_err(|e| CliError::new(e.to_string()))?;
    Ok(twinloop_io::output::write_atomic(path, text + "\n")?)
}

/// The tip-over in 3D (`replay.html` in `dir`, beside the report): the robot's
/// recording with the adapted and prior models as ghosts. A replay that cannot be
/// made is a warning: the demo's result does not depend on it.
fn replay_3d(
    s: &DemoSettings,
    record: &Path,
    adapted: Option<&Path>,
    files: &mut Vec<String>,
) -> Option<PathBuf> {
    let out = s.out.join("replay.html");
    crate::replay3d::replay_for_report(record, &demo::spec(s), adapted, &out, files)
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
        demo::spec(&settings(a)),
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
