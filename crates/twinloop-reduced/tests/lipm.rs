//! LIPM and 3MLIPM against closed-form solutions.

use twinloop_reduced::{
    GRAVITY, LegMotion, Lipm, LipmInput, Plane, PointMass, ThreeMassLipm, ThreeMasses, ankle_torque,
};

#[test]
fn lipm_fall_matches_the_closed_form() {
    // x(t) = x0 cosh(t/Tc) + Tc v0 sinh(t/Tc), written out here independently.
    let p = Lipm::new(3.3, 0.25).unwrap();
    let tc = (0.25f64 / 9.81).sqrt();
    assert!((p.time_constant() - tc).abs() < 1e-15);
    let (x0, v0) = (0.01, -0.02);
    let run = p
        .simulate(x0, v0, |_| LipmInput::default(), 1e-3, 0.6)
        .unwrap();
    assert_eq!(run.len(), 601);
    for s in &run {
        let x = x0 * (s.t / tc).cosh() + tc * v0 * (s.t / tc).sinh();
        let v = x0 / tc * (s.t / tc).sinh() + v0 * (s.t / tc).cosh();
        // RK4 at dt = Tc/160: relative error ~ (t/Tc) (dt/Tc)^4 / 120, below 1e-10.
        assert!(
            (s.x - x).abs() < 1e-9 * x.abs().max(1e-2),
            "t={} {} vs {x}",
            s.t,
            s.x
        );
        assert!(
            (s.xdot - v).abs() < 1e-9 * v.abs().max(1e-2),
            "t={} {} vs {v}",
            s.t,
            s.xdot
        );
        // Eq. 1 and 2 at every sample.
        assert!((s.xddot - 9.81 / 0.25 * s.x).abs() < 1e-12);
        assert!((s.force - 3.3 * s.xddot).abs() < 1e-12);
    }
    assert!((run.last().unwrap().t - 0.6).abs() < 1e-15);
    // A lean from rest falls the same way.
    let f = p.fall(0.01, 1e-3, 0.3).unwrap();
    let last = f.last().unwrap();
    assert!((last.x - 0.01 * (0.3 / tc).cosh()).abs() < 1e-12);
}

#[test]
fn lipm_with_an_ankle_moment_and_eq_3() {
    let p = Lipm::new(2.0, 0.3).unwrap();
    // A constant moment M shifts the ZMP to p = -M / (m g).
    let m = 0.4;
    let zmp = -m / (2.0 * GRAVITY);
    let run = p
        .simulate(
            0.0,
            0.05,
            |_| LipmInput {
                moment: m,
                vertical_acceleration: 0.0,
            },
            5e-4,
            0.4,
        )
        .unwrap();
    let tc = p.time_constant();
    for s in &run {
        let x = zmp + (0.0 - zmp) * (s.t / tc).cosh() + tc * 0.05 * (s.t / tc).sinh();
        assert!((s.x - x).abs() < 1e-11, "{} vs {x}", s.x);
        assert!((s.zmp - zmp).abs() < 1e-15);
    }
    let (x, _) = p.closed_form(0.0, 0.05, m, 0.4);
    assert!((run.last().unwrap().x - x).abs() < 1e-11);
    // Eq. 3: a change of the horizontal force by dF goes with dM = l dF.
    assert!((p.moment_change(2.0) - 0.6).abs() < 1e-15);
    // moment_for_zmp inverts the ZMP.
    assert!((p.moment_for_zmp(zmp) - m).abs() < 1e-15);
    // A vertical acceleration scales gravity in eq. 1.
    let a = p.acceleration(
        0.1,
        LipmInput {
            moment: 0.0,
            vertical_acceleration: 1.0,
        },
    );
    assert!((a - (9.81 + 1.0) * 0.1 / 0.3).abs() < 1e-15);
}

