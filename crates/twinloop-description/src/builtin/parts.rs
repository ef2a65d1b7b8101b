//! Links made of primitive parts: each part a box, cylinder or sphere of uniform
//! density with its own mass; a link's inertial is the sum of its parts (parallel-axis
//! theorem, through [`twinloop_spatial::Inertia`]'s `+`), and every part is also a
//! visual, so what a viewer draws is what the dynamics weighs.

use crate::{Geometry, Inertia, Inertial, Link, Material, Pose, Shape};
use twinloop_spatial::{Inertia as SpatialInertia, Matrix3, Vector3};

/// What a part is, for its colour in a viewer and for the mass tables in the docs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PartKind {
    Servo,
    Structure,
    Electronics,
    Battery,
    Foot,
}

impl PartKind {
    fn material(self) -> Material {
        let (name, rgba) = match self {
            PartKind::Servo => ("servo", [0.15, 0.15, 0.15, 1.0]),
            PartKind::Structure => ("structure", [0.75, 0.75, 0.78, 1.0]),
            PartKind::Electronics => ("electronics", [0.1, 0.45, 0.2, 1.0]),
            PartKind::Battery => ("battery", [0.8, 0.55, 0.1, 1.0]),
            PartKind::Foot => ("foot", [0.55, 0.55, 0.6, 1.0]),
        };
        Material {
            name: name.to_string(),
            rgba: Some(rgba),
            texture: None,
        }
    }
}

/// One primitive with a mass, placed in its link's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    pub name: String,
    pub mass: f64,
    /// Placement of the primitive's centre (cylinders: axis along its z) in the link frame.
    pub origin: Pose,
    pub geometry: Geometry,
    pub kind: PartKind,
}

impl Part {
    pub fn boxed(name: &str, kind: PartKind, mass: f64, size: [f64; 3], xyz: [f64; 3]) -> Part {
        Part {
            name: name.to_string(),
            mass,
            origin: Pose::from_xyz(xyz),
            geometry: Geometry::Box { size },
            kind,
        }
    }

    /// Rotational inertia about the part's own centre, in its own axes.
    pub fn central_inertia(&self) -> Inertia {
        match self.geometry {
            Geometry::Box { size } => Inertia::solid_box(self.mass, size),
            Geometry::Cylinder { radius, length } => {
                Inertia::solid_cylinder(self.mass, radius, length)
            }
            Geometry::Sphere { radius } => Inertia::solid_sphere(self.mass, radius),
            // The seed robots use only the three primitives above. A capsule is counted
            // as the cylinder URDF writes it as; a mesh has no known shape, so it counts
            // as a point mass.
            Geometry::Capsule { radius, length } => {
                Inertia::solid_cylinder(self.mass, radius, length)
            }
            Geometry::Mesh { .. } => Inertia::default(),
        }
    }

    /// The part as a rigid body in the link frame.
    pub fn spatial_inertia(&self) -> SpatialInertia {
        let i = self.central_inertia().matrix();
        let r = self.origin.rotation();
        let rot = Matrix3::from_fn(|a, b| r[a][b]);
        let local = Matrix3::from_fn(|a, b| i[a][b]);
        let [x, y, z] = self.origin.xyz;
        SpatialInertia::new(
            self.mass,
            Vector3::new(x, y, z),
            rot * local * rot.transpose(),
        )
    }
}

/// Rigid composition `a * b` of two placements (b given in a's frame).
pub fn compose(a: &Pose, b: &Pose) -> Pose {
    let (ra, rb) = (a.rotation(), b.rotation());
    let mut r = [[0.0; 3]; 3];
    let mut p = a.xyz;
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = (0..3).map(|k| ra[i][k] * rb[k][j]).sum();
        }
        p[i] += (0..3).map(|k| ra[i][k] * b.xyz[k]).sum::<f64>();
    }
    // With one side unrotated the other's rotation is kept as it was written.
    if b.rotation() == Pose::IDENTITY.rotation() {
        a.with_xyz(clean3(p))
    } else if a.rotation() == Pose::IDENTITY.rotation() {
        b.with_xyz(clean3(p))
    } else {
        Pose::from_matrix(clean3(p), r)
    }
}

