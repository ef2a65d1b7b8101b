//! URDF writer.
//!
//! The output reads back as an equal [`Description`]: numbers are written with Rust's
//! shortest representation that parses back to the same `f64`, items keep their
//! document order ([`Description::items_in_order`]), and extensions and the `extra`
//! children of links and joints are written verbatim.
//!
//! Two things URDF cannot say are written in URDF terms, and read back as such:
//!
//! - a [`Frame`] becomes a massless `<link>` of the frame's name and a fixed
//!   `<joint name="<frame>_frame_joint">` from the frame's link to it, with the
//!   frame's origin; reading the file back gives a link and a joint, not a frame.
//!   URDF has one namespace for links where MJCF has one for bodies and one for
//!   sites (Open Duck Mini v2 has a body and a site both named `left_foot`), so a
//!   frame whose name a link (or a ball joint's helper link, or an earlier frame)
//!   already has is written as `<frame>_frame` (then `<frame>_frame2`, ...), with
//!   an XML comment naming the frame (its joint, if taken, `<frame>_frame_joint2`, ...);
//! - a [`Geometry::Capsule`] (from MJCF) becomes a `<cylinder>` of the same
//!   radius and length, preceded by an XML comment saying so.
//!
//! What other tools require is always written, so that every URDF twinloop writes
//! loads in Pinocchio and urdfdom (`check_urdf`), urdf_parser_py and yourdfpy:
//!
//! - every `<limit>` has `effort` and `velocity` (the URDF specification makes both
//!   required; urdfdom, and so Pinocchio, refuse a limit without them). One the
//!   description does not give is written as [`UNKNOWN_LIMIT`], the largest double:
//!   no limit, which is what Pinocchio assumes for a joint without `<limit>`; the
//!   reader reads that number back as not given;
//! - a revolute or prismatic joint always has a `<limit>` (urdfdom refuses one
//!   without), and a `<material>` always a `name` (empty when it has none);
//! - a prismatic joint's `<limit>` always has `lower` and `upper` (yourdfpy's strict
//!   check requires them); one without position limits gets +-[`UNLIMITED_SLIDE`];
//! - a ball joint ([`JointKind::Spherical`], from MJCF; URDF has none) becomes three
//!   revolute joints `<ball>_x`, `<ball>_y`, `<ball>_z` about the x, y and z axes of
//!   the ball's frame, through two massless links `<ball>_x_link` and
//!   `<ball>_y_link`, each limited to [-pi, pi] (the Euler angles x-y-z, singular at
//!   a y angle of +-pi/2): the same masses, inertias and, at zero angles, the same
//!   mass matrix; it reads back as those three joints. [`to_string_exact`] keeps the
//!   ball as `type="spherical"`, for twinloop's own round trips only.
//!
//! What URDF cannot say at all is written as an XML comment after `<robot>` (see
//! [`unwritable`]): an MJCF free joint's armature and damping, as URDF has no
//! joint for the floating base to carry them.
//!
//! Non-finite numbers (only possible in a description built in code) are
//! written as `NaN`/`inf`, which the reader rejects.

use crate::description::*;
use crate::error::DescriptionError;
use std::collections::HashSet;
use std::fmt::Write as _;
use std::path::Path;

/// What `<limit>` says for an effort or velocity the description does not give: the
/// largest double, i.e. no limit; read back as not given.
pub const UNKNOWN_LIMIT: f64 = f64::MAX;

/// The `upper` (and, negated, `lower`) written for a prismatic joint without
/// position limits (an MJCF slide without `range`). URDF has no unlimited
/// prismatic joint: `lower` and `upper` are optional but default to 0 (ROS wiki,
/// urdf/XML/joint), which pins the joint, and yourdfpy's strict check refuses
/// them missing. Half the largest double keeps `upper - lower` finite, so a tool
/// that takes the range's middle (yourdfpy's `center_cfg`) gets 0, not NaN;
/// Pinocchio reads it as its position limits (and its `randomConfiguration`
/// still overflows to inf on any range past ~1e298: no bound near "unlimited"
/// can serve it). The reader reads it back as not given.
pub const UNLIMITED_SLIDE: f64 = f64::MAX / 2.0;

/// The URDF text of a robot: `<?xml version="1.0"?>` header, 2-space indent; a file
/// other tools load (ball joints as three revolute joints, see the module).
pub fn to_string(robot: &Description) -> String {
    write(robot, true)
}

/// The URDF text with ball joints kept as `type="spherical"`, which only twinloop's
/// reader takes: an exact round trip (Python's pickling), not a file for other tools.
pub fn to_string_exact(robot: &Description) -> String {
    write(robot, false)
}

