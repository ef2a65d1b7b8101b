//! Which parts of a humanoid are its feet, legs, arms and torso, read from the tree
//! and the primitive geometry of the description (no names needed): the experiments
//! need them to stand the robot on the force plate and to pick the joints a pose
//! category moves.

use crate::error::IdentError;
use nalgebra::{Matrix3, Vector2, Vector3};
use twinloop_description::{Description, Geometry, Pose};
use twinloop_dynamics::{BASE, Data, Model};
use twinloop_spatial::Se3;

/// A rigid placement from a URDF pose.
pub fn pose_to_se3(p: &Pose) -> Se3 {
    let r = p.rotation();
    Se3::new(
        Matrix3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        ),
        Vector3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
    )
}

/// A foot: its link, the frame the dynamics model gives it, and its sole.
#[derive(Debug, Clone)]
pub struct Foot {
    /// Description link index (also `Model::links` index).
    pub link: usize,
    pub name: String,
    /// Frame index in `Model::frames`.
    pub frame: usize,
    /// Body the foot belongs to (never the base for a standing robot).
    pub body: usize,
    /// The direction, in the foot frame, that points down when the foot is flat.
    pub down: Vector3<f64>,
    /// The direction, in the foot frame, that points forward (world +x) when the
    /// robot stands in its neutral configuration.
    pub forward: Vector3<f64>,
    /// Sole contact points in the foot frame (corners of the convex contact patch,
    /// counter-clockwise seen from above when the foot is flat).
    pub sole: Vec<Vector3<f64>>,
    /// Centre of the sole patch, in the foot frame.
    pub sole_center: Vector3<f64>,
    /// Sole length (along `forward`) and width, m.
    pub size: [f64; 2],
}

/// The parts of a humanoid the experiments use, as joint (body) indices.
#[derive(Debug, Clone)]
pub struct Anatomy {
    pub left_foot: Foot,
    pub right_foot: Foot,
    pub left_leg: Vec<usize>,
    pub right_leg: Vec<usize>,
    /// Joints between the base and where the arms branch off.
    pub torso: Vec<usize>,
    pub left_arm: Vec<usize>,
    pub right_arm: Vec<usize>,
    /// Everything else (head, neck, grippers not under an arm).
    pub other: Vec<usize>,
}

/// Points that bound a primitive shape (box corners, cylinder rims, sphere poles),
/// in the shape's own frame. `None` for a mesh (no size in the description).
fn primitive_points(g: &Geometry) -> Option<Vec<Vector3<f64>>> {
    let mut pts = Vec::new();
    match *g {
        Geometry::Box { size } => {
            let h = Vector3::new(size[0], size[1], size[2]) * 0.5;
            for sx in [-1.0, 1.0] {
                for sy in [-1.0, 1.0] {
                    for sz in [-1.0, 1.0] {
                        pts.push(Vector3::new(sx * h.x, sy * h.y, sz * h.z));
                    }
                }
            }
        }
        Geometry::Cylinder { radius, length } | Geometry::Capsule { radius, length } => {
            let extra = if matches!(g, Geometry::Capsule { .. }) {
                radius
            } else {
                0.0
            };
            for k in 0..16 {
                let a = std::f64::consts::TAU * k as f64 / 16.0;
                for z in [-0.5 * length, 0.5 * length] {
                    pts.push(Vector3::new(radius * a.cos(), radius * a.sin(), z));
                }
            }
            if extra > 0.0 {
                pts.push(Vector3::new(0.0, 0.0, 0.5 * length + extra));
                pts.push(Vector3::new(0.0, 0.0, -0.5 * length - extra));
            }
        }
        Geometry::Sphere { radius } => {
            for k in 0..3 {
                for s in [-1.0, 1.0] {
                    let mut p = Vector3::zeros();
                    p[k] = s * radius;
                    pts.push(p);
                }
            }
        }
        Geometry::Mesh { .. } => return None,
    }
    Some(pts)
}

