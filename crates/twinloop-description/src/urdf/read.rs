//! URDF reader.

use crate::description::*;
use crate::error::DescriptionError;
use crate::urdf::{UNKNOWN_LIMIT, UNLIMITED_SLIDE};
use crate::xml::{
    Places, error_at, error_at_attr, opt_array, opt_number, parse_array, parse_number,
    qualified_name, read_text, required, source_text, validate_placed,
};
use roxmltree::{Document, Node};
use std::path::Path;

/// Read a URDF from text. Errors name the line, column and element at fault.
pub fn from_str(text: &str) -> Result<Description, DescriptionError> {
    let doc = crate::xml::parse_xml(text)?;
    from_document(&doc)
}

/// Read a URDF file; errors carry the file path.
pub fn read_file(path: impl AsRef<Path>) -> Result<Description, DescriptionError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    from_str(&text).map_err(|e| e.in_file(path))
}

pub(crate) fn from_document(doc: &Document) -> Result<Description, DescriptionError> {
    let root = doc.root_element();
    if root.tag_name().name() != "robot" || qualified_name(root).contains(':') {
        return Err(error_at(
            root,
            format!(
                "root element is <{}>: a URDF has <robot>",
                qualified_name(root)
            ),
        ));
    }
    let mut robot = Description {
        name: root.attribute("name").unwrap_or_default().to_string(),
        ..Default::default()
    };
    for ns in root.namespaces() {
        match ns.name() {
            Some("xml") => {}
            Some(prefix) => robot
                .robot_attributes
                .push((format!("xmlns:{prefix}"), ns.uri().to_string())),
            None => robot
                .robot_attributes
                .push(("xmlns".to_string(), ns.uri().to_string())),
        }
    }
    let text = doc.input_text();
    for a in root.attributes() {
        if a.name() == "name" && a.namespace().is_none() {
            continue;
        }
        let qname = text.get(a.range_qname()).unwrap_or(a.name());
        robot
            .robot_attributes
            .push((qname.to_string(), a.value().to_string()));
    }

    let mut notes = Vec::new();
    let mut places = Places {
        robot: root,
        links: Vec::new(),
        joints: Vec::new(),
    };
    for node in root.children().filter(Node::is_element) {
        let urdf_tag = if qualified_name(node).contains(':') {
            ""
        } else {
            node.tag_name().name()
        };
        match urdf_tag {
            "link" => {
                robot.order.push(Item::Link(robot.links.len()));
                places.links.push(node);
                robot.links.push(read_link(node, &mut notes)?);
            }
            "joint" => {
                robot.order.push(Item::Joint(robot.joints.len()));
                places.joints.push(node);
                robot.joints.push(read_joint(node)?);
            }
            "material" => {
                let name = required(node, "name")?;
                robot.order.push(Item::Material(robot.materials.len()));
                robot.materials.push(read_material(node, name, &mut notes)?);
            }
            _ => {
                robot.order.push(Item::Extension(robot.extensions.len()));
                robot.extensions.push(Extension {
                    tag: qualified_name(node).to_string(),
                    xml: RawXml(source_text(node).to_string()),
                });
            }
        }
    }
    robot.ignored = notes;
    robot.unmodeled = super::schema::check(root);
    validate_placed(&robot, &places)?;
    Ok(robot)
}

/// A note that the reader read past `node`.
fn note(node: Node, what: impl Into<String>) -> FileNote {
    let (line, _) = crate::xml::position(node.document(), node.range().start);
    FileNote {
        element: crate::xml::element_path(node),
        line,
        what: what.into(),
    }
}

/// The element's URDF tag: its name, or "" for a prefixed (foreign) element.
fn tag<'a>(node: Node<'a, '_>) -> &'a str {
    if qualified_name(node).contains(':') {
        ""
    } else {
        node.tag_name().name()
    }
}

fn raw(node: Node) -> RawXml {
    RawXml(source_text(node).to_string())
}

