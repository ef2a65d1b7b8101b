//! Analytic identities every correct rigid-body dynamics must satisfy, on random
//! trees made with the builder (every joint type, rotated inertial frames, fixed
//! links merged into bodies), floating and fixed base.

use nalgebra::{DMatrix, DVector, Vector3};
use twinloop_description::{
    Description, DescriptionBuilder, Inertia, Inertial, JointKind, Link, Pose,
};
use twinloop_dynamics::configuration::{integrate, random_configuration, random_tangent};
use twinloop_dynamics::*;
use twinloop_random::SplitMix64;

fn random_robot(seed: u64, nlinks: usize) -> Description {
    let mut rng = SplitMix64(seed);
    let mut b = DescriptionBuilder::new(format!("random{seed}"));
    let mut names = vec!["base".to_string()];
    let inertial = |rng: &mut SplitMix64| {
        let m = rng.uniform(0.2, 3.0);
        // Positive definite with the triangle inequality: a box rotated.
        Inertial {
            origin: Pose::new(
                [
                    rng.uniform(-0.1, 0.1),
                    rng.uniform(-0.1, 0.1),
                    rng.uniform(-0.1, 0.1),
                ],
                [
                    rng.uniform(-3.0, 3.0),
                    rng.uniform(-1.5, 1.5),
                    rng.uniform(-3.0, 3.0),
                ],
            ),
            mass: m,
            inertia: Inertia::solid_box(
                m,
                [
                    rng.uniform(0.05, 0.3),
                    rng.uniform(0.05, 0.3),
                    rng.uniform(0.05, 0.3),
                ],
            ),
        }
    };
    let mut base = Link::new("base");
    base.inertial = Some(inertial(&mut rng));
    b = b.add_link(base);
    for k in 1..nlinks {
        let name = format!("l{k}");
        let parent = names[(rng.next_u64() % names.len() as u64) as usize].clone();
        let kind = match rng.next_u64() % 7 {
            0 => JointKind::Fixed,
            1 => JointKind::Prismatic,
            2 => JointKind::Continuous,
            _ => JointKind::Revolute,
        };
        let mut link = Link::new(&name);
        // Some massless links fixed to others, to exercise merging (a massless
        // moving leaf would make M singular, which is the model's fault, not ours).
        if kind != JointKind::Fixed || k % 2 == 1 {
            link.inertial = Some(inertial(&mut rng));
        }
        b = b.add_link(link);
        let axis = match rng.next_u64() % 5 {
            0 => [1.0, 0.0, 0.0],
            1 => [0.0, 1.0, 0.0],
            2 => [0.0, 0.0, 1.0],
            3 => [0.0, -1.0, 0.0],
            _ => [
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            ],
        };
        let origin = Pose::new(
            [
                rng.uniform(-0.3, 0.3),
                rng.uniform(-0.3, 0.3),
                rng.uniform(-0.3, 0.3),
            ],
            [
                rng.uniform(-3.0, 3.0),
                rng.uniform(-1.5, 1.5),
                rng.uniform(-3.0, 3.0),
            ],
        );
        let mut jb = b
            .joint(format!("j{k}"), kind, parent, &name)
            .origin(origin)
            .axis(axis);
        if kind == JointKind::Revolute {
            jb = jb.limits(-2.0, 2.0, 10.0, 5.0);
        }
        b = jb.done();
        names.push(name);
    }
    b = b.frame("tool", "l3", Pose::new([0.1, 0.0, 0.05], [0.3, 0.2, 0.1]));
    b.build().unwrap()
}

fn models() -> Vec<Model> {
    let mut out = Vec::new();
    for seed in 1..6 {
        let r = random_robot(seed, 14);
        out.push(Model::from_description(&r).unwrap());
        out.push(Model::from_description_with_base(&r, BaseKind::Fixed).unwrap());
    }
    out
}

fn rel_err(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).norm() / (1.0 + b.norm())
}

