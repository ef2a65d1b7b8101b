//! The batched algorithms (`twinloop_dynamics::batch`) against the single calls:
//! every lane must do the single call's operations in the same order, so the
//! results are compared bit for bit (an exact zero may differ in sign only, which
//! `==` ignores). N is not a multiple of the lane count, so the last group's
//! padding is exercised too. Against Pinocchio's numbers: tests/pinocchio.rs.

use std::path::PathBuf;
use twinloop_description::{DescriptionBuilder, Inertia, JointKind, Pose};
use twinloop_dynamics::batch::{BatchData, uses_lanes};
use twinloop_dynamics::configuration::{random_configuration, random_tangent};
use twinloop_dynamics::*;
use twinloop_random::SplitMix64;

fn load(file: &str, base: BaseKind) -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(file);
    let robot = twinloop_description::load(&path).unwrap_or_else(|e| panic!("{e}"));
    Model::from_description_with_base(&robot, base).unwrap()
}

/// N random states, row-major: q (N x nq), v, a and tau (N x nv).
fn states(model: &Model, n: usize, seed: u64) -> [Vec<f64>; 4] {
    let mut rng = SplitMix64(seed);
    let mut out: [Vec<f64>; 4] = Default::default();
    for _ in 0..n {
        out[0].extend(random_configuration(model, &mut rng));
        for x in out.iter_mut().skip(1) {
            x.extend(random_tangent(model, &mut rng));
        }
    }
    out
}

/// Every entry equal (`==`), else the worst difference relative to max(1, |single|).
/// Prints how many entries are also equal bit for bit (the sign of a zero).
fn same(what: &str, batched: &[f64], single: &[f64]) {
    assert_eq!(batched.len(), single.len(), "{what}: lengths");
    let mut worst = (0.0f64, 0usize);
    let mut bits = 0;
    for (k, (b, s)) in batched.iter().zip(single).enumerate() {
        bits += usize::from(b.to_bits() == s.to_bits());
        if b != s {
            let rel = (b - s).abs() / s.abs().max(1.0);
            if rel.is_nan() || rel > worst.0 {
                worst = (rel, k);
            }
        }
    }
    eprintln!("{what}: {bits} of {} entries bit for bit", single.len());
    assert!(
        worst.0 == 0.0,
        "{what}: entry {} differs from the single call by {:e} (relative)",
        worst.1,
        worst.0
    );
}

/// The four batched algorithms against the single calls on `n` random states.
fn check(model: &Model, n: usize, seed: u64) {
    let [q, v, a, tau] = states(model, n, seed);
    let (nq, nv) = (model.nq, model.nv);
    let mut bd = BatchData::new(model);
    let mut data = Data::new(model);
    let mut out = vec![f64::NAN; n * nv];
    let mut single = Vec::new();

    rnea_batch(model, &mut bd, &q, &v, &a, &mut out);
    for r in 0..n {
        let (qr, vr, ar) = (&q[r * nq..][..nq], &v[r * nv..][..nv], &a[r * nv..][..nv]);
        single.extend(rnea(model, &mut data, qr, vr, ar).iter());
    }
    same(&format!("{} rnea", model.name), &out, &single);

    single.clear();
    aba_batch(model, &mut bd, &q, &v, &tau, &mut out);
    for r in 0..n {
        let (qr, vr, tr) = (&q[r * nq..][..nq], &v[r * nv..][..nv], &tau[r * nv..][..nv]);
        single.extend(aba(model, &mut data, qr, vr, tr).iter());
    }
    same(&format!("{} aba", model.name), &out, &single);
    let checked = out.clone();
    try_aba_batch(model, &mut bd, &q, &v, &tau, &mut out).unwrap();
    same(&format!("{} try_aba", model.name), &out, &checked);

    single.clear();
    let mut m = vec![f64::NAN; n * nv * nv];
    crba_batch(model, &mut bd, &q, &mut m);
    for r in 0..n {
        crba(model, &mut data, &q[r * nq..][..nq]);
        data.symmetrize_mass_matrix();
        single.extend(data.mass_matrix.iter());
    }
    same(&format!("{} crba", model.name), &m, &single);
    // The packed form: each matrix's lower triangle by rows, the same numbers.
    let np = batch::packed_len(nv);
    let mut mp = vec![f64::NAN; n * np];
    batch::crba_batch_packed(model, &mut bd, &q, &mut mp);
    let unpacked: Vec<f64> = (0..n * nv * nv)
        .map(|k| {
            let (r, rc) = (k / (nv * nv), k % (nv * nv));
            mp[r * np + batch::packed_index(rc / nv, rc % nv)]
        })
        .collect();
    same(&format!("{} crba packed", model.name), &unpacked, &single);

    single.clear();
    let mut com = vec![f64::NAN; n * 3];
    center_of_mass_batch(model, &mut bd, &q, &mut com);
    for r in 0..n {
        single.extend(center_of_mass(model, &mut data, &q[r * nq..][..nq]).iter());
    }
    same(&format!("{} com", model.name), &com, &single);
}