fn write(robot: &Description, standard: bool) -> String {
    let mut w = Writer {
        out: String::new(),
        standard,
    };
    w.out.push_str("<?xml version=\"1.0\"?>\n");
    let _ = write!(w.out, "<robot name=\"{}\"", escape(&robot.name));
    for (k, v) in &robot.robot_attributes {
        let _ = write!(w.out, " {}=\"{}\"", k, escape(v));
    }
    w.out.push_str(">\n");
    for what in unwritable(robot) {
        // A comment: no entities to escape, and the sentence holds no "--".
        w.line(1, &format!("<!-- {what} -->"));
    }
    let frame_names = frame_names(robot, standard);
    for item in robot.items_in_order() {
        match item {
            Item::Link(i) => w.link(&robot.links[i]),
            Item::Joint(i) => w.joint(&robot.joints[i]),
            Item::Material(i) => w.material(1, &robot.materials[i]),
            Item::Extension(i) => w.raw(1, &robot.extensions[i].xml),
            Item::Frame(i) => w.frame(&robot.frames[i], &frame_names[i]),
        }
    }
    w.out.push_str("</robot>\n");
    w.out
}

/// What the description holds that a URDF cannot say, one sentence each (written
/// as comments in the file; `twinloop model export` also warns): the floating base's
/// armature and damping (an MJCF free joint's), which URDF has no joint to carry.
/// Read back, the file's base has neither, as Pinocchio's has.
pub fn unwritable(robot: &Description) -> Vec<String> {
    [
        ("armature", robot.base_armature),
        ("damping", robot.base_damping),
    ]
    .into_iter()
    .filter(|(_, v)| *v != 0.0)
    .map(|(what, v)| {
        format!(
            "the floating base's {what} {} (the MJCF free joint's) is not written: URDF has \
             no joint for the floating base to carry it",
            num(v)
        )
    })
    .collect()
}

/// The link and joint names each frame is written with (indexed as `robot.frames`):
/// its own name and `<frame>_frame_joint` unless a link or joint the file writes
/// already has it (URDF link and joint names must be unique; urdfdom refuses a
/// repeated one), else the first free of `<frame>_frame`, `<frame>_frame2`, ...
/// (and `<frame>_frame_joint2`, ...).
fn frame_names(robot: &Description, standard: bool) -> Vec<(String, String)> {
    let mut links: HashSet<String> = robot.links.iter().map(|l| l.name.clone()).collect();
    let mut joints: HashSet<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    for j in robot.joints.iter() {
        if j.kind == JointKind::Spherical && standard {
            links.extend(["x", "y"].map(|a| format!("{}_{a}_link", j.name)));
            joints.extend(["x", "y", "z"].map(|a| format!("{}_{a}", j.name)));
        }
    }
    // The first of `name(1)`, `name(2)`, ... that is not taken.
    let unique = |taken: &mut HashSet<String>, name: &dyn Fn(usize) -> String| {
        let free = (1..)
            .map(name)
            .find(|n| !taken.contains(n))
            .unwrap_or_default();
        taken.insert(free.clone());
        free
    };
    robot
        .frames
        .iter()
        .map(|f| {
            let link = unique(&mut links, &|n| match n {
                1 => f.name.clone(),
                2 => format!("{}_frame", f.name),
                _ => format!("{}_frame{}", f.name, n - 1),
            });
            let joint = unique(&mut joints, &|n| match n {
                1 => format!("{}_frame_joint", f.name),
                _ => format!("{}_frame_joint{n}", f.name),
            });
            (link, joint)
        })
        .collect()
}

/// Write a robot as URDF to a file; an I/O error names the path.
pub fn write_file(robot: &Description, path: impl AsRef<Path>) -> Result<(), DescriptionError> {
    let path = path.as_ref();
    // Written beside the file and renamed when complete: a full disk keeps the old one.
    twinloop_io::output::write_atomic(path, to_string(robot))
        .map_err(|e| DescriptionError::new(e.message).in_file(path))
}

/// A number written so that it parses back to the same `f64`.
fn num(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

fn nums(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ")
}

/// Escape text for a double-quoted attribute value (whitespace characters other
/// than the space are written as references so that they survive reading).
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            '\t' => out.push_str("&#9;"),
            _ => out.push(c),
        }
    }
    out
}

struct Writer {
    out: String,
    /// Ball joints as three revolute joints (else `type="spherical"`).
    standard: bool,
}

impl Writer {
    fn indent(&mut self, level: usize) {
        for _ in 0..level {
            self.out.push_str("  ");
        }
    }

    /// A line at `level` (the text is already escaped).
    fn line(&mut self, level: usize, text: &str) {
        self.indent(level);
        self.out.push_str(text);
        self.out.push('\n');
    }

