//! The seed robots against the seeds' numbers: masses (seed 000 Table I), height,
//! width, foot geometry (F1, F2, L0), segment lengths, servos, and the physics of what
//! was built (inertias, URDF round trip, lint).

use twinloop_description::builtin::{
    FootGeometry, LD2015, RX28, RX64, builtin, foot_geometry, km20, lab17, resolve, servo_of_joint,
    servo_table,
};
use twinloop_description::lint::{Severity, lint};
use twinloop_description::{Description, Geometry, JointKind, urdf};
use twinloop_dynamics::{Data, Model, frames_forward_kinematics};
use twinloop_spatial::{Matrix3, Se3, Vector3};

fn se3(p: &twinloop_description::Pose) -> Se3 {
    let r = p.rotation();
    Se3::new(
        Matrix3::from_fn(|a, b| r[a][b]),
        Vector3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
    )
}

/// World placement of every link in the zero configuration, base at the origin.
fn link_placements(robot: &Description) -> Vec<(String, Se3)> {
    let model = Model::from_description(robot).unwrap();
    let mut data = Data::new(&model);
    let q = model.neutral_configuration();
    frames_forward_kinematics(&model, &mut data, &q);
    model
        .frames
        .iter()
        .zip(&data.o_m_f)
        .filter(|(f, _)| f.link.is_some())
        .map(|(f, m)| (f.name.clone(), *m))
        .collect()
}

fn placement(robot: &Description, link: &str) -> Se3 {
    link_placements(robot)
        .into_iter()
        .find(|(n, _)| n == link)
        .unwrap_or_else(|| panic!("no link {link}"))
        .1
}

/// World-axis bounding box of a primitive at a world placement.
fn extent(m: &Se3, g: &Geometry) -> ([f64; 3], [f64; 3]) {
    let c = m.translation;
    let r = m.rotation;
    let half = match g {
        Geometry::Box { size } => {
            Vector3::from_fn(|i, _| (0..3).map(|k| r[(i, k)].abs() * 0.5 * size[k]).sum())
        }
        Geometry::Cylinder { radius, length } => Vector3::from_fn(|i, _| {
            let a = r[(i, 2)];
            a.abs() * 0.5 * length + radius * (1.0 - a * a).max(0.0).sqrt()
        }),
        Geometry::Sphere { radius } => Vector3::repeat(*radius),
        other => panic!("unexpected geometry {other:?}"),
    };
    (
        [c.x - half.x, c.y - half.y, c.z - half.z],
        [c.x + half.x, c.y + half.y, c.z + half.z],
    )
}

/// Bounding box of every visual of the robot in the zero configuration.
fn visual_bounds(robot: &Description) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (name, m) in link_placements(robot) {
        let link = robot.link(&name).unwrap();
        for v in link.visuals.iter().chain(&link.collisions) {
            let (a, b) = extent(&(m * se3(&v.origin)), &v.geometry);
            for i in 0..3 {
                lo[i] = lo[i].min(a[i]);
                hi[i] = hi[i].max(b[i]);
            }
        }
    }
    (lo, hi)
}

/// Mass of the links below (and including the child of) `joint`.
fn subtree_mass(robot: &Description, joint: &str) -> f64 {
    let mut stack = vec![robot.joint(joint).unwrap().child.clone()];
    let mut mass = 0.0;
    while let Some(l) = stack.pop() {
        mass += robot.link(&l).unwrap().mass();
        stack.extend(
            robot
                .joints
                .iter()
                .filter(|j| j.parent == l)
                .map(|j| j.child.clone()),
        );
    }
    mass
}