/// Bounding points of every primitive collision shape of a link (visual shapes if it
/// has no primitive collision shape), in the link frame.
pub fn link_geometry_points(robot: &Description, link: usize) -> Vec<Vector3<f64>> {
    let l = &robot.links[link];
    let collect = |shapes: &[twinloop_description::Shape]| {
        let mut out = Vec::new();
        for s in shapes {
            if let Some(pts) = primitive_points(&s.geometry) {
                let x = pose_to_se3(&s.origin);
                out.extend(pts.iter().map(|p| x.act_point(p)));
            }
        }
        out
    };
    let c = collect(&l.collisions);
    if c.is_empty() { collect(&l.visuals) } else { c }
}

/// Placement of description link `l` in the world after forward kinematics.
pub fn link_placement(model: &Model, data: &Data, l: usize) -> Se3 {
    let info = &model.links[l];
    let parent = if info.body == BASE {
        data.base_placement
    } else {
        data.o_m_i[info.body]
    };
    parent * info.placement
}

/// Index of the frame of description link `l`.
pub fn link_frame(model: &Model, l: usize) -> usize {
    model
        .frames
        .iter()
        .position(|f| f.link == Some(l))
        .expect("every description link has a frame")
}

/// Convex hull of 2-D points (Andrew's monotone chain), counter-clockwise, no
/// collinear points; indices into `pts`.
pub fn convex_hull(pts: &[Vector2<f64>]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..pts.len()).collect();
    idx.sort_by(|&a, &b| {
        pts[a]
            .x
            .total_cmp(&pts[b].x)
            .then(pts[a].y.total_cmp(&pts[b].y))
    });
    idx.dedup_by(|a, b| (pts[*a] - pts[*b]).norm() < 1e-12);
    if idx.len() < 3 {
        return idx;
    }
    let cross = |o: usize, a: usize, b: usize| {
        let (oa, ob) = (pts[a] - pts[o], pts[b] - pts[o]);
        oa.x * ob.y - oa.y * ob.x
    };
    let mut hull: Vec<usize> = Vec::with_capacity(2 * idx.len());
    // Lower chain left to right, then upper chain right to left; the upper chain
    // never pops below `floor`, the points the lower chain settled.
    for &i in &idx {
        while hull.len() >= 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], i) <= 1e-15 {
            hull.pop();
        }
        hull.push(i);
    }
    let floor = hull.len() + 1;
    for &i in idx.iter().rev().skip(1) {
        while hull.len() >= floor && cross(hull[hull.len() - 2], hull[hull.len() - 1], i) <= 1e-15 {
            hull.pop();
        }
        hull.push(i);
    }
    hull.pop(); // the first point again
    hull
}

/// Signed distance from `p` to the boundary of the convex polygon `poly`
/// (counter-clockwise): positive inside, negative outside.
pub fn polygon_margin(poly: &[Vector2<f64>], p: &Vector2<f64>) -> f64 {
    if poly.len() < 3 {
        return f64::NEG_INFINITY;
    }
    let mut inside = f64::INFINITY;
    for k in 0..poly.len() {
        let a = poly[k];
        let b = poly[(k + 1) % poly.len()];
        let e = b - a;
        let len = e.norm();
        if len < 1e-15 {
            continue;
        }
        // Inward normal of a counter-clockwise edge is (-e.y, e.x).
        let d = (-e.y * (p.x - a.x) + e.x * (p.y - a.y)) / len;
        inside = inside.min(d);
    }
    if inside >= 0.0 {
        return inside;
    }
    // Outside: the true distance to the polygon (for reporting).
    let mut best = f64::INFINITY;
    for k in 0..poly.len() {
        let a = poly[k];
        let b = poly[(k + 1) % poly.len()];
        let e = b - a;
        let t = ((p - a).dot(&e) / e.norm_squared().max(1e-30)).clamp(0.0, 1.0);
        best = best.min((a + e * t - p).norm());
    }
    -best
}