#[test]
fn lipm_walk_is_periodic_for_a_few_steps() {
    let p = Lipm::new(3.3, 0.22).unwrap();
    let (s, t) = (0.04, 0.4);
    let run = p.walk(s, t, 4, 1e-3).unwrap();
    // Every step starts s/2 behind its foothold and ends s/2 ahead of it, with the
    // same velocity (the closed form per step, independently).
    let v0 = p.periodic_walk_velocity(s, t);
    let tc = p.time_constant();
    let v_end = -0.5 * s / tc * (t / tc).sinh() + v0 * (t / tc).cosh();
    assert!(
        (v_end - v0).abs() < 1e-12,
        "periodic velocity {v_end} vs {v0}"
    );
    for k in 0..=4 {
        let at = run
            .iter()
            .find(|x| (x.t - k as f64 * t).abs() < 1e-9)
            .unwrap();
        let want = k as f64 * s - 0.5 * s;
        assert!((at.x - want).abs() < 1e-8, "step {k}: {} vs {want}", at.x);
        assert!((at.xdot - v0).abs() < 1e-7, "step {k}: {} vs {v0}", at.xdot);
    }
    // The ZMP sits on the footholds.
    assert!(run.iter().all(|x| {
        let k = ((x.t / t) - 1e-9).floor().max(0.0);
        (x.zmp - k * s).abs() < 1e-12
    }));
}

#[test]
fn lipm_refuses_bad_input() {
    assert_eq!(Lipm::new(0.0, 1.0).unwrap_err().field, "mass");
    assert_eq!(Lipm::new(1.0, f64::NAN).unwrap_err().field, "length");
    let p = Lipm::new(1.0, 1.0).unwrap();
    assert_eq!(p.fall(0.1, 0.0, 1.0).unwrap_err().field, "dt");
    assert_eq!(p.fall(0.1, 1e-3, -1.0).unwrap_err().field, "duration");
    let e = p
        .simulate(
            0.0,
            0.0,
            |_| LipmInput {
                moment: f64::NAN,
                vertical_acceleration: 0.0,
            },
            1e-3,
            0.1,
        )
        .unwrap_err();
    assert_eq!(e.field, "input");
    let e = p
        .simulate_segments(
            0.0,
            0.0,
            &[(
                0.1,
                LipmInput {
                    moment: f64::INFINITY,
                    vertical_acceleration: 0.0,
                },
            )],
            1e-3,
        )
        .unwrap_err();
    assert_eq!(e.field, "segments[0].moment");
}

fn at(mass: f64, position: [f64; 3]) -> PointMass {
    PointMass { mass, position }
}

#[test]
fn three_masses_at_one_point_are_a_lipm() {
    // Equal masses at the same point, both legs support lines: the 3MLIPM is a LIPM of
    // the total mass at that height, for a fall and with an ankle torque.
    let (m, h, x0) = (1.1, 0.24, 0.008);
    let tm = ThreeMasses::new(
        at(m, [x0, 0.0, h]),
        at(m, [x0, 0.0, h]),
        at(m, [x0, 0.0, h]),
    )
    .unwrap();
    let three = ThreeMassLipm::new(tm).unwrap();
    assert!((three.effective_length() - h).abs() < 1e-15);
    let lipm = Lipm::new(3.0 * m, h).unwrap();
    let torque = |t: f64| 0.05 * (3.0 * t).sin();
    let a = three
        .simulate(
            Plane::Sagittal,
            (LegMotion::SupportLine, LegMotion::SupportLine),
            0.01,
            torque,
            1e-3,
            0.5,
        )
        .unwrap();
    let b = lipm
        .simulate(
            x0,
            0.01,
            |t| LipmInput {
                moment: torque(t),
                vertical_acceleration: 0.0,
            },
            1e-3,
            0.5,
        )
        .unwrap();
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(&b) {
        assert!((p.hip - q.x).abs() < 1e-12, "{} vs {}", p.hip, q.x);
        assert!((p.hip_velocity - q.xdot).abs() < 1e-12);
        assert!((p.com - q.x).abs() < 1e-12);
        // What was integrated is eq. 5: the moment computed back equals the input.
        assert!((p.ankle_torque - torque(p.t)).abs() < 1e-12);
    }
    // The frontal plane (eq. 4, 6) the same, with a lateral lean.
    let tm = ThreeMasses::new(
        at(m, [0.0, x0, h]),
        at(m, [0.0, x0, h]),
        at(m, [0.0, x0, h]),
    )
    .unwrap();
    let f = ThreeMassLipm::new(tm)
        .unwrap()
        .simulate(
            Plane::Frontal,
            (LegMotion::SupportLine, LegMotion::SupportLine),
            0.0,
            |_| 0.0,
            1e-3,
            0.3,
        )
        .unwrap();
    let tc = (h / 9.81).sqrt();
    for s in &f {
        assert!((s.hip - x0 * (s.t / tc).cosh()).abs() < 1e-12);
        assert!(s.ankle_torque.abs() < 1e-12);
    }
}

