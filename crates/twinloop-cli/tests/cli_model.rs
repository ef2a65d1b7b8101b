//! `twinloop model ...` run as a user runs it: the built binary on bundled models.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn model(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(rel)
}

fn twinloop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .output()
        .expect("the twinloop binary runs")
}

fn run_on(args: &[&str], file: &Path) -> Output {
    let mut all: Vec<&str> = args.to_vec();
    all.push(file.to_str().unwrap());
    twinloop(&all)
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).unwrap()
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("not JSON ({e}): {}", stdout(o)))
}

/// A file in this test target's scratch directory.
fn scratch(name: &str, text: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn info_json_of_op3() {
    let o = run_on(
        &["model", "info", "--json", "-"],
        &model("op3/robotis_op3.urdf"),
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["robot"], "robotis_op3");
    assert_eq!(v["format"], "URDF");
    assert_eq!(v["root_link"], "body_link");
    assert_eq!(v["links"], 23);
    assert_eq!(v["joints"], 22);
    assert_eq!(v["joints_by_kind"]["revolute"], 20);
    assert_eq!(v["joints_by_kind"]["fixed"], 2);
    assert_eq!(v["joints_by_kind"]["continuous"], 0);
    assert_eq!(v["dof"], 20);
    assert_eq!(v["actuated_dof"], 20);
    assert_eq!(v["mimic_joints"], serde_json::json!([]));
    assert_eq!(
        v["links_without_inertial"],
        serde_json::json!(["cam_link", "cam_gazebo_link"])
    );
    let mass = v["total_mass"].as_f64().unwrap();
    assert!((mass - 3.14747).abs() < 1e-9, "{mass}");
    let heaviest = v["heaviest_links"].as_array().unwrap();
    assert_eq!(heaviest.len(), 5);
    assert_eq!(heaviest[0]["name"], "body_link");
    assert!((heaviest[0]["mass"].as_f64().unwrap() - 1.34928).abs() < 1e-12);
}

#[test]
fn info_text_of_nao_names_the_mimic_joints() {
    let o = run_on(&["model", "info"], &model("nao/nao_V50.nomesh.urdf"));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let s = stdout(&o);
    assert!(s.contains("robot         NaoH25V50"), "{s}");
    assert!(
        s.contains("joints        78: 26 revolute, 16 continuous, 36 fixed"),
        "{s}"
    );
    assert!(s.contains("dof           42 (25 actuated)"), "{s}");
    assert!(s.contains("mimic joints  17: RHipYawPitch"), "{s}");
    assert!(s.contains("total mass    5.3054 kg"), "{s}");
}

#[test]
fn info_counts_a_floating_joint_as_six_dof() {
    let o = run_on(
        &["model", "info", "--json", "-"],
        &model("coman/coman.nomesh.urdf"),
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["root_link"], "world");
    assert_eq!(v["joints_by_kind"]["floating"], 1);
    assert_eq!(v["dof"], 35);
    assert_eq!(v["actuated_dof"], 29);
}

#[test]
fn lint_fails_on_op2_and_coman_and_passes_op3() {
    for (rel, code) in [
        ("op2/robotis_op2.urdf", 1),
        ("coman/coman.urdf", 1),
        ("op3/robotis_op3.urdf", 0),
        ("sigmaban/sigmaban.urdf", 0),
    ] {
        let o = run_on(&["model", "lint"], &model(rel));
        assert_eq!(
            o.status.code(),
            Some(code),
            "{rel}: {}{}",
            stdout(&o),
            stderr(&o)
        );
        assert!(stderr(&o).is_empty(), "{rel}: {}", stderr(&o));
    }
    let o = run_on(&["model", "lint"], &model("coman/coman.urdf"));
    let s = stdout(&o);
    assert!(s.starts_with("SEVERITY  CODE"), "{s}");
    let line = s.lines().find(|l| l.contains("Xtion_body")).unwrap();
    assert!(
        line.starts_with("error     triangle-inequality  link Xtion_body"),
        "{line}"
    );
    assert!(s.contains("1 error, 0 warnings, 1 info"), "{s}");
}

#[test]
fn mjcf_models_are_read_by_their_root_element() {
    let o = run_on(
        &["model", "info", "--json", "-"],
        &model("talos/mjcf/talos.xml"),
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["format"], "MJCF");
    assert_eq!(v["robot"], "talos");
    assert_eq!(v["joints_by_kind"]["revolute"], 44);
    assert!((v["total_mass"].as_f64().unwrap() - 94.0032).abs() < 1e-3);
    for rel in [
        "op3/mjcf/op3.xml",
        "talos/mjcf/talos.xml",
        "unitree_h1/mjcf/h1_menagerie.xml",
    ] {
        let o = run_on(&["model", "lint"], &model(rel));
        assert_eq!(
            o.status.code(),
            Some(0),
            "{rel}: {}{}",
            stdout(&o),
            stderr(&o)
        );
    }
    // TALOS's gripper equality constraints: warnings, errors with --strict.
    let o = run_on(
        &["model", "lint", "--strict"],
        &model("talos/mjcf/talos.xml"),
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let s = stdout(&o);
    assert_eq!(s.matches("error     unmodeled-element").count(), 6, "{s}");
    assert!(s.contains("<joint> in <equality>"), "{s}");
}

#[test]
fn lint_json_has_stable_fields() {
    let o = run_on(
        &["model", "lint", "--json", "-"],
        &model("op2/robotis_op2.nomesh.urdf"),
    );
    assert_eq!(o.status.code(), Some(1));
    let v = json(&o);
    assert_eq!(v["robot"], "robotis_op2");
    assert_eq!(v["format"], "URDF");
    assert_eq!(v["errors"], 21);
    assert_eq!(v["warnings"], 0);
    for key in [
        "file",
        "total_mass",
        "links",
        "links_without_inertial",
        "joints",
        "moving_joints",
        "dof",
        "mimic_joints",
        "infos",
    ] {
        assert!(v.get(key).is_some(), "{key} missing");
    }
    let findings = v["findings"].as_array().unwrap();
    assert_eq!(findings.len(), 22);
    let first = &findings[0];
    assert_eq!(first["severity"], "error");
    assert_eq!(first["code"], "inertia-not-positive-definite");
    assert_eq!(first["subject"], "link");
    assert_eq!(first["name"], "body_link");
    assert!(first["message"].as_str().unwrap().contains("semi-definite"));
    assert_eq!(findings[21]["code"], "total-mass");
    assert_eq!(findings[21]["subject"], "robot");
}

#[test]
fn malformed_file_exits_2_naming_the_line() {
    let bad = scratch(
        "malformed.urdf",
        "<?xml version=\"1.0\"?>\n<robot name=\"bad\">\n  <link name=\"a\">\n  </lnk>\n</robot>\n",
    );
    for cmd in ["info", "lint"] {
        let o = run_on(&["model", cmd], &bad);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", stderr(&o));
        let err = stderr(&o);
        let expected_start = format!("error: {}:4:", bad.display());
        assert!(err.starts_with(&expected_start), "{cmd}: {err}");
        assert!(stdout(&o).is_empty());
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn invalid_description_exits_2_naming_the_element() {
    let bad = scratch(
        "dangling.urdf",
        "<robot name=\"bad\">\n  <link name=\"a\"/>\n  <joint name=\"j\" type=\"fixed\">\n    <parent link=\"a\"/>\n    <child link=\"nowhere\"/>\n  </joint>\n</robot>\n",
    );
    let o = run_on(&["model", "lint"], &bad);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.starts_with(&format!("error: {}", bad.display())),
        "{err}"
    );
    assert!(err.contains("nowhere"), "{err}");
}

#[test]
fn missing_file_and_foreign_xml_exit_2() {
    let o = run_on(&["model", "info"], Path::new("/nonexistent/robot.urdf"));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).starts_with("error: /nonexistent/robot.urdf"),
        "{}",
        stderr(&o)
    );

    let sdf = scratch(
        "model.sdf",
        "<sdf version=\"1.7\"><model name=\"m\"/></sdf>\n",
    );
    let o = run_on(&["model", "lint"], &sdf);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).starts_with("error: "), "{}", stderr(&o));
}