#[test]
fn km20_masses_are_seed_000_table_i() {
    let r = builtin("km20").unwrap();
    assert!((r.total_mass() - 3.336).abs() < 1e-12, "{}", r.total_mass());
    assert!((subtree_mass(&r, "r_hip_yaw") - 0.743).abs() < 1e-12);
    assert!((subtree_mass(&r, "l_hip_yaw") - 0.740).abs() < 1e-12);
    assert!((subtree_mass(&r, "r_sho_pitch") - 0.238).abs() < 1e-12);
    assert!((subtree_mass(&r, "l_sho_pitch") - 0.240).abs() < 1e-12);
    let torso = r.total_mass()
        - ["r_hip_yaw", "l_hip_yaw", "r_sho_pitch", "l_sho_pitch"]
            .iter()
            .map(|j| subtree_mass(&r, j))
            .sum::<f64>();
    assert!((torso - 1.375).abs() < 1e-12, "torso with head {torso}");
    // Every structure mass the budget closes on is a real, positive part.
    for l in &r.links {
        assert!(l.mass() > 0.0, "{} has no mass", l.name);
    }
}

#[test]
fn km20_height_and_joints() {
    let r = builtin("km20").unwrap();
    let (lo, hi) = visual_bounds(&r);
    // Soles at the ground when the torso frame is 0.276 m up; 0.53 m tall.
    assert!((lo[2] + 0.276).abs() < 1e-12, "sole {}", lo[2]);
    assert!(
        (hi[2] - lo[2] - 0.53).abs() < 1e-12,
        "height {}",
        hi[2] - lo[2]
    );
    let moving: Vec<_> = r
        .joints
        .iter()
        .filter(|j| j.kind == JointKind::Revolute)
        .collect();
    assert_eq!(moving.len(), 20);
    let names: Vec<&str> = moving.iter().map(|j| j.name.as_str()).collect();
    for side in ["l", "r"] {
        // Hip joint order per leg: yaw, roll, pitch, knee, ankle pitch, ankle roll.
        let leg: Vec<String> = [
            "hip_yaw",
            "hip_roll",
            "hip_pitch",
            "knee",
            "ank_pitch",
            "ank_roll",
        ]
        .iter()
        .map(|j| format!("{side}_{j}"))
        .collect();
        let pos: Vec<usize> = leg
            .iter()
            .map(|j| names.iter().position(|n| n == j).unwrap())
            .collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "{pos:?}");
        for w in leg.windows(2) {
            assert_eq!(
                r.joint(&w[1]).unwrap().parent,
                r.joint(&w[0]).unwrap().child
            );
        }
        for j in ["sho_pitch", "sho_roll", "elbow"] {
            assert!(names.contains(&format!("{side}_{j}").as_str()));
        }
    }
    assert!(names.contains(&"head_pan") && names.contains(&"head_tilt"));
}

/// World position of the joint frame of `joint` (its child link's origin).
fn joint_position(r: &Description, joint: &str) -> Vector3<f64> {
    placement(r, &r.joint(joint).unwrap().child).translation
}

#[test]
fn km20_segments_and_foot_are_seeds_000_and_001() {
    let r = builtin("km20").unwrap();
    for s in ["l", "r"] {
        let hip = joint_position(&r, &format!("{s}_hip_pitch"));
        let knee = joint_position(&r, &format!("{s}_knee"));
        let ankle = joint_position(&r, &format!("{s}_ank_pitch"));
        assert!(((hip - knee).norm() - 0.10).abs() < 1e-12, "thigh");
        assert!(((knee - ankle).norm() - 0.10).abs() < 1e-12, "shin");
        // The foot's collision box: front edge 3.5 cm ahead of the ankle axis, back
        // edge 9.5 cm behind, sole 3.1 cm below it (seed 000's F1, F2, L0).
        let foot = r.link(&format!("{s}_foot")).unwrap();
        assert_eq!(foot.collisions.len(), 1);
        let m = placement(&r, &foot.name) * se3(&foot.collisions[0].origin);
        let Geometry::Box { .. } = foot.collisions[0].geometry else {
            panic!("foot collision must be a box");
        };
        let (lo, hi) = extent(&m, &foot.collisions[0].geometry);
        assert!(
            (hi[0] - ankle.x - 0.035).abs() < 1e-12,
            "F1 {}",
            hi[0] - ankle.x
        );
        assert!(
            (ankle.x - lo[0] - 0.095).abs() < 1e-12,
            "F2 {}",
            ankle.x - lo[0]
        );
        assert!(
            (ankle.z - lo[2] - 0.031).abs() < 1e-12,
            "L0 {}",
            ankle.z - lo[2]
        );
        // The sole is the lowest point of the robot: it is what stands on the ground.
        assert!((lo[2] - visual_bounds(&r).0[2]).abs() < 1e-12);
        // The two ankle axes cross (the roll axis passes through the pitch axis).
        let roll = joint_position(&r, &format!("{s}_ank_roll"));
        assert!((roll - ankle).norm() < 1e-12);
    }
    let g = foot_geometry("km20").unwrap();
    assert_eq!((g.front, g.back, g.ankle_height), (0.035, 0.095, 0.031));
    check_foot_geometry_matches_model(&r, &g);
}

