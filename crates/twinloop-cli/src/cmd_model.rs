//! `twinloop model ...`: look at a robot description and check its numbers.

use crate::common::{self, EXIT_BAD_INPUT, EXIT_FINDINGS, EXIT_OK, num};
use clap::{Args, Subcommand};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use twinloop_description::lint::{LintReport, Severity, lint};
use twinloop_description::{Description, JointKind};

#[derive(Subcommand)]
pub enum ModelCommand {
    /// Summarise a robot description: links, joints, degrees of freedom, mass
    #[command(
        long_about = "Summarise a robot description (URDF or MJCF, told apart by the root element): \
robot name, file format, root link, links and joints counted by kind, degrees of freedom, mimic \
joints, total mass, the heaviest links and the links without an <inertial>.",
        after_long_help = "Example:\n  twinloop model info models/op3/robotis_op3.urdf\n\n\
Output:\n  \
dof           velocity degrees of freedom of the joints (a floating joint counts 6; the free\n                \
base the dynamics adds to a URDF without one is not counted)\n  \
actuated      revolute, continuous and prismatic joints that are not <mimic>s\n  \
total mass    sum of every link's <mass> (dummy frame links included), kg: what a scale\n                \
should read if the model is right\n  \
heaviest      the five heaviest links, kg\n\n\
With --json the same facts as one JSON object with stable field names: file, format, robot,\n\
root_link, links, links_without_inertial [names], joints, joints_by_kind {revolute, continuous,\n\
prismatic, fixed, floating, planar}, dof, actuated_dof, mimic_joints [names], total_mass (kg,\n\
full precision), heaviest_links [{name, mass}].\n\n\
Exit code 0, or 2 when the file cannot be read (the message names file, line and element)."
    )]
    Info(FileArgs),

    /// Check the physical plausibility of a description's numbers
    #[command(
        long_about = "Check the numbers of a robot description that parse fine but make dynamics \
wrong or singular: inertia tensors that are not positive definite or violate the triangle inequality \
of principal moments, moving bodies without mass, point masses with zero inertia, joints without \
limits, non-unit axes, mimic joints (which twinloop's dynamics treats as independent).",
        after_long_help = "Example:\n  twinloop model lint models/coman/coman.urdf\n\n\
Output: a table, one finding per line, errors first, then a summary line.\n  \
SEVERITY  error: physically impossible or singular, dynamics from this model is wrong;\n            \
warning: plausible, but the dynamics may differ from the robot or other tools;\n            \
info: worth knowing (missing effort limits, mimic on a fixed joint, total mass)\n  \
CODE      stable, scripts may match on it: negative-mass, inertia-not-positive-definite,\n            \
triangle-inequality, zero-inertia-with-mass, inertia-without-mass,\n            \
zero-mass-moving-link, missing-limits, limits-inverted, limits-empty-range,\n            \
missing-effort-velocity, zero-effort-or-velocity, non-unit-axis, mimic-joint,\n            \
total-mass\n  \
SUBJECT   the link or joint (or robot) by name\n  \
MESSAGE   what is wrong, with the numbers (principal moments in kg m^2, masses in kg)\n\n\
With --json the same as one JSON object: file, format, robot, total_mass, links,\n\
links_without_inertial, joints, moving_joints, dof, mimic_joints, errors, warnings, infos,\n\
findings [{severity, code, subject, name, message}].\n\n\
Exit code 1 if any finding is an error, 0 otherwise, 2 when the file cannot be read (the\n\
message names file, line and element)."
    )]
    Lint(FileArgs),
}

#[derive(Args)]
pub struct FileArgs {
    /// The description: a URDF (<robot>) or MJCF (<mujoco>) file
    pub file: PathBuf,
    /// Print JSON instead of text
    #[arg(long)]
    pub json: bool,
}

pub fn run(cmd: ModelCommand) -> ExitCode {
    match cmd {
        ModelCommand::Info(args) => info(&args),
        ModelCommand::Lint(args) => lint_command(&args),
    }
}

