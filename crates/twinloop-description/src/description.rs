//! The robot description: what a URDF says, kept per link and per joint.
//!
//! This is a description, not a dynamics model: links joined by fixed joints stay
//! distinct here so that identified masses and CoMs can be written back per link.
//! `twinloop-dynamics` compiles a description into its own `Model`.

/// A rigid placement: a translation and a rotation.
///
/// The rotation is kept as a matrix (row-major), so an orientation given as a
/// quaternion, an axis and angle or a frame (MJCF) is kept exactly as its matrix,
/// with no detour through angles. A pose made from roll-pitch-yaw (URDF's
/// `rpy`: fixed-axis X, then Y, then Z; R = Rz(yaw) Ry(pitch) Rx(roll)) also
/// keeps those three numbers, so that a URDF written back carries the numbers
/// the user wrote; otherwise [`Pose::rpy`] derives them from the matrix
/// ([`matrix_to_rpy`], backward stable) when a URDF is written.
#[derive(Debug, Clone, Copy)]
pub struct Pose {
    pub xyz: [f64; 3],
    rotation: [[f64; 3]; 3],
    /// The roll-pitch-yaw the rotation was made from, if it was.
    rpy: Option<[f64; 3]>,
}

/// Two poses are equal when they place the same: translation and rotation
/// matrix (how the rotation was first written does not count).
impl PartialEq for Pose {
    fn eq(&self, other: &Pose) -> bool {
        self.xyz == other.xyz && self.rotation == other.rotation
    }
}

impl Default for Pose {
    fn default() -> Self {
        Pose::IDENTITY
    }
}

const IDENTITY_MATRIX: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl Pose {
    pub const IDENTITY: Pose = Pose {
        xyz: [0.0; 3],
        rotation: IDENTITY_MATRIX,
        rpy: Some([0.0; 3]),
    };

    /// From a translation and roll-pitch-yaw (URDF's `<origin xyz rpy>`).
    pub fn new(xyz: [f64; 3], rpy: [f64; 3]) -> Self {
        Pose {
            xyz,
            rotation: rpy_to_matrix(rpy),
            rpy: Some(rpy),
        }
    }

    pub fn from_xyz(xyz: [f64; 3]) -> Self {
        Pose {
            xyz,
            ..Pose::IDENTITY
        }
    }

    pub fn is_identity(&self) -> bool {
        self.xyz == [0.0; 3] && self.rotation == IDENTITY_MATRIX
    }

    /// Rotation matrix (row-major), the pose's orientation as stored.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        self.rotation
    }

    /// Roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll), as URDF defines it): the
    /// numbers the pose was made from, or else derived from the matrix (without
    /// negative zeros), for writing a URDF.
    pub fn rpy(&self) -> [f64; 3] {
        self.rpy
            .unwrap_or_else(|| matrix_to_rpy(self.rotation).map(|v| v + 0.0))
    }

    /// The same placement with the translation replaced.
    pub fn with_xyz(self, xyz: [f64; 3]) -> Self {
        Pose { xyz, ..self }
    }

    /// Pose from a translation and a unit quaternion (w, x, y, z); the quaternion
    /// is normalised first (MJCF files carry non-unit quaternions).
    pub fn from_quaternion(xyz: [f64; 3], wxyz: [f64; 4]) -> Self {
        Pose::from_matrix(xyz, quaternion_to_matrix(wxyz))
    }

    /// Pose from a translation and a rotation matrix (row-major), kept as given.
    pub fn from_matrix(xyz: [f64; 3], r: [[f64; 3]; 3]) -> Self {
        Pose {
            xyz,
            rotation: r,
            rpy: None,
        }
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.xyz
            .iter()
            .chain(self.rotation.iter().flatten())
            .all(|v| v.is_finite())
            && self.rpy.is_none_or(|r| r.iter().all(|v| v.is_finite()))
    }
}

