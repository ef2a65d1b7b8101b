//! Three masses derived from full models: they sum to the model's mass and their
//! weighted mean is the model's CoM, in any configuration.

use twinloop_dynamics::{Data, Model, center_of_mass};
use twinloop_reduced::{ThreeMasses, ankle_midpoint, com_relative_to_ankles};

fn op3() -> Model {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/op3/robotis_op3.nomesh.urdf"
    );
    Model::from_description(&twinloop_description::load(path).unwrap()).unwrap()
}

fn km20() -> Model {
    Model::from_description(&twinloop_description::builtin::builtin("km20").unwrap()).unwrap()
}

/// A deterministic pseudo-random configuration (splitmix64), base rotated and moved.
fn configuration(model: &Model, seed: u64) -> Vec<f64> {
    let mut s = seed;
    let mut next = move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut q = model.neutral_configuration();
    for v in q.iter_mut().skip(model.q_offset) {
        *v = next();
    }
    let (x, y, z, w) = (next(), next(), next(), next() + 2.0);
    let n = (x * x + y * y + z * z + w * w).sqrt();
    q[..7].copy_from_slice(&[next(), next(), next(), x / n, y / n, z / n, w / n]);
    q
}

fn check(model: &Model, q: &[f64], left: &str, right: &str) -> ThreeMasses {
    let three = ThreeMasses::from_model(model, q, left, right).unwrap();
    assert!(
        (three.total_mass() - model.total_mass).abs() < 1e-12,
        "{} vs {}",
        three.total_mass(),
        model.total_mass
    );
    let mut data = Data::new(model);
    let c = center_of_mass(model, &mut data, q);
    let got = three.com();
    for k in 0..3 {
        assert!((got[k] - c[k]).abs() < 1e-12, "{got:?} vs {c}");
    }
    three
}

#[test]
fn km20_three_masses_are_table_i() {
    let model = km20();
    let q = model.neutral_configuration();
    let three = check(&model, &q, "l_hip_yaw", "r_hip_yaw");
    // The legs are seed 000 Table I's legs; the hip mass is torso + arms + head.
    assert!((three.left_leg.mass - 0.740).abs() < 1e-12);
    assert!((three.right_leg.mass - 0.743).abs() < 1e-12);
    assert!((three.hip.mass - (1.375 + 0.238 + 0.240)).abs() < 1e-12);
    // Legs sit at the hips' lateral positions, the hip mass above them.
    assert!((three.left_leg.position[1] - 0.04).abs() < 0.01);
    assert!((three.right_leg.position[1] + 0.04).abs() < 0.01);
    assert!(three.hip.position[2] > three.left_leg.position[2]);
    for seed in 0..5 {
        check(
            &model,
            &configuration(&model, seed),
            "l_hip_yaw",
            "r_hip_yaw",
        );
    }
}

#[test]
fn op3_and_lab17_three_masses_sum_to_the_model() {
    let model = op3();
    for seed in 0..5 {
        check(
            &model,
            &configuration(&model, seed),
            "l_hip_yaw",
            "r_hip_yaw",
        );
    }
    let lab =
        Model::from_description(&twinloop_description::builtin::builtin("lab17").unwrap()).unwrap();
    for seed in 0..3 {
        check(&lab, &configuration(&lab, seed), "l_hip_roll", "r_hip_roll");
    }
}

#[test]
fn com_relative_to_the_ankles() {
    let model = km20();
    let q = model.neutral_configuration();
    // Standing km20: the ankle axes are 0.031 above the soles, the torso frame 0.276.
    let mid = ankle_midpoint(&model, &q, "l_ank_pitch", "r_ank_pitch").unwrap();
    assert!(mid[0].abs() < 1e-15 && mid[1].abs() < 1e-15);
    assert!((mid[2] - (0.031 - 0.276)).abs() < 1e-12);
    let c = com_relative_to_ankles(&model, &q, "l_ank_pitch", "r_ank_pitch").unwrap();
    let mut data = Data::new(&model);
    let w = center_of_mass(&model, &mut data, &q);
    for k in 0..3 {
        assert!((c[k] - (w[k] - mid[k])).abs() < 1e-15);
    }
}

#[test]
fn bad_input_names_the_field() {
    let model = km20();
    let q = model.neutral_configuration();
    let e = ThreeMasses::from_model(&model, &q, "l_hip", "r_hip_yaw").unwrap_err();
    assert_eq!(e.field, "left_hip_joint");
    assert!(e.to_string().contains("l_hip"), "{e}");
    let e = ThreeMasses::from_model(&model, &q, "l_hip_yaw", "l_knee").unwrap_err();
    assert_eq!(e.field, "right_hip_joint");
    let e = ThreeMasses::from_model(&model, &q[1..], "l_hip_yaw", "r_hip_yaw").unwrap_err();
    assert_eq!(e.field, "q");
    let mut bad = q.clone();
    bad[6] = 2.0;
    let e = ThreeMasses::from_model(&model, &bad, "l_hip_yaw", "r_hip_yaw").unwrap_err();
    assert!(e.field.starts_with("q[base"), "{e}");
    bad = q.clone();
    bad[10] = f64::NAN;
    let e = ThreeMasses::from_model(&model, &bad, "l_hip_yaw", "r_hip_yaw").unwrap_err();
    assert!(e.field.starts_with("q["), "{e}");
    let e = ankle_midpoint(&model, &q, "l_ank_pitch", "nope").unwrap_err();
    assert_eq!(e.field, "right_ankle_joint");
}