#[test]
fn regressor_times_parameters_is_rnea() {
    for model in models() {
        let mut data = Data::new(&model);
        let mut rng = SplitMix64(42);
        for _ in 0..5 {
            let q = random_configuration(&model, &mut rng);
            let v = random_tangent(&model, &mut rng);
            let a = random_tangent(&model, &mut rng);
            let tau = rnea(&model, &mut data, &q, &v, &a).clone();
            let y = joint_torque_regressor(&model, &mut data, &q, &v, &a).clone();
            let phi = DVector::from_vec(body_parameters(&model));
            assert!(
                rel_err(&(&y * &phi), &tau) < 1e-12,
                "{}: Y phi != rnea",
                model.name
            );
            // Per link: Y_body T_link phi_link summed over links.
            let mut per_link = DVector::zeros(model.nv);
            let lp = link_parameters(&model);
            for (l, info) in model.links.iter().enumerate() {
                let Some(block) = parameter_block_of_link(&model, l) else {
                    continue;
                };
                let t = link_to_body_parameter_map(&info.placement);
                let phil =
                    nalgebra::SVector::<f64, 10>::from_column_slice(&lp[10 * l..10 * l + 10]);
                let yb = y.columns(10 * block, 10);
                per_link += yb * (t * phil);
            }
            assert!(
                rel_err(&per_link, &tau) < 1e-12,
                "{}: per-link regressor",
                model.name
            );
        }
    }
}

#[test]
fn crba_and_nonlinear_effects_give_rnea() {
    for model in models() {
        let mut data = Data::new(&model);
        let mut rng = SplitMix64(7);
        for _ in 0..5 {
            let q = random_configuration(&model, &mut rng);
            let v = random_tangent(&model, &mut rng);
            let a = random_tangent(&model, &mut rng);
            let tau = rnea(&model, &mut data, &q, &v, &a).clone();
            let nle = nonlinear_effects(&model, &mut data, &q, &v).clone();
            crba(&model, &mut data, &q);
            data.symmetrize_mass_matrix();
            let m = data.mass_matrix.clone();
            assert!(
                rel_err(&(&m * DVector::from_vec(a.clone()) + &nle), &tau) < 1e-12,
                "{}",
                model.name
            );
            assert!(m.clone().cholesky().is_some(), "M not positive definite");
            let g = generalized_gravity(&model, &mut data, &q).clone();
            let zero = vec![0.0; model.nv];
            let g2 = rnea(&model, &mut data, &q, &zero, &zero).clone();
            assert!(rel_err(&g, &g2) < 1e-14);
        }
    }
}

#[test]
fn aba_inverts_rnea() {
    for model in models() {
        let mut data = Data::new(&model);
        let mut rng = SplitMix64(9);
        for _ in 0..5 {
            let q = random_configuration(&model, &mut rng);
            let v = random_tangent(&model, &mut rng);
            let a = random_tangent(&model, &mut rng);
            let tau = rnea(&model, &mut data, &q, &v, &a).clone();
            let ddq = aba(&model, &mut data, &q, &v, tau.as_slice()).clone();
            assert!(
                rel_err(&ddq, &DVector::from_vec(a)) < 1e-10,
                "{}",
                model.name
            );
        }
    }
}

fn fd_step(model: &Model, q: &[f64], v: &[f64], h: f64) -> Vec<f64> {
    let mut out = vec![0.0; model.nq];
    integrate(model, q, v, h, &mut out);
    out
}

#[test]
fn com_jacobian_matches_finite_differences() {
    for model in models() {
        let mut data = Data::new(&model);
        let mut rng = SplitMix64(5);
        let q = random_configuration(&model, &mut rng);
        let v = random_tangent(&model, &mut rng);
        let j = jacobian_center_of_mass(&model, &mut data, &q).clone();
        let c0 = data.com;
        assert!((center_of_mass(&model, &mut data, &q) - c0).norm() < 1e-14);
        let h = 1e-6;
        let cp = center_of_mass(&model, &mut data, &fd_step(&model, &q, &v, h));
        let cm = center_of_mass(&model, &mut data, &fd_step(&model, &q, &v, -h));
        let fd = (cp - cm) / (2.0 * h);
        let an = &j * DVector::from_vec(v.clone());
        assert!(
            (fd - Vector3::new(an[0], an[1], an[2])).norm() < 1e-7,
            "{}",
            model.name
        );
        // Static regressor: M c = G phi_static.
        let g = static_com_regressor(&model, &mut data, &q).clone();
        let phis = DVector::from_vec(link_static_parameters(&model));
        let mc = &g * phis;
        // A fixed base's root link mass is welded to the world and not in total_mass.
        let welded: f64 = model
            .links
            .iter()
            .filter(|l| l.body == BASE && !model.is_floating())
            .map(|l| l.inertia.mass)
            .sum();
        if welded == 0.0 {
            assert!((Vector3::new(mc[0], mc[1], mc[2]) / model.total_mass - c0).norm() < 1e-12);
        }
    }
}

