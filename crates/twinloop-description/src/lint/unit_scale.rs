//! Whether a description's numbers are in the wrong units by 1000x: lengths in
//! millimetres (a kid-size robot 500 m tall) or masses in grams (3000 kg). CAD
//! exporters write both; the file parses, and every answer computed from it is wrong
//! by orders of magnitude with nothing to say so.
//!
//! Two physical bounds, not a prior on what a humanoid weighs:
//! - size: no robot this toolkit models spans more than [`MAX_EXTENT_M`] (a 2 cm
//!   model in millimetres spans 20 m);
//! - bulk density: a robot's mass over the cube of its largest extent is far below
//!   that of water ([`MAX_BULK_DENSITY`]): a robot is limbs and air, not a solid block
//!   of its own size. The 31 bundled models are 9-62 kg/m^3 by that measure (SigmaBan
//!   9, H1 12, TALOS 21, NAO 29, OP2 62); in grams they are 9000-62000, nine times the
//!   bound at least. Only a robot over [`MIN_SUSPECT_MASS_KG`] is judged so: a compact
//!   2 kg test model can be as dense as aluminium, while every robot in grams (from
//!   0.1 kg up) weighs 100 kg or more; and one smaller than
//!   [`MIN_EXTENT_FOR_DENSITY_M`] (a single link) has too little size to judge by.

use super::{Finding, Severity, Subject, codes, num};
use crate::description::{Description, Pose};
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

/// The largest extent, m, of any robot description: beyond it the lengths are
/// millimetres (or centimetres).
pub const MAX_EXTENT_M: f64 = 20.0;

/// Water's density, kg/m^3: the upper bound of a robot's mass over the cube of its
/// largest extent, sixteen times the densest bundled model (OP2, 62).
pub const MAX_BULK_DENSITY: f64 = 1000.0;

/// Below this total mass, kg, the density bound is not applied: a small model may be
/// dense, and a robot written in grams is past it from 0.1 kg up.
pub const MIN_SUSPECT_MASS_KG: f64 = 100.0;

/// Below this extent, m, the density bound is not applied.
pub const MIN_EXTENT_FOR_DENSITY_M: f64 = 0.05;

/// Where each link's frame is at the zero configuration, with its rotation: from the
/// root link(s) along the joint origins.
fn link_frames(robot: &Description) -> Vec<Option<(Vector3<f64>, Matrix3<f64>)>> {
    let rot = |p: &Pose| {
        let r = p.rotation();
        Matrix3::from_fn(|i, j| r[i][j])
    };
    let mut at = vec![None; robot.links.len()];
    let mut stack: Vec<usize> = robot
        .root_links()
        .iter()
        .filter_map(|r| robot.link_index(r))
        .collect();
    for &r in &stack {
        at[r] = Some((Vector3::zeros(), Matrix3::identity()));
    }
    // Links and children by name, once: a search per link is quadratic in its size.
    let index: HashMap<&str, usize> = robot
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.as_str(), i))
        .collect();
    let mut children: HashMap<&str, Vec<&crate::Joint>> = HashMap::new();
    for j in &robot.joints {
        children.entry(j.parent.as_str()).or_default().push(j);
    }
    while let Some(l) = stack.pop() {
        let Some((p, r)) = at[l] else { continue };
        let name = robot.links[l].name.as_str();
        for j in children.get(name).into_iter().flatten() {
            if let Some(&c) = index.get(j.child.as_str())
                && at[c].is_none()
            {
                at[c] = Some((p + r * Vector3::from(j.origin.xyz), r * rot(&j.origin)));
                stack.push(c);
            }
        }
    }
    at
}

/// The robot's largest extent, m: the widest span along x, y or z of its link
/// frames, centres of mass and shape origins at the zero configuration.
pub fn extent(robot: &Description) -> f64 {
    let frames = link_frames(robot);
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for (link, frame) in robot.links.iter().zip(&frames) {
        let Some((p, r)) = frame else { continue };
        let points = std::iter::once(*p)
            .chain(
                link.inertial
                    .iter()
                    .map(|i| p + r * Vector3::from(i.origin.xyz)),
            )
            .chain(
                link.collisions
                    .iter()
                    .chain(&link.visuals)
                    .map(|s| p + r * Vector3::from(s.origin.xyz)),
            );
        for x in points.filter(|x| x.iter().all(|v| v.is_finite())) {
            lo = lo.inf(&x);
            hi = hi.sup(&x);
        }
    }
    let span = hi - lo;
    if span.iter().all(|v| v.is_finite()) {
        span.max()
    } else {
        0.0
    }
}

/// The `unit-scale` error of `robot`, if its lengths or masses are 1000x off.
pub fn find(robot: &Description) -> Option<Finding> {
    let mut out = Vec::new();
    check(robot, &mut out);
    out.pop()
}

