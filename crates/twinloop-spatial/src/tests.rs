//! Identities of spatial algebra checked against their 6x6 matrix forms.

use super::*;

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn v3(s: &mut u64) -> Vector3<f64> {
    Vector3::new(lcg(s), lcg(s), lcg(s))
}

fn random_se3(s: &mut u64) -> Se3 {
    let axis = v3(s).normalize();
    Se3::new(axis_angle(&axis, 3.0 * lcg(s)), v3(s))
}

/// The 6x6 motion transform of aMb (Featherstone's X), linear part first.
fn action_matrix(x: &Se3) -> Matrix6<f64> {
    let mut m = Matrix6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&x.rotation);
    m.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(skew(&x.translation) * x.rotation));
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&x.rotation);
    m
}

#[test]
fn transforms_match_matrix_forms() {
    let mut s = 7u64;
    for _ in 0..50 {
        let x = random_se3(&mut s);
        let m = Motion::new(v3(&mut s), v3(&mut s));
        let f = Force::new(v3(&mut s), v3(&mut s));
        let ax = action_matrix(&x);
        let mv = m.to_vector6();
        assert!((x.act_motion(&m).to_vector6() - ax * mv).norm() < 1e-12);
        assert!((x.act_inv_motion(&x.act_motion(&m)).to_vector6() - mv).norm() < 1e-12);
        // Forces transform with X^-T: power is invariant.
        let fa = x.act_force(&f);
        assert!(
            (fa.to_vector6() - ax.try_inverse().unwrap().transpose() * f.to_vector6()).norm()
                < 1e-11
        );
        assert!((x.act_motion(&m).dot(&fa) - m.dot(&f)).abs() < 1e-12);
        assert!((x.act_inv_force(&fa).to_vector6() - f.to_vector6()).norm() < 1e-12);
    }
}

#[test]
fn inertia_forms_agree() {
    let mut s = 11u64;
    for _ in 0..50 {
        let a = Matrix3::from_fn(|_, _| lcg(&mut s));
        let inertia = Inertia::new(1.0 + lcg(&mut s).abs(), v3(&mut s), a * a.transpose());
        let m = Motion::new(v3(&mut s), v3(&mut s));
        let f1 = inertia.mul_motion(&m).to_vector6();
        let f2 = inertia.to_symmetric6().to_matrix6() * m.to_vector6();
        assert!((f1 - f2).norm() < 1e-12);
        // Transforming the inertia is the congruence X^-T I X^-1.
        let x = random_se3(&mut s);
        let ax = action_matrix(&x);
        let axi = ax.try_inverse().unwrap();
        let expect = axi.transpose() * inertia.to_symmetric6().to_matrix6() * axi;
        let got = inertia.transformed(&x).to_symmetric6().to_matrix6();
        assert!((expect - got).norm() < 1e-11);
        // Dynamic parameters round trip.
        let back = Inertia::from_dynamic_parameters(&inertia.dynamic_parameters());
        assert!((back.com - inertia.com).norm() < 1e-12);
        assert!((back.inertia - inertia.inertia).norm() < 1e-12);
        // Sum of inertias equals the sum of their 6x6 matrices.
        let other = Inertia::new(0.5, v3(&mut s), Matrix3::identity() * 0.1);
        let sum = (inertia + other).to_symmetric6().to_matrix6();
        let msum = inertia.to_symmetric6().to_matrix6() + other.to_symmetric6().to_matrix6();
        assert!((sum - msum).norm() < 1e-11);
    }
}

#[test]
fn cross_products_match_matrix_forms() {
    let mut s = 3u64;
    let m = Motion::new(v3(&mut s), v3(&mut s));
    let n = Motion::new(v3(&mut s), v3(&mut s));
    let f = Force::new(v3(&mut s), v3(&mut s));
    // crm(m) = [[w^, v^], [0, w^]]
    let mut crm = Matrix6::zeros();
    crm.fixed_view_mut::<3, 3>(0, 0).copy_from(&skew(&m.w));
    crm.fixed_view_mut::<3, 3>(0, 3).copy_from(&skew(&m.v));
    crm.fixed_view_mut::<3, 3>(3, 3).copy_from(&skew(&m.w));
    assert!((m.cross(&n).to_vector6() - crm * n.to_vector6()).norm() < 1e-12);
    let crf = -crm.transpose();
    assert!((m.cross_force(&f).to_vector6() - crf * f.to_vector6()).norm() < 1e-12);
}

