//! Physical plausibility checks of a description: the numbers a URDF may carry
//! that parse fine but make dynamics wrong or singular.
//!
//! ```
//! use twinloop_description::{DescriptionBuilder, Inertia};
//! use twinloop_description::lint::{lint, Severity};
//! let robot = DescriptionBuilder::new("plate")
//!     .link("base").mass(1.0, [0.0; 3], Inertia::diagonal(1.0, 1.0, 0.0)).done()
//!     .build()
//!     .unwrap();
//! let report = lint(&robot);
//! assert!(report.has_errors());
//! assert_eq!(report.findings[0].code, "inertia-not-positive-definite");
//! assert_eq!(report.findings[0].severity, Severity::Error);
//! ```
//!
//! Checks, with their codes (stable: scripts and tests match on them):
//!
//! | code | severity | when |
//! |---|---|---|
//! | `negative-mass` | error | a link's mass is below zero |
//! | `inertia-not-positive-definite` | error | the smallest principal moment is negative, or zero to within [`EIGENVALUE_RELATIVE_TOLERANCE`] of the largest (placeholders such as ixx=iyy=1, izz=0) |
//! | `triangle-inequality` | error | the two smaller principal moments sum to less than the largest (relative slack [`TRIANGLE_RELATIVE_SLACK`]): no real body has that inertia |
//! | `zero-inertia-with-mass` | warning | mass > 0 with an all-zero tensor: a point mass, usually a dummy frame (1e-9 kg) |
//! | `inertia-without-mass` | warning | mass 0 with a non-zero tensor |
//! | `zero-mass-moving-link` | error / warning | a body moved by a non-fixed joint (the joint's child plus every link fixed to it) has no mass. Error when nothing with mass moves with that joint at all (the joint's row of the mass matrix is zero); warning when links further down carry mass |
//! | `singular-mass-matrix` | error | added by the dynamics (`twinloop model lint`, [`LintReport::with_finding`]): the compiled model's mass matrix is singular at a joint that no other error explains (its mass on its axis, a point mass at a ball joint's centre, a massless link between two joints with one axis); forward dynamics refuses it |
//! | `singular-floating-base` | warning | as a floating base (twinloop's default) the mass matrix is singular: the robot has no mass, or its rotational inertia about its CoM is singular (all mass on a line). A warning: the same file is sound with a fixed base, which lint cannot know, and floating-base forward dynamics refuses it with a message |
//! | `missing-limits` | warning | revolute or prismatic joint without lower/upper |
//! | `limits-inverted` | error | lower > upper |
//! | `limits-empty-range` | warning | lower == upper: the joint cannot move |
//! | `missing-effort-velocity` | info | revolute or prismatic joint without effort or velocity limit (all MJCF joints) |
//! | `zero-effort-or-velocity` | warning | an effort or velocity limit <= 0 |
//! | `non-unit-axis` | warning | a moving joint's axis norm differs from 1 by more than [`AXIS_NORM_TOLERANCE`] (twinloop normalises it; other tools may not) |
//! | `mimic-joint` | warning / info | a `<mimic>`: twinloop's dynamics treats the joint as independent (info when the joint is fixed: no effect); also a warning when it names a joint the file does not have |
//! | `unmodeled-element` | warning (error with [`LintReport::strict`]) | an element of the file that acts on the physics but that twinloop's rigid-body dynamics leave out: MJCF tendons, equality constraints, actuators that drive no joint, sensors at sites, composites and flexcomps, free-floating props beside a free-floating robot (a ball: loaded without it), and elements MuJoCo's schema does not have (a misspelt `<geon>`); in a URDF every element the reader passes over (`urdf` module's `schema`: a misspelt `<colision>`, a second `<inertial>`) |
//! | `ignored-detail` | warning | a visual-only detail the reader read past: a URDF `<texture/>` without a file, a mesh `scale` with a fourth number |
//! | `total-mass` | info | the robot's total mass, as a scale would weigh it |
//! | `unit-scale` | error | lengths in millimetres (the robot spans more than 20 m) or masses in grams (over 100 kg and denser than water over its size cubed): see [`unit_scale`] |
//! | `unsafe-name` | error | a link, joint or frame name with a comma, a quote, a control character or spaces at an end: it cannot be a CSV column (see [`refused`]) |
//! | `bad-axis` | error | a moving joint's axis whose length is beyond 1e-100 .. 1e100: no direction the arithmetic can normalise |
//! | `dynamics-refuses` | error | added by `twinloop model lint`: the dynamics cannot compile the file (the message says why) |
//!
//! Axes of fixed and floating joints are not checked: URDF ignores them (many
//! files write `0 0 0` there).