#[test]
fn bad_usage_exits_2() {
    assert_eq!(twinloop(&["model", "lint"]).status.code(), Some(2));
    assert_eq!(twinloop(&["model", "frobnicate"]).status.code(), Some(2));
}

#[test]
fn help_teaches_what_each_command_does() {
    let o = twinloop(&["--help"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(stdout(&o).contains("model"));

    let o = twinloop(&["model", "info", "--help"]);
    let s = stdout(&o);
    assert!(s.contains("Example:"), "{s}");
    assert!(
        s.contains("twinloop model info models/op3/robotis_op3.urdf"),
        "{s}"
    );
    assert!(s.contains("total mass"), "{s}");

    let o = twinloop(&["model", "lint", "--help"]);
    let s = stdout(&o);
    assert!(s.contains("Example:"), "{s}");
    assert!(s.contains("triangle-inequality"), "{s}");
    assert!(s.contains("Exit code 1 if any finding is an error"), "{s}");
}

#[test]
fn lint_flags_a_singular_mass_matrix_naming_the_joint() {
    // A point mass at a ball joint's centre: the ball's rows of M are zero.
    let xml = "<mujoco><worldbody>\n\
        <body name=\"arm\"><joint name=\"shoulder\" axis=\"1 0 0\"/>\
        <inertial pos=\"0 0 -0.2\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/>\n\
        <body name=\"bob\" pos=\"0 0 -0.4\"><joint name=\"pivot\" type=\"ball\"/>\
        <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0 0 0\"/></body>\n\
        </body></worldbody></mujoco>\n";
    let o = run_on(&["model", "lint", "--json", "-"], &scratch("ball.xml", xml));
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let v = json(&o);
    let f = v["findings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["code"] == "singular-mass-matrix")
        .unwrap_or_else(|| panic!("{v}"));
    assert_eq!(f["name"], "pivot");
    assert_eq!(f["severity"], "error");
    // With an inertia about the centre the same model is fine.
    let ok = xml.replace("diaginertia=\"0 0 0\"", "diaginertia=\"0.001 0.001 0.001\"");
    let o = run_on(&["model", "lint"], &scratch("ball_ok.xml", &ok));
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
}

/// A ball joint loads for the dynamics, but work that moves one coordinate per
/// joint (servos, IK, identification, adaptation) refuses the robot naming the
/// joint, instead of reading its quaternion as four hinges.
#[test]
fn one_coordinate_work_refuses_a_ball_joint_by_name() {
    let file = scratch(
        "ball_arm.xml",
        r#"<mujoco>
  <worldbody>
    <body name="torso" pos="0 0 1"><freejoint/><geom type="box" size="0.1 0.1 0.2" mass="5"/>
      <body name="arm" pos="0 0.15 0.1"><joint name="shoulder" type="ball"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.03" mass="1"/>
        <body name="fore" pos="0 0 -0.3"><joint name="elbow" axis="0 1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.03" mass="0.5"/></body>
      </body>
    </body>
  </worldbody>
</mujoco>"#,
    );
    let empty = scratch("ball_arm_empty.csv", "");
    let f = file.to_str().unwrap();
    let e = empty.to_str().unwrap();
    // Not the input: an output that is one of the inputs is refused first (issue 29).
    let out = empty.with_file_name("ball_arm_ik.csv");
    let out = out.to_str().unwrap();
    let info = twinloop(&["model", "info", f]);
    assert!(info.status.success(), "{}", stderr(&info));
    for args in [
        vec!["experiment", "tipover", "--robot", f],
        vec!["adapt", "--robot", f, "--tipover", e, "--total-mass", "7"],
        vec![
            "identify",
            "static",
            "--robot",
            f,
            "--poses",
            e,
            "--total-mass",
            "7",
        ],
        vec![
            "ik",
            "--robot",
            f,
            "--markers",
            e,
            "--frames",
            e,
            "--out",
            out,
        ],
    ] {
        let o = twinloop(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("joint \"shoulder\" is a ball joint") && err.lines().count() == 1,
            "{args:?}: {err}"
        );
    }
}

/// A misspelt `<colision>` in a URDF link: `model lint` warns with its line and the
/// element meant (exit 0), `--strict` fails (exit 1); the same file without it is clean.
#[test]
fn a_misspelt_urdf_element_is_warned_and_strict_fails() {
    let good = "<robot name=\"r\">\n  <link name=\"a\">\n    <inertial><mass value=\"1\"/>\
                <inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial>\n\
                  COLLISION\n  </link>\n</robot>\n";
    let shape = "<geometry><box size=\"1 1 1\"/></geometry>";
    let typo = scratch(
        "typo.urdf",
        &good.replace("COLLISION", &format!("<colision>{shape}</colision>")),
    );
    let clean = scratch(
        "clean.urdf",
        &good.replace("COLLISION", &format!("<collision>{shape}</collision>")),
    );
    let o = run_on(&["model", "lint"], &typo);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let s = stdout(&o);
    let line = s.lines().find(|l| l.contains("unmodeled-element")).unwrap();
    assert!(
        line.starts_with("warning")
            && line.contains("<colision> in <link name=\"a\">")
            && line.contains("line 4:")
            && line.contains("did you mean <collision>?"),
        "{line}"
    );
    let o = run_on(&["model", "lint", "--strict"], &typo);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    let o = run_on(&["model", "lint", "--strict"], &clean);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    assert!(!stdout(&o).contains("unmodeled"), "{}", stdout(&o));
}

/// An MJCF edge case of issue 30 (crates/twinloop-description/tests/data/mjcf/edges).
fn edge_case(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../twinloop-description/tests/data/mjcf/edges")
        .join(name)
}

/// Issue 30 item 6: `model info` counts ball joints (MuJoCo compiles 3 in the file),
/// its `--joints` trajectory header is one `simulate --trajectory` accepts (the
/// hinges; a ball takes no goal), and it says how many elements were left out,
/// pointing to `model lint` (which then names them).
#[test]
fn info_counts_ball_joints_and_its_trajectory_header_simulates() {
    let balls = edge_case("ball_joints.xml");
    let o = run_on(&["model", "info", "--joints", "--json", "-"], &balls);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["joints_by_kind"]["spherical"], 3);
    let header = v["trajectory_header"].as_str().unwrap();
    assert_eq!(header, "t,q:left_knee,q:right_knee");
    let text = stdout(&run_on(&["model", "info"], &balls));
    assert!(text.contains("2 revolute, 3 ball"), "{text}");
    let cells = header.split(',').count();
    let row = |t: f64| {
        std::iter::once(t.to_string())
            .chain(std::iter::repeat_n("0.2".to_string(), cells - 1))
            .collect::<Vec<_>>()
            .join(",")
    };
    let trajectory = scratch(
        "ball_goals.csv",
        &format!("{header}\n{}\n{}\n", row(0.0), row(0.02)),
    );
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("ball_sim.csv");
    let o = twinloop(&[
        "simulate",
        "--robot",
        balls.to_str().unwrap(),
        "--trajectory",
        trajectory.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    let empty = edge_case("empty_static_body.xml");
    let v = json(&run_on(&["model", "info", "--json", "-"], &empty));
    assert_eq!(v["ignored_elements"], 1);
    let text = stdout(&run_on(&["model", "info"], &empty));
    assert!(
        text.contains("ignored       1 element left out or read past: `twinloop model lint"),
        "{text}"
    );
    let lint = stdout(&run_on(&["model", "lint"], &empty));
    assert!(lint.contains("world_link"), "{lint}");
}