/// How many heaviest links `info` lists.
const HEAVIEST: usize = 5;

#[derive(Serialize, Default)]
struct JointsByKind {
    revolute: usize,
    continuous: usize,
    prismatic: usize,
    fixed: usize,
    floating: usize,
    planar: usize,
}

#[derive(Serialize)]
struct LinkMass {
    name: String,
    mass: f64,
}

#[derive(Serialize)]
struct Info {
    file: String,
    format: &'static str,
    robot: String,
    root_link: Option<String>,
    links: usize,
    links_without_inertial: Vec<String>,
    joints: usize,
    joints_by_kind: JointsByKind,
    dof: usize,
    actuated_dof: usize,
    mimic_joints: Vec<String>,
    total_mass: f64,
    heaviest_links: Vec<LinkMass>,
}

fn summarise(robot: &Description, args: &FileArgs, format: common::Format) -> Info {
    let mut by_kind = JointsByKind::default();
    for j in &robot.joints {
        *match j.kind {
            JointKind::Revolute => &mut by_kind.revolute,
            JointKind::Continuous => &mut by_kind.continuous,
            JointKind::Prismatic => &mut by_kind.prismatic,
            JointKind::Fixed => &mut by_kind.fixed,
            JointKind::Floating => &mut by_kind.floating,
            JointKind::Planar => &mut by_kind.planar,
        } += 1;
    }
    let mut heaviest: Vec<LinkMass> = robot
        .links
        .iter()
        .filter(|l| l.inertial.is_some())
        .map(|l| LinkMass {
            name: l.name.clone(),
            mass: l.mass(),
        })
        .collect();
    // Heaviest first; equal masses keep file order.
    heaviest.sort_by(|a, b| b.mass.total_cmp(&a.mass));
    heaviest.truncate(HEAVIEST);
    Info {
        file: args.file.display().to_string(),
        format: format.as_str(),
        robot: robot.name.clone(),
        root_link: robot.root_link().map(str::to_string),
        links: robot.links.len(),
        links_without_inertial: robot
            .links
            .iter()
            .filter(|l| l.inertial.is_none())
            .map(|l| l.name.clone())
            .collect(),
        joints: robot.joints.len(),
        joints_by_kind: by_kind,
        dof: robot.joints.iter().map(|j| j.kind.nv()).sum(),
        actuated_dof: robot
            .joints
            .iter()
            .filter(|j| {
                j.mimic.is_none()
                    && matches!(
                        j.kind,
                        JointKind::Revolute | JointKind::Continuous | JointKind::Prismatic
                    )
            })
            .count(),
        mimic_joints: robot
            .joints
            .iter()
            .filter(|j| j.mimic.is_some())
            .map(|j| j.name.clone())
            .collect(),
        total_mass: robot.total_mass(),
        heaviest_links: heaviest,
    }
}

fn plural(n: usize, word: &str) -> String {
    if n == 1 {
        format!("1 {word}")
    } else {
        format!("{n} {word}s")
    }
}

/// At most `max` names, then "... (N more)".
fn name_list(names: &[String], max: usize) -> String {
    if names.is_empty() {
        return "none".to_string();
    }
    let mut s = names
        .iter()
        .take(max)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > max {
        s.push_str(&format!(", ... ({} more)", names.len() - max));
    }
    s
}

