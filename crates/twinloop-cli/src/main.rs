//! `twinloop`: the command-line program. This file only dispatches; each command
//! group lives in its own module (`cmd_model`, ...). To add a group: a module,
//! a variant in [`Command`], and an arm in `main`.

mod cmd_model;
mod common;

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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Model(cmd) => cmd_model::run(cmd),
    }
}
