//! `twinloop`: the command-line program. This file only dispatches; each command
//! group lives in its own module (`cmd_model`, ...). To add a group: a module,
//! a variant in [`Command`], and an arm in `main`.

mod cmd_bench;
mod cmd_compliant;
mod cmd_compliant_dataset;
mod cmd_dynamics;
mod cmd_experiment;
mod cmd_fit;
mod cmd_gait;
mod cmd_ident;
mod cmd_link;
mod cmd_model;
mod cmd_robot;
mod cmd_sim;
mod cmd_sysid;
mod cmd_zmp;
mod common;
mod progress;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "twinloop",
    version,
    about = "Keep a humanoid robot's simulation true to the physical robot",
    long_about = "twinloop keeps a humanoid robot's simulation true to the physical robot: it reads the \
robot description (URDF or MJCF), checks it, computes its dynamics, and fits it to measurements.\n\n\
Run `twinloop <group> --help` and `twinloop <group> <command> --help` for what each command does, an \
example, and what its output means.",
    after_help = "Exit codes: 0 success, 1 the check found errors, 2 unreadable input or bad usage.",
    propagate_version = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Inspect and check robot descriptions (URDF, MJCF)
    #[command(subcommand)]
    Model(cmd_model::ModelCommand),
    /// Forward kinematics over a trajectory: CoM and frame poses per row
    ///
    /// Reads the q: columns of each row and writes com.x, com.y, com.z and, for each
    /// frame (every link by default), pose:<frame>.x .y .z .qx .qy .qz .qw in the world.
    ///
    /// Example: twinloop kinematics --urdf robot.urdf --trajectory walk.csv --out poses.csv
    Kinematics(cmd_dynamics::KinematicsArgs),
    /// Inverse dynamics (RNEA) over a trajectory: the torques that produce it
    ///
    /// Reads q:, v: and a: columns and writes tau:<joint> per joint and, for a floating
    /// base, tau:base.fx .. tau:base.tz: the wrench the base would need (base frame).
    /// For a robot moving freely under gravity the base wrench should be zero; what is
    /// left is what the model cannot explain.
    ///
    /// Example: twinloop inverse-dynamics --urdf robot.urdf --trajectory squat.csv --out tau.csv
    InverseDynamics(cmd_dynamics::BatchArgs),
    /// Forward dynamics (ABA) over a trajectory: the accelerations torques produce
    ///
    /// Reads q:, v: and tau: columns (tau:base.* is an external wrench on the base,
    /// usually zero) and writes a:<joint> and a:base.vx .. a:base.wz.
    ///
    /// Example: twinloop forward-dynamics --urdf robot.urdf --trajectory cmd.csv --out acc.csv
    ForwardDynamics(cmd_dynamics::BatchArgs),
    /// Simulate a robot standing on its servos, holding a pose or following joint goals
    ///
    /// The robot is placed upright on the ground at its neutral pose with a Dynamixel-type
    /// position servo on every joint (--servo), then simulated for --duration seconds at
    /// --dt (1 ms default). Each output row holds t, q:*, v:*, tau:<joint> (the servo
    /// torques), com.x/y/z, imu:<link>.gx..az (rad/s, m/s^2) and foot:<link>.fz, .cop.x,
    /// .cop.y (N, m) for each foot.
    ///
    /// Example: twinloop simulate --robot models/op3/mjcf/op3.xml --duration 5 --hold --out stand.csv
    Simulate(cmd_sim::SimulateArgs),
    /// Benchmarks (median time per call), to compare with peers such as Pinocchio
    #[command(subcommand)]
    Bench(cmd_bench::BenchCommand),
    /// The built-in seed robots (km20, lab17): list them, export them as URDF
    ///
    /// Built from primitives in code; any --robot option takes them as builtin:NAME.
    ///
    /// Example: twinloop robot export km20 --out km20.urdf
    #[command(subcommand)]
    Robot(cmd_robot::RobotCommand),
    /// Experiments: tip-over (seeds 000/001), virtual force plate poses and squat (seed 004)
    #[command(subcommand)]
    Experiment(cmd_ident::ExperimentCommand),
    /// Identify model parameters from experiments (static masses and CoMs, seed 004)
    #[command(subcommand)]
    Identify(cmd_ident::IdentifyCommand),
    /// IK marker fitting: joint angles and base pose from motion capture (seed 004, eq 7)
    ///
    /// Fits the configuration of each frame, floating base included, to the measured
    /// marker positions by Levenberg-Marquardt (least squares over the markers seen in
    /// that frame), joint limits kept. The first frame starts from the base pose fitted
    /// to the base link's markers alone (3 or more needed), each later frame from the
    /// previous one.
    ///
    /// Example: twinloop ik --urdf robot.urdf --markers markers.toml --frames mocap.csv --out traj.csv
    ///
    /// Output: TRAJ.csv with `t`, `q:*` and the fit quality per frame, `ik.rms` and
    /// `ik.max` (marker distances, m); stdout summarises them.
    #[command(verbatim_doc_comment)]
    Ik(cmd_ident::IkArgs),
    /// Validate a model against measurements (inverse-dynamics residual, seed 004)
    #[command(subcommand)]
    Validate(cmd_ident::ValidateCommand),
    /// Black-box identification from recorded inputs and outputs: MIMO ARX and state-space models
    ///
    /// `sysid arx` fits a MIMO ARX model by least squares; `sysid ss` a state-space model by
    /// subspace identification and the prediction-error method (or the seed 003 route: ARX,
    /// balanced reduction, prediction error). Both evaluate the model as seed 003 does: FIT per
    /// output, Hankel singular values, singular values of the frequency response, residual tests.
    ///
    /// Example: twinloop sysid ss --data walk.csv --inputs 'u:*' --outputs 'gyro:*' --order 6 --json ss.json
    #[command(subcommand)]
    Sysid(cmd_sysid::SysidCommand),
    /// Talk to a robot's Dynamixel servos: scan, read, record, plan a control cycle
    ///
    /// Protocol 1.0 (RX, MX) and 2.0 (X, MX(2.0)) over a serial adapter, a pty from
    /// `twinloop serve`, or TCP. Run `twinloop link <command> --help` for each.
    ///
    /// Example: twinloop link scan --port /dev/ttyUSB0 --baud 1000000
    #[command(subcommand)]
    Link(cmd_link::LinkCommand),
    /// Put a virtual robot on a pseudo-terminal (or TCP) that any Dynamixel program can drive
    ///
    /// Each servo of the robot answers with its own control table in its own protocol
    /// (1.0 and 2.0 on one line), goal positions move the servo, present position,
    /// velocity, load, voltage and temperature come from the servo model, and the
    /// wire time at --baud plus each servo's Return Delay Time are emulated. With a
    /// robot model (builtin:km20) the servos are the physics simulation of the robot
    /// standing on the ground, in real time; --servo-model ideal puts a stand-in
    /// (each servo tracks its goal, 50 ms lag) for protocol-only work.
    ///
    /// The first line printed on stdout is the device path (or tcp:ADDR) to hand to
    /// clients: twinloop link, the ROBOTIS SDK, Dynamixel Wizard via a pty bridge.
    ///
    /// Example: twinloop serve --robot builtin:km20 --link /tmp/km20
    ///          twinloop link scan --port /tmp/km20
    Serve(cmd_link::ServeArgs),
    /// Seed 003's walking sequence as joint goals, and its identification dataset on lab17
    ///
    /// `gait sequence` writes the 13-stage walk as joint goals; `gait dataset` walks it on
    /// lab17 in the simulator and records the ten joint offsets and the six foot gyro rates.
    ///
    /// Example: twinloop gait dataset --robot builtin:lab17 --amplitude 0.7 --out lab17_walk.csv
    #[command(subcommand)]
    Gait(cmd_gait::GaitCommand),
    /// The compliant humanoid of seed 002 (COMAN): Cartesian stiffness and damping at the CoM
    #[command(subcommand)]
    Compliant(cmd_compliant::CompliantCommand),
    /// Fit reduced models to recorded data (seed 002's compact compliant model)
    #[command(subcommand)]
    Fit(cmd_fit::FitCommand),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Model(cmd) => cmd_model::run(cmd),
        Command::Kinematics(args) => cmd_dynamics::kinematics(args),
        Command::InverseDynamics(args) => cmd_dynamics::inverse_dynamics(args),
        Command::ForwardDynamics(args) => cmd_dynamics::forward_dynamics(args),
        Command::Simulate(args) => cmd_sim::simulate(args),
        Command::Bench(cmd) => cmd_bench::run(cmd),
        Command::Robot(cmd) => cmd_robot::run(cmd),
        Command::Experiment(cmd) => cmd_ident::experiment(cmd),
        Command::Identify(cmd) => cmd_ident::identify(cmd),
        Command::Ik(args) => cmd_ident::ik(args),
        Command::Validate(cmd) => cmd_ident::validate(cmd),
        Command::Sysid(cmd) => cmd_sysid::run(cmd),
        Command::Link(cmd) => cmd_link::run(cmd),
        Command::Serve(args) => cmd_link::serve(args),
        Command::Gait(cmd) => cmd_gait::run(cmd),
        Command::Compliant(cmd) => cmd_compliant::run(cmd),
        Command::Fit(cmd) => cmd_fit::run(cmd),
    }
}
