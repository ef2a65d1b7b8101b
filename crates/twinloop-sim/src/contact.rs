//! Ground contact: points on the robot's collision primitives against the plane z = 0.
//!
//! The model is a compliant one, chosen over hard constraints (MuJoCo's soft
//! constraints, an LCP) for three reasons: it is the ground model of seed 003, it has
//! no solver iterations (so a step costs the same every time and is fast), and its
//! stiffness and damping are physical parameters a user can identify. Its known
//! weakness, a stiff spring needing a small step, is removed by treating the contact
//! stiffness and damping implicitly in the step (see `Simulator::step`).
//!
//! Normal: a spring-damper on the penetration, never pulling. Tangential: a stick
//! spring anchored where the point first touched, plus damping; when the spring force
//! exceeds `mu` times the normal force the point slides and the anchor follows it.
//! The anchor is what keeps a standing robot from creeping, which a velocity-only
//! (regularised Coulomb) friction cannot do.

use nalgebra::Vector3;
use twinloop_description::{Description, Geometry};
use twinloop_dynamics::{BASE, Model};

/// A contact point fixed on a body: a corner (radius 0) or the centre of a sphere.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactPoint {
    /// Body index, or `BASE`.
    pub body: usize,
    /// Description link the point belongs to.
    pub link: usize,
    /// Position in the body frame.
    pub local: Vector3<f64>,
    /// Sphere radius (0 for a corner): the contact is the sphere's lowest point.
    pub radius: f64,
}

/// Contact parameters (per point).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Normal stiffness, N/m.
    pub stiffness: f64,
    /// Normal damping, N s/m.
    pub damping: f64,
    /// Tangential (stick) stiffness and damping.
    pub tangential_stiffness: f64,
    pub tangential_damping: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
}

impl ContactParams {
    /// Defaults scaled to the robot: the weight on `points` points sinks `sink` metres
    /// (1 mm by default), critically damped for the mass per point.
    pub fn for_robot(total_mass: f64, points: usize, sink: f64) -> Self {
        let per_point = total_mass / points.max(1) as f64;
        let k = per_point * twinloop_description::GRAVITY / sink;
        let d = 2.0 * (k * per_point).sqrt();
        ContactParams {
            stiffness: k,
            damping: d,
            tangential_stiffness: k,
            tangential_damping: d,
            friction: 1.0,
        }
    }
}

/// Runtime state of one point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactState {
    pub active: bool,
    pub sliding: bool,
    /// Where the tangential spring is anchored on the ground (world x, y).
    pub anchor: [f64; 2],
    /// Last force on the point (world), N.
    pub force: Vector3<f64>,
    /// Last world position of the contact point.
    pub position: Vector3<f64>,
}

/// Points of every collision primitive of the robot: the 8 corners of a box, the
/// centre of a sphere, 8 points on each rim of a cylinder, the two end spheres of a
/// capsule. Meshes give none (their files are not read); list such links in the
/// returned names so the caller can say so.
pub fn contact_points(robot: &Description, model: &Model) -> (Vec<ContactPoint>, Vec<String>) {
    let mut out = Vec::new();
    let mut mesh_only = Vec::new();
    for (li, link) in robot.links.iter().enumerate() {
        let info = &model.links[li];
        if info.body == BASE && !model.is_floating() {
            continue; // welded to the world: never moves
        }
        let mut had_primitive = false;
        for shape in &link.collisions {
            let pose = twinloop_dynamics::model::pose_to_se3(&shape.origin);
            let place = info.placement * pose;
            let mut push = |p: Vector3<f64>, radius: f64| {
                out.push(ContactPoint {
                    body: info.body,
                    link: li,
                    local: place.act_point(&p),
                    radius,
                });
            };
            match &shape.geometry {
                Geometry::Box { size } => {
                    had_primitive = true;
                    let h = Vector3::new(size[0], size[1], size[2]) * 0.5;
                    for sx in [-1.0, 1.0] {
                        for sy in [-1.0, 1.0] {
                            for sz in [-1.0, 1.0] {
                                push(Vector3::new(sx * h.x, sy * h.y, sz * h.z), 0.0);
                            }
                        }
                    }
                }
                Geometry::Sphere { radius } => {
                    had_primitive = true;
                    push(Vector3::zeros(), *radius);
                }
                Geometry::Cylinder { radius, length } => {
                    had_primitive = true;
                    for z in [-0.5 * length, 0.5 * length] {
                        for k in 0..8 {
                            let a = k as f64 * std::f64::consts::TAU / 8.0;
                            push(Vector3::new(radius * a.cos(), radius * a.sin(), z), 0.0);
                        }
                    }
                }
                Geometry::Capsule { radius, length } => {
                    had_primitive = true;
                    push(Vector3::new(0.0, 0.0, -0.5 * length), *radius);
                    push(Vector3::new(0.0, 0.0, 0.5 * length), *radius);
                }
                Geometry::Mesh { .. } => {}
            }
        }
        if !had_primitive
            && link
                .collisions
                .iter()
                .any(|c| matches!(c.geometry, Geometry::Mesh { .. }))
        {
            mesh_only.push(link.name.clone());
        }
    }
    (out, mesh_only)
}
