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
//!   frame's origin; reading the file back gives a link and a joint, not a frame;
//! - a [`Geometry::Capsule`] (from MJCF) becomes a `<cylinder>` of the same
//!   radius and length, preceded by an XML comment saying so.
//!
//! Non-finite numbers (only possible in a description built in code) are
//! written as `NaN`/`inf`, which the reader rejects.

use crate::description::*;
use crate::error::DescriptionError;
use std::fmt::Write as _;
use std::path::Path;

/// The URDF text of a robot: `<?xml version="1.0"?>` header, 2-space indent.
pub fn to_string(robot: &Description) -> String {
    let mut w = Writer { out: String::new() };
    w.out.push_str("<?xml version=\"1.0\"?>\n");
    let _ = write!(w.out, "<robot name=\"{}\"", escape(&robot.name));
    for (k, v) in &robot.robot_attributes {
        let _ = write!(w.out, " {}=\"{}\"", k, escape(v));
    }
    w.out.push_str(">\n");
    for item in robot.items_in_order() {
        match item {
            Item::Link(i) => w.link(&robot.links[i]),
            Item::Joint(i) => w.joint(&robot.joints[i]),
            Item::Material(i) => w.material(1, &robot.materials[i]),
            Item::Extension(i) => w.raw(1, &robot.extensions[i].xml),
            Item::Frame(i) => w.frame(&robot.frames[i]),
        }
    }
    w.out.push_str("</robot>\n");
    w.out
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
        let open = if m.name.is_empty() {
            "<material".to_string()
        } else {
            format!("<material name=\"{}\"", escape(&m.name))
        };
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
        if let Some(l) = &j.limit {
            let attrs = opt_attrs(&[
                ("lower", l.lower),
                ("upper", l.upper),
                ("effort", l.effort),
                ("velocity", l.velocity),
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

    /// A frame as a massless link plus a fixed joint `<frame>_frame_joint`.
    fn frame(&mut self, f: &Frame) {
        self.line(1, &format!("<link name=\"{}\"/>", escape(&f.name)));
        self.line(
            1,
            &format!(
                "<joint name=\"{}\" type=\"fixed\">",
                escape(&format!("{}_frame_joint", f.name))
            ),
        );
        self.origin(2, &f.origin);
        self.line(2, &format!("<parent link=\"{}\"/>", escape(&f.link)));
        self.line(2, &format!("<child link=\"{}\"/>", escape(&f.name)));
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