mod floating_base;
pub mod refused;
pub mod unit_scale;

use crate::description::{Description, Inertia, Joint, JointKind};
use serde::Serialize;
use std::fmt;

/// A principal moment is "zero" when it is at most this fraction of the largest one.
/// Round-off of the eigenvalue computation is ~1e-16; a real thin rod (radius
/// 1e-4 of its length) still has a ratio of 6e-8.
pub const EIGENVALUE_RELATIVE_TOLERANCE: f64 = 1e-12;

/// I1 + I2 >= I3 * (1 - slack): tolerates the rounding of thin plates (I1 + I2 = I3
/// exactly) written with few digits. Same rule as models/*/SOURCE.md.
pub const TRIANGLE_RELATIVE_SLACK: f64 = 1e-9;

/// | |axis| - 1 | above this is reported: a unit axis rounded to 6 significant digits
/// passes (iCub's 0.965926, 0.258819: 1.6e-7), a truncated one does not (NAO's
/// 0.707106: 1.1e-6). Same rule as models/*/SOURCE.md.
pub const AXIS_NORM_TOLERANCE: f64 = 1e-6;

/// The finding codes.
pub mod codes {
    pub const NEGATIVE_MASS: &str = "negative-mass";
    pub const INERTIA_NOT_POSITIVE_DEFINITE: &str = "inertia-not-positive-definite";
    pub const TRIANGLE_INEQUALITY: &str = "triangle-inequality";
    pub const ZERO_INERTIA_WITH_MASS: &str = "zero-inertia-with-mass";
    pub const INERTIA_WITHOUT_MASS: &str = "inertia-without-mass";
    pub const ZERO_MASS_MOVING_LINK: &str = "zero-mass-moving-link";
    pub const SINGULAR_FLOATING_BASE: &str = "singular-floating-base";
    pub const SINGULAR_MASS_MATRIX: &str = "singular-mass-matrix";
    pub const MISSING_LIMITS: &str = "missing-limits";
    pub const LIMITS_INVERTED: &str = "limits-inverted";
    pub const LIMITS_EMPTY_RANGE: &str = "limits-empty-range";
    pub const MISSING_EFFORT_VELOCITY: &str = "missing-effort-velocity";
    pub const ZERO_EFFORT_OR_VELOCITY: &str = "zero-effort-or-velocity";
    pub const NON_UNIT_AXIS: &str = "non-unit-axis";
    pub const MIMIC_JOINT: &str = "mimic-joint";
    pub const UNMODELED_ELEMENT: &str = "unmodeled-element";
    pub const IGNORED_DETAIL: &str = "ignored-detail";
    pub const TOTAL_MASS: &str = "total-mass";
    pub const UNIT_SCALE: &str = "unit-scale";
    pub const UNSAFE_NAME: &str = "unsafe-name";
    pub const BAD_AXIS: &str = "bad-axis";
    pub const DYNAMICS_REFUSES: &str = "dynamics-refuses";

    /// Every code, in the order of the table in the module documentation.
    pub const ALL: [&str; 22] = [
        NEGATIVE_MASS,
        INERTIA_NOT_POSITIVE_DEFINITE,
        TRIANGLE_INEQUALITY,
        ZERO_INERTIA_WITH_MASS,
        INERTIA_WITHOUT_MASS,
        ZERO_MASS_MOVING_LINK,
        SINGULAR_FLOATING_BASE,
        SINGULAR_MASS_MATRIX,
        MISSING_LIMITS,
        LIMITS_INVERTED,
        LIMITS_EMPTY_RANGE,
        MISSING_EFFORT_VELOCITY,
        ZERO_EFFORT_OR_VELOCITY,
        NON_UNIT_AXIS,
        MIMIC_JOINT,
        UNMODELED_ELEMENT,
        IGNORED_DETAIL,
        TOTAL_MASS,
        UNIT_SCALE,
        UNSAFE_NAME,
        BAD_AXIS,
        DYNAMICS_REFUSES,
    ];
}

