//! What every command refuses in a description, and `model lint` reports as errors
//! (issue 29, class 3: lint must not say ok for a file the other commands refuse):
//! lengths or masses in the wrong unit ([`super::unit_scale`]), a name that cannot be
//! a CSV column, and a joint axis that is no direction the arithmetic can normalise.

use super::{Finding, Severity, Subject, codes, num};
use crate::description::Description;

/// The first refusal of `robot`, if any: what a command that loads it says.
pub fn find(robot: &Description) -> Option<Finding> {
    let mut out = Vec::new();
    check(robot, &mut out);
    inverted_limits(robot, &mut out);
    super::unit_scale::check(robot, &mut out);
    out.into_iter().next()
}

/// The refusals besides the unit scale (which `lint` checks on its own).
pub(super) fn check(robot: &Description, out: &mut Vec<Finding>) {
    let names = robot
        .links
        .iter()
        .map(|l| (Subject::Link, l.name.as_str()))
        .chain(
            robot
                .joints
                .iter()
                .map(|j| (Subject::Joint, j.name.as_str())),
        )
        .chain(
            robot
                .frames
                .iter()
                .map(|f| (Subject::Element, f.name.as_str())),
        );
    for (subject, name) in names {
        if let Some(why) = unsafe_name(name) {
            out.push(Finding {
                severity: Severity::Error,
                code: codes::UNSAFE_NAME,
                subject,
                name: name.to_string(),
                message: format!(
                    "the name {why}: it names CSV columns (q:NAME, NAME.x ..), where it would \
                     shift or split the columns; rename it"
                ),
            });
        }
    }
    for j in robot.joints.iter().filter(|j| {
        use crate::description::JointKind as K;
        matches!(
            j.kind,
            K::Revolute | K::Continuous | K::Prismatic | K::Planar
        )
    }) {
        let a = j.axis_or_default();
        let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        // Beyond these the square of the norm overflows or underflows: the axis divided
        // by it is no unit vector.
        if !(1e-100..=1e100).contains(&norm) {
            out.push(Finding {
                severity: Severity::Error,
                code: codes::BAD_AXIS,
                subject: Subject::Joint,
                name: j.name.clone(),
                message: format!(
                    "axis ({}, {}, {}) is no direction (its length is {}); write a unit vector",
                    num(a[0]),
                    num(a[1]),
                    num(a[2]),
                    num(norm)
                ),
            });
        }
    }
}

/// A joint whose lower limit is above its upper one has no position to take: the
/// simulator's clamp of a goal into the range has no answer (it panicked there).
pub(super) fn inverted_limits(robot: &Description, out: &mut Vec<Finding>) {
    for j in &robot.joints {
        if let Some(super::super::description::Limit {
            lower: Some(lo),
            upper: Some(hi),
            ..
        }) = j.limit
            && lo > hi
        {
            out.push(Finding {
                severity: Severity::Error,
                code: codes::LIMITS_INVERTED,
                subject: Subject::Joint,
                name: j.name.clone(),
                message: format!(
                    "lower limit {} is above upper limit {}: no position is within them; \
                     swap them",
                    num(lo),
                    num(hi)
                ),
            });
        }
    }
}

/// Why `name` cannot be a CSV column's part, if it cannot: a comma or a quote splits
/// or quotes the cell, a control character (a newline) breaks the row, and spaces at
/// either end are trimmed when the file is read back.
fn unsafe_name(name: &str) -> Option<String> {
    if let Some(c) = name
        .chars()
        .find(|c| *c == ',' || *c == '"' || c.is_control())
    {
        return Some(format!("{name:?} holds {c:?}"));
    }
    if name.trim() != name {
        return Some(format!("{name:?} starts or ends with a space"));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn robot(link: &str, axis: &str) -> Description {
        crate::urdf::from_str(&format!(
            "<robot name=\"r\"><link name=\"{link}\"><inertial><mass value=\"1\"/><inertia \
             ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>\
             </link><link name=\"b\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" \
             iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\
             <joint name=\"j\" type=\"continuous\"><parent link=\"{link}\"/><child link=\"b\"/>\
             <axis xyz=\"{axis}\"/></joint></robot>"
        ))
        .unwrap()
    }

    /// Issue 29, class 3: names that would shift CSV columns and axes no arithmetic can
    /// normalise are refused (what every command says, and lint reports as errors).
    #[test]
    fn unsafe_names_and_axes_are_refused() {
        assert!(find(&robot("a", "0 0 1")).is_none());
        assert!(
            find(&robot("a", "0 0 1e5")).is_none(),
            "long, but a direction"
        );
        for (link, axis, code, name) in [
            ("tor,so", "0 0 1", codes::UNSAFE_NAME, "tor,so"),
            ("say&quot;a", "0 0 1", codes::UNSAFE_NAME, "say\"a"),
            (" a", "0 0 1", codes::UNSAFE_NAME, " a"),
            ("a", "1e200 0 0", codes::BAD_AXIS, "j"),
            ("a", "1e-200 0 0", codes::BAD_AXIS, "j"),
        ] {
            let f = find(&robot(link, axis)).unwrap();
            assert_eq!((f.code, f.name.as_str()), (code, name), "{}", f.message);
            assert_eq!(f.severity, Severity::Error);
        }
    }
}