#[test]
fn three_mass_fall_is_a_pendulum_of_the_effective_length() {
    // Legs lower than the hip, on the line from the ankle to the hip (x = 0.4 x_hip): u'' = g (sum m k) / (sum m k z) u,
    // a LIPM of length sum m z^2 / sum m z (closed form), which is longer than the CoM
    // height, so the three masses fall more slowly than a single mass at their CoM.
    let tm = ThreeMasses::new(
        at(0.74, [0.008, 0.04, 0.12]),
        at(0.74, [0.008, -0.04, 0.12]),
        at(1.85, [0.02, 0.0, 0.30]),
    )
    .unwrap();
    let three = ThreeMassLipm::new(tm).unwrap();
    let ms = [0.74, 0.74, 1.85];
    let zs = [0.12, 0.12, 0.30];
    let l: f64 = ms.iter().zip(&zs).map(|(m, z)| m * z * z).sum::<f64>()
        / ms.iter().zip(&zs).map(|(m, z)| m * z).sum::<f64>();
    assert!((three.effective_length() - l).abs() < 1e-15);
    let com_height = ms.iter().zip(&zs).map(|(m, z)| m * z).sum::<f64>() / 3.33;
    assert!(l > com_height);
    let run = three
        .simulate(
            Plane::Sagittal,
            (LegMotion::SupportLine, LegMotion::SupportLine),
            0.0,
            |_| 0.0,
            1e-3,
            0.4,
        )
        .unwrap();
    let tc = (l / 9.81).sqrt();
    for s in &run {
        let want = 0.02 * (s.t / tc).cosh();
        assert!((s.hip - want).abs() < 1e-9 * want, "{} vs {want}", s.hip);
        // The legs stay on the line from the ankle to the hip.
        assert!((s.left_leg - 0.4 * s.hip).abs() < 1e-15);
        assert!(s.ankle_torque.abs() < 1e-12);
    }
}

#[test]
fn three_mass_with_a_swing_leg_satisfies_eq_7() {
    // Single support on the right leg, the left leg swinging forward on a prescribed
    // cubic; no ankle torque: eq. 7, sum m x'' z = sum m g x, holds at every sample.
    let tm = ThreeMasses::new(
        at(0.74, [-0.02, 0.08, 0.14]),
        at(0.74, [0.0, 0.0, 0.12]),
        at(1.85, [0.01, 0.04, 0.30]),
    )
    .unwrap();
    let swing = |t: f64| (-0.02 + 0.25 * t * t - 0.2 * t * t * t, 0.5 - 1.2 * t);
    let run = ThreeMassLipm::new(tm)
        .unwrap()
        .simulate(
            Plane::Sagittal,
            (LegMotion::Prescribed(&swing), LegMotion::SupportLine),
            -0.05,
            |_| 0.0,
            1e-3,
            0.4,
        )
        .unwrap();
    for s in &run {
        let ps = [
            at(0.74, [s.left_leg, 0.08, 0.14]),
            at(0.74, [s.right_leg, 0.0, 0.12]),
            at(1.85, [s.hip, 0.04, 0.30]),
        ];
        let acc = [
            [swing(s.t).1, 0.0, 0.0],
            [0.12 / 0.30 * s.hip_acceleration, 0.0, 0.0],
            [s.hip_acceleration, 0.0, 0.0],
        ];
        let lhs: f64 = ps
            .iter()
            .zip(&acc)
            .map(|(p, a)| p.mass * a[0] * p.position[2])
            .sum();
        let rhs: f64 = ps.iter().map(|p| p.mass * 9.81 * p.position[0]).sum();
        assert!(
            (lhs - rhs).abs() < 1e-12,
            "eq. 7 at t={}: {lhs} vs {rhs}",
            s.t
        );
        assert!((s.left_leg - swing(s.t).0).abs() < 1e-15);
        assert!(ankle_torque(&ps, &acc, 9.81)[1].abs() < 1e-12);
    }
}

