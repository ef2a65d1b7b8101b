//! MJCF reader: a MuJoCo model read as MuJoCo's compiler reads it, as far as a
//! rigid-body model goes: the masses, inertias, kinematics and gravity of the
//! description are those of MuJoCo's compiled model, and a joint position is
//! MuJoCo's `qpos` (docs/mjcf.md; checked against MuJoCo on dm_control's and
//! gymnasium's models by crates/twinloop-dynamics/tests/mjcf_mujoco.rs).
//!
//! # How MJCF maps onto a [`Description`]
//!
//! - Every `<body>` becomes a [`Link`] of the body's name (unnamed bodies get
//!   `body<N>`), in a tree that follows the body nesting. The link frame is the
//!   body frame, except that it sits at the last hinge's `pos` (see below).
//! - Top-level bodies: one with a `<freejoint/>` (or `<joint type="free">`) as its
//!   only joint is the floating base: no joint, no `world` link (twinloop adds the
//!   floating base itself when it compiles the dynamics); its `pos`/`quat` are
//!   MuJoCo's initial qpos and are dropped. One jointless body at the origin is
//!   simply the root. Otherwise a link `world` is added and every top-level body
//!   hangs from it at its `pos`/`quat`. When every top-level body is free, the
//!   one with the most bodies is the robot and the others are props (a ball)
//!   left out with an `unmodeled-element` note each. Beside a free robot, a welded
//!   top-level body with no joint and no mass in its subtree (Apptronik Apollo's
//!   `world_link`) is left out too, noted in [`Description::ignored`] (or in
//!   `unmodeled` when it holds collision geoms); one with mass, or a free joint
//!   beside a hinged top-level body, is an error (one floating tree per file).
//! - A body's joints, in order: `hinge` becomes [`JointKind::Revolute`] when
//!   limited (the `range`, converted from degrees unless `<compiler
//!   angle="radian">`) and [`JointKind::Continuous`] otherwise; `slide` becomes
//!   [`JointKind::Prismatic`]; `ball` becomes [`JointKind::Spherical`] (its
//!   `ref` ignored and its cone `range` not kept, as MuJoCo's qpos0 and the
//!   dynamics have them). MuJoCo applies a body's joints
//!   one after the other in the body frame as moved by the ones before; each
//!   joint but the last gets a massless link `<body>_<joint>`. A body without a
//!   joint is attached by a fixed joint named `<body>_fixed`. Joint names are
//!   MJCF's, or `<body>_joint` (`<body>_joint2`, ...) for unnamed ones. "Limited"
//!   follows MuJoCo: `limited="true"`, or `"auto"`/absent with a `range` when
//!   `autolimits` is on (its default). `actuatorfrcrange` gives the limit's
//!   effort (the larger magnitude; an actuator on the joint lowers it to its
//!   `forcerange`, or a `<motor>`'s `ctrlrange` times its gear, when those are limited),
//!   `damping` and `frictionloss` the
//!   [`JointDynamics`], `armature` [`Joint::armature`]. The axis is normalised.
//!   `ref` goes into the joint's origin (a turn or shift of `-ref` along the
//!   axis), so that q is MuJoCo's qpos; `stiffness` and `springref` give
//!   [`Joint::stiffness`] and [`Joint::springref`] (a ball's spring is not kept:
//!   noted in [`Description::unmodeled`]).
//! - A hinge `pos` (a point on the axis, in the body frame) is handled by putting
//!   the joint's link frame at that point, axes unchanged: everything placed in
//!   the body (inertial, geoms, sites, child bodies) is shifted by minus the last
//!   hinge's `pos`. The kinematics are exactly MuJoCo's; only the link frame
//!   differs from the body frame. (A slide keeps the anchor before it.)
//! - Mass properties (modules `inertia` and `mesh`): `<inertial pos quat mass
//!   diaginertia|fullinertia>` as written; a body without one (or every body with
//!   `inertiafromgeom="true"`) gets MuJoCo's sum of its geoms in
//!   `inertiagrouprange` (box, sphere, capsule, cylinder, ellipsoid, solid or
//!   `shellinertia`; STL and OBJ meshes), each of its `mass` or `density`. Then
//!   `boundmass`, `boundinertia`, `balanceinertia` and, over the whole model,
//!   `settotalmass`.
//! - Geoms as shapes: `box` (half sizes, written as full sizes), `sphere`,
//!   `cylinder` and `capsule` (radius and half-length; the [`Geometry`] holds the
//!   full length), and `mesh` by asset name (the asset's `file` with `meshdir` or
//!   `assetdir` in front, and its `scale`). `fromto` is turned into a position and
//!   orientation (box and ellipsoid get a square cross-section of `size[0]`, as
//!   in MuJoCo). `plane`, `hfield`, `ellipsoid` and `sdf` geoms are not shapes. A
//!   geom is a visual if its `group` is 0, 1 or 2 (the groups MuJoCo's viewer
//!   shows by default) and a collision shape if its `contype` or `conaffinity` is
//!   not 0 or a `<contact><pair>` puts it against a world geom such as a scene's
//!   floor (twinloop collides shapes with its ground only: such a pair's sole
//!   touches that ground, Apollo's soles collide only through pairs; a pair of two
//!   robot geoms is a self-collision, left out), so Menagerie's `visual`/`collision` classes land where expected. A
//!   visual's material is the geom's `material` asset (name and rgba) or, failing
//!   that, its `rgba`.
//! - `<site>` becomes a [`Frame`] on the body's link (unnamed: `<body>_site<N>`).
//! - `<default>` classes (nested, `class` and `childclass`) apply to joints,
//!   geoms, sites, meshes and materials, and orientations may be given as `quat`
//!   (normalised), `axisangle`, `euler` (with `eulerseq`), `xyaxes` or `zaxis`.
//! - `<include file>` at the top level splices the file's sections in place
//!   (module `include`); `<option gravity>` and `<flag gravity="disable">` set
//!   [`Description::gravity`].
//! - Read past, and listed in [`Description::unmodeled`] for `lint`: tendons,
//!   equality constraints, actuators that drive no joint, sensors at sites.
//!   Ignored: cameras, lights, other actuators and sensors, contact settings,
//!   keyframes, and geoms and sites attached to the world. `<replicate>` is
//!   expanded as MuJoCo does (replica `i` at the offset and rotation applied `i`
//!   times, names suffixed with `sep` and the padded index).
//!   `<composite>` and `<flexcomp>` (soft bodies, cables, particle sets) are
//!   read past and listed in [`Description::unmodeled`] too; `<attach>` and
//!   nested includes are errors rather than silently dropped bodies.
//! - `<frame>`: its placement is composed onto the bodies, geoms, sites and
//!   frames inside it, and its `childclass` applies to them.

use crate::description::*;
mod hull;
pub(crate) mod include;
mod inertia;
mod mesh;

use crate::error::DescriptionError;
use crate::xml::{
    Places, error_at, error_at_attr, opt_array, parse_array, parse_numbers, read_text, required,
    validate_placed,
};
use inertia::{MassProps, Solid};
use roxmltree::{Document, Node};
use std::collections::HashMap;
use std::path::Path;

/// Read an MJCF model from text. Errors name the line, column and element.
/// `<include>` needs a directory: use [`read_file`] for models that include files.
pub fn from_str(text: &str) -> Result<Description, DescriptionError> {
    let doc = crate::xml::parse_xml(text)?;
    from_document(&doc, None)
}

/// Read an MJCF file (and the files it includes); errors carry the file path.
pub fn read_file(path: impl AsRef<Path>) -> Result<Description, DescriptionError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    let doc = crate::xml::parse_xml(&text).map_err(|e| e.in_file(path))?;
    from_document(&doc, path.parent()).map_err(|e| e.in_file(path))
}

use inertia::{Mat, Vec3};

const IDENTITY: Mat = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A placement: translation and rotation (of `<frame>`s around an element).
type Xf = (Vec3, Mat);

/// No enclosing frame.
const NO_FRAME: Xf = ([0.0; 3], IDENTITY);

/// `(pos, rot)` given inside frame `f`, in the frame's parent.
fn compose(f: &Xf, pos: Vec3, rot: Mat) -> Xf {
    (add(&f.0, &mat_vec(&f.1, &pos)), mat_mul(&f.1, &rot))
}

/// An element seen through the `<frame>`s and `<replicate>`s around it: the
/// element, their placement, the `childclass` in force and the name suffix of
/// its replica (`""` outside any `<replicate>`).
/// The joints from a body's parent to it, in order, each with its child link: one
/// per MuJoCo joint (a link `NAME_JOINT` between two, the body's own after the last)
/// or one fixed joint when the body has none. `parent` is the parent link and its
/// offset, `(pos, rot)` the body's placement in the parent body's frame.
fn joint_chain<'a, 'i>(
    node: Node<'a, 'i>,
    name: &str,
    (parent_link, parent_offset): (String, Vec3),
    (pos, rot): Xf,
    joints: Vec<BodyJoint<'a, 'i>>,
) -> Vec<(Joint, Node<'a, 'i>)> {
    let mut chain = Vec::new();
    // Placement of the next joint frame's base in the previous link frame.
    let mut at = sub(&pos, &parent_offset);
    let mut r = rot;
    let mut prev = (parent_link, [0.0; 3]);
    let n = joints.len();
    for (k, bj) in joints.into_iter().enumerate() {
        let child = if k + 1 == n {
            name.to_string()
        } else {
            format!("{name}_{}", bj.joint.name)
        };
        let axis = bj.joint.axis_or_default();
        let mut xyz = add(&at, &mat_vec(&r, &sub(&bj.anchor, &prev.1)));
        if bj.hinge {
            r = mat_mul(&r, &axis_angle(&axis, -bj.reference));
        } else {
            xyz = add(&xyz, &mat_vec(&r, &axis.map(|a| -bj.reference * a)));
        }
        let mut j = bj.joint;
        j.parent = std::mem::take(&mut prev.0);
        j.child = child.clone();
        j.origin = pose(xyz, &r);
        chain.push((j, bj.node));
        prev = (child, bj.anchor);
        (at, r) = ([0.0; 3], IDENTITY);
    }
    if n == 0 {
        let mut j = Joint::new(
            format!("{name}_fixed"),
            JointKind::Fixed,
            prev.0,
            name.to_string(),
        );
        j.origin = pose(at, &r);
        chain.push((j, node));
    }
    chain
}

type Framed<'a, 'i> = (Node<'a, 'i>, Xf, Option<String>, String);

/// Most elements one body's or the world's `<replicate>`s may expand to.
const MAX_REPLICAS: usize = 100_000;

/// Deepest nesting of `<frame>` elements followed.
const MAX_FRAME_DEPTH: usize = 1000;

/// Longest chain of default classes followed (a guard; class chains are trees).
const MAX_DEPTH: usize = 100_000;

/// A body still to read: its parent link (name, and the offset of that link's
/// frame from its body frame) and the `childclass` in force.
struct Pending<'a, 'i> {
    node: Node<'a, 'i>,
    parent: Option<(String, Vec3)>,
    childclass: Option<String>,
    /// Placement of the `<frame>`s around the body in its parent body.
    frame: Xf,
    /// Name suffix of the replica the body is in (`<replicate>`).
    suffix: String,
}

