//! Descriptions the dynamics cannot compile give an error naming the joint.

use twinloop_description::{DescriptionBuilder, Inertia, JointKind, Pose};
use twinloop_dynamics::{BaseKind, Data, Model, aba, check_mass_matrix, crba, try_aba};

fn two_links(kind: JointKind, origin: Pose) -> twinloop_description::Description {
    DescriptionBuilder::new("r")
        .link("a")
        .mass(1.0, [0.0; 3], Inertia::solid_sphere(1.0, 0.1))
        .done()
        .link("b")
        .mass(1.0, [0.0; 3], Inertia::solid_sphere(1.0, 0.1))
        .done()
        .link("c")
        .mass(1.0, [0.0; 3], Inertia::solid_sphere(1.0, 0.1))
        .done()
        .revolute("hinge", "a", "b", [0.0, 0.0, 1.0])
        .done()
        .joint("odd", kind, "b", "c")
        .origin(origin)
        .axis([1.0, 0.0, 0.0])
        .done()
        .build()
        .unwrap()
}

#[test]
fn planar_and_inner_floating_joints_are_refused_by_name() {
    for kind in [JointKind::Planar, JointKind::Floating] {
        let e = Model::from_description(&two_links(kind, Pose::IDENTITY))
            .unwrap_err()
            .to_string();
        assert!(e.contains("<joint name=\"odd\">"), "{e}");
    }
}

#[test]
fn floating_root_with_offset_is_refused() {
    let robot = DescriptionBuilder::new("r")
        .link("world")
        .done()
        .link("base")
        .mass(1.0, [0.0; 3], Inertia::solid_sphere(1.0, 0.1))
        .done()
        .joint("root", JointKind::Floating, "world", "base")
        .origin(Pose::from_xyz([0.0, 0.0, 1.0]))
        .done()
        .build()
        .unwrap();
    let e = Model::from_description(&robot).unwrap_err().to_string();
    assert!(e.contains("root") && e.contains("origin"), "{e}");
    // Without the offset the floating joint is the free flyer and `world` is dropped.
    let mut ok = robot.clone();
    ok.joints[0].origin = Pose::IDENTITY;
    let m = Model::from_description(&ok).unwrap();
    assert_eq!((m.nq, m.nv, m.base_link.as_str()), (7, 6, "base"));
}

#[test]
fn bodies_are_numbered_depth_first_in_file_order() {
    // base -> a1 -> a2, base -> b1, a1 -> a3: pre-order a1, a2, a3, b1.
    let m = |n: &str| (n.to_string(), Inertia::solid_sphere(1.0, 0.1));
    let mut b = DescriptionBuilder::new("tree")
        .link("base")
        .mass(1.0, [0.0; 3], m("base").1)
        .done();
    for (name, parent) in [("a1", "base"), ("b1", "base"), ("a2", "a1"), ("a3", "a1")] {
        b = b
            .link(name)
            .mass(1.0, [0.0; 3], m(name).1)
            .done()
            .revolute(format!("j_{name}"), parent, name, [0.0, 0.0, 1.0])
            .done();
    }
    let model = Model::from_description(&b.build().unwrap()).unwrap();
    assert_eq!(model.joint_names, ["j_a1", "j_a2", "j_a3", "j_b1"]);
    assert_eq!(model.subtree_end, [3, 2, 3, 4]);
    assert!(
        model
            .parents
            .iter()
            .enumerate()
            .all(|(i, &p)| p == twinloop_dynamics::BASE || p < i)
    );
}

/// A chain too long for memory is refused with a message before `Data` allocates
/// (8 000 joints: the regressor and mass matrix would take 5.6 GB; a 20 000-link
/// chain, 35 GB, used to abort the process).
#[test]
fn too_large_a_model_is_refused_before_allocating() {
    let inertia = Inertia::solid_sphere(1.0, 0.1);
    let mut b = DescriptionBuilder::new("chain")
        .link("l0")
        .mass(1.0, [0.0; 3], inertia)
        .done();
    for i in 1..8_000 {
        b = b
            .link(format!("l{i}"))
            .mass(1.0, [0.0; 3], inertia)
            .done()
            .joint(
                format!("j{i}"),
                JointKind::Continuous,
                format!("l{}", i - 1),
                format!("l{i}"),
            )
            .axis([0.0, 0.0, 1.0])
            .done();
    }
    let robot = b.build().unwrap();
    let e = Model::from_description(&robot).unwrap_err();
    assert!(e.message.contains("7999 moving joints"), "{e}");
    assert!(e.message.contains("5.6 GB"), "{e}");
}

/// A chain whose last link is `leaf` (mass, CoM, inertia) on a revolute joint about y.
fn chain_with_leaf(mass: f64, com: [f64; 3], inertia: twinloop_description::Inertia) -> Model {
    use twinloop_description::Inertia as I;
    let robot = DescriptionBuilder::new("chain")
        .link("root")
        .mass(1.0, [0.0; 3], I::solid_sphere(1.0, 0.1))
        .done()
        .link("upper")
        .mass(1.0, [0.0, 0.0, -0.2], I::solid_box(1.0, [0.05, 0.05, 0.4]))
        .done()
        .revolute("shoulder", "root", "upper", [1.0, 0.0, 0.0])
        .done()
        .link("leaf")
        .mass(mass, com, inertia)
        .done()
        .revolute("wrist", "upper", "leaf", [0.0, 1.0, 0.0])
        .origin(twinloop_description::Pose::new([0.0, 0.0, -0.4], [0.0; 3]))
        .done()
        .build()
        .unwrap();
    Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap()
}

#[test]
fn a_singular_mass_matrix_is_refused_naming_the_joint() {
    use twinloop_description::Inertia as I;
    // Massless leaf; a point mass on the wrist's own axis: both leave the wrist's
    // row of M zero.
    for model in [
        chain_with_leaf(0.0, [0.0; 3], I::diagonal(0.0, 0.0, 0.0)),
        chain_with_leaf(0.5, [0.0, 0.1, 0.0], I::diagonal(0.0, 0.0, 0.0)),
    ] {
        let mut data = Data::new(&model);
        let q = vec![0.3; model.nv];
        // Without the check, ABA's accelerations are not finite.
        aba(&model, &mut data, &q, &q, &q);
        assert!(data.ddq.iter().any(|x| !x.is_finite() || x.abs() > 1e10));
        let e = try_aba(&model, &mut data, &q, &q, &q).unwrap_err();
        assert_eq!(e.joint.as_deref(), Some("wrist"), "{e}");
        assert!(e.to_string().contains("singular at joint \"wrist\""), "{e}");
        assert_eq!(check_mass_matrix(&model, &mut data, &q), Err(e));
        // The mass matrix agrees: its wrist row is zero.
        crba(&model, &mut data, &q);
        assert!(data.mass_matrix[(1, 1)].abs() < 1e-15);
    }
    // The same chain with a real leaf is fine, and try_aba is aba.
    let model = chain_with_leaf(0.5, [0.1, 0.0, -0.1], I::diagonal(1e-3, 1e-3, 1e-3));
    let mut data = Data::new(&model);
    let q = vec![0.3; model.nv];
    let ddq = try_aba(&model, &mut data, &q, &q, &q).unwrap().clone();
    assert_eq!(&ddq, aba(&model, &mut data, &q, &q, &q));
}