#[test]
fn ankle_torque_is_eq_4_and_5() {
    // Two masses at rest: eq. 4 gives g sum m y, eq. 5 gives -g sum m x (hand values).
    let ps = [at(1.0, [0.1, 0.2, 0.3]), at(2.0, [-0.05, 0.0, 0.5])];
    let tau = ankle_torque(&ps, &[[0.0; 3]; 2], 10.0);
    assert!((tau[0] - 10.0 * 0.2).abs() < 1e-15);
    assert!((tau[1] - (-10.0 * (0.1 - 0.1))).abs() < 1e-15);
    // With accelerations: tau_x = m((z''+g) y - y'' z), tau_y = m(x'' z - (z''+g) x).
    let tau = ankle_torque(&[at(2.0, [0.1, 0.2, 0.3])], &[[1.0, -2.0, 0.5]], 10.0);
    assert!((tau[0] - 2.0 * (10.5 * 0.2 + 2.0 * 0.3)).abs() < 1e-14);
    assert!((tau[1] - 2.0 * (1.0 * 0.3 - 10.5 * 0.1)).abs() < 1e-14);
}

#[test]
fn three_masses_refuse_bad_input() {
    let e = ThreeMasses::new(at(0.0, [0.0; 3]), at(1.0, [0.0; 3]), at(1.0, [0.0; 3])).unwrap_err();
    assert_eq!(e.field, "left_leg.mass");
    let e = ThreeMasses::new(
        at(1.0, [0.0; 3]),
        at(1.0, [0.0, f64::NAN, 0.0]),
        at(1.0, [0.0; 3]),
    )
    .unwrap_err();
    assert_eq!(e.field, "right_leg.position.y");
    let tm = ThreeMasses::new(
        at(1.0, [0.0; 3]),
        at(1.0, [0.0, 0.0, 0.1]),
        at(1.0, [0.0, 0.0, 0.3]),
    )
    .unwrap();
    assert_eq!(
        ThreeMassLipm::new(tm).unwrap_err().field,
        "left_leg.position.z"
    );
}

/// The two closed forms of a phase under a linear ZMP (seed 002 eq 12-13) agree: the
/// exponential basis fitted to a start state is the cosh/sinh solution from it, and
/// both satisfy x'' = (x - p) / Tc^2.
#[test]
fn linear_zmp_phase_matches_the_initial_value_closed_form() {
    use twinloop_reduced::lipm::{LipmPhase, linear_zmp_closed_form, time_constant};
    let tc = time_constant(0.5, 9.81);
    assert_eq!(
        tc,
        Lipm::new(30.0, 0.5)
            .unwrap()
            .with_gravity(9.81)
            .unwrap()
            .time_constant()
    );
    let (p0, slope, d) = (0.02, 0.15, 0.7);
    let mut phase = LipmPhase::new(tc, d, p0, slope);
    // Fit B from an end condition, A from a start position; read the start velocity.
    phase.fit_end_divergent_component(0.1);
    let x_end = phase.fit_start_position(-0.01);
    let start = phase.state(0.0);
    assert!((start.x + 0.01).abs() < 1e-15);
    for i in 0..=20 {
        let t = d * i as f64 / 20.0;
        let (x, v) = linear_zmp_closed_form(tc, start.x, start.v, p0, slope, t);
        let s = phase.state(t);
        assert!((x - s.x).abs() < 1e-12 && (v - s.v).abs() < 1e-12, "t {t}");
        assert!((s.a - (s.x - phase.zmp(t)) / (tc * tc)).abs() < 1e-12);
    }
    assert!((phase.state(d).x - x_end).abs() < 1e-14);
    // xi(D) = x + Tc x' is the end condition.
    let end = phase.state(d);
    assert!((end.x + tc * end.v - 0.1).abs() < 1e-14);
}