/// How bad a finding is. Ordered: `Info < Warning < Error`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Worth knowing; nothing is wrong.
    Info,
    /// Plausible, but the dynamics may differ from the robot or from other tools.
    Warning,
    /// Physically impossible or singular: dynamics computed from it is wrong.
    Error,
}

impl Severity {
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Info => "info",
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What a finding is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Subject {
    /// The whole description (URDF's `<robot>` element).
    Robot,
    Link,
    Joint,
    /// An element of the file by its path (line in the message).
    Element,
}

impl Subject {
    pub fn as_str(self) -> &'static str {
        match self {
            Subject::Robot => "robot",
            Subject::Link => "link",
            Subject::Joint => "joint",
            Subject::Element => "element",
        }
    }
}

/// One finding: severity, code, the link or joint (or robot) by name, and a
/// message with the numbers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Finding {
    pub severity: Severity,
    pub code: &'static str,
    pub subject: Subject,
    pub name: String,
    pub message: String,
}

impl fmt::Display for Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}[{}] {} \"{}\": {}",
            self.severity,
            self.code,
            self.subject.as_str(),
            self.name,
            self.message
        )
    }
}

/// The result of [`lint`]: findings (errors first, then warnings, then infos;
/// description order within each) plus the robot's totals.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LintReport {
    pub robot: String,
    /// Sum of all link masses, dummy frames included (kg).
    pub total_mass: f64,
    pub links: usize,
    pub links_without_inertial: usize,
    pub joints: usize,
    /// Joints that are not fixed.
    pub moving_joints: usize,
    /// Velocity degrees of freedom of the joints (a floating joint counts 6);
    /// a free-flyer added by the dynamics for a floating base is not counted.
    pub dof: usize,
    pub mimic_joints: usize,
    pub errors: usize,
    pub warnings: usize,
    pub infos: usize,
    pub findings: Vec<Finding>,
}

impl LintReport {
    pub fn has_errors(&self) -> bool {
        self.errors > 0
    }

    pub fn count(&self, severity: Severity) -> usize {
        self.findings
            .iter()
            .filter(|f| f.severity == severity)
            .count()
    }

    /// Findings with the given code.
    pub fn with_code<'a>(&'a self, code: &'a str) -> impl Iterator<Item = &'a Finding> + 'a {
        self.findings.iter().filter(move |f| f.code == code)
    }

    /// The worst severity found, if any finding at all.
    pub fn worst(&self) -> Option<Severity> {
        self.findings.iter().map(|f| f.severity).max()
    }

    /// The report with every `unmodeled-element` warning made an error: for
    /// users who need the dynamics to be the whole physics of the file.
    pub fn strict(mut self) -> LintReport {
        for f in &mut self.findings {
            if f.code == codes::UNMODELED_ELEMENT {
                f.severity = Severity::Error;
            }
        }
        self.recount()
    }

    /// The report with one more finding (e.g. from a check that needs the compiled
    /// dynamics, which this crate cannot run), in severity order.
    pub fn with_finding(mut self, f: Finding) -> LintReport {
        self.findings.push(f);
        self.recount()
    }

    /// Sort by severity (stable) and count each severity.
    fn recount(mut self) -> LintReport {
        self.findings.sort_by_key(|f| std::cmp::Reverse(f.severity));
        let count = |s| self.findings.iter().filter(|f| f.severity == s).count();
        (self.errors, self.warnings, self.infos) = (
            count(Severity::Error),
            count(Severity::Warning),
            count(Severity::Info),
        );
        self
    }
}