#[test]
fn frame_jacobians_match_finite_differences() {
    for model in models() {
        let mut data = Data::new(&model);
        let mut rng = SplitMix64(11);
        let q = random_configuration(&model, &mut rng);
        let v = random_tangent(&model, &mut rng);
        compute_joint_jacobians(&model, &mut data, &q);
        let h = 1e-6;
        for (fi, _) in model.frames.iter().enumerate() {
            let mut jw = DMatrix::zeros(6, model.nv);
            let mut jl = DMatrix::zeros(6, model.nv);
            let mut ja = DMatrix::zeros(6, model.nv);
            frame_jacobian(&model, &data, fi, ReferenceFrame::World, &mut jw);
            frame_jacobian(&model, &data, fi, ReferenceFrame::Local, &mut jl);
            frame_jacobian(
                &model,
                &data,
                fi,
                ReferenceFrame::LocalWorldAligned,
                &mut ja,
            );
            let vv = DVector::from_vec(v.clone());
            let (tw, tl, ta) = (&jw * &vv, &jl * &vv, &ja * &vv);
            let mut d2 = Data::new(&model);
            frames_forward_kinematics(&model, &mut d2, &fd_step(&model, &q, &v, h));
            let xp = d2.o_m_f[fi];
            frames_forward_kinematics(&model, &mut d2, &fd_step(&model, &q, &v, -h));
            let xm = d2.o_m_f[fi];
            frames_forward_kinematics(&model, &mut d2, &q);
            let x0 = d2.o_m_f[fi];
            // Origin velocity and angular velocity (world axes) by central differences.
            let pdot = (xp.translation - xm.translation) / (2.0 * h);
            let rdot = (xp.rotation - xm.rotation) / (2.0 * h);
            let wskew = rdot * x0.rotation.transpose();
            let w = Vector3::new(wskew[(2, 1)], wskew[(0, 2)], wskew[(1, 0)]);
            let close = |a: Vector3<f64>, b: Vector3<f64>| (a - b).norm() < 1e-6 * (1.0 + b.norm());
            assert!(
                close(Vector3::new(ta[0], ta[1], ta[2]), pdot),
                "LWA linear, frame {fi}"
            );
            assert!(close(Vector3::new(ta[3], ta[4], ta[5]), w), "LWA angular");
            let vo = pdot - w.cross(&x0.translation);
            assert!(close(Vector3::new(tw[0], tw[1], tw[2]), vo), "WORLD linear");
            let rl = x0.rotation.transpose();
            assert!(
                close(Vector3::new(tl[0], tl[1], tl[2]), rl * pdot),
                "LOCAL linear"
            );
            assert!(
                close(Vector3::new(tl[3], tl[4], tl[5]), rl * w),
                "LOCAL angular"
            );
        }
    }
}

#[test]
fn kinetic_energy_matches_bodies() {
    // 1/2 v^T M v equals the sum of body energies computed from FD body velocities.
    for model in models() {
        let mut data = Data::new(&model);
        let mut rng = SplitMix64(13);
        let q = random_configuration(&model, &mut rng);
        let v = random_tangent(&model, &mut rng);
        crba(&model, &mut data, &q);
        data.symmetrize_mass_matrix();
        let vv = DVector::from_vec(v.clone());
        let e1 = 0.5 * vv.dot(&(&data.mass_matrix * &vv));
        // Body twists (body frame) from RNEA's forward pass with zero acceleration.
        nonlinear_effects(&model, &mut data, &q, &v);
        let mut e2 = 0.0;
        for i in 0..model.nbodies {
            let t = data.v[i];
            e2 += 0.5 * t.dot(&model.inertias[i].mul_motion(&t));
        }
        if model.is_floating() {
            let t = twinloop_spatial::Motion::from_slice(&v[0..6]);
            e2 += 0.5 * t.dot(&model.base_inertia.mul_motion(&t));
        }
        assert!(
            (e1 - e2).abs() < 1e-10 * (1.0 + e1.abs()),
            "{}: {e1} vs {e2}",
            model.name
        );
    }
}