pub(super) fn check(robot: &Description, out: &mut Vec<Finding>) {
    let size = extent(robot);
    if size > MAX_EXTENT_M {
        // The joint that places a link furthest: the number to look at in the file.
        let Some(j) = robot.joints.iter().max_by(|a, b| {
            let n = |p: &Pose| Vector3::from(p.xyz).norm();
            n(&a.origin).total_cmp(&n(&b.origin))
        }) else {
            return;
        };
        let xyz = j.origin.xyz.map(num).join(" ");
        out.push(Finding {
            severity: Severity::Error,
            code: codes::UNIT_SCALE,
            subject: Subject::Joint,
            name: j.name.clone(),
            message: format!(
                "origin xyz=\"{xyz}\": the robot spans {} m, more than any robot ({} m); \
                 lengths are metres: are they in millimetres? (that would be {} m)",
                num(size),
                num(MAX_EXTENT_M),
                num(size / 1000.0)
            ),
        });
        return;
    }
    inertia_scale(robot, size, out);
    let mass = robot.total_mass();
    if size < MIN_EXTENT_FOR_DENSITY_M || !mass.is_finite() || mass < MIN_SUSPECT_MASS_KG {
        return;
    }
    let density = mass / size.powi(3);
    if density <= MAX_BULK_DENSITY {
        return;
    }
    let Some(heaviest) = robot
        .links
        .iter()
        .filter(|l| l.inertial.is_some())
        .max_by(|a, b| a.mass().total_cmp(&b.mass()))
    else {
        return;
    };
    out.push(Finding {
        severity: Severity::Error,
        code: codes::UNIT_SCALE,
        subject: Subject::Link,
        name: heaviest.name.clone(),
        message: format!(
            "mass {}: the robot's {} kg over its {} m size cubed is {} kg/m^3, a solid \
             block denser than water ({}; humanoids are 9-62); masses are kilograms: are \
             they in grams? (that would be {} kg)",
            num(heaviest.mass()),
            num(mass),
            num(size),
            num(density.round()),
            num(MAX_BULK_DENSITY),
            num(mass / 1000.0)
        ),
    });
}

/// How many times the robot's size (or [`MIN_GYRATION_BOUND_M`]) a link's radius of
/// gyration may be: a body's sqrt(I/m) is at most its own extent, which is at most the
/// robot's.
pub const MAX_GYRATION_OVER_SIZE: f64 = 30.0;

/// The smallest bound, m, on a radius of gyration: placeholder moments of 1 kg m^2
/// on a link of 10 g or more (OP2's head, a test's hand) pass here, as lint's
/// `inertia-not-positive-definite` reports them; moments in kg mm^2 (1e6x) put a
/// 50 g link with a 2 cm radius of gyration 20 m out.
pub const MIN_GYRATION_BOUND_M: f64 = 10.0;

/// A link whose moment of inertia over its mass puts its mass further from its centre
/// than the robot is large: sqrt(I/m) of a body is at most its extent, so the moments
/// are in g mm^2 (1e9x) or kg mm^2 (1e6x), or the mass is far too small (1e-12 kg under
/// a link's moments); the simulation of such a link is silently wrong. The bundled
/// models' largest ratio of sqrt(I/m) to their size is 17 (OP2's placeholder head
/// moments of 1 kg m^2, which lint reports); moments in kg mm^2 are 1000x theirs.
fn inertia_scale(robot: &Description, size: f64, out: &mut Vec<Finding>) {
    let bound = (size * MAX_GYRATION_OVER_SIZE).max(MIN_GYRATION_BOUND_M);
    for link in &robot.links {
        let Some(i) = &link.inertial else { continue };
        let moment = i.inertia.ixx.max(i.inertia.iyy).max(i.inertia.izz);
        if !(i.mass > 0.0 && moment > 0.0) {
            continue;
        }
        let gyration = (moment / i.mass).sqrt();
        if gyration.is_finite() && gyration <= bound {
            continue;
        }
        out.push(Finding {
            severity: Severity::Error,
            code: codes::UNIT_SCALE,
            subject: Subject::Link,
            name: link.name.clone(),
            message: format!(
                "inertia {} kg m^2 on mass {} kg puts the mass {} m from its centre \
                 (sqrt(I/m)), more than {} times the robot's {} m size: are the moments in \
                 g mm^2 or kg mm^2, or the mass in the wrong unit? (moments are kg m^2, \
                 masses kg)",
                num(moment),
                num(i.mass),
                num(gyration),
                num(MAX_GYRATION_OVER_SIZE),
                num(size)
            ),
        });
        return;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;

    fn scaled(robot: &Description, length: f64, mass: f64) -> Description {
        let mut r = robot.clone();
        for j in &mut r.joints {
            j.origin.xyz = j.origin.xyz.map(|v| v * length);
        }
        for l in &mut r.links {
            for s in l.collisions.iter_mut().chain(&mut l.visuals) {
                s.origin.xyz = s.origin.xyz.map(|v| v * length);
            }
            if let Some(i) = &mut l.inertial {
                i.origin.xyz = i.origin.xyz.map(|v| v * length);
                i.mass *= mass;
            }
        }
        r
    }

    fn findings(robot: &Description) -> Vec<Finding> {
        let mut out = Vec::new();
        check(robot, &mut out);
        out
    }

    #[test]
    fn millimetres_and_grams_are_found_and_metres_and_kilograms_pass() {
        let km20 = builtin::resolve("builtin:km20").unwrap();
        assert!(findings(&km20).is_empty());
        // Scaling lengths scales the extent exactly (every point is a joint offset sum).
        let e = extent(&km20);
        assert!((extent(&scaled(&km20, 1000.0, 1.0)) - 1000.0 * e).abs() < 1e-9 * e);
        let mm = findings(&scaled(&km20, 1000.0, 1.0));
        assert_eq!(mm.len(), 1);
        assert!(mm[0].message.contains("millimetres"), "{}", mm[0]);
        let grams = findings(&scaled(&km20, 1.0, 1000.0));
        assert_eq!(grams.len(), 1);
        assert!(grams[0].message.contains("grams"), "{}", grams[0]);
        // Both at once (a CAD export in mm and g): the lengths are named first.
        let both = findings(&scaled(&km20, 1000.0, 1000.0));
        assert!(both[0].message.contains("millimetres"), "{}", both[0]);
        // A robot ten times as heavy as km20 at the same size is still far from the bound.
        assert!(findings(&scaled(&km20, 1.0, 10.0)).is_empty());
    }
}