/// Check a description. Never fails: a robot that is not a tree (see
/// [`Description::validate`]) is linted as far as its structure allows.
pub fn lint(robot: &Description) -> LintReport {
    let mut out = Vec::new();
    for link in &robot.links {
        check_link_inertial(link, &mut out);
    }
    check_moving_masses(robot, &mut out);
    floating_base::check(robot, &mut out);
    unit_scale::check(robot, &mut out);
    refused::check(robot, &mut out);
    for joint in &robot.joints {
        check_joint(joint, &mut out);
        check_mimic_target(robot, joint, &mut out);
    }
    let notes = [
        (&robot.unmodeled, codes::UNMODELED_ELEMENT),
        (&robot.ignored, codes::IGNORED_DETAIL),
    ];
    for (list, code) in notes {
        for u in list {
            out.push(finding(
                Severity::Warning,
                code,
                Subject::Element,
                &u.element,
                format!("line {}: {}", u.line, u.what),
            ));
        }
    }
    let total_mass = robot.total_mass();
    let without_inertial = robot.links.iter().filter(|l| l.inertial.is_none()).count();
    let heaviest = robot
        .links
        .iter()
        .filter(|l| l.inertial.is_some())
        .max_by(|a, b| a.mass().total_cmp(&b.mass()));
    let mut message = format!(
        "total mass {} kg over {} links ({} without inertial)",
        num(total_mass),
        robot.links.len(),
        without_inertial
    );
    if let Some(h) = heaviest {
        message.push_str(&format!("; heaviest \"{}\" {} kg", h.name, num(h.mass())));
    }
    out.push(Finding {
        severity: Severity::Info,
        code: codes::TOTAL_MASS,
        subject: Subject::Robot,
        name: robot.name.clone(),
        message,
    });

    // Errors first; stable, so description order is kept within a severity.
    out.sort_by_key(|f| std::cmp::Reverse(f.severity));
    let count = |s| out.iter().filter(|f| f.severity == s).count();
    LintReport {
        robot: robot.name.clone(),
        total_mass,
        links: robot.links.len(),
        links_without_inertial: without_inertial,
        joints: robot.joints.len(),
        moving_joints: robot
            .joints
            .iter()
            .filter(|j| j.kind != JointKind::Fixed)
            .count(),
        dof: robot.joints.iter().map(|j| j.kind.nv()).sum(),
        mimic_joints: robot.joints.iter().filter(|j| j.mimic.is_some()).count(),
        errors: count(Severity::Error),
        warnings: count(Severity::Warning),
        infos: count(Severity::Info),
        findings: out,
    }
}

fn finding(
    severity: Severity,
    code: &'static str,
    subject: Subject,
    name: &str,
    message: String,
) -> Finding {
    Finding {
        severity,
        code,
        subject,
        name: name.to_string(),
        message,
    }
}

fn check_link_inertial(link: &crate::description::Link, out: &mut Vec<Finding>) {
    let Some(inertial) = link.inertial else {
        return;
    };
    let mass = inertial.mass;
    let at = |severity, code, message| finding(severity, code, Subject::Link, &link.name, message);
    if mass < 0.0 {
        out.push(at(
            Severity::Error,
            codes::NEGATIVE_MASS,
            format!("mass {} kg is negative", num(mass)),
        ));
    }
    let i = inertial.inertia;
    let entries = [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz];
    if entries.iter().all(|v| *v == 0.0) {
        if mass > 0.0 {
            out.push(at(
                Severity::Warning,
                codes::ZERO_INERTIA_WITH_MASS,
                format!(
                    "mass {} kg with an all-zero inertia tensor: a point mass (a dummy frame?); \
                     give it a small inertia or no inertial at all",
                    num(mass)
                ),
            ));
        }
        return;
    }
    if mass == 0.0 {
        out.push(at(
            Severity::Warning,
            codes::INERTIA_WITHOUT_MASS,
            format!(
                "mass 0 with a non-zero inertia tensor (ixx {}, iyy {}, izz {})",
                num(i.ixx),
                num(i.iyy),
                num(i.izz)
            ),
        ));
    }
    let [l1, l2, l3] = principal_moments(&i);
    let moments = format!(
        "principal moments {}, {}, {} kg m^2",
        num(l1),
        num(l2),
        num(l3)
    );
    if l3 <= 0.0 || l1 < -EIGENVALUE_RELATIVE_TOLERANCE * l3 {
        out.push(at(
            Severity::Error,
            codes::INERTIA_NOT_POSITIVE_DEFINITE,
            format!("inertia tensor has a negative principal moment: {moments}"),
        ));
    } else if l1 <= EIGENVALUE_RELATIVE_TOLERANCE * l3 {
        out.push(at(
            Severity::Error,
            codes::INERTIA_NOT_POSITIVE_DEFINITE,
            format!(
                "inertia tensor is only positive semi-definite (a principal moment is 0, a placeholder?): \
                 {moments} (ixx {}, iyy {}, izz {})",
                num(i.ixx),
                num(i.iyy),
                num(i.izz)
            ),
        ));
    } else if l1 + l2 < l3 * (1.0 - TRIANGLE_RELATIVE_SLACK) {
        out.push(at(
            Severity::Error,
            codes::TRIANGLE_INEQUALITY,
            format!(
                "principal moments violate the triangle inequality: I1+I2={} < I3={} \
                 ({moments}); no mass distribution has this inertia",
                num(l1 + l2),
                num(l3)
            ),
        ));
    }
}