/// A frame whose z axis is `z` and whose x axis is `x` (both unit, orthogonal; the
/// seed robots only use the coordinate axes), at `xyz`.
pub fn frame(xyz: [f64; 3], x: [f64; 3], z: [f64; 3]) -> Pose {
    let y = [
        z[1] * x[2] - z[2] * x[1],
        z[2] * x[0] - z[0] * x[2],
        z[0] * x[1] - z[1] * x[0],
    ];
    let r = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]];
    let rpy = crate::matrix_to_rpy(r);
    Pose::new(xyz, rpy.map(clean))
}

/// Snap values within 1e-15 of 0 to 0 and round-off around multiples of pi/2 to them,
/// so rotations made of coordinate axes read as the numbers a person would write.
fn clean(v: f64) -> f64 {
    let q = v / std::f64::consts::FRAC_PI_2;
    if (q - q.round()).abs() < 1e-12 {
        // `+ 0.0` turns -0 into 0, so the URDF reads "0", not "-0".
        q.round() * std::f64::consts::FRAC_PI_2 + 0.0
    } else {
        v
    }
}

fn clean3(v: [f64; 3]) -> [f64; 3] {
    v.map(|x| if x.abs() < 1e-15 { 0.0 } else { x })
}

/// The sum of parts as a URDF inertial: mass, CoM, and the inertia about the CoM in the
/// link's axes (off-diagonal terms kept; those below 1e-15 of the largest moment are
/// round-off of axis-aligned rotations and are written as 0).
pub fn inertial_of(parts: &[Part]) -> Inertial {
    let total = parts
        .iter()
        .fold(SpatialInertia::ZERO, |acc, p| acc + p.spatial_inertia());
    let scale = total.inertia.abs().max();
    let m = Matrix3::from_fn(|a, b| {
        let v = total.inertia[(a, b)];
        if v.abs() <= 1e-15 * scale { 0.0 } else { v }
    });
    let c = total.com;
    Inertial {
        origin: Pose::from_xyz(clean3([c.x, c.y, c.z])),
        mass: total.mass,
        inertia: Inertia::from_matrix([
            [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
            [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
            [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
        ]),
    }
}

/// A link under construction: its parts and its collision primitives.
#[derive(Debug, Clone, Default)]
pub struct LinkParts {
    pub name: String,
    pub parts: Vec<Part>,
    pub collisions: Vec<(Pose, Geometry)>,
}

impl LinkParts {
    pub fn new(name: &str) -> Self {
        LinkParts {
            name: name.to_string(),
            ..Default::default()
        }
    }

    pub fn with(mut self, part: Part) -> Self {
        self.parts.push(part);
        self
    }

    pub fn with_all(mut self, parts: Vec<Part>) -> Self {
        self.parts.extend(parts);
        self
    }

    pub fn collision_box(mut self, size: [f64; 3], xyz: [f64; 3]) -> Self {
        self.collisions
            .push((Pose::from_xyz(xyz), Geometry::Box { size }));
        self
    }

    pub fn collision_sphere(mut self, radius: f64, xyz: [f64; 3]) -> Self {
        self.collisions
            .push((Pose::from_xyz(xyz), Geometry::Sphere { radius }));
        self
    }

    pub fn mass(&self) -> f64 {
        self.parts.iter().map(|p| p.mass).sum()
    }

    /// The description link: inertial from the parts, one visual per part, the collisions.
    pub fn to_link(&self) -> Link {
        let mut link = Link::new(self.name.clone());
        link.inertial = Some(inertial_of(&self.parts));
        link.visuals = self
            .parts
            .iter()
            .map(|p| Shape {
                name: Some(p.name.clone()),
                origin: p.origin,
                geometry: p.geometry.clone(),
                material: Some(p.kind.material()),
            })
            .collect();
        link.collisions = self
            .collisions
            .iter()
            .map(|(origin, geometry)| Shape {
                name: None,
                origin: *origin,
                geometry: geometry.clone(),
                material: None,
            })
            .collect();
        link
    }
}