    /// Verbatim XML; only its first line is indented.
    fn raw(&mut self, level: usize, xml: &RawXml) {
        self.line(level, &xml.0);
    }

    fn origin(&mut self, level: usize, p: &Pose) {
        self.line(
            level,
            &format!(
                "<origin xyz=\"{}\" rpy=\"{}\"/>",
                nums(&p.xyz),
                nums(&p.rpy())
            ),
        );
    }

    fn link(&mut self, l: &Link) {
        let open = format!("<link name=\"{}\"", escape(&l.name));
        if l.inertial.is_none()
            && l.visuals.is_empty()
            && l.collisions.is_empty()
            && l.extra.is_empty()
        {
            self.line(1, &format!("{open}/>"));
            return;
        }
        self.line(1, &format!("{open}>"));
        if let Some(i) = &l.inertial {
            self.line(2, "<inertial>");
            if !i.origin.is_identity() {
                self.origin(3, &i.origin);
            }
            self.line(3, &format!("<mass value=\"{}\"/>", num(i.mass)));
            let t = &i.inertia;
            self.line(
                3,
                &format!(
                    "<inertia ixx=\"{}\" ixy=\"{}\" ixz=\"{}\" iyy=\"{}\" iyz=\"{}\" izz=\"{}\"/>",
                    num(t.ixx),
                    num(t.ixy),
                    num(t.ixz),
                    num(t.iyy),
                    num(t.iyz),
                    num(t.izz)
                ),
            );
            self.line(2, "</inertial>");
        }
        for s in &l.visuals {
            self.shape("visual", s);
        }
        for s in &l.collisions {
            self.shape("collision", s);
        }
        for x in &l.extra {
            self.raw(2, x);
        }
        self.line(1, "</link>");
    }

    fn shape(&mut self, tag: &str, s: &Shape) {
        match &s.name {
            Some(n) => self.line(2, &format!("<{tag} name=\"{}\">", escape(n))),
            None => self.line(2, &format!("<{tag}>")),
        }
        if !s.origin.is_identity() {
            self.origin(3, &s.origin);
        }
        self.line(3, "<geometry>");
        let g = match &s.geometry {
            Geometry::Box { size } => format!("<box size=\"{}\"/>", nums(size)),
            Geometry::Cylinder { radius, length } => {
                format!(
                    "<cylinder radius=\"{}\" length=\"{}\"/>",
                    num(*radius),
                    num(*length)
                )
            }
            Geometry::Sphere { radius } => format!("<sphere radius=\"{}\"/>", num(*radius)),
            Geometry::Capsule { radius, length } => {
                self.line(
                    4,
                    &format!(
                        "<!-- capsule (radius {}, length {}): URDF has no capsule, written as a cylinder -->",
                        num(*radius),
                        num(*length)
                    ),
                );
                format!(
                    "<cylinder radius=\"{}\" length=\"{}\"/>",
                    num(*radius),
                    num(*length)
                )
            }
            Geometry::Mesh { filename, scale } => match scale {
                Some(sc) => format!(
                    "<mesh filename=\"{}\" scale=\"{}\"/>",
                    escape(filename),
                    nums(sc)
                ),
                None => format!("<mesh filename=\"{}\"/>", escape(filename)),
            },
        };
        self.line(4, &g);
        self.line(3, "</geometry>");
        if let Some(m) = &s.material {
            self.material(3, m);
        }
        self.line(2, &format!("</{tag}>"));
    }

    fn material(&mut self, level: usize, m: &Material) {
        // urdfdom and urdf_parser_py require the name, even an empty one.
        let open = format!("<material name=\"{}\"", escape(&m.name));
        if m.rgba.is_none() && m.texture.is_none() {
            self.line(level, &format!("{open}/>"));
            return;
        }
        self.line(level, &format!("{open}>"));
        if let Some(c) = &m.rgba {
            self.line(level + 1, &format!("<color rgba=\"{}\"/>", nums(c)));
        }
        if let Some(t) = &m.texture {
            self.line(level + 1, &format!("<texture filename=\"{}\"/>", escape(t)));
        }
        self.line(level, "</material>");
    }