fn read_link(node: Node, notes: &mut Vec<FileNote>) -> Result<Link, DescriptionError> {
    let mut link = Link::new(required(node, "name")?);
    let mut have_inertial = false;
    for child in node.children().filter(Node::is_element) {
        match tag(child) {
            "inertial" if !have_inertial => {
                have_inertial = true;
                link.inertial = Some(read_inertial(child)?);
            }
            "visual" => link.visuals.push(read_shape(child, notes)?),
            "collision" => link.collisions.push(read_shape(child, notes)?),
            // Anything else (and a second <inertial>) is kept as written.
            _ => link.extra.push(raw(child)),
        }
    }
    Ok(link)
}

/// The first child element with this URDF tag.
fn child<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    node.children().find(|c| c.is_element() && tag(*c) == name)
}

fn read_origin(node: Node) -> Result<Pose, DescriptionError> {
    match child(node, "origin") {
        None => Ok(Pose::IDENTITY),
        Some(o) => Ok(Pose::new(
            opt_array::<3>(o, "xyz")?.unwrap_or([0.0; 3]),
            opt_array::<3>(o, "rpy")?.unwrap_or([0.0; 3]),
        )),
    }
}

fn read_inertial(node: Node) -> Result<Inertial, DescriptionError> {
    let origin = read_origin(node)?;
    let mass_node = child(node, "mass").ok_or_else(|| error_at(node, "missing <mass>"))?;
    let mass = parse_number(mass_node, "value", required(mass_node, "value")?)?;
    let i = child(node, "inertia").ok_or_else(|| error_at(node, "missing <inertia>"))?;
    let get =
        |attr: &str| -> Result<f64, DescriptionError> { parse_number(i, attr, required(i, attr)?) };
    Ok(Inertial {
        origin,
        mass,
        inertia: Inertia {
            ixx: get("ixx")?,
            ixy: get("ixy")?,
            ixz: get("ixz")?,
            iyy: get("iyy")?,
            iyz: get("iyz")?,
            izz: get("izz")?,
        },
    })
}

fn read_shape(node: Node, notes: &mut Vec<FileNote>) -> Result<Shape, DescriptionError> {
    let origin = read_origin(node)?;
    let g = child(node, "geometry").ok_or_else(|| error_at(node, "missing <geometry>"))?;
    let shape = g
        .children()
        .find(|c| c.is_element())
        .ok_or_else(|| error_at(g, "<geometry> has no shape (box, cylinder, sphere or mesh)"))?;
    let geometry = match tag(shape) {
        "box" => Geometry::Box {
            size: parse_array::<3>(shape, "size", required(shape, "size")?)?,
        },
        "cylinder" => Geometry::Cylinder {
            radius: parse_number(shape, "radius", required(shape, "radius")?)?,
            length: parse_number(shape, "length", required(shape, "length")?)?,
        },
        "sphere" => Geometry::Sphere {
            radius: parse_number(shape, "radius", required(shape, "radius")?)?,
        },
        "mesh" => Geometry::Mesh {
            filename: required(shape, "filename")?.to_string(),
            scale: mesh_scale(shape, notes)?,
        },
        _ => {
            return Err(error_at(
                shape,
                format!(
                    "unknown geometry <{}>: expected box, cylinder, sphere or mesh",
                    qualified_name(shape)
                ),
            ));
        }
    };
    let material = match child(node, "material") {
        Some(m) => Some(read_material(
            m,
            m.attribute("name").unwrap_or_default(),
            notes,
        )?),
        None => None,
    };
    Ok(Shape {
        name: node.attribute("name").map(str::to_string),
        origin,
        geometry,
        material,
    })
}

/// A mesh's `scale`: three numbers; a fourth (written by some exporters) is
/// read past with a note.
fn mesh_scale(
    shape: Node,
    notes: &mut Vec<FileNote>,
) -> Result<Option<[f64; 3]>, DescriptionError> {
    let Some(v) = shape.attribute("scale") else {
        return Ok(None);
    };
    let n = crate::xml::parse_numbers(shape, "scale", v)?;
    if n.len() == 4 {
        notes.push(note(
            shape,
            format!("scale=\"{v}\" has 4 numbers: the first three are used"),
        ));
        return Ok(Some([n[0], n[1], n[2]]));
    }
    parse_array::<3>(shape, "scale", v).map(Some)
}

