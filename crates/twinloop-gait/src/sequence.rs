//! Seed 003's walking algorithm (section 6): a joint coordination sequence of thirteen
//! stages, A to N (there is no I), around the trim angles of its Table 2.
//!
//! # How the seed's controller works, and how we read it
//!
//! The seed prints its stages as fragments of an Arduino C `if / else if` chain:
//!
//! ```c
//! else if (Step_State > 7.08 && Step_State < 19.56)
//! {
//!     Offset_2_R = -10;
//!     Offset_3_R = -20;
//!     Offset_4_R = -20;
//! }
//! ```
//!
//! Our reading, stated once and used everywhere below:
//!
//! 1. **Offsets.** `Offset_i_j` is the offset of eq 6, Delta theta_ij = theta_C,ij -
//!    theta_TRIM,ij, in servo degrees. `i` = 1..5 are the five servos of Table 2 on
//!    side `j`, in its order: 1 ankle roll, 2 ankle pitch, 3 knee pitch, 4 hip pitch,
//!    5 shoulder pitch. The text fixes this: stage D changes "roll of both ankles and
//!    pitch of the right ankle" with `Offset_1_L, Offset_1_R, Offset_2_R`; stage C
//!    pitches "ankle, knee and hip" with `Offset_2_R, 3_R, 4_R`; stage G changes both
//!    ankle rolls and "a pitch of the left shoulder" with `Offset_1_L, Offset_5_L_L,
//!    Offset_1-R` (`5_L_L` and `1-R` read as typos for `5_L` and `1_R`).
//! 2. **Step_State** is the position in the step cycle in percent, 0 to 100: every
//!    printed window lies in (0, 100) and the last one, "A=0", ends at 97.08 just before
//!    the cycle restarts at stage A. We advance it uniformly over a cycle of
//!    [`SequenceOptions::cycle_period`] and evaluate the chain once per control tick
//!    (one sample).
//! 3. **No interpolation in the generator.** Inside a window the code *assigns
//!    constants*; between windows nothing is assigned, so the offsets (C globals) hold
//!    their last values. The generator is therefore piecewise constant, a zero-order
//!    hold of the stage poses, exactly as the seed's code is; the motion between two
//!    stage poses is the servo's own step response, which the seed measured settling
//!    in about 200 ms without overshoot (section 4, Figs. 25-30). The simulator's
//!    two-loop servo reproduces that smoothing, so the joints move as the seed's did.
//!    A window's lower bound is where its stage starts; its upper bound only matters
//!    in that a tick must land inside it, which [`walking_sequence_with`] checks.
//! 4. **Stage A** is the initial pose, all offsets zero ("at initial position the
//!    robot joint angles are set to their trim values"). The sub-stage "A=0" returns
//!    the ankle rolls to zero so each cycle ends where the next begins.
//! 5. **Stages the seed describes but does not print** (B, E, K, M), inferred from its
//!    text and marked [`Stage::printed`] = false:
//!    - B "shifts the CG projection to the left leg by applying ankle roll and right
//!      shoulder pitch"; H is the same weight shift later in the cycle ("the
//!      difference here with respect to stage B is ..." only the already displaced
//!      knees and shoulder) and prints `Offset_1_L = -7; Offset_1_L = -7; Offset_5_R =
//!      +30`. The repeated line is read as `Offset_1_R = -7`: the seed resets *both*
//!      ankle rolls after every weight shift (D, G, L, A=0), so both were set. B = H.
//!    - E and M shift the CG to the right foot ("ankle's roll and shoulder's pitch";
//!      G and N then reset `Offset_1_L, Offset_1_R` and `Offset_5_L`): the mirror of
//!      B, ankle rolls +7 and the left shoulder -30 (the right shoulder's +30 servo
//!      degrees is a 30 degree forward arm swing in lab17, and -30 servo degrees on
//!      the left is the same swing; `lab17::TRIMS` directions). E's text says "four
//!      of the joints": the fourth, the right shoulder, stays at +30 (H's text says it
//!      is still displaced at H), so E changes three servos like M.
//!    - K completes the return of "the ankle and knee joints of the left leg" (J left
//!      knee and hip pitch at the intermediate +20 between F's +40 and K's value, so
//!      K sets them to 0; the left ankle pitch is already 0 since J) and "the right
//!      shoulder joint is set to its trim value": `Offset_3_L = Offset_4_L =
//!      Offset_5_R = 0`.
//!    - Windows: the printed windows start at Step_State = 100 (k + 0.4) / 48 for
//!      integer k (7.08, 21.67, 34.17, 48.75, 55, 61.25, 73.75, 86.25) and most last
//!      two such ticks (4.17); the unprinted stages get the two-tick window in the
//!      middle of the gap their neighbours leave: B (0.83, 5.00), E (27.92, 32.08),
//!      K (67.50, 71.67), M (80.00, 84.17).
//! 6. **Joints.** The ten servos of Table 2 are the seed's inputs ("we only use ten
//!    servo motors for the forward movement"). Section 7.2 calls them "two ankle DOF,
//!    one knee DOF and two hip DOF" per leg, but Table 2 and every printed offset use
//!    the shoulder pitch, never a hip roll, so the ten are Table 2's. The other seven
//!    lab17 joints hold their trims.

