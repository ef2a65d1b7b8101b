//! `link scan --out`: a draft robot profile from what answers on the bus, matched to
//! a description's joints where a built-in profile's servos are exactly what was
//! found, else listing the description's joints for the user to fill in. The draft
//! says what it guessed (on stderr and in its header) and loads back as it is.

use crate::LoopError;
use crate::profile::{is_profile, load_description};
use twinloop_link::mapping::{BoardMapping, JointMapping};
use twinloop_link::{BoardAxes, BoardType, FoundServo, RobotMapping};

/// The draft's text and the lines saying what was guessed.
pub struct Draft {
    pub toml: String,
    pub notes: Vec<String>,
}

/// A draft profile for the devices `found`, describing the robot `robot_spec`
/// (builtin:NAME, a URDF/MJCF file or a profile).
pub fn draft(found: &[FoundServo], robot_spec: &str) -> Result<Draft, LoopError> {
    let (robot, _) = load_description(robot_spec)?;
    let boards: Vec<(&FoundServo, &'static BoardType)> = found
        .iter()
        .filter_map(|s| board_type_of(s).map(|b| (s, b)))
        .collect();
    let servos: Vec<&FoundServo> = found
        .iter()
        .filter(|s| board_type_of(s).is_none() && s.model.is_some())
        .collect();
    let mut notes = Vec::new();
    for s in found
        .iter()
        .filter(|s| s.model.is_none() && board_type_of(s).is_none())
    {
        notes.push(format!(
            "id {} ({}): model number {} is no servo or board twinloop knows: left out",
            s.id, s.protocol, s.model_number
        ));
    }
    let mut mapping = match matching_builtin(&servos, &robot) {
        Some(m) => {
            notes.push(format!(
                "the servos are builtin:{}'s (same ids, protocols and models): its joint names, zeros, directions and roles",
                m.name
            ));
            m
        }
        None => {
            notes.push(format!(
                "no built-in profile has these {} servos: joints named id<N>; rename each to one of the description's joints listed above",
                servos.len()
            ));
            by_ids(&servos)
        }
    };
    mapping.urdf = Some(description_field(robot_spec).into());
    mapping.boards = draft_boards(&boards, &mapping, &robot, &mut notes);
    let mut toml =
        String::from("# Draft robot profile written by `twinloop link scan --out`: check it.\n");
    for n in &notes {
        toml += &format!("# - {n}\n");
    }
    let movable: Vec<&str> = robot
        .joints
        .iter()
        .filter(|j| j.kind != twinloop_description::JointKind::Fixed)
        .map(|j| j.name.as_str())
        .collect();
    toml += &format!("# Joints of \"{}\": {}\n", robot.name, movable.join(", "));
    toml += &mapping.to_toml();
    Ok(Draft { toml, notes })
}

/// The board type a found device answers as, by its model number.
fn board_type_of(s: &FoundServo) -> Option<&'static BoardType> {
    BoardType::BUILTIN
        .iter()
        .filter_map(|n| BoardType::builtin(n))
        .find(|b| b.model_number == s.model_number && b.protocol == s.protocol)
}

/// A built-in profile whose servos are exactly `servos` and whose joints are all the
/// description's.
fn matching_builtin(
    servos: &[&FoundServo],
    robot: &twinloop_description::Description,
) -> Option<RobotMapping> {
    let mut want: Vec<_> = servos
        .iter()
        .map(|s| (s.protocol.number(), s.id, s.model))
        .collect();
    want.sort_by_key(|w| (w.0, w.1));
    RobotMapping::BUILTINS.iter().find_map(|name| {
        let m = RobotMapping::builtin(name)?;
        let mut have: Vec<_> = m
            .joints
            .iter()
            .map(|j| (j.protocol.number(), j.id, Some(j.model)))
            .collect();
        have.sort_by_key(|h| (h.0, h.1));
        let named = m.joints.iter().all(|j| robot.joint(&j.name).is_some());
        (have == want && named).then_some(m)
    })
}

/// Joints named `id<N>` (`p2_id<N>` for a 2.0 servo whose id a 1.0 servo also has),
/// zero 0, direction 1, the servo's range.
fn by_ids(servos: &[&FoundServo]) -> RobotMapping {
    let joints = servos
        .iter()
        .filter_map(|s| {
            let model = s.model?;
            let shared = servos
                .iter()
                .any(|o| o.id == s.id && o.protocol != s.protocol);
            let (min, max) = JointMapping::servo_range(model);
            Some(JointMapping {
                name: if shared {
                    format!("p{}_id{}", s.protocol.number(), s.id)
                } else {
                    format!("id{}", s.id)
                },
                id: s.id,
                protocol: s.protocol,
                model,
                zero: 0.0,
                direction: 1.0,
                min,
                max,
                line: 0,
            })
        })
        .collect();
    let mut m = RobotMapping::parse(
        "[[joint]]\nname = \"x\"\nid = 1\nmodel = \"MX-28\"\n",
        "draft",
    )
    .expect("a one-joint mapping parses");
    m.name = "draft".into();
    m.joints = joints;
    m
}

/// The boards found: where a matched built-in has one at the same id, its link and
/// axes; else the description's root link and axes as read (to check).
fn draft_boards(
    found: &[(&FoundServo, &'static BoardType)],
    mapping: &RobotMapping,
    robot: &twinloop_description::Description,
    notes: &mut Vec<String>,
) -> Vec<BoardMapping> {
    let root = robot
        .links
        .iter()
        .find(|l| !robot.joints.iter().any(|j| j.child == l.name))
        .map(|l| l.name.clone())
        .unwrap_or_default();
    found
        .iter()
        .enumerate()
        .map(|(k, (s, kind))| {
            if let Some(b) = mapping.boards.iter().find(|b| b.id == s.id && b.kind == *kind) {
                return b.clone();
            }
            notes.push(format!(
                "{} at id {}: put on link \"{root}\" (the description's root) with its axes along the link's: check both",
                kind.name, s.id
            ));
            BoardMapping {
                name: if k == 0 { "trunk_imu".into() } else { format!("board{}", s.id) },
                id: s.id,
                protocol: s.protocol,
                kind,
                link: root.clone(),
                axes: BoardAxes::default(),
                line: 0,
            }
        })
        .collect()
}

/// The profile's `description`: builtin:NAME as given; a file as an absolute path (a
/// relative one would be read relative to the profile's folder, not today's).
fn description_field(spec: &str) -> String {
    if spec.starts_with("builtin:") {
        return spec.to_string();
    }
    let path = if is_profile(spec) {
        twinloop_link::RobotMapping::load(spec)
            .ok()
            .and_then(|m| m.urdf)
            .unwrap_or_else(|| spec.into())
    } else {
        spec.into()
    };
    std::fs::canonicalize(&path)
        .unwrap_or(path)
        .display()
        .to_string()
}