#[test]
fn aba_with_external_forces_matches_jacobian_transpose() {
    use twinloop_spatial::Force;
    for model in models() {
        let mut data = Data::new(&model);
        let mut rng = SplitMix64(17);
        let q = random_configuration(&model, &mut rng);
        let v = random_tangent(&model, &mut rng);
        let tau = random_tangent(&model, &mut rng);
        let f3 = |rng: &mut SplitMix64| Vector3::new(rng.normal(), rng.normal(), rng.normal());
        let fext: Vec<Force> = (0..model.nbodies)
            .map(|_| Force::new(f3(&mut rng), f3(&mut rng)))
            .collect();
        let fb = Force::new(f3(&mut rng), f3(&mut rng));
        let ddq = aba_with_forces(&model, &mut data, &q, &v, &tau, &fext, fb).clone();
        // M ddq + nle - tau must equal sum_i J_i^T f_i (world Jacobians, world forces).
        crba(&model, &mut data, &q);
        data.symmetrize_mass_matrix();
        let m = data.mass_matrix.clone();
        let nle = nonlinear_effects(&model, &mut data, &q, &v).clone();
        let lhs = &m * &ddq + nle - DVector::from_vec(tau.clone());
        compute_joint_jacobians(&model, &mut data, &q);
        let mut rhs = DVector::zeros(model.nv);
        let mut j = DMatrix::zeros(6, model.nv);
        let mut add = |frame: usize, f: &Force, rhs: &mut DVector<f64>| {
            frame_jacobian(&model, &data, frame, ReferenceFrame::World, &mut j);
            *rhs += j.transpose() * f.to_vector6();
        };
        for (i, f) in fext.iter().enumerate() {
            let k = model.frame_index(&model.body_names[i]).unwrap();
            add(k, f, &mut rhs);
        }
        if model.is_floating() {
            let k = model.frame_index(&model.base_link).unwrap();
            add(k, &fb, &mut rhs);
        }
        assert!(
            rel_err(&lhs, &rhs) < 1e-10,
            "{}: {}",
            model.name,
            rel_err(&lhs, &rhs)
        );
    }
}

/// A floating chain with a ball joint between two hinges (the passes' general branch).
fn ball_robot() -> Model {
    let mut b = DescriptionBuilder::new("ball");
    for (k, name) in ["base", "l1", "l2", "l3"].iter().enumerate() {
        let mut link = Link::new(*name);
        let m = 1.0 + k as f64;
        link.inertial = Some(Inertial {
            origin: Pose::new([0.02, -0.01, 0.05], [0.3, -0.2, 0.1]),
            mass: m,
            inertia: Inertia::solid_box(m, [0.1, 0.2, 0.15]),
        });
        b = b.add_link(link);
    }
    let kinds = [
        JointKind::Revolute,
        JointKind::Spherical,
        JointKind::Continuous,
    ];
    let links = ["base", "l1", "l2", "l3"];
    for (k, kind) in kinds.iter().enumerate() {
        let mut jb = b
            .joint(format!("j{k}"), *kind, links[k], links[k + 1])
            .origin(Pose::new([0.1, 0.05, -0.2], [0.4, 0.1, -0.3]))
            .axis([0.0, 1.0, 0.0]);
        if *kind == JointKind::Revolute {
            jb = jb.limits(-2.0, 2.0, 10.0, 5.0);
        }
        b = jb.done();
    }
    Model::from_description(&b.build().unwrap()).unwrap()
}

/// The simulator step's one kinematics pass, and CRBA and the bias forces on it, give
/// the bits of the passes that compute the kinematics each on their own.
#[test]
fn one_kinematics_pass_gives_the_same_bits() {
    let mut all = models();
    all.push(ball_robot());
    for model in all {
        let (mut alone, mut shared) = (Data::new(&model), Data::new(&model));
        let mut rng = SplitMix64(11);
        for _ in 0..5 {
            let q = random_configuration(&model, &mut rng);
            let v = random_tangent(&model, &mut rng);
            compute_joint_jacobians(&model, &mut alone, &q);
            let (o, j) = (alone.o_m_i.clone(), alone.joint_jacobians.clone());
            let m = crba(&model, &mut alone, &q).clone();
            let nle = nonlinear_effects(&model, &mut alone, &q, &v).clone();
            kinematics_pass(&model, &mut shared, &q);
            assert_eq!(shared.o_m_i, o, "{}: world placements", model.name);
            assert_eq!(shared.joint_jacobians, j, "{}: Jacobians", model.name);
            assert_eq!(
                crba_from_kinematics(&model, &mut shared),
                &m,
                "{}",
                model.name
            );
            let nle2 = nonlinear_effects_from_kinematics(&model, &mut shared, &v);
            assert_eq!(nle2, &nle, "{}: bias forces", model.name);
            // Both at once, RNEA in base coordinates: M to the bit, the bias forces to
            // rounding.
            let (m3, nle3) = crba_and_bias_from_kinematics(&model, &mut shared, &v);
            assert_eq!(m3, &m, "{}: M beside the bias forces", model.name);
            let err = rel_err(nle3, &nle);
            assert!(
                err < 1e-13,
                "{}: base-frame bias forces off by {err:e}",
                model.name
            );
        }
    }
}
