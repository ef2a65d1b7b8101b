//! Every URDF under models/ reads with the counts its summary.json records and
//! survives a write/read round trip unchanged.

mod models_support;

use models_support::{files_ending, models_dir, summary_for};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use twinloop_description::{Description, Geometry, JointKind, urdf};

fn all_urdfs() -> Vec<PathBuf> {
    let files = files_ending(&models_dir(), ".urdf");
    assert!(
        files.len() >= 25,
        "expected the bundled URDFs, found {}",
        files.len()
    );
    files
}

fn read(path: &Path) -> Description {
    urdf::read_file(path).unwrap_or_else(|e| panic!("{e}"))
}

fn model(rel: &str) -> Description {
    read(&models_dir().join(rel))
}

fn joint_kind_counts(robot: &Description) -> BTreeMap<String, usize> {
    let mut m = BTreeMap::new();
    for j in &robot.joints {
        *m.entry(j.kind.urdf_name().to_string()).or_insert(0) += 1;
    }
    m
}

#[test]
fn every_urdf_matches_its_summary() {
    for path in all_urdfs() {
        let robot = read(&path);
        let s = summary_for(&path)
            .unwrap_or_else(|| panic!("no summary.json entry for {}", path.display()));
        let here = path.display();
        assert_eq!(
            robot.links.len(),
            s.get("n_links").unwrap().num() as usize,
            "{here}: links"
        );
        assert_eq!(
            robot.joints.len(),
            s.get("n_joints").unwrap().num() as usize,
            "{here}: joints"
        );
        let expected: BTreeMap<String, usize> = s
            .get("joints_by_type")
            .unwrap()
            .obj()
            .iter()
            .map(|(k, v)| (k.clone(), v.num() as usize))
            .collect();
        assert_eq!(
            joint_kind_counts(&robot),
            expected,
            "{here}: joints by type"
        );
        let mass = s.get("total_mass_kg").unwrap().num();
        assert!(
            (robot.total_mass() - mass).abs() <= 1e-9 * mass.max(1.0),
            "{here}: mass {} vs {mass}",
            robot.total_mass()
        );
        let root = match s.get("root_links").unwrap() {
            models_support::Json::Arr(a) => a.clone(),
            _ => panic!(),
        };
        assert_eq!(root.len(), 1);
        assert_eq!(
            Some(models_support::Json::Str(
                robot.root_link().unwrap().to_string()
            )),
            root.first().cloned(),
            "{here}: root link"
        );
        // Top-level tags: links, joints, materials, and the rest as extensions.
        let mut tags: BTreeMap<String, usize> = BTreeMap::new();
        for e in &robot.extensions {
            *tags.entry(e.tag.clone()).or_insert(0) += 1;
        }
        if !robot.materials.is_empty() {
            tags.insert("material".into(), robot.materials.len());
        }
        tags.insert("link".into(), robot.links.len());
        tags.insert("joint".into(), robot.joints.len());
        let expected: BTreeMap<String, usize> = s
            .get("top_level_tags")
            .unwrap()
            .obj()
            .iter()
            .map(|(k, v)| (k.clone(), v.num() as usize))
            .collect();
        assert_eq!(tags, expected, "{here}: top-level tags");
        // Document order covers every item once.
        let n =
            robot.links.len() + robot.joints.len() + robot.materials.len() + robot.extensions.len();
        assert_eq!(robot.order.len(), n, "{here}: order");
    }
}

#[test]
fn every_urdf_round_trips() {
    for path in all_urdfs() {
        let robot = read(&path);
        let text = urdf::to_string(&robot);
        let again =
            urdf::from_str(&text).unwrap_or_else(|e| panic!("{}: re-read: {e}\n", path.display()));
        assert!(
            again == robot,
            "{}: round trip changed the robot",
            path.display()
        );
        // Writing is stable: the written text writes as itself.
        assert_eq!(urdf::to_string(&again), text, "{}", path.display());
    }
}

