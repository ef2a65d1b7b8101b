//! The bundled MJCF files: counts and masses against summary.json, the OP3
//! MJCF against the OP3 URDF, and MJCF -> URDF writing.

mod models_support;

use models_support::{Json, files_ending, models_dir, summary_for};
use std::path::Path;
use twinloop_description::{Description, Geometry, Joint, JointKind, Pose, mjcf, urdf};

fn read(path: &Path) -> Description {
    mjcf::read_file(path).unwrap_or_else(|e| panic!("{e}"))
}

/// The robot MJCF files (scene files only `<include>` them).
fn robot_mjcfs() -> Vec<std::path::PathBuf> {
    let files: Vec<_> = files_ending(&models_dir(), ".xml")
        .into_iter()
        .filter(|p| {
            p.parent()
                .and_then(|d| d.file_name())
                .is_some_and(|d| d == "mjcf")
        })
        .filter(|p| p.file_name().is_some_and(|n| n != "scene.xml"))
        .collect();
    // OP3, TALOS, G1 and H1 (G1 and H1 also as Unitree ship them), and the other
    // Menagerie humanoids of issue 30 (ToddlerBot 2xc and 2xm, Atlas, Elf2 among them).
    assert_eq!(files.len(), 19, "{files:?}");
    files
}

#[test]
fn every_mjcf_matches_its_summary() {
    for path in robot_mjcfs() {
        let here = path.display();
        let robot = read(&path);
        let s = summary_for(&path).unwrap_or_else(|| panic!("no summary.json entry for {here}"));
        let by_type = s.get("joints_by_type").unwrap();
        let hinges = by_type.get("hinge").unwrap().num() as usize;
        let moving = robot
            .joints
            .iter()
            .filter(|j| matches!(j.kind, JointKind::Revolute | JointKind::Continuous))
            .count();
        assert_eq!(moving, hinges, "{here}: hinges");
        assert_eq!(by_type.get("free").map(Json::num), Some(1.0), "{here}");
        let balls = by_type.get("ball").map_or(0.0, Json::num) as usize;
        let spherical = robot
            .joints
            .iter()
            .filter(|j| j.kind == JointKind::Spherical)
            .count();
        assert_eq!(spherical, balls, "{here}: balls");
        // One link per body but the empty static ones MuJoCo welds to the world
        // (Apollo's world_link); the free-floating top body is the root, no world link.
        let empty = match s.get("empty_static_bodies") {
            Some(Json::Arr(names)) => names.len(),
            _ => 0,
        };
        assert_eq!(
            robot.links.len(),
            s.get("n_bodies").unwrap().num() as usize - empty,
            "{here}: bodies"
        );
        assert!(robot.link("world").is_none(), "{here}");
        assert_eq!(robot.root_links().len(), 1, "{here}");
        let fixed = robot
            .joints
            .iter()
            .filter(|j| j.kind == JointKind::Fixed)
            .count();
        assert_eq!(
            fixed + hinges + balls + 1,
            robot.links.len(),
            "{here}: a fixed joint per jointless body"
        );
        let mass = s.get("total_mass_kg_from_inertial").unwrap().num();
        assert!(
            (robot.total_mass() - mass).abs() < 1e-9,
            "{here}: mass {} vs {mass}",
            robot.total_mass()
        );
        // Joints with a range in the file are limited, the others are not.
        let with_range = s.get("joints_with_range_attr").unwrap().num() as usize;
        let revolute = robot
            .joints
            .iter()
            .filter(|j| j.kind == JointKind::Revolute)
            .count();
        assert_eq!(revolute, with_range, "{here}: limited hinges");
        for j in robot
            .joints
            .iter()
            .filter(|j| j.kind == JointKind::Revolute)
        {
            let l = j.limit.unwrap();
            assert!(l.lower.unwrap() < l.upper.unwrap(), "{here}: {}", j.name);
        }
    }
}

