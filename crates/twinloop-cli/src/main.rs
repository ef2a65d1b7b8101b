//! `twinloop`: the command-line program. This file only dispatches; each command
//! group lives in its own module (`cmd_model`, ...). To add a group: a module,
//! a variant in [`Command`], and an arm in `main`.
//!
//! Every command returns `Result<Outcome, CliError>`; `main` alone prints
//! `error: ...` and picks the exit code (see `error.rs`).

mod adapt_text;
mod args;
mod bounds;
mod bus_args;
mod cmd_adapt;
mod cmd_bench;
mod cmd_compliant;
mod cmd_demo;
mod cmd_dynamics;
mod cmd_experiment;
mod cmd_gait;
mod cmd_identify;
mod cmd_ik;
mod cmd_link;
mod cmd_log;
mod cmd_model;
mod cmd_serve;
mod cmd_simulate;
mod cmd_validate;
mod cmd_view;
mod common;
mod error;
mod gait_args;
mod limb;
mod live_view;
mod outputs;
mod progress;
mod replay3d;
mod residual_text;
mod result_mcap;
mod sim_args;
mod units;

use clap::{Parser, Subcommand};
use error::CliResult;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "twinloop",
    version,
    about = "Keep a humanoid robot's simulation true to the physical robot",
    long_about = "Keep a humanoid robot's simulation true to the physical robot: read the robot \
description (URDF, MJCF or a built-in robot), check it, compute its dynamics, simulate it, run \
experiments, identify its parameters from measurements, validate the result, and talk to the real \
robot's servos.\n\n\
The groups follow the loop: describe (model, dynamics) -> run (simulate, experiment) -> identify \
-> validate -> see (ik, gait, compliant, link, serve, bench). Run `twinloop <group> --help` and \
`twinloop <group> <command> --help` for what each command does, an example, and what its output \
means.\n\n\
Options mean one thing everywhere: --robot a description (URDF, MJCF or builtin:NAME), --map a \
servo mapping TOML, --port a bus (serial device, pty, tcp:HOST:PORT), --out the main data file \
written, --json FILE the machine-readable result (- for stdout), --report an HTML report, --dt a \
sample period in seconds, --seed every random draw; means are removed before identification \
unless --no-detrend.",
    after_help = "Exit codes: 0 success, 1 a check found problems, 2 bad input or a dead link \
(also bad usage). Errors are one line: `error: ` and the file, line, row, field or servo id at fault.",
    propagate_version = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Recorded logs (.mcap, rosbag2 folder): a topic to read, repeatable; the first
    /// gives the rows. TOPIC=NAME,NAME,.. names a Float64MultiArray's values. Default:
    /// every JointState, Imu, WrenchStamped and TFMessage topic (`twinloop log info`)
    #[arg(long, global = true, value_name = "TOPIC")]
    topic: Vec<String>,
    /// Recorded logs: resample every topic onto this fixed step (s) by linear interpolation
    #[arg(long, global = true, value_name = "SECONDS", value_parser = common::positive)]
    resample: Option<f64>,
}

