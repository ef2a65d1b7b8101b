//! `twinloop model ...`: robot descriptions: read one, check one, list the built-in
//! ones, write one as URDF.

use crate::common::{self, JSON_HELP, emit, num};
use crate::error::{CliError, CliResult, Outcome};
use clap::{Args, Subcommand};
use serde::Serialize;
use std::path::PathBuf;
use twinloop_description::builtin::{builtin, builtin_summaries, servo_table};
use twinloop_description::lint::{LintReport, Severity, lint};
use twinloop_description::{Description, JointKind};
use twinloop_dynamics::{BaseKind, JointType, Model};
use twinloop_io::Quantity;

#[derive(Subcommand)]
pub enum ModelCommand {
    /// Summarise a robot description: links, joints, degrees of freedom, mass
    #[command(
        long_about = "Summarise a robot description (URDF or MJCF, told apart by the root element, or \
builtin:NAME): \
robot name, file format, root link, links and joints counted by kind, degrees of freedom, mimic \
joints, total mass, the heaviest links and the links without an <inertial>.",
        after_long_help = "Example:\n  twinloop model info models/op3/robotis_op3.urdf\n  \
twinloop model info builtin:km20 --json -\n  \
twinloop model info builtin:km20 --joints\n\n\
Output:\n  \
dof           velocity degrees of freedom of the joints (a floating joint counts 6; the free\n                \
base the dynamics adds to a URDF without one is not counted)\n  \
actuated      revolute, continuous and prismatic joints that are not <mimic>s\n  \
total mass    sum of every link's <mass> (dummy frame links included), kg: what a scale\n                \
should read if the model is right\n  \
heaviest      the five heaviest links, kg\n  \
--joints      every moving joint in model order (the order of q:, v:, tau: columns) with\n                \
its kind, limits (rad or m; rad/s or m/s; N m or N) and the CSV headers a trajectory\n                \
(simulate --trajectory: t and any q:<joint>) and a state file (dynamics: q:base.* too) need\n\n\
With --json FILE (- for stdout) the same facts as one JSON object with stable field names: file, format, robot,\n\
root_link, links, links_without_inertial [names], joints, joints_by_kind {revolute, continuous,\n\
prismatic, fixed, floating, planar}, dof, actuated_dof, mimic_joints [names], total_mass (kg,\n\
full precision), heaviest_links [{name, mass}]; with --joints also joint_list [{name, kind,\n\
lower, upper, velocity, effort}], trajectory_header, state_header.\n\n\
Exit code 0, or 2 when the file cannot be read (the message names file, line and element)."
    )]
    Info(InfoArgs),

    /// Check the physical plausibility of a description's numbers
    #[command(
        long_about = "Check the numbers of a robot description that parse fine but make dynamics \
wrong or singular: inertia tensors that are not positive definite or violate the triangle inequality \
of principal moments, moving bodies without mass, point masses with zero inertia, joints without \
limits, non-unit axes, mimic joints (which twinloop's dynamics treats as independent), and \
elements of an MJCF file that the rigid-body dynamics leave out (tendons, equality constraints, \
actuators on no joint, sensors at sites).",
        after_long_help = "Example:\n  twinloop model lint models/coman/coman.urdf\n  \
twinloop model lint models/talos/mjcf/talos.xml --strict\n\n\
Output: a table, one finding per line, errors first, then a summary line.\n  \
SEVERITY  error: physically impossible or singular, dynamics from this model is wrong;\n            \
warning: plausible, but the dynamics may differ from the robot or other tools;\n            \
info: worth knowing (missing effort limits, mimic on a fixed joint, total mass)\n  \
CODE      stable, scripts may match on it: negative-mass, inertia-not-positive-definite,\n            \
triangle-inequality, zero-inertia-with-mass, inertia-without-mass,\n            \
zero-mass-moving-link, singular-mass-matrix, singular-floating-base, missing-limits,\n            \
limits-inverted, limits-empty-range,\n            \
missing-effort-velocity, zero-effort-or-velocity, non-unit-axis, mimic-joint,\n            \
unmodeled-element, ignored-detail, total-mass\n  \
SUBJECT   the link or joint (or robot) by name, or the file's element\n  \
MESSAGE   what is wrong, with the numbers (principal moments in kg m^2, masses in kg)\n\n\
With --json FILE (- for stdout) the same as one JSON object: file, format, robot, total_mass, links,\n\
links_without_inertial, joints, moving_joints, dof, mimic_joints, errors, warnings, infos,\n\
findings [{severity, code, subject, name, message}].\n\n\
With --strict, unmodeled-element findings are errors: for when the dynamics must be the whole\n\
physics of the file.\n\n\
Exit code 1 if any finding is an error, 0 otherwise, 2 when the file cannot be read (the\n\
message names file, line and element)."
    )]
    Lint(LintArgs),

    /// List the built-in robots
    #[command(
        long_about = "List the robots built into twinloop from primitives in code: the seed robots \
of the project's papers. Every ROBOT argument and --robot option takes them as builtin:NAME.",
        after_long_help = "Example:\n  twinloop model list\n  twinloop model list --json -\n\n\
Output: one line per robot.\n  \
NAME   what builtin:NAME takes\n  \
DOF    moving joints\n  \
MASS   total mass, kg\n  \
SERVOS servo models and how many joints each drives\n\n\
With --json FILE (- for stdout): a list of objects {name, description, dof, links, total_mass\n\
(kg), servos [{joint, servo, stall_torque (N m), no_load_speed (rad/s)}]}.\n\n\
Exit code 0."
    )]
    List(ListArgs),

    /// Write a robot description as a URDF file
    #[command(
        long_about = "Write a robot description (builtin:NAME, or a URDF or MJCF file) as URDF. A \
built-in robot gets links with the inertials of their primitive parts, one visual per part, box \
collision soles, joint limits with the servos' stall torque as effort and no-load speed as \
velocity. The file reads back into an identical robot.",
        after_long_help = "Example:\n  twinloop model export builtin:km20 --out km20.urdf\n  \
twinloop model info km20.urdf\n  \
twinloop identify servo --defaults RX-28 --out rx28.toml\n  \
twinloop model export builtin:km20 --servo-params rx28.toml --mjcf-actuators km20-servos.xml --out km20.urdf\n\n\
ROBOT is builtin:NAME (see `twinloop model list`) or a URDF or MJCF file.\n\n\
Output: one line saying what was written, with the robot's DoF and mass.\n\n\
Exit code 0, or 2 for an unknown robot, an unreadable description or a file that cannot be\n\
written."
    )]
    Export(ExportArgs),
}