/// Bodies as the dynamics sees them: each non-fixed joint moves its child link and
/// every link fixed to it. A body without mass is singular unless something with mass
/// moves with it further down.
fn check_moving_masses(robot: &Description, out: &mut Vec<Finding>) {
    let n = robot.links.len();
    let index: std::collections::HashMap<&str, usize> = robot
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.as_str(), i))
        .collect();
    // children[link] = (joint index, child link index)
    let mut children: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
    for (ji, j) in robot.joints.iter().enumerate() {
        if let (Some(&p), Some(&c)) = (index.get(j.parent.as_str()), index.get(j.child.as_str())) {
            children[p].push((ji, c));
        }
    }
    // Walk from `start` over (only fixed | all) joints; the visited guard keeps a
    // malformed (cyclic) description from looping.
    let mass_from = |start: usize, fixed_only: bool| -> f64 {
        let mut seen = vec![false; n];
        let mut stack = vec![start];
        let mut sum = 0.0;
        while let Some(l) = stack.pop() {
            if std::mem::replace(&mut seen[l], true) {
                continue;
            }
            sum += robot.links[l].mass();
            for &(ji, c) in &children[l] {
                if !fixed_only || robot.joints[ji].kind == JointKind::Fixed {
                    stack.push(c);
                }
            }
        }
        sum
    };
    for j in &robot.joints {
        if j.kind == JointKind::Fixed {
            continue;
        }
        let Some(&child) = index.get(j.child.as_str()) else {
            continue;
        };
        let body_mass = mass_from(child, true);
        if body_mass > 0.0 {
            continue;
        }
        let below = mass_from(child, false);
        let kind = j.kind.urdf_name();
        if below > 0.0 && robot.links[child].between_joints {
            // MJCF: one body with several joints; its mass is on the last link.
            continue;
        }
        let (severity, message) = if below > 0.0 {
            (
                Severity::Warning,
                format!(
                    "moved by {kind} joint \"{}\" but it and the links fixed to it have no mass; the {} kg \
                     further down moves through other joints, so the mass matrix stays invertible unless \
                     the next joint's axis coincides with this one; a small mass and inertia is safer",
                    j.name,
                    num(below)
                ),
            )
        } else {
            (
                Severity::Error,
                format!(
                    "moved by {kind} joint \"{}\" but nothing with mass moves with it (composite mass {} kg): \
                     the joint's row of the mass matrix is zero, so forward dynamics is singular",
                    j.name,
                    num(below)
                ),
            )
        };
        out.push(finding(
            severity,
            codes::ZERO_MASS_MOVING_LINK,
            Subject::Link,
            &j.child,
            message,
        ));
    }
}

