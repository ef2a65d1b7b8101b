//! The walking sequence against the numbers printed in seed 003 section 6.

use twinloop_description::builtin::lab17;
use twinloop_gait::*;

fn offset(name: &str, o: &[f64; 10]) -> f64 {
    o[OFFSET_JOINTS.iter().position(|j| *j == name).unwrap()]
}

#[test]
fn printed_windows_and_offsets_are_the_seeds() {
    // (stage, lower, upper, [(joint, servo degrees)]) as printed in Figs. 33-44.
    type Printed = (&'static str, f64, f64, &'static [(&'static str, f64)]);
    let printed: [Printed; 9] = [
        (
            "C",
            7.08,
            19.56,
            &[
                ("r_ank_pitch", -10.0),
                ("r_knee", -20.0),
                ("r_hip_pitch", -20.0),
            ],
        ),
        (
            "D",
            21.67,
            25.83,
            &[
                ("l_ank_roll", 0.0),
                ("r_ank_roll", 0.0),
                ("r_ank_pitch", 0.0),
            ],
        ),
        (
            "F",
            34.17,
            46.67,
            &[
                ("l_ank_pitch", -10.0),
                ("l_knee", 40.0),
                ("l_hip_pitch", 40.0),
            ],
        ),
        (
            "G",
            48.75,
            52.92,
            &[
                ("l_ank_roll", 0.0),
                ("l_sho_pitch", 0.0),
                ("r_ank_roll", 0.0),
            ],
        ),
        (
            "H",
            55.0,
            59.17,
            &[
                ("l_ank_roll", -7.0),
                ("r_ank_roll", -7.0),
                ("r_sho_pitch", 30.0),
            ],
        ),
        (
            "J",
            61.25,
            65.42,
            &[
                ("l_ank_pitch", 0.0),
                ("l_knee", 20.0),
                ("l_hip_pitch", 20.0),
            ],
        ),
        (
            "L",
            73.75,
            77.92,
            &[("l_ank_roll", 0.0), ("r_ank_roll", 0.0)],
        ),
        (
            "N",
            86.25,
            90.42,
            &[("l_sho_pitch", 0.0), ("r_knee", 0.0), ("r_hip_pitch", 0.0)],
        ),
        (
            "A=0",
            92.92,
            97.08,
            &[("l_ank_roll", 0.0), ("r_ank_roll", 0.0)],
        ),
    ];
    for (name, lo, hi, set) in printed {
        let s = STAGES.iter().find(|s| s.name == name).unwrap();
        assert!(s.printed, "{name}");
        assert_eq!((s.lower, s.upper), (lo, hi), "{name}");
        assert_eq!(s.set.len(), set.len(), "{name}");
        for &(j, v) in set {
            let i = OFFSET_JOINTS.iter().position(|x| *x == j).unwrap();
            assert!(s.set.contains(&(i, v)), "{name}: {j} = {v}");
        }
        // Just inside the window the stage is active; on its bounds (open) it is not.
        assert_eq!(stage_at(0.5 * (lo + hi)).unwrap().name, name);
        assert!(stage_at(lo).is_none_or(|s| s.name != name));
        assert!(stage_at(hi).is_none_or(|s| s.name != name));
    }
    // Thirteen stages A..N without I: A is the start pose, the rest have windows.
    let names: Vec<&str> = STAGES.iter().map(|s| s.name).collect();
    assert_eq!(
        names,
        [
            "B", "C", "D", "E", "F", "G", "H", "J", "K", "L", "M", "N", "A=0"
        ]
    );
    // Windows in cycle order and disjoint.
    for w in STAGES.windows(2) {
        assert!(w[0].upper <= w[1].lower, "{} / {}", w[0].name, w[1].name);
    }
}

#[test]
fn offsets_follow_the_stages_and_close_the_cycle() {
    assert_eq!(offsets_at(0.0), [0.0; 10]); // stage A: the trims
    let after_c = offsets_at(20.0);
    assert_eq!(offset("r_knee", &after_c), -20.0);
    assert_eq!(offset("r_sho_pitch", &after_c), 30.0); // from B
    let h = offsets_at(60.0);
    // Seed 003, text of stage H: right knee servos and right shoulder still displaced,
    // left ankle pitch and knee servos too.
    assert_eq!(offset("r_knee", &h), -20.0);
    assert_eq!(offset("r_hip_pitch", &h), -20.0);
    assert_eq!(offset("r_sho_pitch", &h), 30.0);
    assert_eq!(offset("l_ank_pitch", &h), -10.0);
    assert_eq!(offset("l_knee", &h), 40.0);
    // Stage J: the left knee at the intermediate value between F (+40) and K (0).
    assert_eq!(offset("l_knee", &offsets_at(66.0)), 20.0);
    assert_eq!(offset("l_knee", &offsets_at(72.0)), 0.0);
    // After "A=0" every joint is back at its trim.
    assert_eq!(offsets_at(99.0), [0.0; 10]);
}

#[test]
fn goals_are_trims_plus_offsets_over_time() {
    let g = walking_sequence(2, SEED_SAMPLE_TIME).unwrap();
    // Two 4 s cycles of 40 ms ticks: Step_State advances by 1 per tick.
    assert_eq!(g.len(), 200);
    assert_eq!(g.joints.len(), 17);
    let knee = g.joints.iter().position(|j| j == "r_knee").unwrap();
    let hip_roll = g.joints.iter().position(|j| j == "l_hip_roll").unwrap();
    for k in 0..g.len() {
        let st = g.step_state[k];
        // Held offsets equal the stage table's (the first tick of a window applies it).
        assert_eq!(
            g.offsets_deg[k],
            offsets_at(st),
            "tick {k}, Step_State {st}"
        );
        // eq 6: goal = joint angle of servo angle trim + offset.
        let want = lab17::joint_angle("r_knee", 142.0 + g.offsets_deg[k][7]).unwrap();
        assert!((g.goals[k][knee] - want).abs() < 1e-12);
        assert_eq!(g.goals[k][hip_roll], 0.0); // not in Table 2: holds its trim
    }
    // The second cycle repeats the first.
    assert_eq!(g.offsets_deg[..100], g.offsets_deg[100..]);
    // Stage C starts at the first tick past Step_State 7.08: tick 8, t = 0.32 s.
    let first = g.offsets_deg.iter().position(|o| o[7] != 0.0).unwrap();
    assert_eq!(first, 8);
}

#[test]
fn amplitude_scales_every_offset() {
    let o = SequenceOptions {
        cycles: 1,
        amplitude: 0.5,
        ..Default::default()
    };
    let half = walking_sequence_with(&o).unwrap();
    let full = walking_sequence(1, SEED_SAMPLE_TIME).unwrap();
    for (a, b) in half.offsets_deg.iter().zip(&full.offsets_deg) {
        for i in 0..10 {
            assert_eq!(a[i], 0.5 * b[i]);
        }
    }
}

#[test]
fn bad_input_is_an_error_naming_the_field() {
    let e = |r: Result<JointGoals, GaitError>| r.unwrap_err().to_string();
    assert!(e(walking_sequence(0, 0.02)).contains("cycles"));
    assert!(e(walking_sequence(1, 0.0)).contains("sample_time"));
    assert!(walking_sequence(1, 0.02).is_ok());
    assert!(e(walking_sequence(1, f64::NAN)).contains("sample_time"));
    // Too coarse a tick skips the 4.17 % windows: named, with the stage.
    let msg = e(walking_sequence(1, 0.4));
    assert!(
        msg.contains("sample_time") && msg.contains("stage"),
        "{msg}"
    );
    let o = SequenceOptions {
        cycle_period: -1.0,
        ..Default::default()
    };
    assert!(e(walking_sequence_with(&o)).contains("cycle_period"));
}