#[test]
fn write_file_then_read_file() {
    let robot = model("op3/robotis_op3.urdf");
    let dir = std::env::temp_dir().join(format!("twinloop-urdf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("op3.urdf");
    urdf::write_file(&robot, &path).unwrap();
    assert_eq!(urdf::read_file(&path).unwrap(), robot);
    assert_eq!(twinloop_description::load(&path).unwrap(), robot);
    std::fs::remove_dir_all(&dir).unwrap();
    let err = urdf::write_file(&robot, dir.join("no/such/dir/x.urdf")).unwrap_err();
    assert!(err.to_string().contains("no/such/dir/x.urdf"), "{err}");
}

#[test]
fn read_file_errors_name_the_file() {
    let err = urdf::read_file("/nonexistent/robot.urdf").unwrap_err();
    assert!(
        err.to_string().starts_with("/nonexistent/robot.urdf"),
        "{err}"
    );
}

#[test]
fn op3_details() {
    let r = model("op3/robotis_op3.urdf");
    assert_eq!(r.name, "robotis_op3");
    assert_eq!(r.root_link(), Some("body_link"));
    let knee = r.joint("l_knee").unwrap();
    assert_eq!(knee.kind, JointKind::Revolute);
    assert_eq!(
        (knee.parent.as_str(), knee.child.as_str()),
        ("l_hip_pitch_link", "l_knee_link")
    );
    let lim = knee.limit.unwrap();
    assert_eq!((lim.effort, lim.velocity), (Some(1000.0), Some(100.0)));
    assert_eq!(knee.dynamics.unwrap().damping, Some(0.1));
    let body = r.link("body_link").unwrap();
    match &body.visuals[0].geometry {
        Geometry::Mesh { filename, scale } => {
            assert_eq!(filename, "package://op3_description/meshes/body.stl");
            assert_eq!(*scale, Some([0.001; 3]));
        }
        g => panic!("{g:?}"),
    }
    assert!(r.link("cam_link").unwrap().inertial.is_none());
    // Extensions keep their text.
    assert_eq!(
        r.extensions
            .iter()
            .filter(|e| e.tag == "transmission")
            .count(),
        20
    );
    let t = r
        .extensions
        .iter()
        .find(|e| e.xml.0.contains("head_pan_tran"))
        .unwrap();
    assert!(
        t.xml.0.starts_with("<transmission name=\"head_pan_tran\">"),
        "{}",
        t.xml.0
    );
    assert!(t.xml.0.ends_with("</transmission>"));
    assert!(
        t.xml
            .0
            .contains("<mechanicalReduction>1</mechanicalReduction>")
    );
}

#[test]
fn sigmaban_non_standard_children_and_open_limits() {
    let r = model("sigmaban/sigmaban.urdf");
    let revolute: Vec<_> = r
        .joints
        .iter()
        .filter(|j| j.kind == JointKind::Revolute)
        .collect();
    assert_eq!(revolute.len(), 20);
    for j in revolute {
        let l = j.limit.unwrap();
        assert_eq!((l.lower, l.upper), (None, None), "{}", j.name);
        assert!(l.effort.is_some() && l.velocity.is_some());
        assert_eq!(j.extra.len(), 1, "{}", j.name);
        assert_eq!(j.extra[0].0, "<joint_properties friction=\"0.0\"/>");
    }
    // Inline materials inside visuals.
    let torso = r.link("torso").unwrap();
    let m = torso.visuals[0].material.as_ref().unwrap();
    assert_eq!(m.name, "x_plate_material");
    assert_eq!(m.rgba, Some([0.262745, 0.282353, 0.301961, 1.0]));
    assert!(torso.visuals.len() > 1 && torso.collisions.len() > 1);
}

#[test]
fn nao_names_with_slashes_and_mimic() {
    let r = model("nao/nao_V50.urdf");
    assert!(r.joint("LFoot/FSR/FrontLeft_sensor_fixedjoint").is_some());
    let mimic = r.joint("RHipYawPitch").unwrap().mimic.as_ref().unwrap();
    assert_eq!(
        (mimic.joint.as_str(), mimic.multiplier, mimic.offset),
        ("LHipYawPitch", 1.0, 0.0)
    );
    assert_eq!(
        r.joints
            .iter()
            .filter(|j| j.kind == JointKind::Continuous)
            .count(),
        16
    );
}

#[test]
fn coman_exponents_and_floating_base() {
    let r = model("coman/coman.urdf");
    assert_eq!(r.root_link(), Some("world"));
    let reference = r.joint("reference").unwrap();
    assert_eq!(reference.kind, JointKind::Floating);
    assert_eq!(reference.origin, twinloop_description::Pose::IDENTITY);
    let i = r
        .links
        .iter()
        .find_map(|l| l.inertial.filter(|i| i.inertia.ixy == 3.34E-7));
    assert!(i.is_some(), "1.23E-4 notation read");
    assert_eq!(r.materials.len(), 3);
}

#[test]
fn unitree_zero_axes_relative_meshes_and_mujoco_tag() {
    let h1 = model("unitree_h1/h1.urdf");
    let logo = h1.joint("logo_joint").unwrap();
    assert_eq!((logo.kind, logo.axis), (JointKind::Fixed, Some([0.0; 3])));
    assert_eq!(h1.extensions[0].tag, "mujoco");
    assert_eq!(h1.order[0], twinloop_description::Item::Extension(0));
    assert!(
        h1.extensions[0]
            .xml
            .0
            .contains("<compiler meshdir=\"../meshes\" discardvisual=\"false\"/>")
    );
    let g1 = model("unitree_g1/g1_29dof_rev_1_0.urdf");
    match &g1.link("pelvis").unwrap().visuals[0].geometry {
        Geometry::Mesh { filename, scale } => {
            assert_eq!((filename.as_str(), *scale), ("meshes/pelvis.STL", None))
        }
        g => panic!("{g:?}"),
    }
}

#[test]
fn icub_rotated_inertials_and_sensors() {
    let r = model("icub/iCubGazeboV2_5.urdf");
    let rotated = r
        .links
        .iter()
        .filter(|l| l.inertial.is_some_and(|i| i.origin.rpy() != [0.0; 3]))
        .count();
    assert_eq!(rotated, 19);
    assert_eq!(
        r.extensions.iter().filter(|e| e.tag == "sensor").count(),
        83
    );
}

#[test]
fn darwin_namespace_declaration_is_kept() {
    let r = model("darwin_op/robotis_op.urdf");
    assert_eq!(
        r.robot_attributes,
        vec![(
            "xmlns:xacro".to_string(),
            "http://www.ros.org/wiki/xacro".to_string()
        )]
    );
    let text = urdf::to_string(&r);
    assert!(
        text.contains("<robot name=\"robotis_op2\" xmlns:xacro=\"http://www.ros.org/wiki/xacro\">")
    );
}
