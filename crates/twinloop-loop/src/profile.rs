//! Resolving a robot spec (`--robot`, `--map`, Python's `robot=`/`map=`) into a
//! description, a servo mapping and the joint roles: `builtin:NAME` (a built-in
//! description with the built-in profile's roles), a robot profile (`.toml`, parsed by
//! `twinloop_link::RobotMapping`: its description with its `[roles]`), or a URDF or
//! MJCF file told apart by its root element.

use crate::LoopError;
use std::path::Path;
use twinloop_description::{Description, DescriptionError};
use twinloop_link::RobotMapping;

/// Description file formats, told apart by the root element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Urdf,
    Mjcf,
    /// `builtin:NAME`: built from primitives in code.
    Builtin,
    Unknown,
}

impl Format {
    pub fn as_str(self) -> &'static str {
        match self {
            Format::Urdf => "URDF",
            Format::Mjcf => "MJCF",
            Format::Builtin => "built-in",
            Format::Unknown => "unknown",
        }
    }
}

/// The format of a description from its root element (`<robot>`: URDF,
/// `<mujoco>`: MJCF) without parsing the whole file.
pub fn sniff_format(text: &str) -> Format {
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("<?") {
            let Some(end) = r.find("?>") else {
                return Format::Unknown;
            };
            rest = &r[end + 2..];
        } else if let Some(r) = rest.strip_prefix("<!--") {
            let Some(end) = r.find("-->") else {
                return Format::Unknown;
            };
            rest = &r[end + 3..];
        } else if let Some(r) = rest.strip_prefix("<!") {
            let Some(end) = r.find('>') else {
                return Format::Unknown;
            };
            rest = &r[end + 1..];
        } else if let Some(r) = rest.strip_prefix('<') {
            let name: String = r
                .chars()
                .take_while(|c| !c.is_whitespace() && *c != '>' && *c != '/')
                .collect();
            return match name.as_str() {
                "robot" => Format::Urdf,
                "mujoco" => Format::Mjcf,
                _ => Format::Unknown,
            };
        } else {
            return Format::Unknown;
        }
    }
}