#[derive(Args)]
pub struct DescriptionArgs {
    /// The description: a URDF (<robot>) or MJCF (<mujoco>) file, or builtin:NAME
    #[arg(value_name = "ROBOT")]
    pub robot: String,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
}

#[derive(Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub description: DescriptionArgs,
    /// List the moving joints in model order with their limits, and the CSV headers
    /// a trajectory and a state file need
    #[arg(long)]
    pub joints: bool,
}

#[derive(Args)]
pub struct LintArgs {
    #[command(flatten)]
    pub description: DescriptionArgs,
    /// Make elements the dynamics leave out (tendons, equality constraints, ...) errors
    #[arg(long)]
    pub strict: bool,
}

#[derive(Args)]
pub struct ListArgs {
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
}

#[derive(Args)]
pub struct ExportArgs {
    /// The description: builtin:NAME, or a URDF or MJCF file
    #[arg(value_name = "ROBOT")]
    pub robot: String,
    /// The URDF file to write
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Servo parameters (`identify servo --out`) for every moving joint: each joint's
    /// <dynamics damping friction> becomes the servo's back-EMF + viscous damping and
    /// Coulomb friction (docs/servo-models.md)
    #[arg(long, value_name = "FILE.toml")]
    pub servo_params: Option<PathBuf>,
    /// With --servo-params: also write an MJCF fragment (armature, damping,
    /// frictionloss, one <position> actuator per moving joint with kp and forcerange)
    #[arg(long, value_name = "FILE.xml", requires = "servo_params")]
    pub mjcf_actuators: Option<PathBuf>,
    #[command(flatten)]
    pub added: crate::units::AddMassArgs,
}

