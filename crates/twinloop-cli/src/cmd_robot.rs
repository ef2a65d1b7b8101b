//! `twinloop robot ...`: the built-in seed robots (km20, lab17).

use crate::common::{self, EXIT_BAD_INPUT, EXIT_OK, num};
use clap::{Args, Subcommand};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use twinloop_description::builtin::{builtin, builtin_summaries, servo_table};
use twinloop_description::{Description, JointKind};

#[derive(Subcommand)]
pub enum RobotCommand {
    /// List the built-in robots
    #[command(
        long_about = "List the robots built into twinloop from primitives in code: the seed robots \
of the project's papers. Any command that takes --robot accepts them as builtin:NAME.",
        after_long_help = "Example:\n  twinloop robot list\n\n\
Output: one line per robot.\n  \
NAME   what builtin:NAME and `robot export NAME` take\n  \
DOF    moving joints\n  \
MASS   total mass, kg\n  \
SERVOS servo models and how many joints each drives\n\n\
With --json: a list of objects {name, description, dof, links, total_mass (kg), servos\n\
[{joint, servo, stall_torque (N m), no_load_speed (rad/s)}]}.\n\n\
Exit code 0."
    )]
    List(ListArgs),

    /// Write a built-in robot as a URDF file
    #[command(
        long_about = "Write a built-in robot as URDF: links with the inertials of their primitive \
parts, one visual per part, box collision soles, joint limits with the servos' stall torque as \
effort and no-load speed as velocity. The file reads back into an identical robot.",
        after_long_help = "Example:\n  twinloop robot export km20 --out km20.urdf\n  \
twinloop model info km20.urdf\n\n\
NAME is a name from `twinloop robot list` (builtin:NAME also works).\n\n\
Output: one line saying what was written, with the robot's DoF and mass.\n\n\
Exit code 0, or 2 for an unknown robot name or a file that cannot be written."
    )]
    Export(ExportArgs),
}

#[derive(Args)]
pub struct ListArgs {
    /// Print JSON instead of text
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct ExportArgs {
    /// The built-in robot: km20 or lab17
    pub name: String,
    /// The URDF file to write
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

pub fn run(cmd: RobotCommand) -> ExitCode {
    match cmd {
        RobotCommand::List(args) => list(&args),
        RobotCommand::Export(args) => export(&args),
    }
}

#[derive(Serialize)]
struct JointServoJson {
    joint: String,
    servo: &'static str,
    stall_torque: f64,
    no_load_speed: f64,
}

#[derive(Serialize)]
struct RobotJson {
    name: &'static str,
    description: &'static str,
    dof: usize,
    links: usize,
    total_mass: f64,
    servos: Vec<JointServoJson>,
}

fn dof(robot: &Description) -> usize {
    robot
        .joints
        .iter()
        .filter(|j| j.kind != JointKind::Fixed)
        .map(|j| j.kind.nv())
        .sum()
}

/// "18 RX-28, 2 RX-64": servo models by count, in table order.
fn servo_counts(name: &str) -> String {
    let mut counts: Vec<(&str, usize)> = Vec::new();
    for s in servo_table(name).unwrap_or(&[]) {
        match counts.iter_mut().find(|(n, _)| *n == s.servo.name) {
            Some((_, c)) => *c += 1,
            None => counts.push((s.servo.name, 1)),
        }
    }
    counts
        .iter()
        .map(|(n, c)| format!("{c} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn list(args: &ListArgs) -> ExitCode {
    let robots: Vec<RobotJson> = builtin_summaries()
        .iter()
        .map(|&(name, description)| {
            let r = builtin(name).expect("a listed robot is built in");
            RobotJson {
                name,
                description,
                dof: dof(&r),
                links: r.links.len(),
                total_mass: r.total_mass(),
                servos: servo_table(name)
                    .unwrap_or(&[])
                    .iter()
                    .map(|s| JointServoJson {
                        joint: s.joint.to_string(),
                        servo: s.servo.name,
                        stall_torque: s.servo.stall_torque,
                        no_load_speed: s.servo.no_load_speed,
                    })
                    .collect(),
            }
        })
        .collect();
    if args.json {
        return if common::print_json(&robots) {
            ExitCode::from(EXIT_OK)
        } else {
            ExitCode::from(EXIT_BAD_INPUT)
        };
    }
    let mut text = format!(
        "{:<7} {:>4} {:>7}  {:<20} {}\n",
        "NAME", "DOF", "MASS", "SERVOS", "DESCRIPTION"
    );
    for r in &robots {
        text.push_str(&format!(
            "{:<7} {:>4} {:>7}  {:<20} {}\n",
            r.name,
            r.dof,
            num(r.total_mass),
            servo_counts(r.name),
            r.description
        ));
    }
    common::print(&text);
    ExitCode::from(EXIT_OK)
}

fn export(args: &ExportArgs) -> ExitCode {
    let name = args.name.strip_prefix("builtin:").unwrap_or(&args.name);
    let Some(robot) = builtin(name) else {
        eprintln!(
            "error: unknown built-in robot \"{}\" (built-in robots: {})",
            args.name,
            twinloop_description::builtin::BUILTIN_NAMES.join(", ")
        );
        return ExitCode::from(EXIT_BAD_INPUT);
    };
    if let Err(e) = twinloop_description::urdf::write_file(&robot, &args.out) {
        eprintln!("error: {e}");
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    common::print(&format!(
        "wrote {} ({} DoF, {} kg, {} links) to {}\n",
        robot.name,
        dof(&robot),
        num(robot.total_mass()),
        robot.links.len(),
        args.out.display()
    ));
    ExitCode::from(EXIT_OK)
}