fn info(args: &FileArgs) -> ExitCode {
    let (robot, format) = match common::load_robot(&args.file) {
        Ok(r) => r,
        Err(code) => return code,
    };
    let info = summarise(&robot, args, format);
    if args.json {
        return ExitCode::from(if common::print_json(&info) {
            EXIT_OK
        } else {
            EXIT_BAD_INPUT
        });
    }
    let k = &info.joints_by_kind;
    let kinds: Vec<String> = [
        ("revolute", k.revolute),
        ("continuous", k.continuous),
        ("prismatic", k.prismatic),
        ("fixed", k.fixed),
        ("floating", k.floating),
        ("planar", k.planar),
    ]
    .iter()
    .filter(|(_, n)| *n > 0)
    .map(|(name, n)| format!("{n} {name}"))
    .collect();
    let heaviest: Vec<String> = info
        .heaviest_links
        .iter()
        .map(|l| format!("{} {} kg", l.name, num(l.mass)))
        .collect();
    let mut out = String::new();
    let mut row = |label: &str, value: String| out.push_str(&format!("{label:<14}{value}\n"));
    row("robot", info.robot.clone());
    row("file", format!("{} ({})", info.file, info.format));
    row(
        "root link",
        info.root_link
            .clone()
            .unwrap_or_else(|| "none (not a tree)".into()),
    );
    row(
        "links",
        format!(
            "{} ({} without inertial: {})",
            info.links,
            info.links_without_inertial.len(),
            name_list(&info.links_without_inertial, 6)
        ),
    );
    row(
        "joints",
        format!(
            "{}{}",
            info.joints,
            if kinds.is_empty() {
                String::new()
            } else {
                format!(": {}", kinds.join(", "))
            }
        ),
    );
    row(
        "dof",
        format!("{} ({} actuated)", info.dof, info.actuated_dof),
    );
    row(
        "mimic joints",
        if info.mimic_joints.is_empty() {
            "none".to_string()
        } else {
            format!(
                "{}: {}",
                info.mimic_joints.len(),
                name_list(&info.mimic_joints, 6)
            )
        },
    );
    row("total mass", format!("{} kg", num(info.total_mass)));
    row(
        "heaviest",
        if heaviest.is_empty() {
            "none (no link has an inertial)".into()
        } else {
            heaviest.join(", ")
        },
    );
    common::print(&out);
    ExitCode::from(EXIT_OK)
}

#[derive(Serialize)]
struct LintOutput<'a> {
    file: String,
    format: &'static str,
    #[serde(flatten)]
    report: &'a LintReport,
}

fn lint_command(args: &FileArgs) -> ExitCode {
    let (robot, format) = match common::load_robot(&args.file) {
        Ok(r) => r,
        Err(code) => return code,
    };
    let report = lint(&robot);
    let code = ExitCode::from(if report.has_errors() {
        EXIT_FINDINGS
    } else {
        EXIT_OK
    });
    if args.json {
        let out = LintOutput {
            file: args.file.display().to_string(),
            format: format.as_str(),
            report: &report,
        };
        if !common::print_json(&out) {
            return ExitCode::from(EXIT_BAD_INPUT);
        }
        return code;
    }
    common::print(&lint_table(&report, &args.file.display().to_string()));
    code
}

fn lint_table(report: &LintReport, file: &str) -> String {
    let subject =
        |f: &twinloop_description::lint::Finding| format!("{} {}", f.subject.as_str(), f.name);
    let w_code = report
        .findings
        .iter()
        .map(|f| f.code.len())
        .max()
        .unwrap_or(0)
        .max(4);
    let w_subject = report
        .findings
        .iter()
        .map(|f| subject(f).chars().count())
        .max()
        .unwrap_or(0)
        .max(7);
    let mut out = format!(
        "{:<8}  {:<w_code$}  {:<w_subject$}  MESSAGE\n",
        "SEVERITY", "CODE", "SUBJECT"
    );
    for f in &report.findings {
        out.push_str(&format!(
            "{:<8}  {:<w_code$}  {:<w_subject$}  {}\n",
            f.severity.as_str(),
            f.code,
            subject(f),
            f.message
        ));
    }
    let verdict = if report.has_errors() {
        "FAIL: errors make dynamics from this model wrong"
    } else if report.count(Severity::Warning) > 0 {
        "ok (no errors; read the warnings)"
    } else {
        "ok"
    };
    out.push_str(&format!(
        "\n{file}: {}, {}, {}; total mass {} kg; {verdict}\n",
        plural(report.errors, "error"),
        plural(report.warnings, "warning"),
        plural(report.infos, "info"),
        num(report.total_mass)
    ));
    out
}
