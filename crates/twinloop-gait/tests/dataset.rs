//! End to end: the walk recorded on lab17 in the simulator at the seed's full offsets,
//! identified as seed 003 did.

use twinloop_gait::*;
use twinloop_sysid::{ArxOrders, EvaluationOptions, IoData, identify_arx};

fn record(seed: u64, skip: usize) -> WalkDataset {
    let robot = twinloop_robots::resolve("builtin:lab17").unwrap();
    let o = DatasetOptions {
        noise_seed: seed,
        skip_samples: skip,
        ..Default::default()
    };
    assert_eq!(o.sequence.amplitude, 1.0, "the seed's printed offsets");
    record_walk(&robot, &o).unwrap()
}

/// The seven distinct input signals (knee and hip pitch move together on each side,
/// and the two ankle rolls together, so the ten offsets span seven).
const DISTINCT: [&str; 7] = [
    "u:l_ank_roll",
    "u:l_ank_pitch",
    "u:l_knee",
    "u:l_sho_pitch",
    "u:r_ank_pitch",
    "u:r_knee",
    "u:r_sho_pitch",
];

#[test]
fn lab17_walks_forward_at_the_seeds_offsets() {
    // Cycles 1-10 (the identification record) and 11-20 (the validation record): the
    // robot stays upright and walks, about 74 mm per cycle by the stage kinematics
    // (right foot 25.6 mm, left 48.2 mm ahead of the hip, each then overtaken by the
    // body): at least 50 cm per 10 cycles along its starting heading.
    for (skip, what) in [(0, "cycles 1-10"), (1000, "cycles 11-20")] {
        let d = record(1, skip);
        assert!(d.fell_at.is_none(), "{what}: fell at {:?}", d.fell_at);
        assert!(d.max_tilt_deg < 25.0, "{what}: tilt {}", d.max_tilt_deg);
        let forward = d.travel[0];
        assert!(forward > 0.5, "{what}: travelled {forward} m forward");
        assert!(d.yaw_deg.abs() < 45.0, "{what}: turned {} deg", d.yaw_deg);
    }
}

#[test]
fn the_walk_dataset_identifies_end_to_end() {
    let est = record(1, 0);
    let val = record(2, 1000);
    // Shape and columns: t, ten inputs, six gyro rates, 1000 samples (seed 003 section 7).
    assert_eq!(est.rows.len(), 1000);
    assert_eq!(val.rows.len(), 1000);
    assert_eq!(est.columns.len(), 17);
    assert_eq!(est.columns[0], "t");
    for (c, j) in est.columns[1..11].iter().zip(OFFSET_JOINTS) {
        assert_eq!(c, &format!("u:{j}"));
    }
    for (k, f) in ["l_foot", "r_foot"].iter().enumerate() {
        for (a, ax) in ["roll", "pitch", "yaw"].iter().enumerate() {
            assert_eq!(est.columns[11 + 3 * k + a], format!("gyro:{f}.{ax}"));
        }
    }
    // The seed's offsets (servo degrees) appear at full size.
    let max = |c: usize| est.rows.iter().map(|r| r[c].abs()).fold(0.0, f64::max);
    assert_eq!(max(3), 40.0); // l_knee, stage F
    assert_eq!(max(8), 20.0); // r_knee, stage C
    assert_eq!(max(1), 7.0); // l_ank_roll, stages B/E/H/M
    // Gyro values are whole MPU-6050 counts (eq 7: 131 LSB per deg/s), and move.
    for r in &est.rows {
        for &w in &r[11..] {
            let lsb = w * 131.0;
            assert!((lsb - lsb.round()).abs() < 1e-6, "{w} deg/s is not a count");
        }
    }
    // The validation record is a later stretch of the walk: same inputs (the sequence
    // repeats every cycle), different motion.
    assert_eq!(est.rows[500][1..11], val.rows[500][1..11]);
    let diff: f64 = est
        .rows
        .iter()
        .zip(&val.rows)
        .map(|(a, b)| (a[12] - b[12]).powi(2))
        .sum::<f64>()
        .sqrt();
    let norm: f64 = est.rows.iter().map(|a| a[12].powi(2)).sum::<f64>().sqrt();
    assert!(diff > 0.05 * norm, "validation differs by {diff} of {norm}");

    let cols = est.columns.clone();
    let inputs: Vec<String> = DISTINCT.iter().map(|s| s.to_string()).collect();
    let outputs = vec!["gyro:*".to_string()];
    let e = IoData::from_table(&cols, &est.rows, &inputs, &outputs).unwrap();
    let v = IoData::from_table(&cols, &val.rows, &inputs, &outputs).unwrap();
    let id = identify_arx(
        &e,
        Some(&v),
        ArxOrders {
            na: 24,
            nb: 12,
            nk: 1,
        },
        &EvaluationOptions::default(),
    )
    .unwrap();
    for (k, f) in id.evaluation.fit_percent.simulation.iter().enumerate() {
        let f = f.expect("a FIT per output");
        assert!(f > 30.0, "output {k}: validation FIT {f:.1} %");
    }
}
