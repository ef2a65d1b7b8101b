//! What `adapt` checks before it writes a model: over a bus there is no truth to
//! compare with, so the answer is held against what a real change can be. Four
//! checks, each with its bound stated here:
//!
//! | check | passes when |
//! |---|---|
//! | `part-mass-plausible` | the part weighs at most [`MAX_PART_FRACTION`] of the model (a scale reading three times the model is a mistake, not a battery) |
//! | `part-within-reach` | the part sits inside the robot: the box around every link's collision outline and origin, standing, grown by [`REACH_MARGIN`] |
//! | `tips-near-model` | every measured tip (less the protocol's bias) is within [`MAX_TIP_SHIFT_DEG`] of the prior model's static angle |
//! | `one-part-explains` | the fall-angle fit leaves every angle within [`one_part_bound_deg`] of the measured one (less the protocol's bias); on a floor fitted to the sideways tips, the rest within three resolutions beside the sideways pair's common error ([`one_part_explains`]) |
//! | `one-place-explains` | (over a bus, with the total mass and no host named; made by `twinloop_loop::other_places`) the places below the ankles that also pass their checks land the CoM within 2 mm of the kept one, or roll the feet clearly less like the robot did |
//! | `floor-found` | (over a bus, the floor fitted; made by `twinloop_loop::floor_fit`) the floor search found a floor on which the replay tips sideways as the robot did, not stopping at the end of its range short of it |
//!
//! A check that cannot be made (no part placed, no fall-angle fit) is left out, and
//! the notes say so.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The heaviest part `adapt` believes, as a share of the prior's mass: a battery
/// pack, a camera, a gripper are tenths of a kid-size robot; half the robot again is
/// a misread scale.
pub const MAX_PART_FRACTION: f64 = 0.5;

/// How far outside the standing robot's outline a part may sit, m: a part bolted on
/// sticks out by about its own size, and kid-size parts are a few centimetres.
pub const REACH_MARGIN: f64 = 0.05;

/// How far a measured tip may lie from the prior's static angle, deg. Measured: a
/// 0.48 kg part at km20's left hip moves its left tip by 8.3 deg (a 14 % part, low and
/// to the side, where the sideways lever is short); twice that is not a part the other
/// checks would pass, but a robot that fell, slipped or is not the one described.
pub const MAX_TIP_SHIFT_DEG: f64 = 16.0;

/// One check and how it came out.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct AdaptCheck {
    /// Stable name: `part-mass-plausible`, `part-within-reach`, `tips-near-model`,
    /// `one-part-explains`, `one-place-explains`, `floor-found`.
    pub name: String,
    pub passed: bool,
    /// What was measured against what bound, in words.
    pub detail: String,
}

/// The angles' resolution the fit is held to, at most, deg: over a bus each tip is the
/// mean of a second of dithered readings, and two creeps of one direction read within
/// 0.01-0.06 deg of each other (docs/adaptation.md, "Reading between the counts"), finer
/// than RX's half count (0.15 deg). Held to the half count, a km20 part left 0.31 deg
/// on a thigh and was written 4.17 mm from the truth (served sweep, seed 5).
pub const REPEATABILITY_DEG: f64 = 0.05;

/// How close the four angles must be to one part's: the fall-angle fit's residual,
/// deg; three angle resolutions, not under 0.3 deg (the scatter of two real-time
/// creeps on the bus). Angles read over a bus and fitted as read (the protocol's bias
/// not taken off: `adapt --protocol-passes 0`) carry that bias, which reaches
/// [`UNCORRECTED_PROTOCOL_BIAS_DEG`] (docs/adaptation.md): the bound is that.
pub fn one_part_bound_deg(resolution_deg: f64, bias_left_in: bool) -> f64 {
    let bound = (3.0 * resolution_deg).max(0.3);
    if bias_left_in {
        bound.max(UNCORRECTED_PROTOCOL_BIAS_DEG)
    } else {
        bound
    }
}

/// How far the bus tip-over protocol reads past a model's static angles, at most
/// (measured in lockstep on km20: up to 1.0 deg forward, docs/adaptation.md).
pub const UNCORRECTED_PROTOCOL_BIAS_DEG: f64 = 1.0;

/// What `adapt` found, as the checks need it (all angles deg, forward, backward,
/// left, right; lengths m in the standing frame).
#[derive(Debug, Clone)]
pub struct Found {
    /// The part: its mass (negative: taken off) and where it is, if placed.
    pub part: Option<(f64, [f64; 3])>,
    pub prior_mass: f64,
    /// The standing robot's outline: lowest and highest corner of the box around
    /// every link's origin and collision primitives.
    pub robot_box: ([f64; 3], [f64; 3]),
    pub measured_deg: [f64; 4],
    pub protocol_bias_deg: Option<[f64; 4]>,
    pub prior_model_deg: [f64; 4],
    /// The fall-angle fit's residual, if it ran.
    pub fit_residual_deg: Option<[f64; 4]>,
    pub angle_resolution_deg: f64,
    /// The angles were read over a bus.
    pub over_bus: bool,
}