use crate::error::GaitError;
use twinloop_description::builtin::lab17;

/// The ten joints the sequence moves, in the order of seed 003 Table 2 and of the
/// offsets `Offset_1_L .. Offset_5_L, Offset_1_R .. Offset_5_R`.
pub const OFFSET_JOINTS: [&str; 10] = [
    "l_ank_roll",
    "l_ank_pitch",
    "l_knee",
    "l_hip_pitch",
    "l_sho_pitch",
    "r_ank_roll",
    "r_ank_pitch",
    "r_knee",
    "r_hip_pitch",
    "r_sho_pitch",
];

/// Index into [`OFFSET_JOINTS`] of `Offset_<i>_L`.
const fn l(i: usize) -> usize {
    i - 1
}
/// Index into [`OFFSET_JOINTS`] of `Offset_<i>_R`.
const fn r(i: usize) -> usize {
    4 + i
}

/// One stage of the joint coordination sequence: the Step_State window in which the
/// seed's code assigns `set` (offset index, servo degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stage {
    pub name: &'static str,
    /// Open window `lower < Step_State < upper`, percent of the cycle.
    pub lower: f64,
    pub upper: f64,
    /// Assignments `(index into OFFSET_JOINTS, offset in servo degrees)`.
    pub set: &'static [(usize, f64)],
    /// True when the seed prints this stage's code (its figures 33-44); false when
    /// inferred from the text (see the module documentation, point 5).
    pub printed: bool,
}

