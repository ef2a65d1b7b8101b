//! Which elements a URDF element may hold, so that an element the reader would
//! otherwise pass over in silence (a misspelt `<colision>`, a second `<inertial>`,
//! an unknown `<frobnicate/>`) is reported: `model lint` warns (`unmodeled-element`,
//! an error with `--strict`), naming the line and the element, with the URDF element
//! meant when the name is one or two letters off.
//!
//! The children each element may have are those of the URDF XML specification
//! (wiki.ros.org/urdf/XML) as urdfdom reads them. Extensions other tools read are
//! passed quietly: top-level `<gazebo>`, `<transmission>`, `<ros2_control>`,
//! `<sensor>`, `<model_state>` and MuJoCo's `<mujoco>` (kept verbatim as
//! extensions), a link's `<self_collision_checking>` (in the specification) and
//! PyBullet's `<contact>`, a joint's `<joint_properties>` (older ROS; onshape-to-robot
//! writes it), a `<material>` inside `<collision>` (ROBOTIS files; urdfdom reads past
//! it too), and every element with a namespace prefix (`xacro:`, `drake:`, ...).

use crate::description::FileNote;
use roxmltree::Node;

/// What one element may hold.
struct Children {
    /// Read once: a repeat is read past.
    once: &'static [&'static str],
    /// Read every time.
    many: &'static [&'static str],
    /// Other tools' extensions, read past quietly.
    quiet: &'static [&'static str],
}

const ROBOT: Children = Children {
    once: &[],
    many: &["link", "joint", "material"],
    quiet: &[
        "gazebo",
        "transmission",
        "ros2_control",
        "sensor",
        "model_state",
        "mujoco",
    ],
};
const LINK: Children = Children {
    once: &["inertial"],
    many: &["visual", "collision"],
    quiet: &["self_collision_checking", "contact"],
};
const JOINT: Children = Children {
    once: &[
        "origin",
        "parent",
        "child",
        "axis",
        "limit",
        "dynamics",
        "mimic",
        "safety_controller",
        "calibration",
    ],
    many: &[],
    quiet: &["joint_properties"],
};
const INERTIAL: Children = Children {
    once: &["origin", "mass", "inertia"],
    many: &[],
    quiet: &[],
};
const VISUAL: Children = Children {
    once: &["origin", "geometry", "material"],
    many: &[],
    quiet: &[],
};
const COLLISION: Children = Children {
    once: &["origin", "geometry"],
    many: &[],
    quiet: &["material"],
};
const MATERIAL: Children = Children {
    once: &["color", "texture"],
    many: &[],
    quiet: &[],
};

/// The schema of a URDF element by its tag; `None` for elements whose children are
/// not checked (geometry shapes, extensions).
fn children_of(tag: &str) -> Option<&'static Children> {
    Some(match tag {
        "robot" => &ROBOT,
        "link" => &LINK,
        "joint" => &JOINT,
        "inertial" => &INERTIAL,
        "visual" => &VISUAL,
        "collision" => &COLLISION,
        "material" => &MATERIAL,
        _ => return None,
    })
}

/// Notes on every element under `root` (the `<robot>`) that the reader passes over:
/// unknown children, repeats of children read once, shapes after a `<geometry>`'s first.
pub(crate) fn check(root: Node) -> Vec<FileNote> {
    let mut notes = Vec::new();
    walk(root, &mut notes);
    notes
}

fn walk(node: Node, notes: &mut Vec<FileNote>) {
    let parent = node.tag_name().name();
    if parent == "geometry" {
        for extra in node.children().filter(Node::is_element).skip(1) {
            if !prefixed(extra) {
                notes.push(note(
                    extra,
                    format!(
                        "a second shape in <geometry>: only the first is read, <{}> is passed over",
                        extra.tag_name().name()
                    ),
                ));
            }
        }
        return;
    }
    let Some(schema) = children_of(parent) else {
        return;
    };
    let mut seen: Vec<&str> = Vec::new();
    for child in node.children().filter(Node::is_element) {
        if prefixed(child) {
            continue;
        }
        let tag = child.tag_name().name();
        if schema.quiet.contains(&tag) && !schema.once.contains(&tag) {
            continue;
        }
        if schema.once.contains(&tag) {
            if seen.contains(&tag) {
                notes.push(note(
                    child,
                    format!("a second <{tag}> in <{parent}>: only the first is read"),
                ));
                continue;
            }
            seen.push(tag);
        } else if !schema.many.contains(&tag) {
            let known = schema.once.iter().chain(schema.many);
            let meant = known
                .map(|k| (strsim::osa_distance(tag, k), *k))
                .filter(|&(d, k)| d <= 2 && 2 * d < k.len())
                .min();
            let kept = if matches!(parent, "robot" | "link" | "joint") {
                " (a written URDF keeps it)"
            } else {
                ""
            };
            let hint = match meant {
                Some((_, k)) => format!(": did you mean <{k}>?"),
                None => String::new(),
            };
            notes.push(note(
                child,
                format!(
                    "<{tag}> is not a URDF element of <{parent}>; twinloop reads nothing from it{kept}{hint}"
                ),
            ));
            continue;
        }
        walk(child, notes);
    }
}

/// An element in another namespace (`xacro:`, `drake:`, a vendor's): not URDF's to judge.
fn prefixed(node: Node) -> bool {
    crate::xml::qualified_name(node).contains(':')
}

fn note(node: Node, what: String) -> FileNote {
    let (line, _) = crate::xml::position(node.document(), node.range().start);
    FileNote {
        element: crate::xml::element_path(node),
        line,
        what,
    }
}