/// Find the feet of a standing humanoid: in the neutral configuration, the two links
/// with primitive geometry reaching lowest, one on each side (y > 0 left). `feet`
/// names them explicitly instead (left, right).
fn find_feet(
    robot: &Description,
    model: &Model,
    data: &mut Data,
    feet: Option<(&str, &str)>,
) -> Result<(usize, usize), IdentError> {
    let q0 = model.neutral_configuration();
    twinloop_dynamics::forward_kinematics(model, data, &q0);
    let by_name = |n: &str| {
        robot.link_index(n).ok_or_else(|| {
            IdentError::new(format!("no link named \"{n}\" in the description")).option("feet")
        })
    };
    if let Some((l, r)) = feet {
        return Ok((by_name(l)?, by_name(r)?));
    }
    // Lowest geometry point of every link on a moving body.
    let mut lows: Vec<(usize, f64, f64)> = Vec::new(); // (link, lowest z, y of link origin)
    for l in 0..robot.links.len() {
        if model.links[l].body == BASE {
            continue;
        }
        let pts = link_geometry_points(robot, l);
        if pts.is_empty() {
            continue;
        }
        let x = link_placement(model, data, l);
        let z = pts
            .iter()
            .map(|p| x.act_point(p).z)
            .fold(f64::INFINITY, f64::min);
        lows.push((l, z, x.translation.y));
    }
    let pick = |left: bool| {
        lows.iter()
            .filter(|(_, _, y)| if left { *y > 1e-3 } else { *y < -1e-3 })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|t| t.0)
    };
    match (pick(true), pick(false)) {
        (Some(l), Some(r)) => Ok((l, r)),
        _ => Err(IdentError::new(
            "cannot find the feet: no link with primitive (box, cylinder, sphere) geometry on each \
             side (y > 0 left, y < 0 right) of the neutral configuration; name them (feet: LEFT,RIGHT)",
        )
        .option("feet")),
    }
}

/// The sole of a foot link: contact points from the primitive geometry of every link
/// welded to the foot's body, expressed in the foot frame.
fn make_foot(
    robot: &Description,
    model: &Model,
    data: &Data,
    link: usize,
) -> Result<Foot, IdentError> {
    let name = robot.links[link].name.clone();
    let body = model.links[link].body;
    if body == BASE {
        return Err(IdentError::new(format!(
            "\"{name}\" is welded to the base: a foot must move relative to the pelvis"
        ))
        .option("feet"));
    }
    let x_foot = link_placement(model, data, link);
    // Geometry of every link on the same body, in the foot frame.
    let mut pts: Vec<Vector3<f64>> = Vec::new();
    for l in 0..robot.links.len() {
        if model.links[l].body != body {
            continue;
        }
        let x = x_foot.inv_mul(&link_placement(model, data, l));
        pts.extend(
            link_geometry_points(robot, l)
                .iter()
                .map(|p| x.act_point(p)),
        );
    }
    if pts.is_empty() {
        return Err(IdentError::new(format!(
            "foot link \"{name}\" has no primitive collision or visual geometry (box, cylinder, sphere) \
             on its body: its sole cannot be found"
        ))
        .option("feet"));
    }
    // In the neutral configuration the sole is flat: "down" is world -z.
    let r0 = x_foot.rotation;
    let down = r0.tr_mul(&Vector3::new(0.0, 0.0, -1.0));
    let fwd = r0.tr_mul(&Vector3::new(1.0, 0.0, 0.0));
    // World-aligned coordinates about the foot origin.
    let w: Vec<Vector3<f64>> = pts.iter().map(|p| r0 * p).collect();
    let zmin = w.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let contact: Vec<Vector3<f64>> = w.iter().filter(|p| p.z <= zmin + 1e-3).copied().collect();
    let flat: Vec<Vector2<f64>> = contact.iter().map(|p| Vector2::new(p.x, p.y)).collect();
    let hull = convex_hull(&flat);
    let sole_w: Vec<Vector3<f64>> = hull
        .iter()
        .map(|&i| Vector3::new(flat[i].x, flat[i].y, zmin))
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in &sole_w {
        x0 = x0.min(p.x);
        x1 = x1.max(p.x);
        y0 = y0.min(p.y);
        y1 = y1.max(p.y);
    }
    let center_w = Vector3::new(0.5 * (x0 + x1), 0.5 * (y0 + y1), zmin);
    Ok(Foot {
        link,
        name,
        frame: link_frame(model, link),
        body,
        down,
        forward: fwd,
        sole: sole_w.iter().map(|p| r0.tr_mul(p)).collect(),
        sole_center: r0.tr_mul(&center_w),
        size: [x1 - x0, y1 - y0],
    })
}

/// Bodies on the path from the base to `body`, base side first.
fn path_to(model: &Model, body: usize) -> Vec<usize> {
    let mut p: Vec<usize> = model.ancestors(body).collect();
    p.reverse();
    p
}