/// R = Rz(y) Ry(p) Rx(r), row-major.
pub fn rpy_to_matrix(rpy: [f64; 3]) -> [[f64; 3]; 3] {
    let (sr, cr) = rpy[0].sin_cos();
    let (sp, cp) = rpy[1].sin_cos();
    let (sy, cy) = rpy[2].sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// Inverse of [`rpy_to_matrix`], backward stable: `rpy_to_matrix` of the result
/// gives back `r` to rounding everywhere, the pitch +-90 deg singularity included.
///
/// Pitch comes from `atan2` of its sine and cosine (not `asin`, which loses half the
/// digits near +-90 deg); roll from the bottom row; yaw is then the rotation about z
/// that best maps the columns of Ry(pitch) Rx(roll) onto those of `r` (a 2-D
/// Procrustes fit), so any error in roll near the singularity, where only roll -
/// yaw or roll + yaw is defined, is absorbed by yaw instead of showing in the matrix.
pub fn matrix_to_rpy(r: [[f64; 3]; 3]) -> [f64; 3] {
    let cos_pitch = 0.5 * (r[0][0].hypot(r[1][0]) + r[2][1].hypot(r[2][2]));
    let pitch = (-r[2][0]).atan2(cos_pitch);
    let roll = r[2][1].atan2(r[2][2]);
    let (sp, cp) = pitch.sin_cos();
    let (sr, cr) = roll.sin_cos();
    // Top two rows of Ry(pitch) Rx(roll), column by column.
    let m = [[cp, sp * sr, sp * cr], [0.0, cr, -sr]];
    let (mut cross, mut dot) = (0.0, 0.0);
    for j in 0..3 {
        cross += m[0][j] * r[1][j] - m[1][j] * r[0][j];
        dot += m[0][j] * r[0][j] + m[1][j] * r[1][j];
    }
    [roll, pitch, cross.atan2(dot)]
}

/// Rotation matrix of a quaternion (w, x, y, z), normalised first.
pub fn quaternion_to_matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (w, x, y, z) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Symmetric 3x3 inertia tensor about the link's CoM, in the inertial frame
/// (URDF `<inertia>` fields).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Inertia {
    pub ixx: f64,
    pub ixy: f64,
    pub ixz: f64,
    pub iyy: f64,
    pub iyz: f64,
    pub izz: f64,
}

impl Inertia {
    pub fn diagonal(ixx: f64, iyy: f64, izz: f64) -> Self {
        Inertia {
            ixx,
            iyy,
            izz,
            ..Default::default()
        }
    }

    pub fn matrix(&self) -> [[f64; 3]; 3] {
        [
            [self.ixx, self.ixy, self.ixz],
            [self.ixy, self.iyy, self.iyz],
            [self.ixz, self.iyz, self.izz],
        ]
    }

    pub fn from_matrix(m: [[f64; 3]; 3]) -> Self {
        Inertia {
            ixx: m[0][0],
            ixy: 0.5 * (m[0][1] + m[1][0]),
            ixz: 0.5 * (m[0][2] + m[2][0]),
            iyy: m[1][1],
            iyz: 0.5 * (m[1][2] + m[2][1]),
            izz: m[2][2],
        }
    }

    /// Solid box of the given full edge lengths.
    pub fn solid_box(mass: f64, size: [f64; 3]) -> Self {
        let [x, y, z] = size;
        let k = mass / 12.0;
        Inertia::diagonal(
            k * (y * y + z * z),
            k * (x * x + z * z),
            k * (x * x + y * y),
        )
    }

    /// Solid cylinder along z.
    pub fn solid_cylinder(mass: f64, radius: f64, length: f64) -> Self {
        let side = mass * (3.0 * radius * radius + length * length) / 12.0;
        Inertia::diagonal(side, side, 0.5 * mass * radius * radius)
    }

    /// Solid sphere.
    pub fn solid_sphere(mass: f64, radius: f64) -> Self {
        let i = 0.4 * mass * radius * radius;
        Inertia::diagonal(i, i, i)
    }
}

/// URDF `<inertial>`: mass, CoM placement and inertia about the CoM in that
/// (possibly rotated) frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Inertial {
    pub origin: Pose,
    pub mass: f64,
    pub inertia: Inertia,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    Box {
        size: [f64; 3],
    },
    Cylinder {
        radius: f64,
        length: f64,
    },
    Sphere {
        radius: f64,
    },
    /// MJCF capsule along z (URDF has none: written as a cylinder plus a note).
    Capsule {
        radius: f64,
        length: f64,
    },
    /// A mesh by path as written (`package://...`, relative or `file://`).
    Mesh {
        filename: String,
        scale: Option<[f64; 3]>,
    },
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct Material {
    pub name: String,
    pub rgba: Option<[f64; 4]>,
    pub texture: Option<String>,
}

