//! Whether the robot as a floating base (twinloop's default) has a singular mass
//! matrix: the base rows of the mass matrix are the whole robot's spatial inertia,
//! singular when the robot has no mass or its rotational inertia about its CoM
//! is (all mass on one line, point masses only). Forward dynamics of such a
//! model has no solution.

use super::{
    EIGENVALUE_RELATIVE_TOLERANCE, Finding, Severity, Subject, codes, num, principal_moments,
};
use crate::description::{Description, Inertia, Pose};
use nalgebra::{Matrix3, Vector3};
use twinloop_spatial::Se3;

fn se3(p: &Pose) -> Se3 {
    let r = p.rotation();
    Se3::new(Matrix3::from_fn(|i, j| r[i][j]), Vector3::from(p.xyz))
}

/// The whole robot's spatial inertia in the frame of its root link(s), at the
/// zero configuration.
fn whole_robot(robot: &Description) -> twinloop_spatial::Inertia {
    let links = robot.links_by_name();
    let index = |name: &str| links.get(name).copied();
    let mut children: std::collections::HashMap<&str, Vec<&crate::Joint>> = Default::default();
    for j in &robot.joints {
        children.entry(j.parent.as_str()).or_default().push(j);
    }
    let mut total = twinloop_spatial::Inertia::ZERO;
    let mut seen = vec![false; robot.links.len()];
    let mut stack: Vec<(usize, Se3)> = robot
        .root_links()
        .iter()
        .filter_map(|r| index(r))
        .map(|l| (l, Se3::IDENTITY))
        .collect();
    while let Some((l, at)) = stack.pop() {
        if std::mem::replace(&mut seen[l], true) {
            continue;
        }
        if let Some(i) = robot.links[l].inertial {
            let m = i.inertia.matrix();
            let own = twinloop_spatial::Inertia::new(
                i.mass,
                Vector3::zeros(),
                Matrix3::from_fn(|r, c| m[r][c]),
            );
            total += own.transformed(&(at * se3(&i.origin)));
        }
        for j in children
            .get(robot.links[l].name.as_str())
            .into_iter()
            .flatten()
        {
            if let Some(c) = index(&j.child) {
                stack.push((c, at * se3(&j.origin)));
            }
        }
    }
    total
}

pub(super) fn check(robot: &Description, out: &mut Vec<Finding>) {
    if robot.base_armature > 0.0 {
        // The free joint's armature is on every base diagonal entry: never singular.
        return;
    }
    let total = whole_robot(robot);
    // Negative mass or moments are already errors on the links at fault.
    let message = if total.mass < 0.0 {
        return;
    } else if total.mass == 0.0 {
        "the robot has no mass: as a floating base (twinloop's default) its mass matrix is \
         singular and forward dynamics has no solution"
            .to_string()
    } else {
        let i = total.inertia;
        let moments = principal_moments(&Inertia::from_matrix(
            [0, 1, 2].map(|r| [0, 1, 2].map(|c| i[(r, c)])),
        ));
        let largest = moments.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
        if moments[0].abs() > EIGENVALUE_RELATIVE_TOLERANCE * largest {
            return;
        }
        format!(
            "the whole robot's principal moments about its CoM are {}, {}, {} kg m^2: as a \
             floating base (twinloop's default) its mass matrix is singular and forward \
             dynamics has no solution (with a fixed base it may be fine)",
            num(moments[0]),
            num(moments[1]),
            num(moments[2])
        )
    };
    out.push(Finding {
        severity: Severity::Warning,
        code: codes::SINGULAR_FLOATING_BASE,
        subject: Subject::Robot,
        name: robot.name.clone(),
        message,
    });
}