#[derive(Subcommand)]
enum Command {
    /// Robot descriptions: read one, check one, list the built-in ones, write one as URDF
    #[command(subcommand)]
    Model(cmd_model::ModelCommand),
    /// Batch rigid-body dynamics over a trajectory CSV: kinematics, inverse, forward
    #[command(subcommand)]
    Dynamics(cmd_dynamics::DynamicsCommand),
    /// Simulate a robot standing on its servos, holding a pose or following joint goals
    ///
    /// The robot is placed upright on the ground at its neutral pose with a Dynamixel-type
    /// position servo on every joint (--servo), then simulated for --duration seconds at
    /// --dt (1 ms default).
    ///
    /// Example:
    ///   twinloop simulate --robot models/op3/mjcf/op3.xml --duration 5 --hold --out stand.csv
    ///   twinloop simulate --robot builtin:km20 --duration 2 --out km20.csv
    ///   twinloop simulate --robot builtin:km20 --duration 30 --out km20.csv --view
    ///
    /// Output: FILE.csv, each row holding t, q:*, v:*, tau:<joint> (the servo torques),
    /// com.x/y/z, imu:<link>.gx..az (rad/s, m/s^2) and foot:<link>.fz, .cop.x, .cop.y
    /// (N, m) for each foot.
    #[command(verbatim_doc_comment)]
    Simulate(cmd_simulate::SimulateArgs),
    /// Run experiments: tip-over, lean, force-plate poses, squat, lab17 walk, COMAN walk
    #[command(subcommand)]
    Experiment(cmd_experiment::ExperimentCommand),
    /// Identify model parameters from measurements: static, ARX, state space, compliant, walk
    #[command(subcommand)]
    Identify(cmd_identify::IdentifyCommand),
    /// Adapt the model to a hardware change from the tip-over angles (seed 000 III, V.B)
    ///
    /// The exact method turns the measured fall angles (--tipover, the JSON of
    /// `twinloop experiment tipover`) into the CoM; one added point mass explains its
    /// move from the prior model's CoM. --total-mass fixes it in 3-D, and the part's
    /// position is then fitted to the four fall angles at the robot's onset postures
    /// (whatever link it is on, feet included), inside the link's outline if --where
    /// names it; --where LINK alone puts it on the ray from the prior CoM through the
    /// measured one, nearest the link.
    ///
    /// Example:
    ///   twinloop adapt --robot builtin:km20 --tipover tip.json --total-mass 3.636 \
    ///       --out adapted.urdf --json - --report adapt.html --check
    ///
    /// --port PORT --map MAP runs the tip-over in place on the robot's bus first (and writes
    /// it to --tipover); --lean LEAN.csv replays seed 001's lean the robot did on the prior
    /// and the adapted model and compares the ankle and knee torques.
    ///   twinloop adapt --robot builtin:km20 --port /tmp/km20 --map builtin:km20 \
    ///       --total-mass 3.636 --tipover tip.json --out adapted.urdf
    ///
    /// --method ann puts the three masses of the three-mass LIPM where the seed's ANN
    /// (seed 000 V.C) says, from the forward and backward angles and --where; `twinloop
    /// adapt train` trains it on simulated changes.
    ///   twinloop adapt train --robot builtin:km20 --samples 10000 --out net.json
    ///   twinloop adapt --robot builtin:km20 --tipover tip.json --method ann --net net.json \
    ///       --where torso --total-mass 3.636 --json -
    ///
    /// Output: ADAPTED.urdf (an `added_mass` link on a fixed joint, or --merge into the
    /// host), the JSON (measured and prior CoM, the mass found with its uncertainty,
    /// LIPM and three-mass LIPM of the adapted model; with --method ann the three masses,
    /// their CoM and fall angles).
    #[command(verbatim_doc_comment)]
    Adapt(cmd_adapt::AdaptArgs),
    /// Validate a model against measurements: inverse-dynamics residual (seed 004), lean (seed 001)
    #[command(subcommand)]
    Validate(cmd_validate::ValidateCommand),
    /// IK marker fitting: joint angles and base pose from motion capture (seed 004, eq 7)
    ///
    /// Fits the configuration of each frame, floating base included, to the measured
    /// marker positions by Levenberg-Marquardt (least squares over the markers seen in
    /// that frame), joint limits kept. The first frame starts from the base pose fitted
    /// to the base link's markers alone (3 or more needed), each later frame from the
    /// previous one.
    ///
    /// Example:
    ///   twinloop ik --robot robot.urdf --markers markers.toml --frames mocap.csv --out traj.csv
    ///
    /// Output: TRAJ.csv with `t`, `q:*` and the fit quality per frame, `ik.rms` and
    /// `ik.max` (marker distances, m); stdout summarises them.
    #[command(verbatim_doc_comment)]
    Ik(cmd_ik::IkArgs),
    /// Walking references: seed 003's joint sequence, seed 002's ZMP and CoM reference
    #[command(subcommand)]
    Gait(cmd_gait::GaitCommand),
    /// The compact compliant model of seed 002 (COMAN): its stiffness, and rolling it out
    #[command(subcommand)]
    Compliant(cmd_compliant::CompliantCommand),
    /// Talk to a robot's Dynamixel servos on a bus: scan, read, record, plan a control cycle
    ///
    /// Protocol 1.0 (RX, MX) and 2.0 (X, MX(2.0)) over a serial adapter, a pty from
    /// `twinloop serve`, or TCP. Run `twinloop link <command> --help` for each.
    #[command(subcommand)]
    Link(cmd_link::LinkCommand),
    /// Recorded logs (MCAP files, ROS 2 bags): what a log holds and what twinloop reads from it
    ///
    /// Every command that reads recorded data (--trajectory, --data, --poses,
    /// --robot-run, view recordings) takes an .mcap file or a rosbag2 folder (MCAP or
    /// SQLite storage) as well as a CSV; --topic picks topics, --resample a fixed step.
    #[command(subcommand)]
    Log(cmd_log::LogCommand),
    /// Put a virtual robot on a pseudo-terminal (or TCP) that any Dynamixel program can drive
    ///
    /// Each servo of the robot answers with its own control table in its own protocol
    /// (1.0 and 2.0 on one line), goal positions move the servo, present position,
    /// velocity, load, voltage and temperature come from the servo model, and the
    /// wire time at --baud plus each servo's Return Delay Time are emulated. With a
    /// robot description (builtin:km20) the servos are the physics simulation of the
    /// robot standing on the ground, in real time; --servo-model ideal puts a stand-in
    /// (each servo tracks its goal, 50 ms lag) for protocol-only work. --bench MODEL
    /// --load LOAD.toml serves one servo (id 1) swinging a pendulum instead, moved by
    /// the servo model of docs/servo-models.md. --servo-params FILE.toml (every servo
    /// of its type) or ID=FILE.toml (one servo) runs the servos by identified models.
    ///
    /// Example:
    ///   twinloop serve --robot builtin:km20 --link /tmp/km20
    ///   twinloop serve --robot builtin:km20 --servo-params rx28.toml --servo-params 3=knee.toml
    ///   twinloop link scan --port /tmp/km20
    ///   twinloop serve --map builtin:op3 --port tcp:127.0.0.1:5555 --no-timing
    ///   twinloop serve --bench XM430-W350 --load load.toml --link /tmp/bench
    ///
    /// Output: the first line on stdout is the device path (or tcp:ADDR) to hand to
    /// clients (`twinloop link`, the ROBOTIS SDK, Dynamixel Wizard via a pty bridge);
    /// stderr describes what is served. Ctrl-C stops.
    #[command(verbatim_doc_comment)]
    Serve(cmd_serve::ServeArgs),
    /// The adaptation loop with no hardware: a robot with a hidden change, found over its bus
    ///
    /// A simulated robot (a built-in profile, --robot: km20, op3 or darwin_op) with a
    /// change the adapting side is not told (a random mass, --seed, or on km20 a seed 000
    /// battery scenario, --scenario) answers on a pseudo-terminal as a real robot does on
    /// its USB adapter, faster than real time. Over that bus, exactly as on a real robot: the servos are found, the robot leans until it tips in four
    /// directions (each twice, the second time creeping up to the tip; the robot's own
    /// IMU board gives the tilt), the change is found from the fall angles and the
    /// weight (seed 000's exact inversion), the adapted URDF is written and its fall
    /// angles checked against the robot's, with the checks `adapt` makes. Then the truth
    /// is shown beside what was found.
    ///
    /// Example:
    ///   twinloop demo --seed 3 --json demo.json
    ///   twinloop demo --scenario a
    ///   twinloop demo --robot op3 --seed 2
    #[command(verbatim_doc_comment)]
    Demo(cmd_demo::DemoArgs),
    /// Benchmarks against peers (median time per call): dynamics, simulator, servo link
    #[command(subcommand)]
    Bench(cmd_bench::BenchCommand),
    /// See the robot in 3D in the browser, replay recordings, compare runs as ghosts
    ///
    /// Serves a page on this computer (127.0.0.1, a free port; the URL is printed):
    /// the robot (URDF meshes, or primitives), each recording replayed from its q:*
    /// (and q:base.*) columns with play, speed, stepping and scrubbing, the second
    /// and later recordings as translucent ghosts with a time offset, overlays (CoM
    /// and its ground projection, support polygon, centre of pressure, link frames,
    /// inertia boxes, joints at a limit), plots of any columns following the
    /// timeline, and joint sliders. --export writes the same page as one file.
    /// --live FILE.csv follows a CSV while another command writes it and shows
    /// its newest row (decimated to --rate per second, never queued).
    ///
    /// Example:
    ///   twinloop view builtin:km20 km20.csv
    ///   twinloop view models/op3/robotis_op3.urdf --package-dir op3_description=~/op3 --open
    ///   twinloop view builtin:km20 real.csv sim.csv --export replay.html
    ///   twinloop view builtin:km20 --live run.csv
    ///   twinloop simulate --robot builtin:km20 --duration 60 --out run.csv   # in another terminal
    ///   twinloop simulate --robot builtin:km20 --duration 60 --out run.csv --view   # the same, one command
    ///
    /// Output: the page's URL on stdout (then it serves until Ctrl-C); warnings
    /// (missing meshes, missing joint columns) on stderr and on the page.
    #[command(verbatim_doc_comment)]
    View(cmd_view::ViewArgs),
}

