//! Orientations are kept as rotation matrices end to end: a pose made from a
//! quaternion or a matrix (MJCF) keeps that matrix bit for bit, also at the
//! pitch +-90 deg singularity, and one made from roll-pitch-yaw (URDF) keeps
//! those numbers for writing. The roll-pitch-yaw derived from a matrix, only
//! for writing a URDF, is backward stable to rounding there too (where
//! recovering pitch through `asin` loses half the digits).

use twinloop_description::{Pose, matrix_to_rpy, mjcf, quaternion_to_matrix, rpy_to_matrix};

fn max_diff(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> f64 {
    (0..9)
        .map(|k| (a[k / 3][k % 3] - b[k / 3][k % 3]).abs())
        .fold(0.0, f64::max)
}

/// A quaternion turned about y by `pitch` after a random turn, so that the
/// matrix sits at (or within `eps` of) the singularity.
fn near_singular(seed: u64, eps: f64) -> [[f64; 3]; 3] {
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let roll = 3.0 * next();
    let yaw = 3.0 * next();
    let sign = if next() > 0.0 { 1.0 } else { -1.0 };
    let pitch = sign * (std::f64::consts::FRAC_PI_2 - eps * next());
    rpy_to_matrix([roll, pitch, yaw])
}

#[test]
fn rpy_round_trip_is_exact_to_rounding_everywhere() {
    let mut worst: f64 = 0.0;
    for seed in 0..2000 {
        for eps in [0.0, 1e-16, 1e-12, 1e-8, 1e-4, 0.5, 1.5] {
            let r = near_singular(seed, eps);
            worst = worst.max(max_diff(&rpy_to_matrix(matrix_to_rpy(r)), &r));
        }
    }
    assert!(worst < 2e-15, "largest matrix error {worst:e}");
    // MuJoCo's pitch-90 quaternion as the MJCF files write it.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let q = quaternion_to_matrix([h, 0.0, h, 0.0]);
    assert!(max_diff(&rpy_to_matrix(matrix_to_rpy(q)), &q) < 1e-15);
}

/// A pose keeps the matrix it was made from exactly (no angles in between),
/// at and near the singularity; one made from roll-pitch-yaw gives those
/// numbers back exactly and its matrix is `rpy_to_matrix` of them.
#[test]
fn poses_keep_their_rotation_exactly() {
    for seed in 0..2000 {
        for eps in [0.0, 1e-16, 1e-12, 1e-8, 0.5] {
            let r = near_singular(seed, eps);
            let p = Pose::from_matrix([0.1, 0.2, 0.3], r);
            assert_eq!(p.rotation(), r);
            // The URDF angles derived from it are still right to rounding.
            assert!(max_diff(&rpy_to_matrix(p.rpy()), &r) < 2e-15);
        }
    }
    let h = std::f64::consts::FRAC_1_SQRT_2;
    for q in [[h, 0.0, h, 0.0], [h, 0.0, -h, 0.0], [0.5, 0.5, 0.5, 0.5]] {
        let p = Pose::from_quaternion([0.0; 3], q);
        assert_eq!(p.rotation(), quaternion_to_matrix(q));
    }
    let rpy = [0.1, std::f64::consts::FRAC_PI_2, -2.9];
    let p = Pose::new([0.0; 3], rpy);
    assert_eq!((p.rpy(), p.rotation()), (rpy, rpy_to_matrix(rpy)));
}

/// An MJCF body turned by MuJoCo's pitch-90 quaternion: the joint that places it
/// carries exactly the quaternion's matrix, and its inertial exactly its own (it lost 8 digits through `asin`
/// when the description stored roll-pitch-yaw, and ~1e-16 through the
/// backward-stable angles after that).
#[test]
fn mjcf_orientations_reach_the_description_exactly() {
    let r = mjcf::from_str(
        r#"<mujoco><worldbody><body name="a">
  <body name="b" pos="0.1 0 0" quat="0.7071067811865476 0 0.7071067811865476 0"><joint name="j" pos="0 0 0"/>
    <inertial pos="0 0 0.1" quat="0.5 0.5 -0.5 0.5" mass="1" diaginertia="0.1 0.2 0.3"/></body>
</body></worldbody></mujoco>"#,
    )
    .unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2; // as the file writes it
    assert_eq!(
        r.joint("j").unwrap().origin.rotation(),
        quaternion_to_matrix([h, 0.0, h, 0.0])
    );
    let i = r.link("b").unwrap().inertial.unwrap();
    // So does the inertial frame (its principal axes), from its own quaternion.
    assert_eq!(i.origin.xyz, [0.0, 0.0, 0.1]);
    assert_eq!(
        i.origin.rotation(),
        quaternion_to_matrix([0.5, 0.5, -0.5, 0.5])
    );
}