/// Whether `spec` names a robot profile (a mapping TOML) rather than a description.
pub fn is_profile(spec: &str) -> bool {
    Path::new(spec)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

/// The description a profile names (`[robot] description`, relative to the profile
/// already), with the profile's `[roles]`; `None` if it names none.
pub fn profile_description(
    mapping: &RobotMapping,
) -> Result<Option<(Description, Format)>, LoopError> {
    let Some(d) = &mapping.urdf else {
        return Ok(None);
    };
    let spec = d.display().to_string();
    if is_profile(&spec) {
        return Err(LoopError::new(format!(
            "{}: robot.description {spec:?} is a profile; name a URDF or MJCF file or builtin:NAME",
            mapping.source
        )));
    }
    let (mut robot, format) = read_description(&spec)?;
    attach_roles(&mut robot, mapping)?;
    Ok(Some((robot, format)))
}

/// Put a profile's `[roles]` on its description, each role's joint checked to be one
/// of the description's.
pub fn attach_roles(robot: &mut Description, mapping: &RobotMapping) -> Result<(), LoopError> {
    // A servo mapped to a joint the description does not have would be read under a
    // name nothing uses, and its joint left unmoved: a misspelt name is refused.
    if let Some(j) = mapping
        .joints
        .iter()
        .find(|j| robot.joint(&j.name).is_none())
    {
        let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
        let near = twinloop_io::nearest(&j.name, &names, 1);
        let meant = near
            .first()
            .map_or(String::new(), |n| format!(" (did you mean {n}?)"));
        return Err(LoopError::new(format!(
            "{} line {}: joint \"{}\" (servo id {}) is not a joint of \"{}\"{meant}",
            mapping.source, j.line, j.name, j.id, robot.name
        )));
    }
    for (role, joint) in &mapping.roles {
        if robot.joint(joint).is_none() {
            return Err(LoopError::new(format!(
                "{}: roles.{role}: \"{joint}\" is not a joint of \"{}\"",
                mapping.source, robot.name
            )));
        }
        robot.roles.set(role, joint.clone());
    }
    Ok(())
}

/// Load a robot description: `builtin:NAME` or a URDF or MJCF file (told apart by
/// the root element). The error names the file, line and element at fault. A file
/// whose lengths are millimetres or masses grams (lint's `unit-scale`) is refused
/// here, for every command, naming the joint or link and the unit it looks like.
pub fn load_description(spec: &str) -> Result<(Description, Format), LoopError> {
    let (robot, format) = read_description(spec)?;
    // What `model lint` reports as errors of the file itself, every command refuses.
    if let Some(f) = twinloop_description::lint::refused::find(&robot) {
        return Err(LoopError::new(format!(
            "{spec}: {} \"{}\" {}",
            f.subject.as_str(),
            f.name,
            f.message
        )));
    }
    Ok((robot, format))
}

/// [`load_description`] without the unit-scale refusal: for `model lint`, which
/// reports it among its findings.
pub fn read_description(spec: &str) -> Result<(Description, Format), LoopError> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        let mut robot = twinloop_description::builtin::resolve(spec)?;
        // A built-in profile of the same name gives the joint roles.
        if let Some(profile) = RobotMapping::builtin(name) {
            attach_roles(&mut robot, &profile)?;
        }
        return Ok((robot, Format::Builtin));
    }
    if is_profile(spec) {
        let mapping = RobotMapping::load(spec)?;
        return profile_description(&mapping)?.ok_or_else(|| {
            LoopError::new(format!(
                "{spec}: the profile names no description; add description = \"FILE\" to its [robot]"
            ))
        });
    }
    let path = Path::new(spec);
    let format = twinloop_io::input::read_to_string(path)
        .map(|t| sniff_format(&t))
        .unwrap_or(Format::Unknown);
    // A reader bug must not turn into a panic trace for the user: report it as
    // unreadable input, naming the file.
    let previous_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let loaded = std::panic::catch_unwind(|| twinloop_description::load(path));
    std::panic::set_hook(previous_hook);
    let result = match loaded {
        Ok(r) => r,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown cause".to_string());
            Err(DescriptionError::new(format!(
                "the reader failed unexpectedly ({what}); please report this file"
            )))
        }
    };
    match result {
        Ok(robot) => Ok((robot, format)),
        Err(mut e) => {
            if e.location.file.is_none() {
                e.location.file = Some(path.to_path_buf());
            }
            Err(e.into())
        }
    }
}

/// Refuse a robot with a ball joint for work that moves one coordinate per joint
/// (servos, IK, identification, reduced models): its quaternion would be read as
/// four hinges, a silent wrong answer. Names the first ball joint.
pub fn hinges_only(robot: &Description, spec: &str, work: &str) -> Result<(), LoopError> {
    match robot
        .joints
        .iter()
        .find(|j| j.kind == twinloop_description::JointKind::Spherical)
    {
        None => Ok(()),
        Some(j) => Err(LoopError::new(format!(
            "{spec}: joint \"{}\" is a ball joint; {work} handles hinge and slide joints only \
             (model, kinematics, dynamics, simulate and view take ball joints)",
            j.name
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_from_root_element() {
        assert_eq!(
            sniff_format("<?xml version=\"1.0\"?>\n<!-- c -->\n<robot name=\"x\">"),
            Format::Urdf
        );
        assert_eq!(sniff_format("\u{feff}<mujoco model=\"op3\">"), Format::Mjcf);
        assert_eq!(sniff_format("<!DOCTYPE x><robot/>"), Format::Urdf);
        assert_eq!(sniff_format("<sdf>"), Format::Unknown);
        assert_eq!(sniff_format("not xml"), Format::Unknown);
        assert_eq!(sniff_format("<!-- unterminated"), Format::Unknown);
    }
}