fn mat_mul(a: &Mat, b: &Mat) -> Mat {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

fn mat_vec(a: &Mat, v: &Vec3) -> Vec3 {
    [
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    ]
}

fn sub(a: &Vec3, b: &Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn add(a: &Vec3, b: &Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn dot(a: &Vec3, b: &Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: &Vec3, b: &Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: &Vec3) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|`, or `None` for a (near) zero vector.
fn unit(a: &Vec3) -> Option<Vec3> {
    let n = norm(a);
    (n > 1e-12 && n.is_finite()).then(|| [a[0] / n, a[1] / n, a[2] / n])
}

/// Rotation by `angle` about the unit `axis` (Rodrigues).
fn axis_angle(axis: &Vec3, angle: f64) -> Mat {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    let [x, y, z] = *axis;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// The smallest rotation taking +z to the unit vector `z` (MuJoCo's `zaxis`).
fn z_to(z: &Vec3) -> Mat {
    let ez = [0.0, 0.0, 1.0];
    let c = cross(&ez, z);
    match unit(&c) {
        Some(axis) => axis_angle(&axis, dot(&ez, z).clamp(-1.0, 1.0).acos()),
        None if z[2] < 0.0 => axis_angle(&[1.0, 0.0, 0.0], std::f64::consts::PI),
        None => IDENTITY,
    }
}

/// A pose from a translation (without negative zeros) and a rotation matrix.
fn pose(xyz: Vec3, r: &Mat) -> Pose {
    Pose::from_matrix(xyz.map(|v| v + 0.0), *r)
}

/// A hinge or slide joint of a body: the joint (axis, limits, dynamics), its
/// element, its anchor in the body frame (a hinge's `pos`; a slide keeps the
/// anchor before it) and its `ref` (radians for a hinge).
struct BodyJoint<'a, 'i> {
    joint: Joint,
    node: Node<'a, 'i>,
    anchor: Vec3,
    hinge: bool,
    reference: f64,
}

/// `<compiler>` settings that change how numbers are read.
struct Compiler {
    degrees: bool,
    /// `eulerseq`: axis per angle, lowercase = rotating axes, uppercase = fixed.
    eulerseq: [u8; 3],
    autolimits: bool,
    meshdir: Option<String>,
    inertia_from_geom: FromGeom,
    /// `inertiagrouprange`: the geom groups that count for a body's inertia.
    inertia_groups: [i64; 2],
    bound_mass: f64,
    bound_inertia: f64,
    balance_inertia: bool,
    /// `settotalmass`: every body's mass and inertia scaled to give this total.
    total_mass: Option<f64>,
}

/// `inertiafromgeom`: when a body's mass properties come from its geoms.
#[derive(Clone, Copy, PartialEq)]
enum FromGeom {
    /// Never: a body without `<inertial>` is massless.
    False,
    /// Always, overriding `<inertial>`.
    True,
    /// When the body has no `<inertial>` (MuJoCo's default).
    Auto,
}

/// A default class: its parent and its element templates (`<joint>`, `<geom>`, ...).
struct Class<'a, 'i> {
    parent: Option<String>,
    elements: Vec<Node<'a, 'i>>,
}

#[derive(Clone)]
struct MeshAsset {
    file: Option<String>,
    scale: Option<Vec3>,
    /// `inertia`: how MuJoCo counts the mesh's volume (legacy, exact, convex, shell).
    inertia: Option<String>,
}

struct Reader<'a, 'i> {
    /// The model file's directory: where mesh paths start.
    dir: Option<std::path::PathBuf>,
    compiler: Compiler,
    classes: HashMap<String, Class<'a, 'i>>,
    meshes: HashMap<String, MeshAsset>,
    materials: HashMap<String, [f64; 4]>,
    robot: Description,
    places: Places<'a, 'i>,
    unnamed_bodies: usize,
    /// The replica suffix of the body being read: appended to the names given in
    /// the file (bodies, joints, sites, geoms), as MuJoCo's `<replicate>` does.
    suffix: String,
    /// Geoms a `<contact><pair>` puts against a world geom (the floor): they collide
    /// with twinloop's ground whatever their `contype` and `conaffinity` (Apptronik
    /// Apollo's soles touch the floor only so).
    paired: std::collections::HashSet<&'a str>,
    /// The files the `<include>`s bring in: every loop over an element's
    /// children reads them through [`include::Includes::elements`].
    includes: include::Includes<'a, 'i>,
}

/// Where an attribute's value came from: the element itself or a default class.
type Found<'a, 'i> = (Node<'a, 'i>, &'a str);

/// The sections of `<mujoco>` in MuJoCo's schema (XML reference, "MJCF elements").
const SECTIONS: &[&str] = &[
    "compiler",
    "option",
    "size",
    "visual",
    "statistic",
    "default",
    "extension",
    "custom",
    "asset",
    "worldbody",
    "contact",
    "deformable",
    "equality",
    "tendon",
    "actuator",
    "sensor",
    "keyframe",
    "include",
];

/// What a `<body>` (or `<worldbody>`) may hold in MuJoCo's schema.
const BODY_CHILDREN: &[&str] = &[
    "inertial",
    "joint",
    "freejoint",
    "geom",
    "site",
    "camera",
    "light",
    "body",
    "frame",
    "replicate",
    "composite",
    "flexcomp",
    "plugin",
    "attach",
    "include",
];

const ORIENTATIONS: [&str; 5] = ["quat", "axisangle", "euler", "xyaxes", "zaxis"];

/// Read an MJCF document; `dir` is the directory `<include>` paths are relative to.
pub(crate) fn from_document(
    doc: &Document,
    dir: Option<&Path>,
) -> Result<Description, DescriptionError> {
    let root = doc.root_element();
    if root.tag_name().name() != "mujoco" {
        return Err(error_at(
            root,
            format!(
                "root element is <{}>: an MJCF model has <mujoco>",
                crate::xml::qualified_name(root)
            ),
        ));
    }
    let texts = include::read_includes(root, dir)?;
    let mut docs = Vec::with_capacity(texts.len());
    for (path, text) in &texts {
        docs.push(crate::xml::parse_xml(text).map_err(|e| e.in_file(path))?);
    }
    let _files = crate::xml_origin::register(&docs, &texts);
    let includes = include::Includes::new(root, &docs);
    let sections = includes.elements(root);
    let mut reader = Reader::new(root, includes);
    reader.dir = dir.map(Path::to_path_buf);
    reader.read(root, &sections)?;
    Ok(reader.robot)
}

impl<'a, 'i> Reader<'a, 'i> {
    fn new(root: Node<'a, 'i>, includes: include::Includes<'a, 'i>) -> Self {
        Reader {
            includes,
            dir: None,
            compiler: Compiler {
                degrees: true,
                eulerseq: *b"xyz",
                autolimits: true,
                meshdir: None,
                inertia_from_geom: FromGeom::Auto,
                inertia_groups: [0, 5],
                bound_mass: 0.0,
                bound_inertia: 0.0,
                balance_inertia: false,
                total_mass: None,
            },
            classes: HashMap::new(),
            meshes: HashMap::new(),
            materials: HashMap::new(),
            robot: Description {
                name: root.attribute("model").unwrap_or_default().to_string(),
                ..Default::default()
            },
            places: Places {
                robot: root,
                links: Vec::new(),
                joints: Vec::new(),
            },
            unnamed_bodies: 0,
            suffix: String::new(),
            paired: Default::default(),
        }
    }

    /// The sections of `<mujoco>` (includes spliced in): settings, defaults,
    /// assets, then the bodies; last the compiler's `settotalmass`.
    fn read(
        &mut self,
        root: Node<'a, 'i>,
        sections: &[Node<'a, 'i>],
    ) -> Result<(), DescriptionError> {
        self.settings(sections)?;
        let top = self.top_bodies(sections)?;
        if top.is_empty() {
            return Err(error_at(root, "no <body> in <worldbody>"));
        }
        let (robot_name, props, empties) = self.props(&top)?;
        let trees: Vec<Framed> = top
            .iter()
            .filter(|t| !props.contains(&t.0) && !empties.contains(&t.0))
            .cloned()
            .collect();
        let world = self.needs_world_link(&trees)?;
        if world {
            self.robot.order.push(Item::Link(self.robot.links.len()));
            self.places.links.push(root);
            self.robot.links.push(Link::new("world"));
        }
        let mut aside = self.trees(top, &props, &empties, world)?;
        aside = self.drop_empty(aside, &empties, &robot_name)?;
        let prop_mass: f64 = aside.iter().map(|(_, d)| d.total_mass()).sum();
        let scale = match self.compiler.total_mass {
            Some(total) => self.set_total_mass(total, prop_mass),
            None => 1.0,
        };
        for (node, prop) in &aside {
            self.note_prop(*node, prop, scale, &robot_name);
        }
        for &s in sections {
            self.unmodeled(s);
            if s.tag_name().name() == "actuator" {
                self.actuator_limits(s)?;
            }
            if !SECTIONS.contains(&s.tag_name().name()) {
                self.unknown(s);
            }
        }
        validate_placed(&self.robot, &self.places)
    }

    /// What the bodies depend on, in the order MuJoCo applies it: compiler, option
    /// and contact pairs, then every default class, then the assets.
    fn settings(&mut self, sections: &[Node<'a, 'i>]) -> Result<(), DescriptionError> {
        for &s in sections {
            match s.tag_name().name() {
                "compiler" => self.compiler(s)?,
                "option" => self.option(s)?,
                "contact" => {
                    let pairs = ground_pairs(&self.includes, s, sections);
                    self.paired.extend(pairs);
                }
                _ => {}
            }
        }
        for &s in sections {
            if s.tag_name().name() == "default" {
                let name = s.attribute("class").unwrap_or("main").to_string();
                self.default_class(s, name)?;
            }
        }
        for &s in sections {
            if s.tag_name().name() == "asset" {
                self.assets(s)?;
            }
        }
        Ok(())
    }

    /// The top-level bodies of every `<worldbody>`, frames opened; soft bodies and
    /// unknown elements noted, `<attach>` and `<include>` refused.
    fn top_bodies(
        &mut self,
        sections: &[Node<'a, 'i>],
    ) -> Result<Vec<Framed<'a, 'i>>, DescriptionError> {
        let mut top: Vec<Framed> = Vec::new();
        for &s in sections {
            if s.tag_name().name() != "worldbody" {
                continue;
            }
            for (c, xf, cc, sfx) in self.through_frames(s, None, "")? {
                match c.tag_name().name() {
                    "body" => top.push((c, xf, cc, sfx)),
                    "composite" | "flexcomp" => self.soft_body(c),
                    "attach" => return Err(error_at(c, "<attach> is not supported")),
                    t if !BODY_CHILDREN.contains(&t) => self.unknown(c),
                    _ => {} // world geoms, sites, lights, cameras
                }
            }
        }
        Ok(top)
    }

    /// Read each top-level tree into the robot; a prop (or an empty body) is read
    /// aside into a description of its own, returned with its node.
    fn trees(
        &mut self,
        top: Vec<Framed<'a, 'i>>,
        props: &[Node<'a, 'i>],
        empties: &[Node<'a, 'i>],
        world: bool,
    ) -> Result<Vec<(Node<'a, 'i>, Description)>, DescriptionError> {
        // One top-level tree after the other in file order (unnamed bodies are
        // numbered in that order), each depth first, children in file order, with
        // an explicit stack: deep nesting must not become deep recursion. A prop
        // is read aside, for its mass and the note that it is left out.
        let mut aside: Vec<(Node, Description)> = Vec::new();
        for (node, frame, childclass, suffix) in top {
            let prop = props.contains(&node) || empties.contains(&node);
            let saved = prop.then(|| {
                let places = Places {
                    robot: self.places.robot,
                    links: Vec::new(),
                    joints: Vec::new(),
                };
                (
                    std::mem::take(&mut self.robot),
                    std::mem::replace(&mut self.places, places),
                )
            });
            let mut pending = vec![Pending {
                node,
                parent: (world && !prop).then(|| ("world".to_string(), [0.0; 3])),
                childclass,
                frame,
                suffix,
            }];
            while let Some(p) = pending.pop() {
                self.body(p, &mut pending)?;
            }
            if let Some((robot, places)) = saved {
                aside.push((node, std::mem::replace(&mut self.robot, robot)));
                self.places = places;
            }
        }
        Ok(aside)
    }

    /// The element children of `node` with every `<frame>` and `<replicate>`
    /// opened: each with the placement of the frames around it (in `node`'s
    /// frame), the `childclass` in force (a frame's own, else `cc`) and its name
    /// suffix (`suffix`, the enclosing body's, after those of the replicas it is in).
    fn through_frames(
        &self,
        node: Node<'a, 'i>,
        cc: Option<&str>,
        suffix: &str,
    ) -> Result<Vec<Framed<'a, 'i>>, DescriptionError> {
        let mut out = Vec::new();
        // (element, enclosing placement, childclass, suffix, depth), in file order.
        let mut stack: Vec<(Node, Xf, Option<String>, String, usize)> = self
            .includes
            .elements(node)
            .into_iter()
            .map(|c| (c, NO_FRAME, cc.map(str::to_string), suffix.to_string(), 0))
            .collect();
        stack.reverse();
        while let Some((c, xf, cc, sfx, depth)) = stack.pop() {
            let tag = c.tag_name().name();
            if tag != "frame" && tag != "replicate" {
                out.push((c, xf, cc, sfx));
                continue;
            }
            if depth >= MAX_FRAME_DEPTH {
                return Err(error_at(c, format!("<{tag}>s nested too deep")));
            }
            if stack.len() + out.len() > MAX_REPLICAS {
                return Err(error_at(
                    c,
                    format!("<replicate>s expand to more than {MAX_REPLICAS} elements"),
                ));
            }
            let children = self.includes.elements(c);
            if tag == "replicate" {
                for (inner, name) in self.replicas(c, &xf)?.into_iter().rev() {
                    for &k in children.iter().rev() {
                        stack.push((k, inner, cc.clone(), format!("{name}{sfx}"), depth + 1));
                    }
                }
                continue;
            }
            let pos = opt_array::<3>(c, "pos")?.unwrap_or([0.0; 3]);
            let inner = compose(&xf, pos, self.orientation(c, "frame", None)?);
            let cc = self.childclass(c, cc)?;
            for k in children.into_iter().rev() {
                stack.push((k, inner, cc.clone(), sfx.clone(), depth + 1));
            }
        }
        Ok(out)
    }

    /// MuJoCo's `<replicate count sep offset (orientation)>`: replica `i` (from 0)
    /// is placed at `T^i` with `T` the offset and rotation, and its names get
    /// `sep` and `i` padded to the digits of `count`.
    fn replicas(&self, r: Node<'a, 'i>, xf: &Xf) -> Result<Vec<(Xf, String)>, DescriptionError> {
        let count = required(r, "count")?;
        let n: usize = match count.trim().parse::<u64>() {
            Ok(n) if (1..=MAX_REPLICAS as u64).contains(&n) => n as usize,
            Ok(n) if n > MAX_REPLICAS as u64 => {
                return Err(error_at_attr(
                    r,
                    "count",
                    format!(
                        "{n} replicas are more than the {MAX_REPLICAS} a description may make \
                         (a bound on the loader's work and memory)"
                    ),
                ));
            }
            _ => {
                return Err(error_at_attr(
                    r,
                    "count",
                    format!(
                        "\"{count}\" is not a replica count: a whole number from 1 to {MAX_REPLICAS}"
                    ),
                ));
            }
        };
        let offset = opt_array::<3>(r, "offset")?.unwrap_or([0.0; 3]);
        let rot = self.orientation(r, "frame", None)?;
        let sep = r.attribute("sep").unwrap_or("");
        let width = n.to_string().len();
        let mut at = *xf;
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            out.push((at, format!("{sep}{i:0width$}")));
            at = compose(&at, offset, rot);
        }
        Ok(out)
    }

    /// Free-floating props beside the robot. When every top-level body is free
    /// (its only joint a free joint), the robot is the one with the most bodies in
    /// its tree (the first in file order on a tie) and the others, such as the
    /// ball of dm_control's quadruped and dog, are props. When some are not free
    /// (welded or jointed to the world: an arm on a table) and those have more
    /// bodies together than the largest free tree, they are the robot and every
    /// free tree is a prop (pybullet's striker and thrower with their objects);
    /// otherwise nothing is a prop and `needs_world_link` refuses the file.
    /// MuJoCo couples separate trees only through contact, so the robot's mass
    /// matrix and bias forces do not depend on the props. Beside free trees, the
    /// welded top-level bodies without a joint in their subtree are candidates for
    /// empty static bodies (Apptronik Apollo's `world_link`), read aside and left
    /// out if they weigh nothing ([`Self::drop_empty`]). Returns the robot's name
    /// for the notes, the props' bodies and the empty candidates.
    #[allow(clippy::type_complexity)]
    fn props(
        &self,
        top: &[Framed<'a, 'i>],
    ) -> Result<(String, Vec<Node<'a, 'i>>, Vec<Node<'a, 'i>>), DescriptionError> {
        let none = Ok((String::new(), Vec::new(), Vec::new()));
        if top.len() < 2 {
            return none;
        }
        let (mut free, mut fixed) = (Vec::new(), Vec::new());
        for (b, _, _, _) in top {
            let js: Vec<Node> = self
                .includes
                .elements(*b)
                .into_iter()
                .filter(|c| matches!(c.tag_name().name(), "joint" | "freejoint"))
                .collect();
            if js.len() == 1 && self.joint_type(js[0], None)? == "free" {
                free.push(*b);
            } else {
                fixed.push(*b);
            }
        }
        let size = |b: &Node<'a, 'i>| {
            let all = self.includes.descendants(*b);
            all.iter().filter(|d| d.has_tag_name("body")).count()
        };
        let Some(largest) = free
            .iter()
            .copied()
            .reduce(|a, b| if size(&b) > size(&a) { b } else { a })
        else {
            return none;
        };
        let jointless = |b: &Node<'a, 'i>| {
            let all = self.includes.descendants(*b);
            !all.iter()
                .any(|d| d.has_tag_name("joint") || d.has_tag_name("freejoint"))
        };
        if !fixed.is_empty() && fixed.iter().map(size).sum::<usize>() > size(&largest) {
            let robot = "the robot (the bodies held by the world)".to_string();
            return Ok((robot, free, Vec::new()));
        }
        if fixed.iter().all(jointless) {
            let name = largest.attribute("name").unwrap_or("body").to_string();
            let props = free.into_iter().filter(|b| *b != largest).collect();
            return Ok((format!("the robot \"{name}\""), props, fixed));
        }
        none
    }

    /// The empty static bodies among the trees read aside (`empties`, see
    /// [`Self::props`]): each is left out with a note if it weighs nothing (MuJoCo
    /// welds it to the world, where it moves nothing); one with mass is a second
    /// body tree beside the floating robot, which twinloop refuses. Returns the rest.
    fn drop_empty(
        &mut self,
        aside: Vec<(Node<'a, 'i>, Description)>,
        empties: &[Node<'a, 'i>],
        robot: &str,
    ) -> Result<Vec<(Node<'a, 'i>, Description)>, DescriptionError> {
        let mut rest = Vec::with_capacity(aside.len());
        for (node, d) in aside {
            if !empties.contains(&node) {
                rest.push((node, d));
                continue;
            }
            let name = d.links.first().map_or("", |l| l.name.as_str());
            if d.total_mass() > 0.0 {
                return Err(error_at(
                    node,
                    format!(
                        "a second top-level body beside {robot}: \"{name}\" weighs {:.6} kg; \
                         twinloop models one floating body tree per file (a body beside it is \
                         left out only when it has no mass and no joint)",
                        d.total_mass()
                    ),
                ));
            }
            let geoms = d.links.iter().map(|l| l.collisions.len()).sum::<usize>();
            let (line, _) = crate::xml::position(node.document(), node.range().start);
            let mut what = format!(
                "empty static body \"{name}\" ({} bod{}, no mass, no joint) beside {robot}: \
                 MuJoCo welds it to the world, where it changes nothing; twinloop leaves it out",
                d.links.len(),
                if d.links.len() == 1 { "y" } else { "ies" }
            );
            let note = FileNote {
                element: crate::xml::element_path(node),
                line,
                what: String::new(),
            };
            if geoms > 0 {
                // Massless collision geoms fixed in the world are scenery the robot
                // could touch: that is physics left out.
                what.push_str(&format!(
                    ", with its {geoms} collision geom(s): contacts with them are not simulated"
                ));
                self.robot.unmodeled.push(FileNote { what, ..note });
            } else {
                self.robot.ignored.push(FileNote { what, ..note });
            }
        }
        Ok(rest)
    }

    /// The `unmodeled-element` note for a prop left out (see [`Self::props`]):
    /// what it is (its mass as compiled: `scale` is `settotalmass`'s factor) and
    /// what leaving it out changes.
    fn note_prop(&mut self, node: Node, aside: &Description, scale: f64, robot: &str) {
        let bodies = aside.links.iter().filter(|l| !l.between_joints).count();
        let dofs: usize = 6 + aside.joints.iter().map(|j| j.kind.nv()).sum::<usize>();
        let name = aside.links.first().map_or("", |l| l.name.as_str());
        let (line, _) = crate::xml::position(node.document(), node.range().start);
        self.robot.unmodeled.push(FileNote {
            element: crate::xml::element_path(node),
            line,
            what: format!(
                "free-floating body \"{name}\" ({bodies} bod{}, {:.6} kg, {dofs} DoFs) is a \
                 separate body tree beside {robot}, not part of it: twinloop \
                 loads only the robot and leaves out its mass and DoFs. MuJoCo couples the \
                 two only through contact: the robot's mass matrix and bias forces are \
                 MuJoCo's, but the prop's contacts with the robot (pushing, carrying or \
                 hitting it) are not simulated",
                if bodies == 1 { "y" } else { "ies" },
                aside.total_mass() * scale
            ),
        });
    }

    /// Whether the top-level bodies hang from a `world` link. Not for one body
    /// with a free joint (the floating base; its `pos`/`quat` are only MuJoCo's
    /// initial qpos) nor for one jointless body at the origin (the root itself);
    /// otherwise yes, and then no top-level body may have a free joint.
    fn needs_world_link(&self, top: &[Framed<'a, 'i>]) -> Result<bool, DescriptionError> {
        let joints = |b: Node<'a, 'i>| -> Vec<Node<'a, 'i>> {
            let mut all = self.includes.elements(b);
            all.retain(|c| matches!(c.tag_name().name(), "joint" | "freejoint"));
            all
        };
        if let [(only, frame, _, _)] = top {
            let (only, framed) = (*only, *frame != NO_FRAME);
            let js = joints(only);
            if js.len() == 1 && self.joint_type(js[0], None)? == "free" {
                return Ok(false);
            }
            let placed = framed
                || only.attribute("pos").is_some()
                || ORIENTATIONS.iter().any(|a| only.attribute(*a).is_some());
            if js.is_empty() && !placed {
                return Ok(false);
            }
        }
        for (b, _, _, _) in top {
            let b = *b;
            for j in joints(b) {
                if self.joint_type(j, None)? == "free" && top.len() > 1 {
                    let other = if top[0].0 == b { top[1].0 } else { top[0].0 };
                    return Err(error_at(
                        other,
                        format!(
                            "a second top-level body beside the free-floating \"{}\": twinloop \
                             models one floating body tree per file",
                            b.attribute("name").unwrap_or("body")
                        ),
                    ));
                }
            }
        }
        Ok(true)
    }

    /// The force limits of the actuators on joints, as MuJoCo clamps them: the
    /// actuator's `forcerange` when force-limited (any actuator: a `<position>`'s too,
    /// as Open Duck Mini v2's `<default><position forcerange>` gives its servos), and
    /// for a `<motor>` its `ctrlrange` times its gear when control-limited (a
    /// position or velocity actuator's control is a target, not a force). "Limited"
    /// as for joints: `"auto"` or absent means given and `autolimits`. The smallest,
    /// with the joint's `actuatorfrcrange`, is the joint's effort limit, so the
    /// simulator knows where a motor saturates. MuJoCo keeps one actuator default
    /// per class, which every actuator element in `<default>` writes, so an
    /// attribute comes from the element, else from the class's default of its own
    /// kind, else of any actuator kind.
    fn actuator_limits(&mut self, section: Node<'a, 'i>) -> Result<(), DescriptionError> {
        const KINDS: [&str; 6] = [
            "motor",
            "general",
            "position",
            "velocity",
            "intvelocity",
            "damper",
        ];
        for e in self
            .includes
            .elements(section)
            .into_iter()
            .filter(|e| KINDS.contains(&e.tag_name().name()))
        {
            let Some(joint) = e.attribute("joint") else {
                continue;
            };
            let kind = e.tag_name().name();
            let class = self.class_of(e, None)?;
            let get = |attr: &str| {
                std::iter::once(kind)
                    .chain(KINDS)
                    .find_map(|k| self.get(e, k, &class, attr))
            };
            let limit = |range: &str, limited: &str| -> Result<Option<f64>, DescriptionError> {
                let r = match get(range) {
                    Some((n, v)) => parse_array::<2>(n, range, v)?,
                    None => return Ok(None),
                };
                let on = match get(limited) {
                    Some((_, "auto")) | None => self.compiler.autolimits,
                    Some((n, v)) => bool_attr(n, limited, v)?,
                };
                Ok(on.then(|| r[0].abs().max(r[1].abs())))
            };
            let gear = match get("gear") {
                Some((n, v)) => v
                    .split_whitespace()
                    .next()
                    .map(|g| g.parse::<f64>())
                    .transpose()
                    .map_err(|_| error_at_attr(n, "gear", "not a number"))?
                    .unwrap_or(1.0),
                None => 1.0,
            };
            let force = limit("forcerange", "forcelimited")?;
            let ctrl = match kind {
                "motor" => limit("ctrlrange", "ctrllimited")?.map(|c| c * gear.abs()),
                _ => None,
            };
            let Some(effort) = [force, ctrl].into_iter().flatten().reduce(f64::min) else {
                continue;
            };
            let name = format!("{joint}{}", self.suffix);
            if let Some(j) = self.robot.joints.iter_mut().find(|j| j.name == name) {
                let lim = j.limit.get_or_insert_with(Limit::default);
                lim.effort = Some(lim.effort.map_or(effort, |x| x.min(effort)));
            }
        }
        Ok(())
    }

    /// Elements of a section that act on the physics beyond the rigid-body tree:
    /// tendons, equality constraints, actuators that do not drive a joint,
    /// sensors at sites, and deformable flexes and skins.
    fn unmodeled(&mut self, section: Node<'a, 'i>) {
        for e in self.includes.elements(section) {
            let what = match (section.tag_name().name(), e.tag_name().name()) {
                ("tendon", t) => format!(
                    "{t} tendon: its length limits, stiffness, damping and any actuator on it \
                     act on the joints it spans; twinloop's dynamics leave them out"
                ),
                ("equality", t) => format!(
                    "{t} equality constraint: twinloop's dynamics leave it out (the joints \
                     or bodies it ties move independently)"
                ),
                ("actuator", t) if e.attribute("joint").is_none() => {
                    let on = ["tendon", "site", "body", "jointinparent", "cranksite"]
                        .into_iter()
                        .find(|a| e.attribute(*a).is_some())
                        .unwrap_or("something other than a joint");
                    format!(
                        "{t} actuator on a {on}: only actuators on a joint become joint \
                         torques in twinloop"
                    )
                }
                ("deformable", t) => format!(
                    "{t} in <deformable>: a deformable body (flex or skin); twinloop's \
                     rigid-body dynamics leave it out"
                ),
                ("sensor", t) if e.attribute("site").is_some() => {
                    format!("{t} sensor at a site: twinloop does not simulate it")
                }
                _ => continue,
            };
            let (line, _) = crate::xml::position(e.document(), e.range().start);
            self.robot.unmodeled.push(FileNote {
                element: crate::xml::element_path(e),
                line,
                what,
            });
        }
    }

    /// An element MuJoCo's schema does not have (a misspelt `<geon>`, a section of
    /// another format): MuJoCo refuses the file; twinloop reads past it and notes it
    /// for `lint`, so it is never dropped without a word.
    fn unknown(&mut self, e: Node<'a, 'i>) {
        let (line, _) = crate::xml::position(e.document(), e.range().start);
        self.robot.unmodeled.push(FileNote {
            element: crate::xml::element_path(e),
            line,
            what: format!(
                "<{}> is not an MJCF element (MuJoCo refuses the file); twinloop reads past \
                 it and whatever it meant: check its spelling",
                e.tag_name().name()
            ),
        });
    }

    /// A `<composite>` or `<flexcomp>`: MuJoCo expands it into bodies (a cable,
    /// a particle set, a deformable flex) that the rigid-body tree does not
    /// hold, so it is read past and noted for `lint`, with what that leaves out.
    fn soft_body(&mut self, e: Node<'a, 'i>) {
        let tag = e.tag_name().name();
        let kind = e.attribute("type").unwrap_or("unspecified");
        let what = if tag == "composite" {
            format!(
                "composite of type \"{kind}\": MuJoCo generates its bodies, joints and \
                 tendons; twinloop's rigid-body dynamics leave them out, with their mass \
                 and their forces on the body that holds them"
            )
        } else {
            format!(
                "flexcomp of type \"{kind}\": a deformable body whose vertices MuJoCo \
                 simulates; twinloop's rigid-body dynamics leave it out, with its mass"
            )
        };
        let (line, _) = crate::xml::position(e.document(), e.range().start);
        self.robot.unmodeled.push(FileNote {
            element: crate::xml::element_path(e),
            line,
            what,
        });
    }

    /// MuJoCo's `settotalmass`: every body's mass and inertia scaled by one factor,
    /// the props' (`aside`, their mass, left out of the description) counted in
    /// the total as MuJoCo counts them.
    /// Returns the factor.
    fn set_total_mass(&mut self, total: f64, aside: f64) -> f64 {
        let now = self.robot.total_mass() + aside;
        if now <= 0.0 {
            return 1.0;
        }
        let k = total / now;
        for l in &mut self.robot.links {
            if let Some(i) = &mut l.inertial {
                i.mass *= k;
                let t = &mut i.inertia;
                for v in [
                    &mut t.ixx, &mut t.iyy, &mut t.izz, &mut t.ixy, &mut t.ixz, &mut t.iyz,
                ] {
                    *v *= k;
                }
            }
        }
        k
    }

    /// `<option gravity>` and `<flag gravity="disable">`.
    fn option(&mut self, node: Node<'a, 'i>) -> Result<(), DescriptionError> {
        if let Some(v) = node.attribute("gravity") {
            self.robot.gravity = Some(parse_array::<3>(node, "gravity", v)?);
        }
        for f in self.includes.elements(node) {
            if !f.has_tag_name("flag") {
                continue;
            }
            match f.attribute("gravity") {
                Some("disable") => self.robot.gravity = Some([0.0; 3]),
                Some("enable") | None => {}
                Some(v) => {
                    return Err(error_at_attr(
                        f,
                        "gravity",
                        format!("gravity=\"{v}\": expected \"enable\" or \"disable\""),
                    ));
                }
            }
        }
        Ok(())
    }

    fn compiler(&mut self, node: Node<'a, 'i>) -> Result<(), DescriptionError> {
        if let Some(a) = node.attribute("angle") {
            self.compiler.degrees = match a {
                "degree" => true,
                "radian" => false,
                _ => {
                    return Err(error_at_attr(
                        node,
                        "angle",
                        format!("angle=\"{a}\": expected \"degree\" or \"radian\""),
                    ));
                }
            };
        }
        if let Some(s) = node.attribute("eulerseq") {
            let b = s.as_bytes();
            if b.len() != 3 || !b.iter().all(|c| b"xyzXYZ".contains(c)) {
                return Err(error_at_attr(
                    node,
                    "eulerseq",
                    format!("eulerseq=\"{s}\": expected three of x, y, z, X, Y, Z"),
                ));
            }
            self.compiler.eulerseq = [b[0], b[1], b[2]];
        }
        if let Some(v) = node.attribute("autolimits") {
            self.compiler.autolimits = bool_attr(node, "autolimits", v)?;
        }
        if let Some(v) = node.attribute("inertiafromgeom") {
            self.compiler.inertia_from_geom = match v {
                "true" => FromGeom::True,
                "false" => FromGeom::False,
                "auto" => FromGeom::Auto,
                _ => {
                    return Err(error_at_attr(
                        node,
                        "inertiafromgeom",
                        format!("inertiafromgeom=\"{v}\": expected true, false or auto"),
                    ));
                }
            };
        }
        if let Some(v) = node.attribute("inertiagrouprange") {
            let r = parse_array::<2>(node, "inertiagrouprange", v)?;
            self.compiler.inertia_groups = r.map(|g| g as i64);
        }
        let number = |attr: &str| match node.attribute(attr) {
            Some(v) => crate::xml::parse_number(node, attr, v).map(Some),
            None => Ok(None),
        };
        if let Some(m) = number("boundmass")? {
            self.compiler.bound_mass = m;
        }
        if let Some(i) = number("boundinertia")? {
            self.compiler.bound_inertia = i;
        }
        if let Some(m) = number("settotalmass")? {
            self.compiler.total_mass = (m > 0.0).then_some(m);
        }
        if let Some(v) = node.attribute("balanceinertia") {
            self.compiler.balance_inertia = bool_attr(node, "balanceinertia", v)?;
        }
        if node.attribute("coordinate") == Some("global") {
            return Err(error_at_attr(
                node,
                "coordinate",
                "coordinate=\"global\" is not supported",
            ));
        }
        if let Some(d) = node.attribute("meshdir").or(node.attribute("assetdir")) {
            self.compiler.meshdir = Some(d.to_string());
        }
        Ok(())
    }

    /// A `<default>` and the classes nested in it (iteratively: nesting depth
    /// must not become stack depth).
    fn default_class(
        &mut self,
        top: Node<'a, 'i>,
        top_name: String,
    ) -> Result<(), DescriptionError> {
        let mut pending: Vec<(Node<'a, 'i>, String, Option<String>)> = vec![(top, top_name, None)];
        while let Some((node, name, parent)) = pending.pop() {
            let all = self.includes.elements(node);
            let (nested, elements): (Vec<Node>, Vec<Node>) = all
                .into_iter()
                .partition(|c| c.tag_name().name() == "default");
            match self.classes.get_mut(&name) {
                // Two top-level <default> sections both define "main": merge them.
                Some(c) if parent.is_none() && name == "main" => c.elements.extend(elements),
                Some(_) => {
                    return Err(error_at(
                        node,
                        format!("default class \"{name}\" is defined twice"),
                    ));
                }
                None => {
                    self.classes
                        .insert(name.clone(), Class { parent, elements });
                }
            }
            for c in nested.into_iter().rev() {
                let child = required(c, "class")?.to_string();
                pending.push((c, child, Some(name.clone())));
            }
        }
        Ok(())
    }

    /// The class an element uses: its `class`, the nearest `childclass`, or "main".
    fn class_of(
        &self,
        node: Node<'a, 'i>,
        childclass: Option<&str>,
    ) -> Result<String, DescriptionError> {
        match node.attribute("class") {
            Some(c) if self.classes.contains_key(c) => Ok(c.to_string()),
            Some(c) => Err(error_at_attr(
                node,
                "class",
                format!("unknown default class \"{c}\""),
            )),
            None => Ok(childclass.unwrap_or("main").to_string()),
        }
    }

    /// An attribute of an element of kind `kind` (`geom`, `joint`, ...): its own,
    /// else the nearest default class's.
    fn get(
        &self,
        node: Node<'a, 'i>,
        kind: &str,
        class: &str,
        attr: &str,
    ) -> Option<Found<'a, 'i>> {
        if let Some(v) = node.attribute(attr) {
            return Some((node, v));
        }
        let mut at = Some(class);
        let mut steps = 0;
        while let Some(name) = at {
            let c = self.classes.get(name)?;
            for e in c.elements.iter().rev() {
                if e.tag_name().name() == kind
                    && let Some(v) = e.attribute(attr)
                {
                    return Some((*e, v));
                }
            }
            at = c.parent.as_deref();
            steps += 1;
            if steps > MAX_DEPTH {
                break;
            }
        }
        None
    }

    /// The element's own orientation, else the one of its nearest default class.
    fn orientation(
        &self,
        node: Node<'a, 'i>,
        kind: &str,
        class: Option<&str>,
    ) -> Result<Mat, DescriptionError> {
        let own: Vec<&str> = ORIENTATIONS
            .iter()
            .copied()
            .filter(|a| node.attribute(*a).is_some())
            .collect();
        if own.len() > 1 {
            return Err(error_at(
                node,
                format!("more than one orientation ({})", own.join(", ")),
            ));
        }
        if let Some(attr) = own.first() {
            return self.rotation(node, attr, node.attribute(*attr).unwrap_or_default());
        }
        let Some(class) = class else {
            return Ok(IDENTITY);
        };
        let mut at = Some(class);
        let mut steps = 0;
        while let Some(name) = at {
            let Some(c) = self.classes.get(name) else {
                break;
            };
            for e in c.elements.iter().rev() {
                if e.tag_name().name() != kind {
                    continue;
                }
                if let Some(attr) = ORIENTATIONS.iter().find(|a| e.attribute(**a).is_some()) {
                    return self.rotation(*e, attr, e.attribute(*attr).unwrap_or_default());
                }
            }
            at = c.parent.as_deref();
            steps += 1;
            if steps > MAX_DEPTH {
                break;
            }
        }
        Ok(IDENTITY)
    }

    fn angle(&self, v: f64) -> f64 {
        if self.compiler.degrees {
            v.to_radians()
        } else {
            v
        }
    }

    /// The rotation an orientation attribute describes.
    fn rotation(&self, node: Node, attr: &str, value: &str) -> Result<Mat, DescriptionError> {
        let bad = |what: &str| error_at_attr(node, attr, format!("{attr}=\"{value}\": {what}"));
        match attr {
            "quat" => {
                let q = parse_array::<4>(node, attr, value)?;
                let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
                if !(n > 1e-12 && n.is_finite()) {
                    return Err(bad("zero quaternion"));
                }
                Ok(quaternion_to_matrix(q))
            }
            "axisangle" => {
                let a = parse_array::<4>(node, attr, value)?;
                let axis = unit(&[a[0], a[1], a[2]]).ok_or_else(|| bad("zero axis"))?;
                Ok(axis_angle(&axis, self.angle(a[3])))
            }
            "euler" => {
                let e = parse_array::<3>(node, attr, value)?;
                let mut r = IDENTITY;
                for (k, &c) in self.compiler.eulerseq.iter().enumerate() {
                    let axis = match c.to_ascii_lowercase() {
                        b'x' => [1.0, 0.0, 0.0],
                        b'y' => [0.0, 1.0, 0.0],
                        _ => [0.0, 0.0, 1.0],
                    };
                    let step = axis_angle(&axis, self.angle(e[k]));
                    r = if c.is_ascii_lowercase() {
                        mat_mul(&r, &step) // about the rotated (moving) axes
                    } else {
                        mat_mul(&step, &r) // about the fixed axes
                    };
                }
                Ok(r)
            }
            "xyaxes" => {
                let v = parse_array::<6>(node, attr, value)?;
                let x = unit(&[v[0], v[1], v[2]]).ok_or_else(|| bad("zero x axis"))?;
                let y0 = [v[3], v[4], v[5]];
                let d = dot(&x, &y0);
                let y = unit(&sub(&y0, &[d * x[0], d * x[1], d * x[2]]))
                    .ok_or_else(|| bad("y axis parallel to x axis"))?;
                let z = cross(&x, &y);
                Ok([[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]])
            }
            _ => {
                let z = parse_array::<3>(node, attr, value)?;
                let z = unit(&z).ok_or_else(|| bad("zero axis"))?;
                Ok(z_to(&z))
            }
        }
    }

    fn assets(&mut self, node: Node<'a, 'i>) -> Result<(), DescriptionError> {
        for a in self.includes.elements(node) {
            match a.tag_name().name() {
                "mesh" => {
                    let class = self.class_of(a, None)?;
                    let file = a.attribute("file").map(|f| self.asset_path(f));
                    let name = match a.attribute("name") {
                        Some(n) => n.to_string(),
                        None => {
                            let f = required(a, "file")?;
                            file_stem(f).to_string()
                        }
                    };
                    let scale = match self.get(a, "mesh", &class, "scale") {
                        Some((n, v)) => Some(parse_array::<3>(n, "scale", v)?),
                        None => None,
                    };
                    let inertia = self
                        .get(a, "mesh", &class, "inertia")
                        .map(|f| f.1.to_string());
                    self.meshes.insert(
                        name,
                        MeshAsset {
                            file,
                            scale,
                            inertia,
                        },
                    );
                }
                "material" => {
                    let class = self.class_of(a, None)?;
                    let name = required(a, "name")?.to_string();
                    let rgba = match self.get(a, "material", &class, "rgba") {
                        Some((n, v)) => parse_array::<4>(n, "rgba", v)?,
                        None => [1.0; 4],
                    };
                    self.materials.insert(name, rgba);
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// A mesh file as MuJoCo finds it: behind `meshdir` unless absolute.
    fn asset_path(&self, file: &str) -> String {
        match &self.compiler.meshdir {
            Some(dir) if !dir.is_empty() && !file.starts_with('/') => {
                format!("{}/{}", dir.trim_end_matches('/'), file)
            }
            _ => file.to_string(),
        }
    }

    fn number(&self, found: Option<Found>, attr: &str) -> Result<Option<f64>, DescriptionError> {
        match found {
            Some((n, v)) => Ok(Some(crate::xml::parse_number(n, attr, v)?)),
            None => Ok(None),
        }
    }

    fn integer(
        &self,
        found: Option<Found>,
        attr: &str,
        default: i64,
    ) -> Result<i64, DescriptionError> {
        match found {
            Some((n, v)) => v
                .trim()
                .parse::<i64>()
                .map_err(|_| error_at_attr(n, attr, format!("{attr}=\"{v}\": not an integer"))),
            None => Ok(default),
        }
    }

    /// One body and its contents; its child bodies go onto `pending`.
    ///
    /// MuJoCo applies a body's joints in order, each about its own anchor (`pos`)
    /// and axis in the body frame as moved by the joints before it, at `qpos - ref`.
    /// Here each joint gets a link: massless ones `<body>_<joint>` for all but the
    /// last, whose link is the body's, with its frame at the last hinge anchor.
    /// A joint's `ref` goes into its origin (a turn or shift of `-ref` along its
    /// axis), so a twinloop joint position is MuJoCo's qpos.
    fn body(
        &mut self,
        todo: Pending<'a, 'i>,
        pending: &mut Vec<Pending<'a, 'i>>,
    ) -> Result<(), DescriptionError> {
        let Pending {
            node,
            parent,
            childclass,
            frame,
            suffix,
        } = todo;
        self.suffix = suffix;
        let name = self.body_name(node);
        let childclass = self.childclass(node, childclass)?;
        let cc = childclass.as_deref();
        let pos = opt_array::<3>(node, "pos")?.unwrap_or([0.0; 3]);
        let (pos, rot) = compose(&frame, pos, self.orientation(node, "body", None)?);
        let mut joints = self.body_joints(node, &name, parent.is_some(), cc)?;
        if parent.is_none() {
            self.base_joint_terms(node, cc)?;
        }
        let offset = joints.last().map_or([0.0; 3], |j| j.anchor);
        self.drop_ball_springs(&mut joints);

        let (link, frames) = self.link_contents(node, &name, cc, offset)?;
        // Joints to the parent, in order, each with its child link.
        let mut chain: Vec<(Joint, Node)> = match parent {
            Some(parent) => joint_chain(node, &name, parent, (pos, rot), joints),
            None => Vec::new(),
        };
        // Massless links between joints, each before its joint; the body's link
        // before the joint that moves it.
        let last = chain.pop();
        for (j, jn) in chain {
            let link = Link {
                between_joints: true,
                ..Link::new(j.child.clone())
            };
            self.push_link(link, node);
            self.push_joint(j, jn);
        }
        self.push_link(link, node);
        if let Some((j, jn)) = last {
            self.push_joint(j, jn);
        }
        for f in frames {
            self.robot.order.push(Item::Frame(self.robot.frames.len()));
            self.robot.frames.push(f);
        }
        self.queue_child_bodies(node, &name, offset, cc, pending)
    }

    /// A ball joint's spring set to zero, with a note: MuJoCo's ball spring acts on
    /// the rotation from springref's quaternion, which twinloop does not model.
    fn drop_ball_springs(&mut self, joints: &mut [BodyJoint<'a, 'i>]) {
        for j in joints.iter_mut() {
            if j.joint.kind == JointKind::Spherical && j.joint.stiffness != 0.0 {
                // MuJoCo's ball spring acts on the rotation from springref's quaternion.
                let (line, _) = crate::xml::position(j.node.document(), j.node.range().start);
                self.robot.unmodeled.push(FileNote {
                    element: crate::xml::element_path(j.node),
                    line,
                    what: format!(
                        "ball joint stiffness {}: twinloop does not model a ball joint's \
                         spring (its hinge and slide springs it does)",
                        j.joint.stiffness
                    ),
                });
                j.joint.stiffness = 0.0;
            }
        }
    }

    /// Queue a body's child bodies, `<frame>`s opened (in file order: pushed
    /// reversed onto the stack); soft bodies are noted, and elements that would
    /// bring in rigid bodies twinloop cannot read are errors.
    fn queue_child_bodies(
        &mut self,
        node: Node<'a, 'i>,
        name: &str,
        offset: Vec3,
        childclass: Option<&str>,
        pending: &mut Vec<Pending<'a, 'i>>,
    ) -> Result<(), DescriptionError> {
        let mut children = Vec::new();
        for (c, frame, cc, suffix) in self.through_frames(node, childclass, &self.suffix)? {
            match c.tag_name().name() {
                "body" => children.push(Pending {
                    node: c,
                    parent: Some((name.to_string(), offset)),
                    childclass: cc,
                    frame,
                    suffix,
                }),
                "composite" | "flexcomp" => self.soft_body(c),
                "attach" => return Err(error_at(c, "<attach> is not supported")),
                t if !BODY_CHILDREN.contains(&t) => self.unknown(c),
                _ => {}
            }
        }
        pending.extend(children.into_iter().rev());
        Ok(())
    }

    fn push_link(&mut self, l: Link, node: Node<'a, 'i>) {
        self.robot.order.push(Item::Link(self.robot.links.len()));
        self.places.links.push(node);
        self.robot.links.push(l);
    }

    fn push_joint(&mut self, j: Joint, node: Node<'a, 'i>) {
        self.robot.order.push(Item::Joint(self.robot.joints.len()));
        self.places.joints.push(node);
        self.robot.joints.push(j);
    }

    /// The body's name; an unnamed body is `body1`, `body2`, ... in reading order.
    fn body_name(&mut self, node: Node) -> String {
        match node.attribute("name") {
            Some(n) => format!("{n}{}", self.suffix),
            None => {
                self.unnamed_bodies += 1;
                format!("body{}", self.unnamed_bodies)
            }
        }
    }

    /// The `childclass` in force inside a body: its own (which must be a known
    /// class), else the one inherited.
    fn childclass(
        &self,
        node: Node,
        inherited: Option<String>,
    ) -> Result<Option<String>, DescriptionError> {
        match node.attribute("childclass") {
            Some(c) if self.classes.contains_key(c) => Ok(Some(c.to_string())),
            Some(c) => Err(error_at_attr(
                node,
                "childclass",
                format!("unknown default class \"{c}\""),
            )),
            None => Ok(inherited),
        }
    }

    /// A joint element's type: `free` for `<freejoint>`, else its (or its
    /// class's) `type`, `hinge` by default.
    fn joint_type(&self, j: Node<'a, 'i>, cc: Option<&str>) -> Result<&'a str, DescriptionError> {
        if j.tag_name().name() == "freejoint" {
            return Ok("free");
        }
        let class = self.class_of(j, cc)?;
        Ok(self
            .get(j, "joint", &class, "type")
            .map_or("hinge", |f| f.1))
    }

    /// The body's hinge and slide joints in order (a free joint only as the only
    /// joint of a top-level body, where it makes no joint).
    fn body_joints(
        &self,
        node: Node<'a, 'i>,
        name: &str,
        has_parent: bool,
        cc: Option<&str>,
    ) -> Result<Vec<BodyJoint<'a, 'i>>, DescriptionError> {
        let mut elements = self.includes.elements(node);
        elements.retain(|c| matches!(c.tag_name().name(), "joint" | "freejoint"));
        let mut out = Vec::new();
        let mut anchor = [0.0; 3];
        for &j in &elements {
            let class = self.class_of(j, cc)?;
            match self.joint_type(j, cc)? {
                "free" => {
                    if elements.len() > 1 {
                        return Err(error_at(
                            node,
                            "a free joint must be the body's only joint (MuJoCo allows 6 dofs per body)",
                        ));
                    }
                    if has_parent {
                        return Err(error_at(
                            j,
                            "a free joint is only supported on the top-level body",
                        ));
                    }
                }
                kind @ ("hinge" | "slide" | "ball") => {
                    // A ball turns about its anchor like a hinge (about every axis).
                    let hinge = kind != "slide";
                    let ball = kind == "ball";
                    if hinge {
                        anchor = match self.get(j, "joint", &class, "pos") {
                            Some((n, v)) => parse_array::<3>(n, "pos", v)?,
                            None => [0.0; 3],
                        };
                    }
                    let jname = match j.attribute("name") {
                        Some(n) => format!("{n}{}", self.suffix),
                        None if out.is_empty() => format!("{name}_joint"),
                        None => format!("{name}_joint{}", out.len() + 1),
                    };
                    // MuJoCo ignores `ref` on a ball: its qpos0 is the unit quaternion.
                    let reference = match ball {
                        true => 0.0,
                        false => self
                            .number(self.get(j, "joint", &class, "ref"), "ref")?
                            .unwrap_or(0.0),
                    };
                    let mut joint = self.joint(j, &class, jname, hinge)?;
                    if ball {
                        // q is a quaternion: no axis; MuJoCo's ball `range` is a cone
                        // the dynamics leaves out, so it is not a 1-DoF position limit.
                        joint.kind = JointKind::Spherical;
                        joint.axis = None;
                        if let Some(l) = &mut joint.limit {
                            (l.lower, l.upper) = (None, None);
                        }
                    }
                    out.push(BodyJoint {
                        joint,
                        node: j,
                        anchor,
                        hinge,
                        reference: if hinge {
                            self.angle(reference)
                        } else {
                            reference
                        },
                    });
                }
                other => {
                    let (n, _) = self.get(j, "joint", &class, "type").unwrap_or((j, other));
                    return Err(error_at_attr(
                        n,
                        "type",
                        format!(
                            "unknown joint type \"{other}\" (expected free, ball, slide or hinge)"
                        ),
                    ));
                }
            }
        }
        Ok(out)
    }

    /// The passive terms of the floating base's `<joint type="free">`, which MuJoCo
    /// applies to its six velocities (its `<default>` class reaches it, as Elf2's
    /// `armature="0.01"` does; a `<freejoint>` takes no defaults and has none):
    /// `armature` and `damping` go into the description; a `frictionloss` (a dry
    /// friction constraint per base velocity) or `stiffness` (a spring towards the
    /// initial pose) is not modelled, so it is noted by name for `lint`.
    fn base_joint_terms(
        &mut self,
        node: Node<'a, 'i>,
        cc: Option<&str>,
    ) -> Result<(), DescriptionError> {
        let Some(j) = self.includes.elements(node).into_iter().find(|c| {
            c.has_tag_name("joint") && self.joint_type(*c, cc).is_ok_and(|t| t == "free")
        }) else {
            return Ok(());
        };
        let class = self.class_of(j, cc)?;
        let value = |s: &Self, attr: &str| -> Result<f64, DescriptionError> {
            Ok(s.number(s.get(j, "joint", &class, attr), attr)?
                .unwrap_or(0.0))
        };
        self.robot.base_armature = value(self, "armature")?;
        self.robot.base_damping = value(self, "damping")?;
        for (attr, what) in [
            (
                "frictionloss",
                "a dry friction MuJoCo applies to each of the six base velocities",
            ),
            (
                "stiffness",
                "a spring MuJoCo applies towards the base's initial pose",
            ),
        ] {
            let v = value(self, attr)?;
            if v != 0.0 {
                let (line, _) = crate::xml::position(j.document(), j.range().start);
                self.robot.unmodeled.push(FileNote {
                    element: crate::xml::element_path(j),
                    line,
                    what: format!(
                        "free joint {attr} {v}: {what}; twinloop's floating base has none \
                         (its armature and damping it models)"
                    ),
                });
            }
        }
        Ok(())
    }

    /// A hinge or slide joint (name, parent, child and origin are set by the caller).
    fn joint(
        &self,
        j: Node<'a, 'i>,
        class: &str,
        name: String,
        hinge: bool,
    ) -> Result<Joint, DescriptionError> {
        let axis = match self.get(j, "joint", class, "axis") {
            Some((n, v)) => {
                let a = parse_array::<3>(n, "axis", v)?;
                unit(&a).ok_or_else(|| error_at_attr(n, "axis", "zero axis"))?
            }
            None => [0.0, 0.0, 1.0],
        };
        let range = match self.get(j, "joint", class, "range") {
            Some((n, v)) => {
                let r = parse_array::<2>(n, "range", v)?;
                // Named here, in the numbers and unit the file has (degrees by
                // default), not later in radians.
                if r[0] > r[1] {
                    return Err(error_at_attr(
                        n,
                        "range",
                        format!(
                            "range=\"{}\": the lower end is above the upper one: no \
                             position is within them; swap them",
                            v.trim()
                        ),
                    ));
                }
                Some(if hinge {
                    [self.angle(r[0]), self.angle(r[1])]
                } else {
                    r
                })
            }
            None => None,
        };
        let limited = self.limited(j, class, "limited", range.is_some())?;
        let force = match self.get(j, "joint", class, "actuatorfrcrange") {
            Some((n, v)) => Some(parse_array::<2>(n, "actuatorfrcrange", v)?),
            None => None,
        };
        let force_limited = self.limited(j, class, "actuatorfrclimited", force.is_some())?;
        let (lower, upper) = match (limited, range) {
            (true, Some(r)) => (Some(r[0]), Some(r[1])),
            (true, None) => {
                return Err(error_at(j, "limited joint without a range"));
            }
            _ => (None, None),
        };
        let effort = match (force_limited, force) {
            (true, Some(f)) => Some(f[0].abs().max(f[1].abs())),
            _ => None,
        };
        let kind = match (hinge, limited) {
            (true, true) => JointKind::Revolute,
            (true, false) => JointKind::Continuous,
            (false, _) => JointKind::Prismatic,
        };
        let mut joint = Joint::new(name, kind, String::new(), String::new());
        joint.axis = Some(axis);
        if lower.is_some() || effort.is_some() {
            joint.limit = Some(Limit {
                lower,
                upper,
                effort,
                velocity: None,
            });
        }
        let damping = self.number(self.get(j, "joint", class, "damping"), "damping")?;
        let friction = self.number(self.get(j, "joint", class, "frictionloss"), "frictionloss")?;
        if damping.is_some() || friction.is_some() {
            joint.dynamics = Some(JointDynamics { damping, friction });
        }
        joint.armature = self
            .number(self.get(j, "joint", class, "armature"), "armature")?
            .unwrap_or(0.0);
        joint.stiffness = self
            .number(self.get(j, "joint", class, "stiffness"), "stiffness")?
            .unwrap_or(0.0);
        // springref is a qpos value: an angle in the compiler's unit for a hinge.
        let springref = self
            .number(self.get(j, "joint", class, "springref"), "springref")?
            .unwrap_or(0.0);
        joint.springref = if hinge {
            self.angle(springref)
        } else {
            springref
        };
        Ok(joint)
    }

    /// MuJoCo's "limited" logic: true, false, or auto (limited when the range is
    /// given and autolimits is on).
    fn limited(
        &self,
        j: Node<'a, 'i>,
        class: &str,
        attr: &str,
        has_range: bool,
    ) -> Result<bool, DescriptionError> {
        match self.get(j, "joint", class, attr) {
            Some((_, "auto")) | None => Ok(has_range && self.compiler.autolimits),
            Some((n, v)) => bool_attr(n, attr, v),
        }
    }

    /// Inertial, geoms and sites of a body, shifted by `-offset`.
    fn link_contents(
        &self,
        node: Node<'a, 'i>,
        name: &str,
        childclass: Option<&str>,
        offset: Vec3,
    ) -> Result<(Link, Vec<Frame>), DescriptionError> {
        let mut link = Link::new(name);
        let mut frames = Vec::new();
        let mut geoms = 0;
        let mut explicit: Option<(Vec3, Mat, f64, Inertia)> = None;
        let from_geoms = match self.compiler.inertia_from_geom {
            FromGeom::True => true,
            FromGeom::False => false,
            FromGeom::Auto => !self
                .includes
                .elements(node)
                .iter()
                .any(|c| c.has_tag_name("inertial")),
        };
        let mut parts = Vec::new();
        // Sites and geoms in a body's own replicas: their suffixes (MuJoCo's
        // names); the body's own suffix is `self.suffix`.
        for (c, xf, cc, sfx) in self.through_frames(node, childclass, &self.suffix)? {
            let childclass = cc.as_deref();
            match c.tag_name().name() {
                "inertial" => {
                    if explicit.is_some() {
                        return Err(error_at(c, "a second <inertial> in the body"));
                    }
                    explicit = Some(self.inertial(c)?);
                }
                "geom" => {
                    geoms += 1;
                    let default_name = format!("{name}_geom{geoms}");
                    let named = c.attribute("name").map(|n| format!("{n}{sfx}"));
                    let names = (named, default_name.as_str());
                    self.geom(c, childclass, offset, &xf, names, &mut link)?;
                    if from_geoms && let Some(p) = self.geom_mass(c, childclass, &xf)? {
                        parts.push(p);
                    }
                }
                "site" => {
                    let class = self.class_of(c, childclass)?;
                    let (pos, rot) = self.placement(c, "site", &class)?;
                    let (pos, rot) = compose(&xf, pos, rot);
                    frames.push(Frame {
                        name: match c.attribute("name") {
                            Some(n) => format!("{n}{sfx}"),
                            None => format!("{name}_site{}", frames.len() + 1),
                        },
                        link: name.to_string(),
                        origin: pose(sub(&pos, &offset), &rot),
                    });
                }
                _ => {}
            }
        }
        let c = &self.compiler;
        let bounds = c.bound_mass > 0.0 || c.bound_inertia > 0.0 || c.balance_inertia;
        // MuJoCo: geoms replace the inertial only when there are some to sum.
        let from_geoms = if from_geoms {
            MassProps::combine(&parts)
        } else {
            None
        };
        let bound = |p: MassProps| p.bounded(c.bound_mass, c.bound_inertia, c.balance_inertia);
        let props = match (from_geoms, bounds) {
            (Some(p), true) => Some(bound(p)),
            (Some(p), false) => Some(p),
            (None, true) => Some(bound(match explicit {
                Some((pos, rot, mass, i)) => MassProps::rotated(mass, pos, &rot, i.matrix()),
                // Nothing to weigh: MuJoCo puts the CoM at the body's own `pos`
                // (in the body frame), which matters once boundmass gives it mass.
                None => MassProps {
                    com: opt_array::<3>(node, "pos")?.unwrap_or([0.0; 3]),
                    ..MassProps::NONE
                },
            })),
            (None, false) => None,
        };
        link.inertial = match props {
            Some(p) => Some(Inertial {
                origin: pose(sub(&p.com, &offset), &IDENTITY),
                mass: p.mass,
                inertia: Inertia::from_matrix(p.inertia),
            }),
            // As written: the file's numbers in the file's frame.
            None => explicit.map(|(pos, rot, mass, inertia)| Inertial {
                origin: pose(sub(&pos, &offset), &rot),
                mass,
                inertia,
            }),
        };
        Ok((link, frames))
    }

    /// `<inertial pos quat mass diaginertia|fullinertia>`: CoM, frame, mass and
    /// the tensor in that frame.
    fn inertial(&self, c: Node<'a, 'i>) -> Result<(Vec3, Mat, f64, Inertia), DescriptionError> {
        let pos = parse_array::<3>(c, "pos", required(c, "pos")?)?;
        let rot = self.orientation(c, "inertial", None)?;
        let mass = crate::xml::parse_number(c, "mass", required(c, "mass")?)?;
        let inertia = match (c.attribute("fullinertia"), c.attribute("diaginertia")) {
            (Some(v), _) => {
                let f = parse_array::<6>(c, "fullinertia", v)?;
                Inertia {
                    ixx: f[0],
                    iyy: f[1],
                    izz: f[2],
                    ixy: f[3],
                    ixz: f[4],
                    iyz: f[5],
                }
            }
            (None, Some(v)) => {
                let d = parse_array::<3>(c, "diaginertia", v)?;
                Inertia::diagonal(d[0], d[1], d[2])
            }
            (None, None) => {
                return Err(error_at(
                    c,
                    "missing attribute \"diaginertia\" or \"fullinertia\"",
                ));
            }
        };
        Ok((pos, rot, mass, inertia))
    }

    /// A geom's part of its body's mass properties, in the body frame, as
    /// MuJoCo's compiler makes it: `mass`, else `density` (1000) times the volume
    /// (the area with `shellinertia`); `None` for a geom outside
    /// `inertiagrouprange`.
    fn geom_mass(
        &self,
        g: Node<'a, 'i>,
        childclass: Option<&str>,
        frame: &Xf,
    ) -> Result<Option<MassProps>, DescriptionError> {
        let class = self.class_of(g, childclass)?;
        let group = self.integer(self.get(g, "geom", &class, "group"), "group", 0)?;
        let [lo, hi] = self.compiler.inertia_groups;
        if group < lo || group > hi {
            return Ok(None);
        }
        let kind = match self.get(g, "geom", &class, "type") {
            Some((_, t)) => t,
            None if self.get(g, "geom", &class, "mesh").is_some() => "mesh",
            None => "sphere",
        };
        let fromto = match self.get(g, "geom", &class, "fromto") {
            Some((n, v)) => Some(from_to(n, v)?),
            None => None,
        };
        let size = self.geom_size(g, &class)?;
        let (pos, rot) = match &fromto {
            Some((p, r, _)) => (*p, *r),
            None => self.placement(g, "geom", &class)?,
        };
        let (pos, rot) = compose(frame, pos, rot);
        let sized = |k: usize| size.get(k).copied().unwrap_or(0.0);
        // With fromto: the half-length along the segment, and (box, ellipsoid) a
        // cross-section of size[0] both ways, as MuJoCo does.
        let (y, z) = match &fromto {
            Some(f) => (sized(0), f.2),
            None => (sized(1), sized(2)),
        };
        let solid = match kind {
            "sphere" => Solid::Sphere { radius: sized(0) },
            "capsule" => Solid::Capsule {
                radius: sized(0),
                half: fromto.as_ref().map_or(y, |f| f.2),
            },
            "cylinder" => Solid::Cylinder {
                radius: sized(0),
                half: fromto.as_ref().map_or(y, |f| f.2),
            },
            "box" => Solid::Box {
                half: [sized(0), y, z],
            },
            "ellipsoid" => Solid::Ellipsoid {
                semi: [sized(0), y, z],
            },
            "mesh" => return self.mesh_mass(g, &class, pos, &rot).map(Some),
            "plane" => {
                return Ok(Some(MassProps {
                    com: pos,
                    ..MassProps::NONE
                }));
            }
            other => {
                return Err(error_at(
                    g,
                    format!(
                        "the inertia of a {other} geom is not computed: give the body an \
                         <inertial>, or put the geom outside inertiagrouprange"
                    ),
                ));
            }
        };
        let shell = match self.get(g, "geom", &class, "shellinertia") {
            Some((n, v)) => bool_attr(n, "shellinertia", v)?,
            None => false,
        };
        let measure = solid.measure(shell);
        let density = match self.number(self.get(g, "geom", &class, "mass"), "mass")? {
            // MuJoCo turns a geom's mass into a density, then back.
            Some(m) if measure > 0.0 => m / measure,
            Some(_) => 0.0,
            None => self
                .number(self.get(g, "geom", &class, "density"), "density")?
                .unwrap_or(1000.0),
        };
        let mass = density * measure;
        let principal = solid.principal_inertia(mass, shell);
        Ok(Some(MassProps::placed(mass, pos, &rot, principal)))
    }

    /// A mesh geom's part of its body's mass properties: the mesh's volume, CoM
    /// and inertia (MuJoCo's, see [`mesh`]) placed by the geom, at the geom's
    /// `mass` or `density`.
    fn mesh_mass(
        &self,
        g: Node<'a, 'i>,
        class: &str,
        pos: Vec3,
        rot: &Mat,
    ) -> Result<MassProps, DescriptionError> {
        let Some((n, name)) = self.get(g, "geom", class, "mesh") else {
            return Err(error_at(g, "a mesh geom without a mesh"));
        };
        let asset = self
            .meshes
            .get(name)
            .ok_or_else(|| error_at_attr(n, "mesh", format!("unknown mesh \"{name}\"")))?;
        let bad = |what: String| error_at(g, format!("mesh \"{name}\": {what}"));
        let Some(file) = &asset.file else {
            return Err(bad("no file (inline meshes are not read)".into()));
        };
        if let Some((n, v)) = self.get(g, "geom", class, "shellinertia")
            && bool_attr(n, "shellinertia", v)?
        {
            // MuJoCo's own rule: a mesh's shell is its asset's inertia="shell".
            return Err(bad(
                "for mesh geoms, shellinertia is not read: give the mesh asset inertia=\"shell\""
                    .into(),
            ));
        }
        let how = asset.inertia.as_deref().unwrap_or("legacy");
        if !matches!(how, "legacy" | "exact" | "convex" | "shell") {
            return Err(bad(format!(
                "unknown inertia=\"{how}\" (expected legacy, exact, convex or shell)"
            )));
        }
        let path = match &self.dir {
            Some(d) => d.join(file),
            None => std::path::PathBuf::from(file),
        };
        let trimesh = mesh::read(&path)
            .map_err(&bad)?
            .scaled(asset.scale.unwrap_or([1.0; 3]));
        let props = match how {
            "shell" => trimesh.shell_properties(),
            "convex" => hull::convex_hull(&trimesh.vertices)
                .and_then(|h| h.mass_properties(mesh::Signed::Exact)),
            "exact" => trimesh.mass_properties(mesh::Signed::Exact),
            _ => trimesh.mass_properties(mesh::Signed::Legacy),
        }
        .map_err(|e| bad(e.to_string()))?;
        let density = match self.number(self.get(g, "geom", class, "mass"), "mass")? {
            Some(m) => m / props.volume,
            None => self
                .number(self.get(g, "geom", class, "density"), "density")?
                .unwrap_or(1000.0),
        };
        let mass = density * props.volume;
        let unit = mass / props.volume;
        let com = add(&pos, &mat_vec(rot, &props.com));
        Ok(MassProps::rotated(
            mass,
            com,
            rot,
            props.inertia.map(|row| row.map(|v| unit * v)),
        ))
    }

    /// Position and orientation of a geom or site; `fromto` wins over both.
    fn placement(
        &self,
        node: Node<'a, 'i>,
        kind: &str,
        class: &str,
    ) -> Result<(Vec3, Mat), DescriptionError> {
        if let Some((n, v)) = self.get(node, kind, class, "fromto") {
            let (pos, rot, _) = from_to(n, v)?;
            return Ok((pos, rot));
        }
        let pos = match self.get(node, kind, class, "pos") {
            Some((n, v)) => parse_array::<3>(n, "pos", v)?,
            None => [0.0; 3],
        };
        Ok((pos, self.orientation(node, kind, Some(class))?))
    }

    fn geom(
        &self,
        g: Node<'a, 'i>,
        childclass: Option<&str>,
        offset: Vec3,
        frame: &Xf,
        (name, default_name): (Option<String>, &str),
        link: &mut Link,
    ) -> Result<(), DescriptionError> {
        let class = self.class_of(g, childclass)?;
        let mesh = self.get(g, "geom", &class, "mesh");
        let kind = match self.get(g, "geom", &class, "type") {
            Some((_, t)) => t,
            None if mesh.is_some() => "mesh",
            None => "sphere",
        };
        let fromto = match self.get(g, "geom", &class, "fromto") {
            Some((n, v)) => Some(from_to(n, v)?),
            None => None,
        };
        let size = self.geom_size(g, &class)?;
        let Some(geometry) = self.geometry(g, &class, kind, mesh, &fromto, &size)? else {
            return Ok(());
        };
        let (pos, rot) = match &fromto {
            Some((p, r, _)) => (*p, *r),
            None => self.placement(g, "geom", &class)?,
        };
        let (pos, rot) = compose(frame, pos, rot);
        let origin = pose(sub(&pos, &offset), &rot);
        let group = self.integer(self.get(g, "geom", &class, "group"), "group", 0)?;
        let contype = self.integer(self.get(g, "geom", &class, "contype"), "contype", 1)?;
        let conaffinity =
            self.integer(self.get(g, "geom", &class, "conaffinity"), "conaffinity", 1)?;
        if (0..=2).contains(&group) {
            let material =
                self.geom_material(g, &class, name.as_deref().unwrap_or(default_name))?;
            link.visuals.push(Shape {
                name: name.clone(),
                origin,
                geometry: geometry.clone(),
                material,
            });
        }
        let paired = name.as_deref().is_some_and(|n| self.paired.contains(n));
        if contype != 0 || conaffinity != 0 || paired {
            link.collisions.push(Shape {
                name,
                origin,
                geometry,
                material: None,
            });
        }
        Ok(())
    }

    /// A geom's `size`: one to three numbers (none when absent).
    fn geom_size(&self, g: Node<'a, 'i>, class: &str) -> Result<Vec<f64>, DescriptionError> {
        Ok(match self.get(g, "geom", class, "size") {
            Some((n, v)) => {
                let s = parse_numbers(n, "size", v)?;
                if s.is_empty() || s.len() > 3 {
                    return Err(error_at_attr(
                        n,
                        "size",
                        format!("size=\"{v}\": expected 1 to 3 numbers"),
                    ));
                }
                s
            }
            None => Vec::new(),
        })
    }

    /// The shape of a geom of type `kind` from its `size` (or `fromto`) and, for a
    /// mesh, its asset; `None` for the types twinloop ignores (plane, height field,
    /// ellipsoid, SDF).
    fn geometry(
        &self,
        g: Node<'a, 'i>,
        class: &str,
        kind: &str,
        mesh: Option<(Node<'a, 'i>, &'a str)>,
        fromto: &Option<(Vec3, Mat, f64)>,
        size: &[f64],
    ) -> Result<Option<Geometry>, DescriptionError> {
        let need = |k: usize| -> Result<(), DescriptionError> {
            if size.len() < k {
                Err(error_at(
                    g,
                    format!(
                        "a {kind} geom needs {k} size value(s), found {}",
                        size.len()
                    ),
                ))
            } else {
                Ok(())
            }
        };
        let half_length = |need_from_size: usize| -> Result<f64, DescriptionError> {
            match fromto {
                Some((_, _, h)) => Ok(*h),
                None => {
                    need(need_from_size + 1)?;
                    Ok(size[need_from_size])
                }
            }
        };
        Ok(Some(match kind {
            "sphere" => {
                need(1)?;
                Geometry::Sphere { radius: size[0] }
            }
            "capsule" | "cylinder" => {
                need(1)?;
                let radius = size[0];
                let length = 2.0 * half_length(1)?;
                if kind == "capsule" {
                    Geometry::Capsule { radius, length }
                } else {
                    Geometry::Cylinder { radius, length }
                }
            }
            "box" => {
                // With fromto MuJoCo makes the cross-section square: size[0] both ways.
                let y = if fromto.is_some() { 0 } else { 1 };
                need(y + 1)?;
                let z = half_length(2)?;
                Geometry::Box {
                    size: [2.0 * size[0], 2.0 * size[y], 2.0 * z],
                }
            }
            "mesh" => {
                let Some((n, m)) = mesh else {
                    return Err(error_at(g, "a mesh geom without a mesh"));
                };
                let asset = self
                    .meshes
                    .get(m)
                    .ok_or_else(|| error_at_attr(n, "mesh", format!("unknown mesh \"{m}\"")))?;
                let Some(file) = &asset.file else {
                    return Err(error_at_attr(
                        n,
                        "mesh",
                        format!("mesh \"{m}\" has no file (inline meshes are not supported)"),
                    ));
                };
                Geometry::Mesh {
                    filename: file.clone(),
                    scale: asset.scale,
                }
            }
            "plane" | "hfield" | "ellipsoid" | "sdf" => return Ok(None),
            other => {
                let (n, _) = self.get(g, "geom", class, "type").unwrap_or((g, other));
                return Err(error_at_attr(
                    n,
                    "type",
                    format!("unknown geom type \"{other}\""),
                ));
            }
        }))
    }

    /// A visual geom's material: its named `material`, else one made of its `rgba`
    /// named after the geom (`name`).
    fn geom_material(
        &self,
        g: Node<'a, 'i>,
        class: &str,
        name: &str,
    ) -> Result<Option<Material>, DescriptionError> {
        Ok(match self.get(g, "geom", class, "material") {
            Some((n, m)) => {
                let rgba = self.materials.get(m).ok_or_else(|| {
                    error_at_attr(n, "material", format!("unknown material \"{m}\""))
                })?;
                Some(Material {
                    name: m.to_string(),
                    rgba: Some(*rgba),
                    texture: None,
                })
            }
            None => match self.get(g, "geom", class, "rgba") {
                Some((n, v)) => Some(Material {
                    name: format!("{name}_material"),
                    rgba: Some(parse_array::<4>(n, "rgba", v)?),
                    texture: None,
                }),
                None => None,
            },
        })
    }
}

/// `fromto="x1 y1 z1 x2 y2 z2"`: the midpoint, the rotation taking +z along the
/// segment, and the half-length.
fn from_to(node: Node, value: &str) -> Result<(Vec3, Mat, f64), DescriptionError> {
    let v = parse_array::<6>(node, "fromto", value)?;
    let a = [v[0], v[1], v[2]];
    let b = [v[3], v[4], v[5]];
    let d = sub(&b, &a);
    let len = norm(&d);
    let z = unit(&d).ok_or_else(|| {
        error_at_attr(
            node,
            "fromto",
            format!("fromto=\"{value}\": the two points are the same"),
        )
    })?;
    let mid = [
        0.5 * (a[0] + b[0]),
        0.5 * (a[1] + b[1]),
        0.5 * (a[2] + b[2]),
    ];
    Ok((mid, z_to(&z), 0.5 * len))
}

fn bool_attr(node: Node, attr: &str, v: &str) -> Result<bool, DescriptionError> {
    match v {
        "true" => Ok(true),
        "false" => Ok(false),
        _ => Err(error_at_attr(
            node,
            attr,
            format!("{attr}=\"{v}\": expected \"true\" or \"false\""),
        )),
    }
}

/// `dir/name.stl` -> `name` (MuJoCo's default name of a mesh asset).
fn file_stem(path: &str) -> &str {
    let base = path.rsplit(['/', '\\']).next().unwrap_or(path);
    match base.rfind('.') {
        Some(i) if i > 0 => &base[..i],
        _ => base,
    }
}

/// The robot geoms that a `<pair>` of `contact` puts against a geom of the world
/// body (a direct child of `<worldbody>`, where a scene's floor is). A pair of two
/// robot geoms (Apollo's arm against its pelvis) is a self-collision, which
/// twinloop does not model: it must not make those geoms touch the ground.
fn ground_pairs<'a, 'i>(
    includes: &include::Includes<'a, 'i>,
    contact: Node<'a, 'i>,
    sections: &[Node<'a, 'i>],
) -> Vec<&'a str> {
    let world: std::collections::HashSet<&str> = sections
        .iter()
        .filter(|s| s.has_tag_name("worldbody"))
        .flat_map(|w| includes.elements(*w))
        .filter(|g| g.has_tag_name("geom"))
        .filter_map(|g| g.attribute("name"))
        .collect();
    let mut out = Vec::new();
    for p in includes.elements(contact) {
        if !p.has_tag_name("pair") {
            continue;
        }
        if let (Some(a), Some(b)) = (p.attribute("geom1"), p.attribute("geom2")) {
            if world.contains(b) {
                out.push(a);
            }
            if world.contains(a) {
                out.push(b);
            }
        }
    }
    out
}
