//! The arms as places for the part (`adapt`'s other places, [`crate::other_places`]):
//! where the CoM inversion's place disagrees with the feet's roll, the part is also
//! tried on the links of the arm on its side (both arms when it sits within
//! [`crate::other_places::MIDDLE_M`] of the middle), each on the floor found by the
//! feet's roll. An arm turns with the trunk in every lean, so the roll cannot tell it
//! from the trunk; what the arm adds is its outline: the fit holds the part inside the
//! arm where the free point (the CoM's error times total mass over the part's) goes
//! wherever the floor's trade sends it (km20 seed 4 of the served sweep: 0.156 kg on
//! `r_upper_arm`, put 52 mm above the head and refused by `part-within-reach`).

use crate::LoopError;
use crate::other_places::MIDDLE_M;
use twinloop_description::Description;
use twinloop_ident::tipover_study::links_of_arms;

/// Links lighter than this are frames, not places a part is bolted to, kg.
const MIN_LINK_KG: f64 = 1e-3;

/// The links of the arm on the side of `position` (standing frame), less `host` and
/// frames without mass.
pub(crate) fn arm_hosts(
    prior: &Description,
    host: &str,
    position: [f64; 3],
) -> Result<Vec<String>, LoopError> {
    let [left, right] = links_of_arms(prior).map_err(LoopError::from)?;
    let mut sides = Vec::new();
    if position[1] > -MIDDLE_M {
        sides.extend(left);
    }
    if position[1] < MIDDLE_M {
        sides.extend(right);
    }
    Ok(sides
        .into_iter()
        .filter(|l| l != host)
        .filter(|l| prior.link(l).is_some_and(|l| l.mass() >= MIN_LINK_KG))
        .collect())
}