#[test]
fn expected_numbers() {
    let op3 = read(&models_dir().join("op3/mjcf/op3.xml"));
    assert_eq!(
        op3.joints
            .iter()
            .filter(|j| j.kind == JointKind::Continuous)
            .count(),
        20
    );
    assert!((op3.total_mass() - 3.14747).abs() < 1e-12);
    assert_eq!(op3.root_link(), Some("body_link"));
    assert_eq!(op3.frames.len(), 1);
    assert_eq!(
        (op3.frames[0].name.as_str(), op3.frames[0].link.as_str()),
        ("torso", "body_link")
    );
    // Default-class joint dynamics.
    let d = op3.joint("l_knee").unwrap().dynamics.unwrap();
    assert_eq!((d.damping, d.friction), (Some(1.084), Some(0.03)));
    // Mesh assets: meshdir in front, the default class's scale.
    let body = op3.link("body_link").unwrap();
    assert_eq!(body.visuals.len(), 1);
    assert_eq!(
        body.visuals[0].geometry,
        Geometry::Mesh {
            filename: "assets/body.stl".into(),
            scale: Some([0.001; 3])
        }
    );
    assert_eq!(
        body.visuals[0].material.as_ref().unwrap().rgba,
        Some([0.2, 0.2, 0.2, 1.0])
    );
    assert_eq!(body.collisions.len(), 5);
    // The foot class: boxes from half sizes, collision only.
    let foot = op3.link("l_ank_roll_link").unwrap();
    assert_eq!(foot.visuals.len(), 1);
    assert_eq!(foot.collisions.len(), 2);
    assert_eq!(
        foot.collisions[0].geometry,
        Geometry::Box {
            size: [0.127, 0.056, 0.008]
        }
    );
    assert_eq!(foot.collisions[0].origin.xyz, [0.024, 0.013, -0.0265]);

    let talos = read(&models_dir().join("talos/mjcf/talos.xml"));
    assert_eq!(
        talos
            .joints
            .iter()
            .filter(|j| j.kind == JointKind::Revolute)
            .count(),
        44
    );
    assert!((talos.total_mass() - 94.00319).abs() < 1e-9);
    // fullinertia is Ixx Iyy Izz Ixy Ixz Iyz.
    let i = talos.link("base_link").unwrap().inertial.unwrap().inertia;
    assert_eq!(
        (i.ixx, i.iyy, i.izz),
        (0.20105075811, 0.08411496729, 0.2318908414)
    );
    assert_eq!(
        (i.ixy, i.ixz, i.iyz),
        (0.00023244734, 0.0040167728, -0.00087206649)
    );
    let t1 = talos.joint("torso_1_joint").unwrap();
    let l = t1.limit.unwrap();
    assert_eq!(
        (l.lower, l.upper, l.effort),
        (Some(-1.25664), Some(1.25664), Some(200.0))
    );
    // frictionloss on the joint overrides the class's; damping comes from the class.
    assert_eq!(t1.dynamics.unwrap().friction, Some(2.0));
    assert_eq!(t1.dynamics.unwrap().damping, Some(1.0));
    // Mirrored mesh scale of a right-arm asset.
    let arm = talos.link("arm_right_1_link").unwrap();
    assert!(
        matches!(&arm.visuals[0].geometry, Geometry::Mesh { filename, scale: Some([1.0, -1.0, 1.0]) } if filename == "assets/arm/arm_1.stl"),
        "{:?}",
        arm.visuals[0].geometry
    );

    // H1: fromto capsules from nested default classes.
    let h1 = read(&models_dir().join("unitree_h1/mjcf/h1_menagerie.xml"));
    let ankle = h1.link("left_ankle_link").unwrap();
    let capsules: Vec<_> = ankle
        .collisions
        .iter()
        .filter(|s| matches!(s.geometry, Geometry::Capsule { .. }))
        .collect();
    assert_eq!(capsules.len(), 3);
    let Geometry::Capsule { radius, length } = capsules[2].geometry else {
        panic!()
    };
    assert_eq!(radius, 0.014);
    assert!((length - 0.06).abs() < 1e-12, "{length}");
    assert!((capsules[2].origin.xyz[0] - 0.14).abs() < 1e-12);
}