/// Seed 003 section 6, stages B to N and the sub-stage "A=0", in cycle order.
/// Stage A is the starting pose (all offsets zero) and has no window.
pub const STAGES: [Stage; 13] = [
    Stage {
        name: "B",
        lower: 0.83,
        upper: 5.00,
        set: &[(l(1), -7.0), (r(1), -7.0), (r(5), 30.0)],
        printed: false,
    },
    // Figure 33.
    Stage {
        name: "C",
        lower: 7.08,
        upper: 19.56,
        set: &[(r(2), -10.0), (r(3), -20.0), (r(4), -20.0)],
        printed: true,
    },
    // Figure 34.
    Stage {
        name: "D",
        lower: 21.67,
        upper: 25.83,
        set: &[(l(1), 0.0), (r(1), 0.0), (r(2), 0.0)],
        printed: true,
    },
    Stage {
        name: "E",
        lower: 27.92,
        upper: 32.08,
        set: &[(l(1), 7.0), (r(1), 7.0), (l(5), -30.0)],
        printed: false,
    },
    // Figure 36.
    Stage {
        name: "F",
        lower: 34.17,
        upper: 46.67,
        set: &[(l(2), -10.0), (l(3), 40.0), (l(4), 40.0)],
        printed: true,
    },
    // Figure 37.
    Stage {
        name: "G",
        lower: 48.75,
        upper: 52.92,
        set: &[(l(1), 0.0), (l(5), 0.0), (r(1), 0.0)],
        printed: true,
    },
    // Figure 38 (the repeated `Offset_1_L = -7` read as `Offset_1_R = -7`).
    Stage {
        name: "H",
        lower: 55.0,
        upper: 59.17,
        set: &[(l(1), -7.0), (r(1), -7.0), (r(5), 30.0)],
        printed: true,
    },
    // Figure 39.
    Stage {
        name: "J",
        lower: 61.25,
        upper: 65.42,
        set: &[(l(2), 0.0), (l(3), 20.0), (l(4), 20.0)],
        printed: true,
    },
    Stage {
        name: "K",
        lower: 67.50,
        upper: 71.67,
        set: &[(l(3), 0.0), (l(4), 0.0), (r(5), 0.0)],
        printed: false,
    },
    // Figure 41.
    Stage {
        name: "L",
        lower: 73.75,
        upper: 77.92,
        set: &[(l(1), 0.0), (r(1), 0.0)],
        printed: true,
    },
    Stage {
        name: "M",
        lower: 80.00,
        upper: 84.17,
        set: &[(l(1), 7.0), (r(1), 7.0), (l(5), -30.0)],
        printed: false,
    },
    // Figure 43.
    Stage {
        name: "N",
        lower: 86.25,
        upper: 90.42,
        set: &[(l(5), 0.0), (r(3), 0.0), (r(4), 0.0)],
        printed: true,
    },
    // Figure 44.
    Stage {
        name: "A=0",
        lower: 92.92,
        upper: 97.08,
        set: &[(l(1), 0.0), (r(1), 0.0)],
        printed: true,
    },
];

/// The stage whose window holds `step_state` (seed 003's `else if` chain), if any.
pub fn stage_at(step_state: f64) -> Option<&'static Stage> {
    STAGES
        .iter()
        .find(|s| step_state > s.lower && step_state < s.upper)
}

/// The offsets (servo degrees, [`OFFSET_JOINTS`] order) held at `step_state` within a
/// cycle that started at stage A, if every window up to it was visited: the last
/// assignment of each offset, else zero. Seed 003 section 6.
pub fn offsets_at(step_state: f64) -> [f64; 10] {
    let mut o = [0.0; 10];
    for s in STAGES.iter().filter(|s| s.lower < step_state) {
        for &(i, v) in s.set {
            o[i] = v;
        }
    }
    o
}

/// How to lay the sequence out in time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SequenceOptions {
    /// Number of step cycles (each is two steps: right foot, then left).
    pub cycles: usize,
    /// Control tick and sample time, s.
    pub sample_time: f64,
    /// Duration of one step cycle (Step_State 0 to 100), s.
    pub cycle_period: f64,
    /// Factor on every offset (1 = the seed's numbers).
    pub amplitude: f64,
}

/// The seed gives no sample time. Two facts bound it: its servos take a 0.5-2.5 ms
/// pulse in the standard 20 ms (50 Hz) frame (section 2.1), so a goal cannot change
/// faster than every 20 ms; and its initial model has a bandwidth of 54.8 rad/s
/// (section 8.1), which a sampled model can only show below the Nyquist frequency
/// pi / T, so T < 57 ms. We take T = 40 ms (two servo frames; one tick of the Arduino
/// loop that writes the goals and reads both gyros, and one sample).
pub const SEED_SAMPLE_TIME: f64 = 0.04;
/// The seed gives no cycle duration either, but warns (section 5, "inertial forces")
/// that "if the frequency of the step cycle is increased beyond certain limit the
/// abundant energy from uncompensated inertial forces cannot be dampen fast enough and
/// leads to instability". On lab17 the limit is near 3.5 s per cycle: at 2 and 3 s the
/// weight shifts (the ankle rolls step by 7 degrees at servo speed) throw the body
/// sideways or backwards off the supporting foot within the first two steps; from 3.5
/// to 5 s it walks (docs/lab17-walking-identification.md). We take 4 s: with
/// Step_State advanced by 1 (percent) per 40 ms tick a cycle is 100 ticks, the
/// shortest windows (4.17) hold 4 ticks (160 ms, about the seed's 200 ms servo
/// settling), and the 1000 samples of the seed's record are 10 cycles (20 steps).
pub const SEED_CYCLE_PERIOD: f64 = 4.0;
/// Seed 003 section 7: "The data contains 1000 points".
pub const SEED_SAMPLES: usize = 1000;