fn read_material(
    node: Node,
    name: &str,
    notes: &mut Vec<FileNote>,
) -> Result<Material, DescriptionError> {
    let rgba = match child(node, "color") {
        Some(c) => Some(parse_array::<4>(c, "rgba", required(c, "rgba")?)?),
        None => None,
    };
    let texture = match child(node, "texture") {
        Some(t) => match t.attribute("filename") {
            Some(f) => Some(f.to_string()),
            None => {
                notes.push(note(t, "a <texture> without a filename: no texture"));
                None
            }
        },
        None => None,
    };
    Ok(Material {
        name: name.to_string(),
        rgba,
        texture,
    })
}

fn read_joint(node: Node) -> Result<Joint, DescriptionError> {
    let name = required(node, "name")?;
    let kind_name = required(node, "type")?;
    let kind = JointKind::from_urdf_name(kind_name).ok_or_else(|| {
        error_at_attr(
            node,
            "type",
            format!(
                "unknown joint type \"{kind_name}\" (expected revolute, continuous, prismatic, fixed, floating or planar)"
            ),
        )
    })?;
    let link_of = |which: &str| -> Result<String, DescriptionError> {
        let n = child(node, which).ok_or_else(|| error_at(node, format!("missing <{which}>")))?;
        Ok(required(n, "link")?.to_string())
    };
    let mut joint = Joint::new(name, kind, link_of("parent")?, link_of("child")?);
    let mut seen: Vec<&str> = Vec::new();
    for c in node.children().filter(Node::is_element) {
        let t = tag(c);
        let first = !seen.contains(&t);
        if first {
            seen.push(t);
        }
        match t {
            "origin" | "parent" | "child" if first => {} // read above and below
            "axis" if first => {
                joint.axis = Some(opt_array::<3>(c, "xyz")?.unwrap_or([1.0, 0.0, 0.0]));
            }
            "limit" if first => {
                // A limit that says nothing but the writer's "not given" is no limit
                // (how a revolute joint without one is written).
                joint.limit = Some(Limit {
                    lower: opt_number(c, "lower")?.filter(|&x| x != -UNLIMITED_SLIDE),
                    upper: opt_number(c, "upper")?.filter(|&x| x != UNLIMITED_SLIDE),
                    // The writer's "not given" (see `to_string`) reads back as such.
                    effort: opt_number(c, "effort")?.filter(|&e| e != UNKNOWN_LIMIT),
                    velocity: opt_number(c, "velocity")?.filter(|&v| v != UNKNOWN_LIMIT),
                })
                .filter(|l| *l != Limit::default());
            }
            "dynamics" if first => {
                joint.dynamics = Some(JointDynamics {
                    damping: opt_number(c, "damping")?,
                    friction: opt_number(c, "friction")?,
                });
            }
            "mimic" if first => {
                joint.mimic = Some(Mimic {
                    joint: required(c, "joint")?.to_string(),
                    multiplier: opt_number(c, "multiplier")?.unwrap_or(1.0),
                    offset: opt_number(c, "offset")?.unwrap_or(0.0),
                });
            }
            "safety_controller" if first => {
                joint.safety_controller = Some(SafetyController {
                    soft_lower_limit: opt_number(c, "soft_lower_limit")?,
                    soft_upper_limit: opt_number(c, "soft_upper_limit")?,
                    k_position: opt_number(c, "k_position")?,
                    k_velocity: opt_number(c, "k_velocity")?,
                });
            }
            "calibration" if first => {
                joint.calibration = Some(Calibration {
                    rising: opt_number(c, "rising")?,
                    falling: opt_number(c, "falling")?,
                });
            }
            // Non-URDF children, and repeats of URDF ones, are kept as written.
            _ => joint.extra.push(raw(c)),
        }
    }
    joint.origin = read_origin(node)?;
    Ok(joint)
}