    fn joint(&mut self, j: &Joint) {
        if j.kind == JointKind::Spherical && self.standard {
            return self.ball_as_revolutes(j);
        }
        self.line(
            1,
            &format!(
                "<joint name=\"{}\" type=\"{}\">",
                escape(&j.name),
                j.kind.urdf_name()
            ),
        );
        self.origin(2, &j.origin);
        self.line(2, &format!("<parent link=\"{}\"/>", escape(&j.parent)));
        self.line(2, &format!("<child link=\"{}\"/>", escape(&j.child)));
        if let Some(a) = &j.axis {
            self.line(2, &format!("<axis xyz=\"{}\"/>", nums(a)));
        }
        let needs_limit = matches!(j.kind, JointKind::Revolute | JointKind::Prismatic);
        if let Some(l) = j.limit.or(needs_limit.then(Limit::default)) {
            // A slide without range: see UNLIMITED_SLIDE.
            let slide = j.kind == JointKind::Prismatic;
            let attrs = opt_attrs(&[
                ("lower", l.lower.or(slide.then_some(-UNLIMITED_SLIDE))),
                ("upper", l.upper.or(slide.then_some(UNLIMITED_SLIDE))),
                ("effort", Some(l.effort.unwrap_or(UNKNOWN_LIMIT))),
                ("velocity", Some(l.velocity.unwrap_or(UNKNOWN_LIMIT))),
            ]);
            self.line(2, &format!("<limit{attrs}/>"));
        }
        if let Some(d) = &j.dynamics {
            let attrs = opt_attrs(&[("damping", d.damping), ("friction", d.friction)]);
            self.line(2, &format!("<dynamics{attrs}/>"));
        }
        if let Some(m) = &j.mimic {
            self.line(
                2,
                &format!(
                    "<mimic joint=\"{}\" multiplier=\"{}\" offset=\"{}\"/>",
                    escape(&m.joint),
                    num(m.multiplier),
                    num(m.offset)
                ),
            );
        }
        if let Some(s) = &j.safety_controller {
            let attrs = opt_attrs(&[
                ("soft_lower_limit", s.soft_lower_limit),
                ("soft_upper_limit", s.soft_upper_limit),
                ("k_position", s.k_position),
                ("k_velocity", s.k_velocity),
            ]);
            self.line(2, &format!("<safety_controller{attrs}/>"));
        }
        if let Some(c) = &j.calibration {
            let attrs = opt_attrs(&[("rising", c.rising), ("falling", c.falling)]);
            self.line(2, &format!("<calibration{attrs}/>"));
        }
        for x in &j.extra {
            self.raw(2, x);
        }
        self.line(1, "</joint>");
    }

    /// A ball joint as three revolute joints about x, y, z through two massless links
    /// (see the module); each keeps the ball's effort limit, dynamics and extras.
    fn ball_as_revolutes(&mut self, j: &Joint) {
        self.line(
            1,
            &format!(
                "<!-- ball joint \"{}\": URDF has none, written as three revolute joints (x, y, z) -->",
                escape(&j.name).replace("--", "- -")
            ),
        );
        let pi = std::f64::consts::PI;
        let effort = j.limit.and_then(|l| l.effort);
        let links = [format!("{}_x_link", j.name), format!("{}_y_link", j.name)];
        let parents = [j.parent.as_str(), &links[0], &links[1]];
        let children = [links[0].as_str(), &links[1], j.child.as_str()];
        for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
            if k < 2 {
                self.line(1, &format!("<link name=\"{}\"/>", escape(&links[k])));
            }
            let mut r = Joint::new(
                format!("{}_{axis}", j.name),
                JointKind::Revolute,
                parents[k],
                children[k],
            );
            let mut a = [0.0; 3];
            a[k] = 1.0;
            r.axis = Some(a);
            r.limit = Some(Limit {
                lower: Some(-pi),
                upper: Some(pi),
                effort,
                velocity: None,
            });
            r.dynamics = j.dynamics;
            if k == 0 {
                r.origin = j.origin;
                r.extra = j.extra.clone();
            }
            self.joint(&r);
        }
    }

    /// A frame as a massless link plus a fixed joint, named as [`frame_names`] says.
    fn frame(&mut self, f: &Frame, (link, joint): &(String, String)) {
        if *link != f.name {
            self.line(
                1,
                &format!(
                    "<!-- frame \"{}\" written as link \"{}\": a link has its name -->",
                    escape(&f.name).replace("--", "- -"),
                    escape(link).replace("--", "- -")
                ),
            );
        }
        self.line(1, &format!("<link name=\"{}\"/>", escape(link)));
        self.line(
            1,
            &format!("<joint name=\"{}\" type=\"fixed\">", escape(joint)),
        );
        self.origin(2, &f.origin);
        self.line(2, &format!("<parent link=\"{}\"/>", escape(&f.link)));
        self.line(2, &format!("<child link=\"{}\"/>", escape(link)));
        self.line(1, "</joint>");
    }
}

/// ` a="1" b="2"` for the attributes that are set.
fn opt_attrs(attrs: &[(&str, Option<f64>)]) -> String {
    let mut s = String::new();
    for (k, v) in attrs {
        if let Some(v) = v {
            let _ = write!(s, " {k}=\"{}\"", num(*v));
        }
    }
    s
}