impl Default for SequenceOptions {
    fn default() -> Self {
        SequenceOptions {
            cycles: 1,
            sample_time: SEED_SAMPLE_TIME,
            cycle_period: SEED_CYCLE_PERIOD,
            amplitude: 1.0,
        }
    }
}

/// Joint goals over time.
#[derive(Debug, Clone, PartialEq)]
pub struct JointGoals {
    /// All lab17 joints (`lab17::SERVOS` order).
    pub joints: Vec<String>,
    pub times: Vec<f64>,
    /// Per sample, per joint: the goal joint angle, rad (lab17's joint zero is the trim).
    pub goals: Vec<Vec<f64>>,
    /// Per sample: the ten offsets of eq 6, servo degrees ([`OFFSET_JOINTS`] order).
    pub offsets_deg: Vec<[f64; 10]>,
    /// Per sample: Step_State (percent of the cycle).
    pub step_state: Vec<f64>,
}

impl JointGoals {
    pub fn len(&self) -> usize {
        self.times.len()
    }

    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}

/// Seed 003 section 6: the walking sequence for `cycles` step cycles sampled every
/// `sample_time` seconds, with the default cycle period ([`SEED_CYCLE_PERIOD`]).
pub fn walking_sequence(cycles: usize, sample_time: f64) -> Result<JointGoals, GaitError> {
    walking_sequence_with(&SequenceOptions {
        cycles,
        sample_time,
        ..Default::default()
    })
}

/// Seed 003 section 6 and eq 6: run the `else if` chain of [`STAGES`] once per tick
/// and turn the held offsets into goals, theta_C = theta_TRIM + Delta theta (Table 2
/// trims, `lab17::joint_angle`).
pub fn walking_sequence_with(o: &SequenceOptions) -> Result<JointGoals, GaitError> {
    let samples = samples_for(o)?;
    generate(o, samples)
}

/// The number of ticks in `o.cycles` cycles, after checking the options.
fn samples_for(o: &SequenceOptions) -> Result<usize, GaitError> {
    check_timing(o)?;
    if o.cycles == 0 {
        return Err(GaitError("cycles must be at least 1".into()));
    }
    let ticks = o.cycles as f64 * o.cycle_period / o.sample_time;
    if ticks > MAX_TICKS {
        return Err(GaitError(format!(
            "cycles: {} cycles of {} s every {} s are {ticks:.3e} ticks, more than the {MAX_TICKS:.0e} \
             one sequence has",
            o.cycles, o.cycle_period, o.sample_time
        )));
    }
    Ok((o.cycles as f64 * o.cycle_period / o.sample_time).round() as usize)
}

/// The most ticks one sequence has: 10 million (the CLI's bound on the rows of one
/// command, docs/architecture.md), so a huge count or a tiny step is refused at once.
pub const MAX_TICKS: f64 = 1e7;