#[test]
fn scene_files_with_include_read_the_included_robot() {
    let dir = models_dir();
    let scene = twinloop_description::load(dir.join("op3/mjcf/scene.xml")).unwrap();
    let robot = twinloop_description::load(dir.join("op3/mjcf/op3.xml")).unwrap();
    assert_eq!(scene.links, robot.links);
    assert_eq!(scene.joints, robot.joints);
    assert_eq!(scene.frames, robot.frames);
}

#[test]
fn load_picks_the_reader_by_root_element() {
    let dir = models_dir();
    let m = twinloop_description::load(dir.join("op3/mjcf/op3.xml")).unwrap();
    assert_eq!(m, read(&dir.join("op3/mjcf/op3.xml")));
    let u = twinloop_description::load(dir.join("op3/robotis_op3.urdf")).unwrap();
    assert_eq!(
        u,
        urdf::read_file(dir.join("op3/robotis_op3.urdf")).unwrap()
    );
    // A file that is neither.
    let e = twinloop_description::load(dir.join("op3/summary.json")).unwrap_err();
    assert!(e.to_string().contains("summary.json"), "{e}");
}

fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

fn transpose(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = a[j][i];
        }
    }
    m
}

/// The inertia tensor about the CoM in the link frame: R I R^T.
fn link_frame_inertia(i: &twinloop_description::Inertial) -> [[f64; 3]; 3] {
    let r = i.origin.rotation();
    mat_mul(&mat_mul(&r, &i.inertia.matrix()), &transpose(&r))
}

/// OP3: the Menagerie MJCF was made from the ROBOTIS URDF. Link names are the
/// same in both; the URDF has two more (massless camera links). Masses, CoMs
/// and inertia tensors (MJCF: principal moments + quaternion, rounded to 6
/// digits; URDF: full tensor) agree per link, and so does the kinematic tree.
#[test]
fn op3_mjcf_agrees_with_op3_urdf() {
    let dir = models_dir();
    let u = urdf::read_file(dir.join("op3/robotis_op3.urdf")).unwrap();
    let m = read(&dir.join("op3/mjcf/op3.xml"));
    let extra: Vec<&str> = u
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| m.link(n).is_none())
        .collect();
    assert_eq!(extra, ["cam_link", "cam_gazebo_link"]);
    assert!(extra.iter().all(|n| u.link(n).unwrap().inertial.is_none()));
    let tol = 5e-6;
    let mut worst = 0.0f64;
    for lm in &m.links {
        let lu = u
            .link(&lm.name)
            .unwrap_or_else(|| panic!("URDF has no link {}", lm.name));
        let (im, iu) = (lm.inertial.unwrap(), lu.inertial.unwrap());
        assert_eq!(im.mass, iu.mass, "{} mass", lm.name);
        // CoM in the link frame.
        for d in 0..3 {
            let e = (im.origin.xyz[d] - iu.origin.xyz[d]).abs();
            worst = worst.max(e);
            assert!(
                e <= tol,
                "{} com[{d}]: {} vs {}",
                lm.name,
                im.origin.xyz[d],
                iu.origin.xyz[d]
            );
        }
        let (tm, tu) = (link_frame_inertia(&im), link_frame_inertia(&iu));
        for r in 0..3 {
            for c in 0..3 {
                let e = (tm[r][c] - tu[r][c]).abs();
                worst = worst.max(e);
                assert!(
                    e <= tol,
                    "{} inertia[{r}][{c}]: {} vs {}",
                    lm.name,
                    tm[r][c],
                    tu[r][c]
                );
            }
        }
    }
    assert!(worst < 1e-7, "worst difference {worst:e}");
    // Same joints, same places, same axes. (The MJCF has no ranges: its hinges
    // are continuous, the URDF's revolute.)
    for jm in &m.joints {
        let ju = u.joint(&jm.name).unwrap();
        assert_eq!(
            (jm.parent.as_str(), jm.child.as_str()),
            (ju.parent.as_str(), ju.child.as_str())
        );
        assert_eq!(jm.origin, ju.origin, "{}", jm.name);
        assert_eq!(jm.axis, ju.axis, "{}", jm.name);
        assert_eq!(
            (jm.kind, ju.kind),
            (JointKind::Continuous, JointKind::Revolute)
        );
    }
}

