//! Orientations survive the description's roll-pitch-yaw to rounding, also at
//! the pitch +-90 deg singularity (where recovering pitch through `asin` loses
//! half the digits).

use twinloop_description::{matrix_to_rpy, quaternion_to_matrix, rpy_to_matrix};

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