fn run(command: Command) -> CliResult {
    match command {
        Command::Model(cmd) => cmd_model::run(cmd),
        Command::Dynamics(cmd) => cmd_dynamics::run(cmd),
        Command::Simulate(args) => cmd_simulate::run(args),
        Command::Experiment(cmd) => cmd_experiment::run(cmd),
        Command::Identify(cmd) => cmd_identify::run(cmd),
        Command::Adapt(args) => cmd_adapt::run(args),
        Command::Validate(cmd) => cmd_validate::run(cmd),
        Command::Ik(args) => cmd_ik::run(&args),
        Command::Gait(cmd) => cmd_gait::run(cmd),
        Command::Compliant(cmd) => cmd_compliant::run(cmd),
        Command::Link(cmd) => cmd_link::run(cmd),
        Command::Log(cmd) => cmd_log::run(cmd),
        Command::Serve(args) => cmd_serve::run(args),
        Command::Demo(args) => cmd_demo::run(args),
        Command::Bench(cmd) => cmd_bench::run(cmd),
        Command::View(args) => cmd_view::run(args),
    }
}

fn main() -> ExitCode {
    // A file over the size limit (`ulimit -f`, a quota) makes write(2) raise SIGXFSZ,
    // whose default kills the process before the write can fail with EFBIG: with a
    // handler the write fails, and the output's error path keeps the old file and
    // removes the partial one (issue 29, class 1), as it does on a full disk.
    let _ = signal_hook::flag::register(
        signal_hook::consts::SIGXFSZ,
        std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false)),
    );
    let cli: Cli = args::parse_args();
    // Every recording a library opens (a guarded robot's --record, the bus
    // tip-over's) is MCAP when its path ends in .mcap.
    twinloop_io::sink::register_recording_format("mcap", twinloop_logs::open_mcap_recording);
    // `--out run/` (or an existing folder): a rosbag2 folder of the same MCAP.
    twinloop_io::sink::register_recording_format(
        twinloop_io::sink::FOLDER,
        twinloop_logs::open_mcap_recording,
    );
    let result = common::set_log_options(&cli.topic, cli.resample).and_then(|()| run(cli.command));
    match result {
        Ok(outcome) => outcome.exit_code(),
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::{CommandFactory, Parser};

    /// Split a command line into words as a shell would for the examples: quotes
    /// ('..', "..") group, a backslash escapes, an unquoted `#` starts a comment.
    fn shell_words(line: &str) -> Result<Vec<String>, String> {
        let mut words = Vec::new();
        let mut word = String::new();
        let mut in_word = false;
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '\'' => {
                    in_word = true;
                    loop {
                        match chars.next() {
                            Some('\'') => break,
                            Some(q) => word.push(q),
                            None => return Err(format!("unclosed ' in {line}")),
                        }
                    }
                }
                '"' => {
                    in_word = true;
                    loop {
                        match chars.next() {
                            Some('"') => break,
                            Some('\\') => word.extend(chars.next()),
                            Some(q) => word.push(q),
                            None => return Err(format!("unclosed \" in {line}")),
                        }
                    }
                }
                '\\' => {
                    in_word = true;
                    word.extend(chars.next());
                }
                '#' if !in_word => break,
                c if c.is_whitespace() => {
                    if in_word {
                        words.push(std::mem::take(&mut word));
                        in_word = false;
                    }
                }
                c => {
                    in_word = true;
                    word.push(c);
                }
            }
        }
        if in_word {
            words.push(word);
        }
        Ok(words)
    }

    /// The example command lines of a help text: every line starting with
    /// `twinloop ` (after trimming), joined with its `\` continuation lines.
    fn examples(help: &str) -> Vec<String> {
        let mut out = Vec::new();
        let mut lines = help.lines().map(str::trim);
        while let Some(line) = lines.next() {
            if !line.starts_with("twinloop ") {
                continue;
            }
            let mut full = line.to_string();
            while full.ends_with('\\') {
                full.pop();
                match lines.next() {
                    Some(next) => {
                        full.push(' ');
                        full.push_str(next);
                    }
                    None => break,
                }
            }
            out.push(full);
        }
        out
    }

    /// Every command's help, with the command path (`twinloop model info`).
    fn all_helps(cmd: &mut clap::Command, path: &str, out: &mut Vec<(String, String, bool)>) {
        let help = cmd.render_long_help().to_string();
        let leaf = !cmd.has_subcommands();
        out.push((path.to_string(), help, leaf));
        for sub in cmd.get_subcommands_mut() {
            if sub.get_name() == "help" {
                continue;
            }
            let p = format!("{path} {}", sub.get_name());
            all_helps(sub, &p, out);
        }
    }

    #[test]
    fn the_command_tree_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn every_example_in_the_help_parses() {
        // No wrapping: each example stays on its lines as written.
        let mut cmd = Cli::command().term_width(0);
        cmd.build();
        let mut helps = Vec::new();
        all_helps(&mut cmd, "twinloop", &mut helps);
        let mut failures = Vec::new();
        let mut checked = 0;
        for (path, help, leaf) in &helps {
            let found = examples(help);
            if *leaf && (found.is_empty() || !help.contains("Example")) {
                failures.push(format!("{path}: no `Example:` with a `twinloop ...` line"));
            }
            for line in found {
                checked += 1;
                let words = match shell_words(&line) {
                    Ok(w) => w,
                    Err(e) => {
                        failures.push(format!("{path}: {e}"));
                        continue;
                    }
                };
                if let Err(e) = Cli::try_parse_from(&words) {
                    let first = e.to_string().lines().next().unwrap_or("").to_string();
                    failures.push(format!("{path}: `{line}` does not parse: {first}"));
                }
            }
        }
        assert!(checked > 30, "only {checked} examples found");
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    /// Numeric options that take a negative number on purpose (a signed quantity: an
    /// offset, an angle either way), with why. Every other numeric option refuses one.
    const NEGATIVE_ALLOWED: &[(&str, &str, &str)] = &[
        ("gait zmp", "step-length", "a negative step walks backward"),
        (
            "experiment compliant-walk",
            "step-length",
            "a negative step walks backward",
        ),
    ];

    /// Whether an option's values are numbers (its value parser gives a number type).
    fn is_numeric(arg: &clap::Arg) -> bool {
        use std::any::TypeId as Id;
        let t = arg.get_value_parser().type_id();
        [
            Id::of::<f64>(),
            Id::of::<f32>(),
            Id::of::<u8>(),
            Id::of::<u16>(),
            Id::of::<u32>(),
            Id::of::<u64>(),
            Id::of::<usize>(),
            Id::of::<i8>(),
            Id::of::<i16>(),
            Id::of::<i32>(),
            Id::of::<i64>(),
            Id::of::<isize>(),
        ]
        .iter()
        .any(|id| t == *id)
    }

    /// Every leaf command's path (`["model", "info"]`) and its clap command.
    fn leaves(cmd: &clap::Command, path: Vec<String>, out: &mut Vec<(Vec<String>, clap::Command)>) {
        if !cmd.has_subcommands() {
            out.push((path, cmd.clone()));
            return;
        }
        for sub in cmd.get_subcommands() {
            if sub.get_name() != "help" {
                let mut p = path.clone();
                p.push(sub.get_name().to_string());
                leaves(sub, p, out);
            }
        }
    }

    /// Every option that takes a number refuses NaN and (unless [`NEGATIVE_ALLOWED`]
    /// says why not) a negative number while the command line is parsed, before any
    /// work: a new numeric option gets this check without a new test. The command line
    /// is parsed as `main` parses it (`-1` taken as a value, see `parse_args`).
    #[test]
    fn every_numeric_option_refuses_nan_and_negatives() {
        use clap::error::ErrorKind;
        fn allow_negative(c: clap::Command) -> clap::Command {
            c.allow_negative_numbers(true)
                .mut_subcommands(allow_negative)
        }
        let mut cli = allow_negative(Cli::command());
        cli.build();
        let mut all = Vec::new();
        leaves(&cli, vec![], &mut all);
        let (mut failures, mut checked) = (Vec::new(), 0);
        for (path, cmd) in &all {
            for arg in cmd.get_arguments() {
                if !arg.get_action().takes_values() || !is_numeric(arg) {
                    continue;
                }
                let Some(long) = arg.get_long() else { continue };
                checked += 1;
                let name = format!("{} --{long}", path.join(" "));
                let allowed = NEGATIVE_ALLOWED
                    .iter()
                    .any(|(c, o, _)| *c == path.join(" ") && *o == long);
                let mut bad = vec!["nan", "NaN", "inf"];
                if !allowed {
                    bad.extend(["-1", "-0.5"]);
                }
                for value in bad {
                    let mut words = vec!["twinloop".to_string()];
                    words.extend(path.iter().cloned());
                    words.push(format!("--{long}"));
                    words.push(value.to_string());
                    match cli.clone().try_get_matches_from(&words) {
                        Err(e)
                            if matches!(
                                e.kind(),
                                ErrorKind::ValueValidation | ErrorKind::InvalidValue
                            ) =>
                        {
                            let text = e.to_string();
                            if !text.contains(&format!("--{long}")) {
                                failures.push(format!(
                                    "{name} {value}: the error does not name the option: {text}"
                                ));
                            }
                        }
                        Err(e) => failures.push(format!(
                            "{name} {value}: taken (then: {})",
                            e.to_string().lines().next().unwrap_or("")
                        )),
                        Ok(_) => failures.push(format!("{name} {value}: taken")),
                    }
                }
            }
        }
        assert!(checked > 100, "only {checked} numeric options found");
        for (c, o, why) in NEGATIVE_ALLOWED {
            assert!(
                all.iter().any(|(p, cmd)| p.join(" ") == *c
                    && cmd.get_arguments().any(|a| a.get_long() == Some(o))),
                "NEGATIVE_ALLOWED names {c} --{o} ({why}), which the CLI does not have"
            );
        }
        assert!(
            failures.is_empty(),
            "{} numeric option values taken that should not be:\n{}",
            failures.len(),
            failures.join("\n")
        );
    }

    #[test]
    fn shell_words_split_like_a_shell() {
        assert_eq!(
            shell_words(r#"twinloop a --x 'u:*' "b c" d\ e # note"#).unwrap(),
            ["twinloop", "a", "--x", "u:*", "b c", "d e"]
        );
    }
}