/// All joint checks, in the order their findings are reported.
fn check_joint(j: &Joint, out: &mut Vec<Finding>) {
    let ranged = matches!(j.kind, JointKind::Revolute | JointKind::Prismatic);
    if ranged {
        check_position_limits(j, out);
        check_effort_velocity_present(j, out);
    }
    if matches!(
        j.kind,
        JointKind::Revolute | JointKind::Prismatic | JointKind::Continuous
    ) {
        check_effort_velocity_positive(j, out);
        check_axis_norm(j, out);
    }
    check_mimic(j, out);
}

/// A finding about joint `j`.
fn joint_finding(j: &Joint, severity: Severity, code: &'static str, message: String) -> Finding {
    finding(severity, code, Subject::Joint, &j.name, message)
}

/// `limits-inverted`, `limits-empty-range` and `missing-limits` of a ranged joint.
fn check_position_limits(j: &Joint, out: &mut Vec<Finding>) {
    let kind = j.kind.urdf_name();
    let limit = j.limit.unwrap_or_default();
    match (limit.lower, limit.upper) {
        (Some(lo), Some(hi)) if lo > hi => out.push(joint_finding(
            j,
            Severity::Error,
            codes::LIMITS_INVERTED,
            format!("lower limit {} is above upper limit {}", num(lo), num(hi)),
        )),
        (Some(lo), Some(hi)) if lo == hi => out.push(joint_finding(
            j,
            Severity::Warning,
            codes::LIMITS_EMPTY_RANGE,
            format!(
                "lower and upper limit are both {}: the joint cannot move",
                num(lo)
            ),
        )),
        (Some(_), Some(_)) => {}
        (lo, hi) => {
            let missing: Vec<&str> = [("lower", lo), ("upper", hi)]
                .iter()
                .filter(|(_, v)| v.is_none())
                .map(|(n, _)| *n)
                .collect();
            out.push(joint_finding(
                j,
                Severity::Warning,
                codes::MISSING_LIMITS,
                format!(
                    "{kind} joint without {} limit: nothing bounds its range in simulation \
                     (URDF requires both; some readers take 0 and lock the joint)",
                    missing.join("/")
                ),
            ));
        }
    }
}

/// `missing-effort-velocity` of a ranged joint.
fn check_effort_velocity_present(j: &Joint, out: &mut Vec<Finding>) {
    let kind = j.kind.urdf_name();
    let limit = j.limit.unwrap_or_default();
    let missing: Vec<&str> = [("effort", limit.effort), ("velocity", limit.velocity)]
        .iter()
        .filter(|(_, v)| v.is_none())
        .map(|(n, _)| *n)
        .collect();
    if !missing.is_empty() {
        out.push(joint_finding(
            j,
            Severity::Info,
            codes::MISSING_EFFORT_VELOCITY,
            format!(
                "{kind} joint without {} limit: {}",
                missing.join(" and "),
                if limit.effort.is_none() {
                    "actuator saturation is unknown"
                } else {
                    "the actuator's top speed is unknown (its torque limit is known)"
                }
            ),
        ));
    }
}

/// `zero-effort-or-velocity` of a moving joint.
fn check_effort_velocity_positive(j: &Joint, out: &mut Vec<Finding>) {
    let limit = j.limit.unwrap_or_default();
    for (name, value) in [("effort", limit.effort), ("velocity", limit.velocity)] {
        if let Some(v) = value
            && v <= 0.0
        {
            out.push(joint_finding(
                j,
                Severity::Warning,
                codes::ZERO_EFFORT_OR_VELOCITY,
                format!("{name} limit is {}: the joint could not be driven", num(v)),
            ));
        }
    }
}

/// `non-unit-axis` of a moving joint.
fn check_axis_norm(j: &Joint, out: &mut Vec<Finding>) {
    let a = j.axis_or_default();
    let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if (norm - 1.0).abs() > AXIS_NORM_TOLERANCE {
        out.push(joint_finding(
            j,
            Severity::Warning,
            codes::NON_UNIT_AXIS,
            format!(
                "axis ({}, {}, {}) has norm {}; twinloop normalises it, other tools may not",
                num(a[0]),
                num(a[1]),
                num(a[2]),
                num_digits(norm, 10)
            ),
        ));
    }
}