/// The FootGeometry record agrees with the built model's feet.
fn check_foot_geometry_matches_model(r: &Description, g: &FootGeometry) {
    for (foot, pitch, roll, side) in [
        (&g.left_foot, &g.left_ankle_pitch, &g.left_ankle_roll, 1.0),
        (
            &g.right_foot,
            &g.right_ankle_pitch,
            &g.right_ankle_roll,
            -1.0,
        ),
    ] {
        let link = r.link(foot).unwrap();
        let m = placement(r, foot) * se3(&link.collisions[0].origin);
        let (lo, hi) = extent(&m, &link.collisions[0].geometry);
        let p = joint_position(r, pitch);
        let q = joint_position(r, roll);
        assert!((hi[0] - p.x - g.front).abs() < 1e-12);
        assert!((p.x - lo[0] - g.back).abs() < 1e-12);
        assert!((p.z - lo[2] - g.ankle_height).abs() < 1e-12);
        assert!((q.z - lo[2] - g.roll_axis_height).abs() < 1e-12);
        assert!((side * q.y - g.ankle_half_spacing).abs() < 1e-12);
        let (outer, inner) = if side > 0.0 {
            (hi[1] - q.y, q.y - lo[1])
        } else {
            (q.y - lo[1], hi[1] - q.y)
        };
        assert!((outer - g.outer).abs() < 1e-12 && (inner - g.inner).abs() < 1e-12);
    }
}

#[test]
fn km20_servos() {
    let r = builtin("km20").unwrap();
    let table = servo_table("km20").unwrap();
    assert_eq!(table.len(), 20);
    let count = |name: &str| table.iter().filter(|s| s.servo.name == name).count();
    assert_eq!((count("RX-28"), count("RX-64")), (18, 2));
    for j in r.joints.iter().filter(|j| j.kind == JointKind::Revolute) {
        let s = servo_of_joint("km20", &j.name).unwrap_or_else(|| panic!("{}", j.name));
        let lim = j.limit.unwrap();
        assert_eq!(lim.effort, Some(s.stall_torque));
        assert_eq!(lim.velocity, Some(s.no_load_speed));
        assert!(lim.lower.unwrap() < 0.0 && lim.upper.unwrap() > 0.0);
    }
    // ROBOTIS e-manual: 85 rpm, 64 rpm.
    assert!((RX28.no_load_speed - 85.0 * 2.0 * std::f64::consts::PI / 60.0).abs() < 1e-12);
    assert!((RX64.no_load_speed - 6.702064327658225).abs() < 1e-12);
    assert_eq!(servo_of_joint("km20", "no_such_joint"), None);
    assert_eq!(servo_of_joint("op3", "l_knee"), None);
}