/// Every check that can be made on what was found.
pub fn plausibility(f: &Found) -> Vec<AdaptCheck> {
    let mut out = Vec::new();
    if let Some((mass, position)) = f.part {
        out.push(part_mass(mass, f.prior_mass));
        out.push(part_reach(Vector3::from(position), f.robot_box));
    }
    out.push(tips_near_model(f));
    if let Some(residual) = &f.fit_residual_deg {
        let bias_left_in = f.over_bus && f.protocol_bias_deg.is_none();
        out.push(one_part_explains(
            residual,
            f.angle_resolution_deg,
            bias_left_in,
            false,
        ));
    }
    out
}

/// The sideways pair's common error a floor fitted to the robot's sideways tips may
/// leave, deg: the floor is found with the first pass's model and kept through the
/// passes, which move the sideways reading by up to the protocol's bias
/// ([`UNCORRECTED_PROTOCOL_BIAS_DEG`]); more than that is not the floor's.
pub const FLOOR_SIDEWAYS_BOUND_DEG: f64 = UNCORRECTED_PROTOCOL_BIAS_DEG;

/// The `one-part-explains` check of a fall-angle fit's `residual` (static minus
/// measured, deg: forward, backward, left, right). With `floor_takes_sideways` (the
/// protocol was replayed on the floor on which the model tips sideways as the robot
/// did: `twinloop_loop::floor_fit`), the left and right angles' common error is the
/// floor's (the floor and the sideways mean trade one for one, and the floor, found on
/// the first pass's model, is not refitted as the passes move the model); what one
/// part must explain is the rest, to three angle resolutions (half an ankle count,
/// averaged over a creep's last second; the fore-aft pair fixes the part's x and z
/// exactly, so a residual there means the part cannot sit where the angles put it).
/// Measured on 13 served tip-overs (docs/adaptation.md): the right answers left
/// 0.24-0.37 deg common sideways and at most 0.06 deg of the rest; the two wrong ones
/// (7.1 and 9.2 mm) 0.17-0.28 deg fore and aft.
pub fn one_part_explains(
    residual: &[f64; 4],
    resolution_deg: f64,
    bias_left_in: bool,
    floor_takes_sideways: bool,
) -> AdaptCheck {
    let resolution_deg = resolution_deg.min(REPEATABILITY_DEG);
    if !floor_takes_sideways {
        let bound = one_part_bound_deg(resolution_deg, bias_left_in);
        let (k, worst) = largest(residual);
        return AdaptCheck {
            name: "one-part-explains".into(),
            passed: worst.abs() <= bound,
            detail: format!(
                "one part explains the four angles to {:.2} deg (largest {}; bound {bound:.2} deg)",
                worst.abs(),
                DIRECTIONS[k]
            ),
        };
    }
    let bound = 3.0 * resolution_deg;
    let common = 0.5 * (residual[2] + residual[3]);
    let rest = [
        residual[0],
        residual[1],
        residual[2] - common,
        residual[3] - common,
    ];
    let (k, worst) = largest(&rest);
    AdaptCheck {
        name: "one-part-explains".into(),
        passed: worst.abs() <= bound && common.abs() <= FLOOR_SIDEWAYS_BOUND_DEG,
        detail: format!(
            "one part explains the four angles to {:.2} deg (largest {}; bound {bound:.2} deg, \
             three resolutions) beside a common sideways error of {common:+.2} deg, the \
             floor's (bound {FLOOR_SIDEWAYS_BOUND_DEG:.2} deg)",
            worst.abs(),
            DIRECTIONS[k]
        ),
    }
}

const DIRECTIONS: [&str; 4] = ["forward", "backward", "left", "right"];

fn largest(v: &[f64; 4]) -> (usize, f64) {
    v.iter().copied().enumerate().fold(
        (0, 0.0),
        |b, (k, x)| if x.abs() > b.1.abs() { (k, x) } else { b },
    )
}

fn part_mass(mass: f64, prior: f64) -> AdaptCheck {
    let bound = MAX_PART_FRACTION * prior;
    let what = if mass >= 0.0 { "added" } else { "taken off" };
    let passed = mass.abs() <= bound;
    let detail = if passed {
        format!(
            "{:.3} kg {what}, within {bound:.3} kg ({:.0} % of the model's {prior:.3} kg)",
            mass.abs(),
            MAX_PART_FRACTION * 100.0
        )
    } else {
        format!(
            "a part of {:.3} kg {what} is {:.0} % of the model's {prior:.3} kg (the scale read \
             {:.3} kg): that is a mistake, not a battery; check the --total-mass reading (the \
             unit, the robot alone on the scale)",
            mass.abs(),
            100.0 * mass.abs() / prior,
            prior + mass
        )
    };
    AdaptCheck {
        name: "part-mass-plausible".into(),
        passed,
        detail,
    }
}