pub fn run(cmd: ModelCommand) -> CliResult {
    match cmd {
        ModelCommand::Info(args) => info(&args),
        ModelCommand::Lint(args) => lint_command(&args.description, args.strict),
        ModelCommand::List(args) => list(&args),
        ModelCommand::Export(args) => export(&args),
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
    spherical: usize,
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
    /// Elements the reader left out or read past (`model lint` lists each).
    ignored_elements: usize,
    /// Why the dynamics (every command that computes with the file) refuse it, if
    /// they do: `model info` then exits 1, as `model lint` reports `dynamics-refuses`.
    #[serde(skip_serializing_if = "Option::is_none")]
    dynamics_refuses: Option<String>,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    joint_order: Option<JointOrder>,
}

/// One moving joint of the compiled model, as `--joints` lists it.
#[derive(Serialize)]
struct JointRow {
    name: String,
    kind: &'static str,
    lower: f64,
    upper: f64,
    velocity: f64,
    effort: f64,
}

/// What `--joints` adds: the joints in the order of every `q:`, `v:` and `tau:`
/// column, and the headers that name them: the trajectory's has the joints that take
/// a goal (hinges and slides; a ball joint has none), the state's every coordinate.
#[derive(Serialize)]
struct JointOrder {
    joint_list: Vec<JointRow>,
    trajectory_header: String,
    state_header: String,
}

/// The joints of `robot` as the dynamics and the simulator order them (floating
/// base, as `simulate` and `dynamics` use it).
fn joint_order(robot: &Description, spec: &str) -> Result<JointOrder, crate::error::CliError> {
    let model = Model::from_description_with_base(robot, BaseKind::Floating).map_err(|mut e| {
        if e.location.file.is_none() {
            e.location.file = Some(PathBuf::from(spec));
        }
        crate::error::CliError::from(e)
    })?;
    let joint_list = (0..model.nbodies)
        .map(|i| JointRow {
            name: model.joint_names[i].clone(),
            kind: match model.joint_types[i] {
                JointType::Prismatic => "prismatic",
                JointType::Spherical => "spherical",
                _ => "revolute",
            },
            lower: model.lower_limits[i],
            upper: model.upper_limits[i],
            velocity: model.velocity_limits[i],
            effort: model.effort_limits[i],
        })
        .collect();
    let header = |names: Vec<String>| {
        std::iter::once("t".to_string())
            .chain(Quantity::Q.column_names(&names))
            .collect::<Vec<_>>()
            .join(",")
    };
    // `simulate --trajectory` takes one goal per hinge or slide: a ball has none.
    let goals = (0..model.nbodies)
        .filter(|&i| model.joint_types[i] != JointType::Spherical)
        .map(|i| model.joint_names[i].clone())
        .collect();
    Ok(JointOrder {
        joint_list,
        trajectory_header: header(goals),
        state_header: header(model.q_names()),
    })
}

fn joint_order_text(j: &JointOrder) -> String {
    let mut out = format!(
        "\njoints in model order (q:<name> columns; rad or m)\n  {:>3}  {:<24}{:<11}{:>10}{:>10}{:>10}{:>10}\n",
        "#", "name", "kind", "lower", "upper", "velocity", "effort"
    );
    for (i, r) in j.joint_list.iter().enumerate() {
        out.push_str(&format!(
            "  {:>3}  {:<24}{:<11}{:>10}{:>10}{:>10}{:>10}\n",
            i + 1,
            r.name,
            r.kind,
            num(r.lower),
            num(r.upper),
            num(r.velocity),
            num(r.effort)
        ));
    }
    out.push_str(&format!(
        "\ntrajectory header (simulate --trajectory; any subset of the q: columns; \
         ball joints take no goal):\n{}\n\
         \nstate header (dynamics, floating base; add v:, a:, tau: alike):\n{}\n",
        j.trajectory_header, j.state_header
    ));
    out
}

fn summarise(robot: &Description, args: &DescriptionArgs, format: common::Format) -> Info {
    let mut by_kind = JointsByKind::default();
    for j in &robot.joints {
        *match j.kind {
            JointKind::Revolute => &mut by_kind.revolute,
            JointKind::Continuous => &mut by_kind.continuous,
            JointKind::Prismatic => &mut by_kind.prismatic,
            JointKind::Fixed => &mut by_kind.fixed,
            JointKind::Floating => &mut by_kind.floating,
            JointKind::Planar => &mut by_kind.planar,
            JointKind::Spherical => &mut by_kind.spherical,
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
        file: args.robot.clone(),
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
        ignored_elements: robot.unmodeled.len() + robot.ignored.len(),
        // What the file is for: a description nothing can compute with is no ok
        // (issue 29, class 3).
        dynamics_refuses: Model::from_description_with_base(robot, BaseKind::Fixed)
            .err()
            .map(|e| e.to_string()),
        joint_order: None,
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

fn info(args: &InfoArgs) -> CliResult {
    let d = &args.description;
    let (robot, format) = common::load_description(&d.robot)?;
    let mut info = summarise(&robot, d, format);
    let mut text = info_text(&info);
    if args.joints {
        let j = joint_order(&robot, &d.robot)?;
        text.push_str(&joint_order_text(&j));
        info.joint_order = Some(j);
    }
    emit(&text, d.json.as_ref(), &info)?;
    match &info.dynamics_refuses {
        Some(why) => Err(CliError::problems(format!(
            "{}: the dynamics refuse the file, so every command that computes with it \
             will: {why}",
            info.file
        ))),
        None => Ok(Outcome::Ok),
    }
}

fn info_text(info: &Info) -> String {
    let k = &info.joints_by_kind;
    let kinds: Vec<String> = [
        ("revolute", k.revolute),
        ("continuous", k.continuous),
        ("prismatic", k.prismatic),
        ("fixed", k.fixed),
        ("floating", k.floating),
        ("planar", k.planar),
        ("ball", k.spherical),
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
    row(
        "ignored",
        match info.ignored_elements {
            0 => "none".to_string(),
            n => format!(
                "{} left out or read past: `twinloop model lint {}` lists them",
                plural(n, "element"),
                info.file
            ),
        },
    );
    if let Some(why) = &info.dynamics_refuses {
        row("dynamics", format!("refused: {why}"));
    }
    out
}

#[derive(Serialize)]
struct LintOutput<'a> {
    file: String,
    format: &'static str,
    #[serde(flatten)]
    report: &'a LintReport,
}

fn lint_command(args: &DescriptionArgs, strict: bool) -> CliResult {
    let (robot, format) = common::read_description(&args.robot)?;
    let report = if strict {
        lint(&robot).strict()
    } else {
        lint(&robot)
    };
    let report = with_singular_mass_matrix(&robot, report);
    let out = LintOutput {
        file: args.robot.clone(),
        format: format.as_str(),
        report: &report,
    };
    emit(&lint_table(&report, &args.robot), args.json.as_ref(), &out)?;
    Ok(if report.has_errors() {
        Outcome::Problems
    } else {
        Outcome::Ok
    })
}

/// `singular-mass-matrix`: the compiled model's (fixed base) mass matrix singular at
/// both the neutral and a bent configuration, unless a lint error already names the
/// joint's link.
fn with_singular_mass_matrix(robot: &Description, report: LintReport) -> LintReport {
    use twinloop_description::lint::{Finding, Subject, codes};
    let model = match Model::from_description_with_base(robot, BaseKind::Fixed) {
        Ok(m) => m,
        // What every command that computes with the file says: an error here too, not
        // an ok for a file nothing else takes (issue 29, class 3).
        Err(e) => {
            return report.with_finding(Finding {
                severity: Severity::Error,
                code: codes::DYNAMICS_REFUSES,
                subject: Subject::Robot,
                name: robot.name.clone(),
                message: format!("the dynamics refuse the file: {e}"),
            });
        }
    };
    let mut data = twinloop_dynamics::Data::new(&model);
    // A second, bent configuration: a singularity of the zero pose only (aligned
    // axes that bending separates) is not reported.
    let mut bent = model.neutral_configuration();
    for i in 0..model.nbodies {
        if model.joint_types[i].nq() == 1 {
            bent[model.idx_q[i]] = 0.5;
        }
    }
    let Some(e) = [model.neutral_configuration(), bent]
        .iter()
        .map(|q| twinloop_dynamics::check_mass_matrix(&model, &mut data, q).err())
        .reduce(|a, b| a.and(b))
        .flatten()
    else {
        return report;
    };
    let Some(joint) = e.joint.as_deref().and_then(|j| robot.joint(j)) else {
        return report;
    };
    let explained = report
        .findings
        .iter()
        .any(|f| f.severity == Severity::Error && f.name == joint.child);
    if explained {
        return report;
    }
    report.with_finding(Finding {
        severity: Severity::Error,
        code: codes::SINGULAR_MASS_MATRIX,
        subject: Subject::Joint,
        name: joint.name.clone(),
        message: e.to_string(),
    })
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

fn list(args: &ListArgs) -> CliResult {
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
    emit(&text, args.json.as_ref(), &robots)?;
    Ok(Outcome::Ok)
}

fn export(args: &ExportArgs) -> CliResult {
    let (mut robot, _) = common::load_description(&args.robot)?;
    args.added.apply(&mut robot)?;
    if let Some(path) = &args.servo_params {
        export_servos(&mut robot, path, args.mjcf_actuators.as_deref())?;
    }
    twinloop_description::urdf::write_file(&robot, &args.out)?;
    for what in twinloop_description::urdf::unwritable(&robot) {
        eprintln!("warning: {what}");
    }
    common::print(&format!(
        "wrote {} ({} DoF, {} kg, {} links) to {}\n",
        robot.name,
        dof(&robot),
        num(robot.total_mass()),
        robot.links.len(),
        args.out.display()
    ));
    Ok(Outcome::Ok)
}

/// `model export --servo-params`: the servo's MuJoCo terms on every moving joint
/// (URDF <dynamics>), and with `mjcf` the MJCF fragment.
fn export_servos(
    robot: &mut twinloop_description::Description,
    path: &std::path::Path,
    mjcf: Option<&std::path::Path>,
) -> Result<(), CliError> {
    let params = twinloop_actuator::ServoParams::read(path)?;
    let m = twinloop_actuator::mujoco::mujoco_servo(&params, params.servo.factory_firmware(), 1.0);
    let mut joints = Vec::new();
    for j in &mut robot.joints {
        if matches!(j.kind, JointKind::Revolute | JointKind::Continuous) && j.mimic.is_none() {
            j.dynamics = Some(twinloop_description::JointDynamics {
                damping: Some(m.damping),
                friction: Some(m.frictionloss),
            });
            j.armature = m.armature;
            joints.push(j.name.clone());
        }
    }
    if let Some(out) = mjcf {
        let text = twinloop_actuator::mujoco::mjcf_fragment(&joints, params.servo.name(), &m);
        twinloop_io::output::write_atomic(out, text)?;
    }
    Ok(())
}