#[test]
fn a_dynamixel_body_is_three_boxes_and_two_cylinders() {
    for spec in [&RX28, &RX64] {
        let parts =
            twinloop_description::builtin::servo::dynamixel_body(spec, "s", Default::default());
        let boxes = parts
            .iter()
            .filter(|p| matches!(p.geometry, Geometry::Box { .. }))
            .count();
        let cylinders = parts
            .iter()
            .filter(|p| matches!(p.geometry, Geometry::Cylinder { .. }))
            .count();
        assert_eq!((boxes, cylinders), (3, 2));
        let mass: f64 = parts.iter().map(|p| p.mass).sum();
        assert!((mass - spec.mass).abs() < 1e-15);
        // The five primitives fill exactly the W x H x D envelope of the datasheet.
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &parts {
            let (a, b) = extent(&se3(&p.origin), &p.geometry);
            for i in 0..3 {
                lo[i] = lo[i].min(a[i]);
                hi[i] = hi[i].max(b[i]);
            }
        }
        let [w, h, d] = spec.size;
        for (got, want) in [(hi[0] - lo[0], h), (hi[1] - lo[1], w), (hi[2] - lo[2], d)] {
            assert!((got - want).abs() < 1e-12, "{} {got} vs {want}", spec.name);
        }
        // The output axis is in the middle of the W x W square at the case's end.
        assert!((hi[0] - 0.5 * w).abs() < 1e-12);
    }
}

/// A link's inertial as mass and rotational inertia about the link origin.
fn inertia_about_origin(link: &twinloop_description::Link) -> (f64, Matrix3<f64>) {
    let i = link.inertial.unwrap();
    let c = Vector3::new(i.origin.xyz[0], i.origin.xyz[1], i.origin.xyz[2]);
    let r = i.origin.rotation();
    let rot = Matrix3::from_fn(|a, b| r[a][b]);
    let ic = rot * Matrix3::from_fn(|a, b| i.inertia.matrix()[a][b]) * rot.transpose();
    let shift = (Matrix3::identity() * c.dot(&c) - c * c.transpose()) * i.mass;
    (i.mass, ic + shift)
}

#[test]
fn link_inertias_are_the_sum_of_their_parts() {
    // Rebuild km20's foot from its parts by hand: each part's own tensor rotated into
    // the link axes, shifted to the link origin, summed.
    use twinloop_description::builtin::parts::Part;
    let r = builtin("km20").unwrap();
    let foot = r.link("l_foot").unwrap();
    let (m, io) = inertia_about_origin(foot);
    let servo = twinloop_description::builtin::servo::dynamixel_body(
        &RX28,
        "l_ankle_roll_servo",
        twinloop_description::builtin::parts::frame(
            [-0.030, 0.0, 0.0],
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
        ),
    );
    let servo_mass: f64 = servo.iter().map(|p| p.mass).sum();
    let plate = Part::boxed(
        "l_sole_plate",
        twinloop_description::builtin::parts::PartKind::Foot,
        m - servo_mass,
        [0.13, 0.07, 0.004],
        [-0.03, 0.0, -0.031 + 0.002],
    );
    let mut expect = Matrix3::zeros();
    for p in servo.iter().chain(std::iter::once(&plate)) {
        let own = p.central_inertia().matrix();
        let rr = p.origin.rotation();
        let rot = Matrix3::from_fn(|a, b| rr[a][b]);
        let c = Vector3::new(p.origin.xyz[0], p.origin.xyz[1], p.origin.xyz[2]);
        expect += rot * Matrix3::from_fn(|a, b| own[a][b]) * rot.transpose()
            + (Matrix3::identity() * c.dot(&c) - c * c.transpose()) * p.mass;
    }
    assert!((io - expect).norm() < 1e-15, "{io} vs {expect}");
    assert_eq!(foot.visuals.len(), 6);
}

fn principal_moments_valid(robot: &Description) {
    for l in &robot.links {
        let i = l.inertial.unwrap();
        let m = Matrix3::from_fn(|a, b| i.inertia.matrix()[a][b]);
        assert!((m - m.transpose()).norm() == 0.0);
        let mut e: Vec<f64> = m.symmetric_eigenvalues().iter().copied().collect();
        e.sort_by(f64::total_cmp);
        assert!(e[0] > 0.0, "{}: {e:?}", l.name);
        assert!(e[0] + e[1] >= e[2], "{}: triangle {e:?}", l.name);
        assert!(i.mass > 0.0);
    }
}