/// `mimic-joint`: twinloop does not couple mimic joints.
fn check_mimic(j: &Joint, out: &mut Vec<Finding>) {
    let kind = j.kind.urdf_name();
    if let Some(m) = &j.mimic {
        let how = format!(
            "mimics \"{}\" (q = {} * q_{} + {})",
            m.joint,
            num(m.multiplier),
            m.joint,
            num(m.offset)
        );
        if j.kind == JointKind::Fixed {
            out.push(joint_finding(
                j,
                Severity::Info,
                codes::MIMIC_JOINT,
                format!("{how} but is fixed: the mimic has no effect"),
            ));
        } else {
            out.push(joint_finding(
                j,
                Severity::Warning,
                codes::MIMIC_JOINT,
                format!("{how}; twinloop's dynamics treats it as an independent {kind} joint"),
            ));
        }
    }
}

/// `mimic-joint` (warning): a mimic of a joint the file does not have.
fn check_mimic_target(robot: &Description, j: &Joint, out: &mut Vec<Finding>) {
    if let Some(m) = &j.mimic
        && robot.joint(&m.joint).is_none()
    {
        out.push(joint_finding(
            j,
            Severity::Warning,
            codes::MIMIC_JOINT,
            format!(
                "mimics \"{}\", which the file does not have: the mimic means nothing (twinloop's \
                 dynamics treats every mimic joint as independent anyway)",
                m.joint
            ),
        ));
    }
}

/// Principal moments of inertia (eigenvalues of the symmetric tensor), ascending.
///
/// Cyclic Jacobi rotations: exact on diagonal tensors (placeholders such as
/// ixx=iyy=1, izz=0 give an exact 0) and accurate to round-off on the rest.
pub fn principal_moments(inertia: &Inertia) -> [f64; 3] {
    let mut a = inertia.matrix();
    let scale: f64 = a.iter().flatten().map(|v| v * v).sum::<f64>();
    for _sweep in 0..32 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        if off <= scale * 1e-36 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            // Rotation angle that zeroes a[p][q]; t = tan(angle), the smaller root.
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = if theta.abs() > 1e150 {
                0.5 / theta
            } else {
                theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
            };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            a[p][p] -= t * apq;
            a[q][q] += t * apq;
            a[p][q] = 0.0;
            a[q][p] = 0.0;
            let r = 3 - p - q;
            let (arp, arq) = (a[r][p], a[r][q]);
            a[r][p] = c * arp - s * arq;
            a[p][r] = a[r][p];
            a[r][q] = s * arp + c * arq;
            a[q][r] = a[r][q];
        }
    }
    let mut d = [a[0][0], a[1][1], a[2][2]];
    d.sort_by(f64::total_cmp);
    d
}

/// A number for a message: 7 significant digits, no float noise.
fn num(x: f64) -> String {
    num_digits(x, 7)
}

fn num_digits(x: f64, digits: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{:.*e}", digits - 1, x).parse().unwrap_or(x);
    let mag = rounded.abs();
    if (1e-4..1e7).contains(&mag) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn principal_moments_of_a_rotated_box_are_its_diagonal() {
        let d = Inertia::solid_box(2.0, [0.1, 0.2, 0.3]);
        let r = crate::description::rpy_to_matrix([0.3, -0.7, 1.1]);
        let m = d.matrix();
        // R D R^T
        let mut rot = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                rot[i][j] = (0..3).map(|k| r[i][k] * m[k][k] * r[j][k]).sum();
            }
        }
        let got = principal_moments(&Inertia::from_matrix(rot));
        let mut want = [d.ixx, d.iyy, d.izz];
        want.sort_by(f64::total_cmp);
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-15, "{got:?} vs {want:?}");
        }
    }

    #[test]
    fn placeholder_gives_an_exact_zero() {
        assert_eq!(
            principal_moments(&Inertia::diagonal(1.0, 1.0, 0.0)),
            [0.0, 1.0, 1.0]
        );
    }

    #[test]
    fn numbers_print_without_noise() {
        assert_eq!(num(0.1 + 0.2), "0.3");
        assert_eq!(num(1e-9), "1e-9");
        assert_eq!(num(3.14747), "3.14747");
        assert_eq!(num(-2.5), "-2.5");
    }
}
