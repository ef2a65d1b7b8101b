//! End to end: the walk recorded on lab17 in the simulator, identified as seed 003 did.

use twinloop_gait::*;
use twinloop_sysid::{ArxOrders, EvaluationOptions, IoData, identify_arx};

fn record(seed: u64) -> WalkDataset {
    let robot = twinloop_robots::resolve("builtin:lab17").unwrap();
    let mut o = DatasetOptions {
        noise_seed: seed,
        ..Default::default()
    };
    // The seed's amplitudes tip our lab17 over (docs/lab17-walking-identification.md).
    o.sequence.amplitude = 0.7;
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
fn the_walk_dataset_identifies_end_to_end() {
    let est = record(1);
    let val = record(2);
    // Shape and columns: t, ten inputs, six gyro rates, 1000 samples (seed 003 section 7).
    assert_eq!(est.rows.len(), 1000);
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
    assert!(est.fell_at.is_none(), "upright at amplitude 0.7");
    // Gyro values are whole MPU-6050 counts (eq 7: 131 LSB per deg/s), and move.
    for r in &est.rows {
        for &w in &r[11..] {
            let lsb = w * 131.0;
            assert!((lsb - lsb.round()).abs() < 1e-6, "{w} deg/s is not a count");
        }
    }
    // Different noise seeds: different records.
    assert_ne!(est.rows[500][11..], val.rows[500][11..]);

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
        assert!(f > 20.0, "output {k}: validation FIT {f:.1} %");
    }
}