/// `b` is `a` as a URDF gives it back: the same translation, and the rotation
/// through URDF's roll-pitch-yaw, to rounding (the conversion is backward
/// stable). Returns `b` with `a`'s exact placement, for comparing the rest.
fn through_rpy(a: &Pose, b: &Pose, what: &str) -> Pose {
    assert_eq!(a.xyz, b.xyz, "{what}");
    let (ra, rb) = (a.rotation(), b.rotation());
    let err = (0..9)
        .map(|k| (ra[k / 3][k % 3] - rb[k / 3][k % 3]).abs())
        .fold(0.0, f64::max);
    assert!(err < 4e-15, "{what}: rotation off by {err:e}");
    *a
}

#[test]
fn mjcf_models_write_as_urdf() {
    for path in robot_mjcfs() {
        let m = read(&path);
        let text = urdf::to_string(&m);
        let back = urdf::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        // Frames come back as links with fixed joints, capsules as cylinders, a ball
        // joint (Cassie's) as three revolute joints through two massless links.
        let balls = m
            .joints
            .iter()
            .filter(|j| j.kind == JointKind::Spherical)
            .count();
        assert_eq!(
            back.links.len(),
            m.links.len() + m.frames.len() + 2 * balls,
            "{}",
            path.display()
        );
        assert_eq!(
            back.joints.len(),
            m.joints.len() + m.frames.len() + 2 * balls
        );
        assert!((back.total_mass() - m.total_mass()).abs() < 1e-12);
        for l in &m.links {
            let b = back.link(&l.name).unwrap();
            let mut bi = b.inertial;
            if let (Some(bi), Some(li)) = (&mut bi, &l.inertial) {
                bi.origin = through_rpy(&li.origin, &bi.origin, &l.name);
            }
            assert_eq!(bi, l.inertial, "{}", l.name);
            assert_eq!(b.visuals.len(), l.visuals.len());
        }
        for j in &m.joints {
            if j.kind == JointKind::Spherical {
                for axis in ["x", "y", "z"] {
                    let r = back.joint(&format!("{}_{axis}", j.name)).unwrap();
                    assert!(
                        matches!(r.kind, JointKind::Revolute | JointKind::Continuous),
                        "{}_{axis}: {:?}",
                        j.name,
                        r.kind
                    );
                }
                continue;
            }
            // URDF has no armature or spring.
            let urdf_joint = Joint {
                armature: 0.0,
                stiffness: 0.0,
                springref: 0.0,
                ..j.clone()
            };
            let mut bj = back.joint(&j.name).unwrap().clone();
            bj.origin = through_rpy(&j.origin, &bj.origin, &j.name);
            assert_eq!(bj, urdf_joint);
        }
        for f in &m.frames {
            let j = back.joint(&format!("{}_frame_joint", f.name)).unwrap();
            assert_eq!(j.parent, f.link);
            through_rpy(&f.origin, &j.origin, &f.name);
        }
        let capsules = m
            .links
            .iter()
            .flat_map(|l| l.collisions.iter().chain(&l.visuals))
            .filter(|s| matches!(s.geometry, Geometry::Capsule { .. }))
            .count();
        assert_eq!(text.matches("URDF has no capsule").count(), capsules);
    }
}

/// Issue 30 item 1: Apptronik Apollo's empty static `world_link` beside its free
/// robot (no mass, no joint, no geom: MuJoCo welds it to the world) is left out with
/// a note naming it, not refused.
#[test]
fn an_empty_static_body_beside_the_robot_is_left_out_with_a_note() {
    let apollo = read(&models_dir().join("apptronik_apollo/mjcf/apptronik_apollo.xml"));
    assert!(apollo.link("world_link").is_none());
    assert_eq!(apollo.root_link(), Some("base_link"));
    let note = apollo
        .ignored
        .iter()
        .find(|n| n.element == "<body name=\"world_link\">")
        .expect("a note for world_link");
    assert!(note.what.contains("no mass, no joint"), "{}", note.what);
}