fn part_reach(p: Vector3<f64>, robot_box: ([f64; 3], [f64; 3])) -> AdaptCheck {
    let (lo, hi) = (Vector3::from(robot_box.0), Vector3::from(robot_box.1));
    let m = Vector3::repeat(REACH_MARGIN);
    let (lo, hi) = (lo - m, hi + m);
    let outside = (lo - p).sup(&(p - hi)).sup(&Vector3::zeros());
    let mm = |v: Vector3<f64>| format!("[{:.0}, {:.0}, {:.0}] mm", v.x * 1e3, v.y * 1e3, v.z * 1e3);
    AdaptCheck {
        name: "part-within-reach".into(),
        passed: outside.norm() == 0.0,
        detail: if outside.norm() == 0.0 {
            format!(
                "the part at {} is inside the robot's outline grown by {:.0} mm",
                mm(p),
                REACH_MARGIN * 1e3
            )
        } else {
            format!(
                "the part at {} lies {:.0} mm outside the robot (its outline {} to {} grown by {:.0} mm): \
                 no part sits there; the angles were not measured on a rigid robot, or the change is not one part",
                mm(p),
                outside.norm() * 1e3,
                mm(lo + m),
                mm(hi - m),
                REACH_MARGIN * 1e3
            )
        },
    }
}

fn tips_near_model(f: &Found) -> AdaptCheck {
    let bias = f.protocol_bias_deg.unwrap_or([0.0; 4]);
    let shift: [f64; 4] =
        std::array::from_fn(|k| f.measured_deg[k] - bias[k] - f.prior_model_deg[k]);
    let (k, worst) = largest(&shift);
    let passed = worst.abs() <= MAX_TIP_SHIFT_DEG && shift.iter().all(|s| s.is_finite());
    AdaptCheck {
        name: "tips-near-model".into(),
        passed,
        detail: if passed {
            format!(
                "the tips are within {:.2} deg of the model's static angles (largest {}; bound {MAX_TIP_SHIFT_DEG} deg)",
                worst.abs(),
                DIRECTIONS[k]
            )
        } else {
            format!(
                "the {} tip is {:+.2} deg from the model's static angle (bound {MAX_TIP_SHIFT_DEG} deg): \
                 more than a plausible part moves it; were the servos soft, did a foot slip, is it this robot?",
                DIRECTIONS[k], worst
            )
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fits of served OP3 tip-overs (docs/adaptation.md, 2026-12-07 sweep; static
    /// minus measured less the protocol's bias, deg), adapted on the floor fitted to
    /// their sideways tips, at the XM430's half count (0.044 deg).
    const RIGHT_0_68_MM: [f64; 4] = [-0.035, -0.033, 0.362, 0.368];
    const WRONG_7_1_MM: [f64; 4] = [-0.173, -0.189, 0.452, 0.472];
    const WRONG_9_2_MM: [f64; 4] = [-0.284, -0.279, 0.331, 0.332];
    const XM430_HALF_COUNT: f64 = 0.044;

    /// The right answer was refused at the old 0.3 deg bound for its sideways pair's
    /// common error; with that left to the fitted floor it passes, and the two wrong
    /// answers still fail, on their fore-aft pair.
    #[test]
    fn the_floor_takes_the_sideways_pairs_common_error_only() {
        let check = |r| one_part_explains(&r, XM430_HALF_COUNT, false, true);
        assert!(!one_part_explains(&RIGHT_0_68_MM, XM430_HALF_COUNT, false, false).passed);
        assert!(
            check(RIGHT_0_68_MM).passed,
            "{}",
            check(RIGHT_0_68_MM).detail
        );
        for wrong in [WRONG_7_1_MM, WRONG_9_2_MM] {
            let c = check(wrong);
            assert!(!c.passed, "{}", c.detail);
            assert!(c.detail.contains("largest backward") || c.detail.contains("largest forward"));
        }
        // A sideways pair off together by more than a floor explains is refused.
        assert!(!check([0.0, 0.0, 1.2, 1.2]).passed);
        // The two sideways angles apart is the part's, not the floor's.
        assert!(!check([0.0, 0.0, 0.2, -0.2]).passed);
    }

    /// km20 seed 5 of the served sweep (0.183 kg on r_shin, placed on r_thigh on the
    /// floor by the feet's roll, 4.17 mm from the truth): 0.31 deg left. Held to RX's
    /// half count (0.15 deg: a bound of 0.45) it passed and was written; held to the
    /// readings' repeatability it fails.
    #[test]
    fn the_fit_is_held_to_the_readings_repeatability_not_the_half_count() {
        const KM20_SEED5: [f64; 4] = [0.2386, 0.2379, -0.3085, -0.3083];
        let c = one_part_explains(&KM20_SEED5, 0.1505, false, false);
        assert!(!c.passed, "{}", c.detail);
        assert!(c.detail.contains("bound 0.30"), "{}", c.detail);
    }
}