#[test]
fn quaternion_round_trip() {
    let mut s = 5u64;
    for _ in 0..100 {
        let r = random_se3(&mut s).rotation;
        let q = matrix_to_quaternion_xyzw(&r);
        let r2 = quaternion_xyzw_to_matrix(q[0], q[1], q[2], q[3]);
        assert!((r - r2).norm() < 1e-12);
    }
}

#[test]
fn linear_inertia_agrees_with_inertia() {
    let mut s = 13u64;
    for _ in 0..50 {
        let a = Matrix3::from_fn(|_, _| lcg(&mut s));
        let y1 = Inertia::new(1.0 + lcg(&mut s).abs(), v3(&mut s), a * a.transpose());
        let y2 = Inertia::new(0.5, v3(&mut s), Matrix3::identity() * 0.1);
        let m = Motion::new(v3(&mut s), v3(&mut s));
        let l1 = LinearInertia::from_inertia(&y1);
        assert!((l1.mul_motion(&m).to_vector6() - y1.mul_motion(&m).to_vector6()).norm() < 1e-12);
        assert!((l1.i - y1.inertia_about_origin()).norm() < 1e-12);
        // The linear form's plain sum is the rigid union.
        let mut sum = l1;
        sum.add(&LinearInertia::from_inertia(&y2));
        let expect = (y1 + y2).mul_motion(&m).to_vector6();
        assert!((sum.mul_motion(&m).to_vector6() - expect).norm() < 1e-11);
    }
}

#[test]
fn sin_cos_matches_the_library() {
    // Joint angles (dense near zero and out to many turns), the quadrant edges,
    // and the hand-over to the library at 1e5.
    let mut seed = 3u64;
    let mut worst: f64 = 0.0;
    let mut check = |x: f64| {
        let (s, c) = sin_cos(x);
        let (s0, c0) = x.sin_cos();
        worst = worst.max((s - s0).abs()).max((c - c0).abs());
    };
    for k in 0..200_000 {
        let scale = [1.0, 4.0, 40.0, 1e4][k % 4];
        check(scale * lcg(&mut seed));
    }
    for k in -400..=400 {
        let edge = f64::from(k) * std::f64::consts::FRAC_PI_4;
        for d in [-1e-12, -1e-16, 0.0, 1e-16, 1e-12] {
            check(edge + d);
        }
    }
    for x in [0.0, -0.0, 1e-300, 99_999.9, 1e5, 1e6, -1e7] {
        check(x);
    }
    assert!(worst <= 2.3e-16, "worst difference {worst:e}");
    assert!(sin_cos(f64::NAN).0.is_nan() && sin_cos(f64::INFINITY).1.is_nan());
}

#[test]
fn sin_cos_lanes_is_sin_cos_bit_for_bit() {
    // Ordinary angles beside the library's lanes (NaN, infinity, >= 1e5) in one call.
    let mut seed = 11u64;
    for k in 0..20_000 {
        let mut x = [0.0; 4];
        for (l, xl) in x.iter_mut().enumerate() {
            *xl = [1.0, 4.0, 40.0, 1e4][(k + l) % 4] * lcg(&mut seed);
        }
        if k % 50 == 0 {
            x[k % 4] = [f64::NAN, f64::INFINITY, 1e5, -3e7][(k / 50) % 4];
        }
        let (s, c) = sin_cos_lanes(&x);
        for l in 0..4 {
            let (s0, c0) = sin_cos(x[l]);
            assert_eq!(s[l].to_bits(), s0.to_bits(), "sin({})", x[l]);
            assert_eq!(c[l].to_bits(), c0.to_bits(), "cos({})", x[l]);
        }
    }
}