impl Anatomy {
    /// Read the anatomy of a humanoid description. `feet` names the foot links
    /// (left, right) when the geometry does not make them obvious.
    pub fn detect(
        robot: &Description,
        model: &Model,
        feet: Option<(&str, &str)>,
    ) -> Result<Anatomy, IdentError> {
        let mut data = Data::new(model);
        let (lf, rf) = find_feet(robot, model, &mut data, feet)?;
        let q0 = model.neutral_configuration();
        twinloop_dynamics::forward_kinematics(model, &mut data, &q0);
        let left_foot = make_foot(robot, model, &data, lf)?;
        let right_foot = make_foot(robot, model, &data, rf)?;
        let left_leg = path_to(model, left_foot.body);
        let right_leg = path_to(model, right_foot.body);
        if left_leg.iter().any(|b| right_leg.contains(b)) {
            return Err(IdentError::new(format!(
                "the feet \"{}\" and \"{}\" share a joint: they are not two legs",
                left_foot.name, right_foot.name
            ))
            .option("feet"));
        }
        let nb = model.nbodies;
        let on_leg = |b: usize| left_leg.contains(&b) || right_leg.contains(&b);
        // Leaves of the upper body, with their side and chain length.
        let mut left_leaf: Option<(usize, usize, f64)> = None;
        let mut right_leaf: Option<(usize, usize, f64)> = None;
        let is_leaf = |b: usize| !model.parents.contains(&b);
        for b in 0..nb {
            if on_leg(b) || !is_leaf(b) {
                continue;
            }
            if model.ancestors(b).any(on_leg) {
                continue; // below a foot (toes)
            }
            let y = data.o_m_i[b].translation.y;
            let depth = model.ancestors(b).count();
            let better = |cur: &Option<(usize, usize, f64)>| match cur {
                None => true,
                Some((_, d, yy)) => depth > *d || (depth == *d && y.abs() > yy.abs()),
            };
            if y > 0.02 && better(&left_leaf) {
                left_leaf = Some((b, depth, y));
            } else if y < -0.02 && better(&right_leaf) {
                right_leaf = Some((b, depth, y));
            }
        }
        let mut torso = Vec::new();
        let mut left_arm = Vec::new();
        let mut right_arm = Vec::new();
        if let (Some((lb, _, _)), Some((rb, _, _))) = (left_leaf, right_leaf) {
            let lp = path_to(model, lb);
            let rp = path_to(model, rb);
            let common = lp.iter().zip(&rp).take_while(|(a, b)| a == b).count();
            torso = lp[..common].to_vec();
            // Each arm: the whole subtree of its first joint past the branch point.
            let subtree = |first: usize| {
                (0..nb)
                    .filter(|&b| model.ancestors(b).any(|a| a == first))
                    .collect::<Vec<_>>()
            };
            left_arm = subtree(lp[common]);
            right_arm = subtree(rp[common]);
        }
        let other = (0..nb)
            .filter(|b| {
                !on_leg(*b) && !torso.contains(b) && !left_arm.contains(b) && !right_arm.contains(b)
            })
            .collect();
        Ok(Anatomy {
            left_foot,
            right_foot,
            left_leg,
            right_leg,
            torso,
            left_arm,
            right_arm,
            other,
        })
    }

    pub fn foot(&self, left: bool) -> &Foot {
        if left {
            &self.left_foot
        } else {
            &self.right_foot
        }
    }

    pub fn leg(&self, left: bool) -> &[usize] {
        if left {
            &self.left_leg
        } else {
            &self.right_leg
        }
    }
}

/// World sole polygon of a foot placed at `x` (x, y of its contact points).
pub fn sole_polygon(foot: &Foot, x: &Se3) -> Vec<Vector2<f64>> {
    foot.sole
        .iter()
        .map(|p| {
            let w = x.act_point(p);
            Vector2::new(w.x, w.y)
        })
        .collect()
}

/// Convex hull of the given feet's sole polygons (the support polygon).
pub fn support_polygon(soles: &[Vec<Vector2<f64>>]) -> Vec<Vector2<f64>> {
    let all: Vec<Vector2<f64>> = soles.iter().flatten().copied().collect();
    convex_hull(&all).into_iter().map(|i| all[i]).collect()
}