#[test]
fn inertias_are_physical_and_lint_is_clean() {
    for name in ["km20", "lab17"] {
        let r = builtin(name).unwrap();
        principal_moments_valid(&r);
        let report = lint(&r);
        assert_eq!(report.errors, 0, "{name}: {:?}", report.findings);
        assert_eq!(
            report.count(Severity::Warning),
            0,
            "{name}: {:?}",
            report.findings
        );
    }
}

#[test]
fn urdf_export_reads_back_equal() {
    for name in ["km20", "lab17"] {
        let r = builtin(name).unwrap();
        let text = urdf::to_string(&r);
        assert_eq!(urdf::from_str(&text).unwrap(), r, "{name}");
        let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.urdf"));
        urdf::write_file(&r, &path).unwrap();
        assert_eq!(resolve(path.to_str().unwrap()).unwrap(), r);
        std::fs::remove_file(&path).unwrap();
    }
}

#[test]
fn resolve_names_builtins_and_refuses_unknown_ones() {
    assert_eq!(resolve("builtin:km20").unwrap().name, "km20");
    assert_eq!(resolve("builtin:lab17").unwrap().name, "lab17");
    let e = resolve("builtin:km21").unwrap_err().to_string();
    assert!(
        e.contains("km21") && e.contains("km20") && e.contains("lab17"),
        "{e}"
    );
    let e = resolve("/no/such/file.urdf").unwrap_err().to_string();
    assert!(e.contains("/no/such/file.urdf"), "{e}");
    assert!(builtin("nope").is_none());
}

#[test]
fn lab17_is_seed_003() {
    let r = builtin("lab17").unwrap();
    assert!((r.total_mass() - 1.65).abs() < 1e-12, "{}", r.total_mass());
    let (lo, hi) = visual_bounds(&r);
    assert!(
        (hi[2] - lo[2] - 0.365).abs() < 1e-12,
        "height {}",
        hi[2] - lo[2]
    );
    assert!(
        (hi[1] - lo[1] - 0.215).abs() < 1e-12,
        "width {}",
        hi[1] - lo[1]
    );
    assert!((lo[2] + lab17::TRUNK_ORIGIN_HEIGHT).abs() < 1e-12);
    let moving = r
        .joints
        .iter()
        .filter(|j| j.kind == JointKind::Revolute)
        .count();
    assert_eq!(moving, 17);
    for j in r.joints.iter().filter(|j| j.kind == JointKind::Revolute) {
        assert_eq!(servo_of_joint("lab17", &j.name), Some(&LD2015));
        let lim = j.limit.unwrap();
        // Seed 003: 17 kg/cm at 7.4 V.
        assert!((lim.effort.unwrap() - 17.0 * 9.80665 / 100.0).abs() < 1e-12);
        assert!(lim.lower.unwrap() < 0.0 && lim.upper.unwrap() > 0.0);
        // 0-180 degrees of travel.
        let span = lim.upper.unwrap() - lim.lower.unwrap();
        assert!((span - std::f64::consts::PI).abs() < 1e-12);
    }
    check_foot_geometry_matches_model(&r, &foot_geometry("lab17").unwrap());
}

