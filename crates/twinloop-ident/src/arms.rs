//! The arms of a humanoid description: the branches of the trunk off its middle, the
//! places `adapt` tries for a part besides the legs'.

use crate::IdentError;
use crate::adapt::standing_point;
use crate::tipover_study::{hip_roll_names, links_below};
use twinloop_description::Description;

/// The arms: per side (left, right), the links of each branch that hangs from the
/// trunk (the last link both hip roll joints hang from) off its middle on that side
/// (its first link's origin more than [`ARM_SIDE_M`] from the middle, standing frame),
/// in the description's order; the legs and a head on the middle are not among them.
/// An arm turns with the trunk in every lean, so the CoM inversion's one body places a
/// part on it rightly, but at the point nearest the CoM's error, which the floor trades
/// with the CoM's height: a km20 part of 0.156 kg on its upper arm was put 52 mm above
/// the head. Held to the arm's own outline the fit may explain the angles where the
/// free point does not (`adapt`'s other places).
pub fn links_of_arms(robot: &Description) -> Result<[Vec<String>; 2], IdentError> {
    let hips = hip_roll_names(robot).map_err(IdentError::new)?;
    let parent_of = |link: &str| {
        robot
            .joints
            .iter()
            .find(|j| j.child == link)
            .map(|j| j.parent.as_str())
    };
    let up = |joint: &str| {
        let mut chain = Vec::new();
        let mut at = robot.joint(joint).map(|j| j.parent.as_str());
        while let Some(l) = at.filter(|l| !chain.contains(l)) {
            chain.push(l);
            at = parent_of(l);
        }
        chain
    };
    let (left, right) = (up(&hips[0]), up(&hips[1]));
    let Some(trunk) = left.iter().find(|l| right.contains(l)) else {
        return Ok([Vec::new(), Vec::new()]);
    };
    let legs: Vec<&str> = hips
        .iter()
        .filter_map(|h| robot.joint(h).map(|j| j.child.as_str()))
        .collect();
    let mut arms = [Vec::new(), Vec::new()];
    for j in robot.joints.iter().filter(|j| j.parent == *trunk) {
        let branch = links_below(robot, &j.name);
        if branch.iter().any(|l| legs.contains(&l.as_str())) {
            continue;
        }
        let y = standing_point(robot, &j.child, [0.0; 3])?[1];
        if y > ARM_SIDE_M {
            arms[0].extend(branch);
        } else if y < -ARM_SIDE_M {
            arms[1].extend(branch);
        }
    }
    Ok(arms)
}

/// A branch of the trunk whose first link lies farther than this from the middle is an
/// arm, m: a kid-size robot's shoulders are 5-10 cm out, its neck on the middle.
pub const ARM_SIDE_M: f64 = 0.02;