/// A `<visual>` or `<collision>` element.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    pub name: Option<String>,
    pub origin: Pose,
    pub geometry: Geometry,
    /// Visuals only: the material, by reference or inline.
    pub material: Option<Material>,
}

/// XML that twinloop does not interpret but must write back unchanged
/// (`<gazebo>`, `<transmission>`, `<sensor>`, vendor children of links/joints).
#[derive(Debug, Clone, PartialEq)]
pub struct RawXml(pub String);

#[derive(Debug, Clone, PartialEq, Default)]
pub struct Link {
    pub name: String,
    pub inertial: Option<Inertial>,
    pub visuals: Vec<Shape>,
    pub collisions: Vec<Shape>,
    /// Children of `<link>` that are not URDF, kept verbatim.
    pub extra: Vec<RawXml>,
    /// A link the MJCF reader put between two joints of one body (MuJoCo has no
    /// such body): massless by design, the body's mass is on the last link.
    pub between_joints: bool,
}

impl Link {
    pub fn new(name: impl Into<String>) -> Self {
        Link {
            name: name.into(),
            ..Default::default()
        }
    }

    pub fn mass(&self) -> f64 {
        self.inertial.map_or(0.0, |i| i.mass)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JointKind {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
    Floating,
    Planar,
    /// A ball joint (MJCF `type="ball"`): three rotational DoF about the joint's
    /// origin, configured by a unit quaternion. Not part of the URDF standard; written
    /// and read as `spherical` so a converted MJCF round-trips.
    Spherical,
}

impl JointKind {
    pub fn urdf_name(self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
            JointKind::Fixed => "fixed",
            JointKind::Floating => "floating",
            JointKind::Planar => "planar",
            JointKind::Spherical => "spherical",
        }
    }

    pub fn from_urdf_name(s: &str) -> Option<Self> {
        Some(match s {
            "revolute" => JointKind::Revolute,
            "continuous" => JointKind::Continuous,
            "prismatic" => JointKind::Prismatic,
            "fixed" => JointKind::Fixed,
            "floating" => JointKind::Floating,
            "planar" => JointKind::Planar,
            "spherical" => JointKind::Spherical,
            _ => return None,
        })
    }

    /// Degrees of freedom of the velocity (floating: 6).
    pub fn nv(self) -> usize {
        match self {
            JointKind::Revolute | JointKind::Continuous | JointKind::Prismatic => 1,
            JointKind::Fixed => 0,
            JointKind::Floating => 6,
            JointKind::Planar | JointKind::Spherical => 3,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Limit {
    pub lower: Option<f64>,
    pub upper: Option<f64>,
    pub effort: Option<f64>,
    pub velocity: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointDynamics {
    pub damping: Option<f64>,
    pub friction: Option<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Mimic {
    pub joint: String,
    pub multiplier: f64,
    pub offset: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SafetyController {
    pub soft_lower_limit: Option<f64>,
    pub soft_upper_limit: Option<f64>,
    pub k_position: Option<f64>,
    pub k_velocity: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Calibration {
    pub rising: Option<f64>,
    pub falling: Option<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    pub parent: String,
    pub child: String,
    /// Placement of the joint frame (= child link frame at zero) in the parent link frame.
    pub origin: Pose,
    /// Axis in the joint frame as written; URDF's default is (1, 0, 0).
    /// `None` when the file has no `<axis>` (written back the same way).
    pub axis: Option<[f64; 3]>,
    pub limit: Option<Limit>,
    pub dynamics: Option<JointDynamics>,
    pub mimic: Option<Mimic>,
    pub safety_controller: Option<SafetyController>,
    pub calibration: Option<Calibration>,
    /// Children of `<joint>` that are not URDF, kept verbatim.
    pub extra: Vec<RawXml>,
    /// Rotor inertia reflected to the joint (MJCF `armature`), added to the
    /// mass matrix diagonal; 0 when the file gives none (URDF has no such field).
    pub armature: f64,
    /// Joint spring (MJCF `stiffness`, N m/rad or N/m): a passive torque
    /// `-stiffness (q - springref)`; 0 when the file gives none (URDF has none).
    pub stiffness: f64,
    /// The spring's rest position (MJCF `springref`, in q's units: rad or m).
    pub springref: f64,
}

impl Joint {
    pub fn new(
        name: impl Into<String>,
        kind: JointKind,
        parent: impl Into<String>,
        child: impl Into<String>,
    ) -> Self {
        Joint {
            name: name.into(),
            kind,
            parent: parent.into(),
            child: child.into(),
            origin: Pose::IDENTITY,
            axis: None,
            limit: None,
            dynamics: None,
            mimic: None,
            safety_controller: None,
            calibration: None,
            extra: Vec::new(),
            armature: 0.0,
            stiffness: 0.0,
            springref: 0.0,
        }
    }

    /// The axis the dynamics uses: as written, or URDF's default (1, 0, 0).
    pub fn axis_or_default(&self) -> [f64; 3] {
        self.axis.unwrap_or([1.0, 0.0, 0.0])
    }
}

/// A named frame attached to a link (sensor mounts, MJCF sites, frames made in code).
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub name: String,
    pub link: String,
    pub origin: Pose,
}

/// An element the reader or the dynamics leave out: where it is and what is lost.
#[derive(Debug, Clone, PartialEq)]
pub struct FileNote {
    /// The element, e.g. `<spatial name="tendon1"> in <tendon>`.
    pub element: String,
    /// 1-based line in the file.
    pub line: u32,
    /// What is left out.
    pub what: String,
}

/// Top-level elements kept verbatim, with their position among the links and
/// joints so a written URDF keeps the original order.
#[derive(Debug, Clone, PartialEq)]
pub struct Extension {
    /// Element name (`gazebo`, `transmission`, `sensor`, ...).
    pub tag: String,
    pub xml: RawXml,
}

/// One top-level item in document order, so a written URDF reads like the input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Item {
    Link(usize),
    Joint(usize),
    Material(usize),
    Extension(usize),
    Frame(usize),
}

/// A robot description.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Description {
    pub name: String,
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
    /// Top-level `<material>` definitions.
    pub materials: Vec<Material>,
    pub frames: Vec<Frame>,
    pub extensions: Vec<Extension>,
    /// Document order of everything above; items missing here are written after.
    pub order: Vec<Item>,
    /// Attributes of `<robot>` other than `name` (xmlns declarations, version), verbatim.
    pub robot_attributes: Vec<(String, String)>,
    /// Elements of the file that change the physics but that twinloop's rigid-body
    /// dynamics leave out (MJCF tendons, equality constraints, ...): `lint` warns.
    pub unmodeled: Vec<FileNote>,
    /// Visual-only details the reader could not take and read past (a URDF
    /// `<texture/>` without a file, a mesh scale with a fourth number): `lint` warns.
    pub ignored: Vec<FileNote>,
    /// The floating base's armature: an MJCF `<joint type="free" armature>` (or one a
    /// `<default>` class gives it; `<freejoint>` takes no defaults and has none).
    /// MuJoCo adds it to the six diagonal entries of the mass matrix that belong to
    /// the free joint; 0 otherwise (URDF has no such field).
    pub base_armature: f64,
    /// The floating base's viscous damping (MJCF free joint `damping`): MuJoCo's
    /// passive force `-damping qvel` on the six base velocities; 0 otherwise.
    pub base_damping: f64,
    /// Gravity in the world frame when the file sets it (MJCF `<option gravity>`,
    /// zero with `<flag gravity="disable">`); `None` means (0, 0, -[`crate::GRAVITY`]).
    pub gravity: Option<[f64; 3]>,
    /// Which joints play the parts experiments need, from a robot profile's `[roles]`
    /// (no URDF or MJCF holds them: empty for a description read from one).
    pub roles: JointRoles,
}

/// The joint roles an experiment asks for, by the names a robot profile's `[roles]`
/// table uses ([`JointRoles::NAMES`]), each a joint of the description.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointRoles {
    /// Joint names, in the order of [`JointRoles::NAMES`].
    pub joints: [Option<String>; 8],
}

impl JointRoles {
    /// The roles: ankle pitch and roll, hip roll and knee, each left and right.
    pub const NAMES: [&'static str; 8] = [
        "left_ankle_pitch",
        "right_ankle_pitch",
        "left_ankle_roll",
        "right_ankle_roll",
        "left_hip_roll",
        "right_hip_roll",
        "left_knee",
        "right_knee",
    ];

    /// The joint playing `role` (one of [`JointRoles::NAMES`]), if named.
    pub fn get(&self, role: &str) -> Option<&str> {
        let k = JointRoles::NAMES.iter().position(|n| *n == role)?;
        self.joints[k].as_deref()
    }

    /// Name the joint playing `role`; `false` if `role` is not one of the names.
    pub fn set(&mut self, role: &str, joint: impl Into<String>) -> bool {
        match JointRoles::NAMES.iter().position(|n| *n == role) {
            Some(k) => {
                self.joints[k] = Some(joint.into());
                true
            }
            None => false,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.joints.iter().all(|j| j.is_none())
    }
}

impl Description {
    pub fn link(&self, name: &str) -> Option<&Link> {
        self.links.iter().find(|l| l.name == name)
    }

    pub fn link_mut(&mut self, name: &str) -> Option<&mut Link> {
        self.links.iter_mut().find(|l| l.name == name)
    }

    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Every link's index by name, built once for a walk over the tree (a
    /// [`Description::link_index`] per joint is quadratic in the robot's size).
    pub fn links_by_name(&self) -> std::collections::HashMap<&str, usize> {
        self.links
            .iter()
            .enumerate()
            .map(|(i, l)| (l.name.as_str(), i))
            .collect()
    }

    pub fn joint(&self, name: &str) -> Option<&Joint> {
        self.joints.iter().find(|j| j.name == name)
    }

    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Sum of all link masses (dummy frame links included, as a scale would weigh them).
    pub fn total_mass(&self) -> f64 {
        self.links.iter().map(Link::mass).sum()
    }

    /// Links that are no joint's child. A valid tree has exactly one.
    pub fn root_links(&self) -> Vec<&str> {
        // A set of children, not a search of the joints per link: linear in the
        // robot's size (a 100 000-link chain took minutes).
        let children: std::collections::HashSet<&str> =
            self.joints.iter().map(|j| j.child.as_str()).collect();
        self.links
            .iter()
            .filter(|l| !children.contains(l.name.as_str()))
            .map(|l| l.name.as_str())
            .collect()
    }

    /// The joint whose child is `link`, if any.
    pub fn parent_joint(&self, link: &str) -> Option<&Joint> {
        self.joints.iter().find(|j| j.child == link)
    }

    /// Items in document order: the recorded order, then anything added since.
    pub fn items_in_order(&self) -> Vec<Item> {
        let mut seen_l = vec![false; self.links.len()];
        let mut seen_j = vec![false; self.joints.len()];
        let mut seen_m = vec![false; self.materials.len()];
        let mut seen_e = vec![false; self.extensions.len()];
        let mut seen_f = vec![false; self.frames.len()];
        let mut out = Vec::new();
        for &it in &self.order {
            let slot = match it {
                Item::Link(i) => seen_l.get_mut(i),
                Item::Joint(i) => seen_j.get_mut(i),
                Item::Material(i) => seen_m.get_mut(i),
                Item::Extension(i) => seen_e.get_mut(i),
                Item::Frame(i) => seen_f.get_mut(i),
            };
            if let Some(s) = slot
                && !*s
            {
                *s = true;
                out.push(it);
            }
        }
        out.extend(
            (0..self.materials.len())
                .filter(|&i| !seen_m[i])
                .map(Item::Material),
        );
        out.extend(
            (0..self.links.len())
                .filter(|&i| !seen_l[i])
                .map(Item::Link),
        );
        out.extend(
            (0..self.joints.len())
                .filter(|&i| !seen_j[i])
                .map(Item::Joint),
        );
        out.extend(
            (0..self.frames.len())
                .filter(|&i| !seen_f[i])
                .map(Item::Frame),
        );
        out.extend(
            (0..self.extensions.len())
                .filter(|&i| !seen_e[i])
                .map(Item::Extension),
        );
        out
    }
}