#[test]
fn lab17_boxes_follow_seed_003_table_1() {
    // Table 1 by hand for an LD-2015 case lying with its 40.5 mm height along z, 20 mm
    // along y and 40 mm along x: Ix = m/12 (a^2 + b^2) with a = 0.0405, b = 0.02.
    let i = lab17::table1_box_inertia(0.06, 0.0405, 0.02, 0.04);
    assert!((i.ixx - 0.005 * (0.0405f64.powi(2) + 0.0004)).abs() < 1e-18);
    assert!((i.iyy - 0.005 * (0.0405f64.powi(2) + 0.0016)).abs() < 1e-18);
    assert!((i.izz - 0.005 * (0.0004 + 0.0016)).abs() < 1e-18);
    // Every lab17 part is a box, its own tensor Table 1's.
    let r = builtin("lab17").unwrap();
    let mut parts = 0;
    for l in &r.links {
        for v in &l.visuals {
            let Geometry::Box { size } = v.geometry else {
                panic!("{}: lab17 is boxes only", l.name);
            };
            let p = twinloop_description::builtin::parts::Part::boxed(
                "x",
                twinloop_description::builtin::parts::PartKind::Structure,
                1.0,
                size,
                [0.0; 3],
            );
            let t = lab17::table1_box_inertia(1.0, size[2], size[1], size[0]);
            let own = p.central_inertia();
            assert!((own.ixx - t.ixx).abs() < 1e-18 && (own.iyy - t.iyy).abs() < 1e-18);
            assert!((own.izz - t.izz).abs() < 1e-18);
            parts += 1;
        }
    }
    assert!(parts >= 17 + 10);
}

/// The lab17 configuration with some joints at given angles.
fn lab17_placement(angles: &[(&str, f64)], link: &str) -> Se3 {
    let r = builtin("lab17").unwrap();
    let model = Model::from_description(&r).unwrap();
    let mut data = Data::new(&model);
    let mut q = model.neutral_configuration();
    for (j, a) in angles {
        q[model.q_offset + model.joint_index(j).unwrap()] = *a;
    }
    frames_forward_kinematics(&model, &mut data, &q);
    data.o_m_f[model.frame_index(link).unwrap()]
}

#[test]
fn lab17_trims_turn_the_seed_gait_offsets_into_steps() {
    // Table 2 at its trim is joint angle 0, and the mapping inverts.
    for t in lab17::TRIMS {
        assert_eq!(lab17::joint_angle(t.joint, t.servo_deg), Some(0.0));
        let a = lab17::joint_angle(t.joint, t.servo_deg + 12.5).unwrap();
        assert!((lab17::servo_angle_deg(t.joint, a).unwrap() - t.servo_deg - 12.5).abs() < 1e-12);
    }
    assert_eq!(lab17::TRIMS.len(), 10);
    let trim = |j: &str| lab17::trim(j).unwrap().servo_deg;
    assert_eq!(
        [
            trim("l_ank_roll"),
            trim("l_ank_pitch"),
            trim("l_knee"),
            trim("l_hip_pitch"),
            trim("l_sho_pitch")
        ],
        [97.0, 74.0, 6.0, 85.0, 155.0]
    );
    assert_eq!(
        [
            trim("r_ank_roll"),
            trim("r_ank_pitch"),
            trim("r_knee"),
            trim("r_hip_pitch"),
            trim("r_sho_pitch")
        ],
        [79.0, 82.0, 142.0, 70.0, 87.0]
    );
    // Stage C (right leg forward: ankle -10, knee -20, hip -20 servo degrees) and stage F
    // (left leg: ankle -10, knee +40, hip +40) move the stepping foot forward and up
    // relative to the trunk, with the toe up.
    for (side, knee_hip) in [("r", -20.0), ("l", 40.0)] {
        let offsets = [
            (format!("{side}_ank_pitch"), -10.0),
            (format!("{side}_knee"), knee_hip),
            (format!("{side}_hip_pitch"), knee_hip),
        ];
        let angles: Vec<(&str, f64)> = offsets
            .iter()
            .map(|(j, d)| {
                let t = lab17::trim(j).unwrap();
                (j.as_str(), lab17::joint_angle(j, t.servo_deg + d).unwrap())
            })
            .collect();
        let foot = format!("{side}_foot");
        let before = lab17_placement(&[], &foot);
        let after = lab17_placement(&angles, &foot);
        let d = after.translation - before.translation;
        assert!(d.x > 0.0 && d.z > 0.0, "{side}: foot moved by {d}");
        let toe = after.rotation * Vector3::x();
        assert!(toe.z > 0.0, "{side}: toe {toe}");
    }
    // Stage H: left ankle roll -7 servo degrees shifts the weight onto the left foot:
    // seen from the left foot, the trunk moves left.
    // Both ankle rolls get -7 (H prints Offset_1_L twice; the second is Offset_1_R):
    // equal offsets must lean the body the same way over both feet (a parallelogram),
    // or the weight never leaves a foot.
    let trunk = Vector3::new(0.0, 0.0, 0.05);
    for (side, trim) in [("l", 97.0), ("r", 79.0)] {
        let joint = format!("{side}_ank_roll");
        let a = lab17::joint_angle(&joint, trim - 7.0).unwrap();
        let foot = format!("{side}_foot");
        let foot0 = lab17_placement(&[], &foot);
        let foot1 = lab17_placement(&[(joint.as_str(), a)], &foot);
        let y0 = foot0.act_inv_point(&trunk).y;
        let y1 = foot1.act_inv_point(&trunk).y;
        assert!(y1 > y0, "{side}: {y0} -> {y1}");
    }
    // B/H right shoulder +30, E/M left shoulder -30: both arms swing forward (they help
    // move the CG onto the foot that stepped forward).
    for (side, trim, d) in [("r", 87.0, 30.0), ("l", 155.0, -30.0)] {
        let joint = format!("{side}_sho_pitch");
        let a = lab17::joint_angle(&joint, trim + d).unwrap();
        let hand = format!("{side}_forearm");
        let h0 = lab17_placement(&[], &hand).translation;
        let h1 = lab17_placement(&[(joint.as_str(), a)], &hand).translation;
        assert!(h1.x > h0.x + 0.02, "{side}: hand x {} -> {}", h0.x, h1.x);
    }
}