#[test]
fn batched_op3_is_the_single_call() {
    let model = load("models/op3/robotis_op3.nomesh.urdf", BaseKind::Floating);
    assert!(uses_lanes(&model));
    check(&model, 23, 1);
    check(
        &load("models/op3/robotis_op3.nomesh.urdf", BaseKind::Fixed),
        6,
        2,
    );
    check(&load("models/op3/mjcf/op3.xml", BaseKind::Floating), 5, 3);
}

/// The floating base's armature (an MJCF free joint's, `Model::base_armature`) in
/// RNEA, ABA and CRBA: the lanes add it where the single calls do.
#[test]
fn batched_base_armature_is_the_single_call() {
    let mut model = load("models/op3/robotis_op3.nomesh.urdf", BaseKind::Floating);
    model.base_armature = 0.37;
    check(&model, 9, 4);
}

#[test]
fn batched_g1_is_the_single_call() {
    let model = load(
        "models/unitree_g1/g1_29dof_rev_1_0.nomesh.urdf",
        BaseKind::Floating,
    );
    assert!(uses_lanes(&model));
    check(&model, 23, 4);
    // One and zero states: a group of one real lane, and nothing to do.
    check(&model, 1, 5);
    check(&model, 0, 6);
}

/// Two links on a hinge and a slider (nv = 2 with a fixed base).
fn every_one_dof_joint_fixed() -> twinloop_description::Description {
    DescriptionBuilder::new("short")
        .link("base")
        .mass(
            2.0,
            [0.0, 0.0, 0.05],
            Inertia::solid_box(2.0, [0.2, 0.3, 0.1]),
        )
        .done()
        .link("arm")
        .mass(
            0.5,
            [0.01, 0.02, -0.1],
            Inertia::solid_cylinder(0.5, 0.03, 0.2),
        )
        .done()
        .revolute("hinge", "base", "arm", [1.0, 0.0, 0.0])
        .done()
        .link("bead")
        .mass(0.2, [0.0, 0.1, 0.0], Inertia::solid_sphere(0.2, 0.02))
        .done()
        .joint("slide", JointKind::Prismatic, "arm", "bead")
        .axis([0.0, 1.0, 0.0])
        .done()
        .build()
        .unwrap()
}