fn check_timing(o: &SequenceOptions) -> Result<(), GaitError> {
    if !(o.sample_time.is_finite() && o.sample_time > 0.0) {
        return Err(GaitError(format!(
            "sample_time must be a positive number of seconds, got {}",
            o.sample_time
        )));
    }
    if !(o.cycle_period.is_finite() && o.cycle_period > 0.0) {
        return Err(GaitError(format!(
            "cycle_period must be a positive number of seconds, got {}",
            o.cycle_period
        )));
    }
    if !(o.amplitude.is_finite() && (0.0..=1.5).contains(&o.amplitude)) {
        return Err(GaitError(format!(
            "amplitude must be between 0 and 1.5 (1 = the seed's offsets), got {}",
            o.amplitude
        )));
    }
    if o.cycle_period / o.sample_time > MAX_TICKS {
        return Err(GaitError(format!(
            "cycle_period {} s is {:.1e} ticks of sample_time {} s, more than the \
             {MAX_TICKS:.0e} one cycle may hold",
            short(o.cycle_period),
            o.cycle_period / o.sample_time,
            short(o.sample_time)
        )));
    }
    // Every window must hold at least one tick of every cycle, or its stage is skipped.
    let per_cycle = (o.cycle_period / o.sample_time).round() as usize;
    for s in &STAGES {
        let hit = (0..per_cycle.max(1)).any(|k| {
            let st = step_state(k as f64 * o.sample_time, o.cycle_period);
            st > s.lower && st < s.upper
        });
        if !hit {
            return Err(GaitError(format!(
                "sample_time {} s is too coarse for cycle_period {} s: no tick lands in stage {}'s \
                 window ({} < Step_State < {}); use a sample time below {:.4} s",
                o.sample_time,
                o.cycle_period,
                s.name,
                s.lower,
                s.upper,
                (s.upper - s.lower) / 100.0 * o.cycle_period / 2.0
            )));
        }
    }
    Ok(())
}

/// Step_State (percent of the cycle) at time `t`.
fn step_state(t: f64, period: f64) -> f64 {
    let c = t / period;
    // Guard the rounding of k * dt / T just below an integer.
    let f = c - (c + 1e-9).floor();
    (100.0 * f).max(0.0)
}

/// The sequence over exactly `samples` ticks (the last cycle may be partial).
pub(crate) fn generate(o: &SequenceOptions, samples: usize) -> Result<JointGoals, GaitError> {
    check_timing(o)?;
    let joints: Vec<String> = lab17::SERVOS.iter().map(|s| s.joint.to_string()).collect();
    let idx: Vec<usize> = OFFSET_JOINTS
        .iter()
        .map(|j| joints.iter().position(|n| n == j).expect("Table 2 joint"))
        .collect();
    let mut held = [0.0f64; 10];
    let mut out = JointGoals {
        joints,
        times: Vec::with_capacity(samples),
        goals: Vec::with_capacity(samples),
        offsets_deg: Vec::with_capacity(samples),
        step_state: Vec::with_capacity(samples),
    };
    for k in 0..samples {
        let t = k as f64 * o.sample_time;
        let st = step_state(t, o.cycle_period);
        if let Some(s) = stage_at(st) {
            for &(i, v) in s.set {
                held[i] = o.amplitude * v;
            }
        }
        let mut g = vec![0.0; out.joints.len()];
        for (n, &j) in idx.iter().enumerate() {
            let trim = lab17::TRIMS[n];
            debug_assert_eq!(trim.joint, OFFSET_JOINTS[n]);
            // eq 6 backwards: the servo angle theta_C = trim + offset, then the joint angle.
            g[j] = lab17::joint_angle(trim.joint, trim.servo_deg + held[n])
                .expect("Table 2 joint has a trim")
                + 0.0; // no -0.0 in the output
        }
        out.times.push(t);
        out.goals.push(g);
        out.offsets_deg.push(held);
        out.step_state.push(st);
    }
    Ok(out)
}

/// The sequence over `samples` ticks (used for the 1000-sample record).
pub fn walking_sequence_samples(
    o: &SequenceOptions,
    samples: usize,
) -> Result<JointGoals, GaitError> {
    if samples == 0 {
        return Err(GaitError("samples must be at least 1".into()));
    }
    generate(o, samples)
}

/// A number as people write it: `1e12`, not `1000000000000`.
fn short(x: f64) -> String {
    if x.abs() >= 1e6 {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_joints_are_table_2_in_order() {
        for (t, j) in lab17::TRIMS.iter().zip(OFFSET_JOINTS) {
            assert_eq!(t.joint, j);
        }
    }

    #[test]
    fn step_state_wraps_per_cycle() {
        assert_eq!(step_state(0.0, 2.0), 0.0);
        assert!((step_state(0.02 * 100.0, 2.0)).abs() < 1e-6);
        assert!((step_state(0.02 * 150.0, 2.0) - 50.0).abs() < 1e-6);
    }
}