#[test]
fn battery_scenarios_add_0_2_kg_where_they_say() {
    use twinloop_dynamics::center_of_mass;
    let base = builtin("km20").unwrap();
    let model0 = Model::from_description(&base).unwrap();
    let mut d0 = Data::new(&model0);
    let q0 = model0.neutral_configuration();
    let c0 = center_of_mass(&model0, &mut d0, &q0);
    for s in km20::BATTERY_SCENARIOS {
        let r = km20::with_battery(&s).unwrap();
        let added: f64 = s.masses.iter().map(|m| m.mass).sum();
        assert!((r.total_mass() - 3.336 - added).abs() < 1e-12);
        assert!(added == 0.0 || (added - 0.2).abs() < 1e-15, "{}", s.label);
        // The new CoM is the mass-weighted mean of the old one and the added points
        // (placed by the unchanged robot's link frames).
        let model = Model::from_description(&r).unwrap();
        let mut data = Data::new(&model);
        let c = center_of_mass(&model, &mut data, &model.neutral_configuration());
        let mut want = c0 * 3.336;
        for m in s.masses {
            let p = placement(&base, m.link).act_point(&Vector3::new(m.xyz[0], m.xyz[1], m.xyz[2]));
            want += p * m.mass;
        }
        want /= 3.336 + added;
        assert!((c - want).norm() < 1e-12, "{}: {c} vs {want}", s.label);
        assert_eq!(lint(&r).errors, 0);
    }
    let mut r = builtin("km20").unwrap();
    let e =
        twinloop_description::builtin::add_point_mass(&mut r, "l_tigh", 0.1, [0.0; 3]).unwrap_err();
    assert!(
        e.to_string().contains("l_tigh") && e.to_string().contains("l_thigh"),
        "{e}"
    );
    // Zero is no part; a negative mass is a part taken off, at most what the link has.
    let e = twinloop_description::builtin::add_point_mass(&mut r, "l_thigh", 0.0, [0.0; 3])
        .unwrap_err();
    assert!(e.to_string().contains("not 0"), "{e}");
    let e = twinloop_description::builtin::add_point_mass(&mut r, "l_thigh", -10.0, [0.0; 3])
        .unwrap_err();
    assert!(e.to_string().contains("l_thigh"), "{e}");
    assert!(
        twinloop_description::builtin::add_point_mass(&mut r, "l_thigh", 0.1, [f64::NAN, 0.0, 0.0])
            .is_err()
    );
}