/// A chain with every 1-DoF joint kind the lanes take: axis-aligned revolutes with
/// and without a rotated placement, a general axis, a negative axis, a prismatic joint.
fn every_one_dof_joint() -> Model {
    let mut b = DescriptionBuilder::new("joints")
        .link("base")
        .mass(
            2.0,
            [0.0, 0.0, 0.05],
            Inertia::solid_box(2.0, [0.2, 0.3, 0.1]),
        )
        .done();
    let axes = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, -1.0],
        [0.0, 0.6, 0.8],
        [0.0, 0.0, 1.0],
    ];
    let mut parent = "base".to_string();
    for (k, axis) in axes.iter().enumerate() {
        let name = format!("l{k}");
        let kind = if k == 4 {
            JointKind::Prismatic
        } else {
            JointKind::Revolute
        };
        let rpy = if k % 2 == 0 {
            [0.0; 3]
        } else {
            [0.1, -0.2, 0.3]
        };
        b = b
            .link(&name)
            .mass(
                0.5,
                [0.01, 0.02, -0.1],
                Inertia::solid_cylinder(0.5, 0.03, 0.2),
            )
            .done()
            .joint(format!("j{k}"), kind, &parent, &name)
            .axis(*axis)
            .origin(Pose::new([0.0, 0.1, -0.1], rpy))
            .done();
        parent = name;
    }
    Model::from_description(&b.build().unwrap()).unwrap()
}

#[test]
fn batched_general_joints_are_the_single_call() {
    let model = every_one_dof_joint();
    assert!(uses_lanes(&model));
    check(&model, 9, 7);
}

#[test]
fn a_ball_joint_runs_the_single_call_row_by_row() {
    let robot = DescriptionBuilder::new("ball")
        .link("base")
        .mass(
            2.0,
            [0.0, 0.0, 0.05],
            Inertia::solid_box(2.0, [0.2, 0.3, 0.1]),
        )
        .done()
        .link("arm")
        .mass(
            0.5,
            [0.01, 0.02, -0.1],
            Inertia::solid_cylinder(0.5, 0.03, 0.2),
        )
        .done()
        .joint("ball", JointKind::Spherical, "base", "arm")
        .done()
        .build()
        .unwrap();
    let model = Model::from_description(&robot).unwrap();
    assert!(!uses_lanes(&model));
    check(&model, 6, 8);
}

#[test]
fn a_singular_row_is_refused_naming_the_row_and_the_joint() {
    // A massless leaf on a fixed chain: the wrist's pivot is zero at every q.
    let robot = DescriptionBuilder::new("chain")
        .link("root")
        .mass(1.0, [0.0; 3], Inertia::solid_sphere(1.0, 0.1))
        .done()
        .link("upper")
        .mass(
            1.0,
            [0.0, 0.0, -0.2],
            Inertia::solid_box(1.0, [0.05, 0.05, 0.4]),
        )
        .done()
        .revolute("shoulder", "root", "upper", [1.0, 0.0, 0.0])
        .done()
        .link("leaf")
        .mass(0.0, [0.0; 3], Inertia::diagonal(0.0, 0.0, 0.0))
        .done()
        .revolute("wrist", "upper", "leaf", [0.0, 1.0, 0.0])
        .done()
        .build()
        .unwrap();
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    let [q, v, _, tau] = states(&model, 6, 9);
    let mut bd = BatchData::new(&model);
    let mut out = vec![0.0; 6 * model.nv];
    let e = try_aba_batch(&model, &mut bd, &q, &v, &tau, &mut out).unwrap_err();
    let mut data = Data::new(&model);
    let single = try_aba(&model, &mut data, &q[0..2], &v[0..2], &tau[0..2]).unwrap_err();
    // Fewer than six coordinates and a regular chain: the check passes (a fixed base
    // has no base rows to test).
    let regular =
        Model::from_description_with_base(&every_one_dof_joint_fixed(), BaseKind::Fixed).unwrap();
    let [q2, v2, _, t2] = states(&regular, 3, 10);
    let mut out2 = vec![0.0; 3 * regular.nv];
    try_aba_batch(
        &regular,
        &mut BatchData::new(&regular),
        &q2,
        &v2,
        &t2,
        &mut out2,
    )
    .unwrap();
    assert_eq!((e.row, &e.joint), (0, &single));
    assert!(
        e.to_string()
            .starts_with("row 0: the mass matrix is singular at joint \"wrist\""),
        "{e}"
    );
}
