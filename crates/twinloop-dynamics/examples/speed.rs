//! Quick single-call timings of the dynamics on one model (for development; the
//! reported numbers come from `twinloop bench dynamics` beside Pinocchio).
//! `cargo run --profile ci -p twinloop-dynamics --example speed -- MODEL [SECONDS]`
use std::hint::black_box;
use std::time::Instant;
use twinloop_dynamics::configuration::{random_configuration, random_tangent};
use twinloop_dynamics::*;
use twinloop_random::SplitMix64;

fn time(n: usize, secs: f64, mut round: impl FnMut()) -> f64 {
    round();
    let mut s = Vec::new();
    let t0 = Instant::now();
    while s.len() < 11 || t0.elapsed().as_secs_f64() < secs {
        let t = Instant::now();
        round();
        s.push(t.elapsed().as_nanos() as f64 / n as f64);
    }
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// Every algorithm's output on one state, one number a line (to compare builds).
fn dump(model: &Model, d: &mut Data, q: &[f64], v: &[f64], a: &[f64]) {
    let mut out = Vec::new();
    forward_kinematics(model, d, q);
    for m in &d.o_m_i {
        out.extend(m.rotation.iter().chain(m.translation.iter()).copied());
    }
    out.extend(center_of_mass(model, d, q).iter().copied());
    out.extend(rnea(model, d, q, v, a).iter().copied());
    out.extend(crba(model, d, q).iter().copied());
    out.extend(aba(model, d, q, v, a).iter().copied());
    compute_joint_jacobians(model, d, q);
    out.extend(d.joint_jacobians.iter().copied());
    out.extend(jacobian_center_of_mass(model, d, q).iter().copied());
    out.extend(joint_torque_regressor(model, d, q, v, a).iter().copied());
    for x in out {
        println!("{x:e}");
    }
}

/// Static count of the multiplications and additions each algorithm's code does on
/// this model (1-DoF joints; sin/cos pairs apart), from the formulas in src/ with
/// R v = 15, R R = 45, a cross product 9, a dot product 5 (3 vectors) or 11 (spatial),
/// a spatial transform 42, a motion or force cross product 30, I v = 42.
fn flops(model: &Model) {
    let nb = model.nbodies;
    let floating = model.is_floating();
    let ident = |i: usize| model.joint_placements[i].rotation == nalgebra::Matrix3::identity();
    let aligned = |i: usize| {
        matches!(
            model.joint_types[i],
            JointType::RevoluteX | JointType::RevoluteY | JointType::RevoluteZ
        )
    };
    let keeps = |i: usize| aligned(i) && ident(i);
    // liMi from q: none for a kept axis, two rotated columns, Rodrigues and R R, R a q.
    let joint = |i: usize| match model.joint_types[i] {
        _ if keeps(i) => 0,
        JointType::Revolute => 34 + 45,
        JointType::Prismatic => 21,
        _ => 18,
    };
    // parent * liMi: R t + t, then two columns or a full R R.
    let compose = |i: usize| 18 + if keeps(i) { 18 } else { 45 };
    let column = |i: usize| match model.joint_types[i] {
        JointType::Revolute => 24,
        JointType::Prismatic => 15,
        _ => 9,
    };
    let depth = |i: usize| model.ancestors(i).count();
    let quat = if floating { 24 } else { 0 };
    let fk: usize = quat + (0..nb).map(|i| joint(i) + compose(i)).sum::<usize>();
    let com = fk + (nb + usize::from(floating)) * 24 + 3;
    // The base's six columns: three cross products (the unit twists' other products are zeros).
    let jac = fk + (0..nb).map(column).sum::<usize>() + if floating { 27 } else { 0 };
    let pass: usize = (0..nb)
        .map(|i| {
            joint(i)
                + column(i)
                + if model.parents[i] == BASE {
                    0
                } else {
                    compose(i)
                }
        })
        .sum();
    // CRBA: the pass, each inertia to the base frame (c: 18, R I R^T: 90, parallel
    // axis: 26), composite sums (13), F = Y S (33), S.F down the chain (11 each).
    let crba = quat
        + pass
        + (0..nb)
            .map(|i| 108 + 26 + 13 + 33 + 12 + 11 * depth(i))
            .sum::<usize>()
        + if floating { 26 + 6 * 33 } else { 0 };
    // RNEA: a and v to the body (2 x 42 + 12), v x vj (36), I a + v x* I v (120),
    // S^T f and armature (2), f to the parent (42 + 6); the base's 138.
    let rnea =
        quat + if floating { 138 } else { 18 } + (0..nb).map(|i| joint(i) + 302).sum::<usize>();
    // Regressor: the forward pass (the joint, compose, subspace column, two motions
    // to the body 2 x 42, v x vj 30, sums 12), the 6 x 10 body regressor (190), its
    // columns to the base frame (24 + 3 x 42 + 6 x 15), and per (body, row on its
    // support, itself included) 4 full dot products and 6 angular ones (4 x 11 + 6 x 5).
    let reg = quat
        + if floating { 190 } else { 0 }
        + (0..nb)
            .map(|i| {
                let up = if model.parents[i] == BASE {
                    0
                } else {
                    compose(i)
                };
                joint(i) + up + column(i) + 126 + 190 + 240 + 74 * depth(i)
            })
            .sum::<usize>();
    let trig = (0..nb)
        .filter(|&i| model.joint_types[i].is_revolute())
        .count();
    println!(
        "flops fk {fk} com {com} jacobians {jac} crba {crba} rnea {rnea} regressor {reg} (+ {trig} sin/cos pairs; {} of {nb} joints keep an axis)",
        (0..nb).filter(|&i| keeps(i)).count()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let secs: f64 = args.get(2).map_or(0.3, |s| s.parse().unwrap());
    let robot = twinloop_description::load(&args[1]).unwrap();
    let model = Model::from_description_with_base(&robot, BaseKind::Floating).unwrap();
    let mut rng = SplitMix64(0);
    let n = 200;
    let qs: Vec<Vec<f64>> = (0..n)
        .map(|_| random_configuration(&model, &mut rng))
        .collect();
    let vs: Vec<Vec<f64>> = (0..n).map(|_| random_tangent(&model, &mut rng)).collect();
    let as_: Vec<Vec<f64>> = (0..n).map(|_| random_tangent(&model, &mut rng)).collect();
    let mut d = Data::new(&model);
    if args.get(3).map(String::as_str) == Some("flops") {
        flops(&model);
        return;
    }
    if let Some(algo) = args.get(3) {
        // Fixed work for an instruction counter (valgrind): ALGO run once per state.
        for i in 0..n {
            let (q, v, a) = (black_box(&qs[i]), &vs[i], &as_[i]);
            match algo.as_str() {
                "fk" => forward_kinematics(&model, &mut d, q),
                "com" => drop(black_box(center_of_mass(&model, &mut d, q))),
                "rnea" => drop(black_box(rnea(&model, &mut d, q, v, a))),
                "crba" => drop(black_box(crba(&model, &mut d, q))),
                "aba" => drop(black_box(aba(&model, &mut d, q, v, a))),
                "jacobians" => compute_joint_jacobians(&model, &mut d, q),
                "regressor" => drop(black_box(joint_torque_regressor(&model, &mut d, q, v, a))),
                "dump" => dump(&model, &mut d, q, v, a),
                _ => {}
            }
        }
        black_box(&d);
        return;
    }
    let fk = time(n, secs, || {
        for q in &qs {
            forward_kinematics(&model, &mut d, black_box(q));
        }
        black_box(&d.o_m_i);
    });
    let com = time(n, secs, || {
        for q in &qs {
            black_box(center_of_mass(&model, &mut d, black_box(q)));
        }
    });
    let rn = time(n, secs, || {
        for i in 0..n {
            black_box(rnea(&model, &mut d, black_box(&qs[i]), &vs[i], &as_[i]));
        }
    });
    let cr = time(n, secs, || {
        for q in &qs {
            black_box(crba(&model, &mut d, black_box(q)));
        }
    });
    let ab = time(n, secs, || {
        for i in 0..n {
            black_box(aba(&model, &mut d, black_box(&qs[i]), &vs[i], &as_[i]));
        }
    });
    let jac = time(n, secs, || {
        for q in &qs {
            compute_joint_jacobians(&model, &mut d, black_box(q));
            black_box(&d.joint_jacobians);
        }
    });
    let reg = time(n, secs, || {
        for i in 0..n {
            black_box(joint_torque_regressor(
                &model,
                &mut d,
                black_box(&qs[i]),
                &vs[i],
                &as_[i],
            ));
        }
    });
    let sc = time(n, secs, || {
        for q in &qs {
            let mut acc = 0.0;
            for x in &q[7..] {
                let (s, c) = black_box(*x).sin_cos();
                acc += s + c;
            }
            black_box(acc);
        }
    });
    println!(
        "fk {fk:.0} com {com:.0} rnea {rn:.0} crba {cr:.0} aba {ab:.0} jac {jac:.0} reg {reg:.0} sincos-all-joints {sc:.0}"
    );
}
