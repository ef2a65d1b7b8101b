//! Robot profiles from the command line: the built-ins as `--robot` (tip-over on the
//! simulator with their roles), a profile file as `--robot` from another folder, the
//! served OP3's OpenCR read by the bus experiment, and `link scan --out` drafts that
//! load back.

use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "support/served.rs"]
mod served;
use served::serve;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_twinloop")
}

fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str], dir: &Path) -> (bool, String, String) {
    let o = Command::new(bin())
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn the_link_and_description_crates_agree_on_the_role_names() {
    assert_eq!(
        twinloop_link::RobotMapping::ROLES,
        twinloop_description::JointRoles::NAMES
    );
}

#[test]
fn model_list_shows_the_builtin_profiles() {
    let (ok, out, err) = run(&["model", "list"], &scratch("list"));
    assert!(ok, "{err}");
    for name in ["op3", "darwin_op", "km20"] {
        assert!(out.contains(name), "{out}");
    }
}

/// The four tip-over angles of a built-in profile on the simulator, each near the
/// model's static angle, with no guessing by name (the profile's roles).
fn tipover_near_statics(name: &str) {
    let dir = scratch(&format!("tip-{name}"));
    let json = dir.join("tip.json");
    let spec = format!("builtin:{name}");
    let (ok, _, err) = run(
        &[
            "experiment",
            "tipover",
            "--robot",
            &spec,
            "--json",
            json.to_str().unwrap(),
        ],
        &dir,
    );
    assert!(ok, "{err}");
    assert!(!err.contains("guessed by name"), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for d in ["forward", "backward", "left", "right"] {
        let measured = v[d]["measured_deg"].as_f64().unwrap();
        let statics = v[d]["static_deg"].as_f64().unwrap_or(f64::NAN);
        assert!(
            (measured - statics).abs() < 0.3,
            "{name} {d}: measured {measured} deg, static {statics} deg"
        );
    }
}

#[test]
fn op3_tips_over_near_its_statics() {
    tipover_near_statics("op3");
}

#[test]
fn darwin_op_tips_over_near_its_statics() {
    tipover_near_statics("darwin_op");
}

#[test]
fn a_profile_file_is_a_robot_from_any_folder() {
    let dir = scratch("profile-file");
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/op3");
    std::fs::write(
        dir.join("op3.toml"),
        format!(
            "[robot]\ndescription = \"{}\"\n[roles]\nleft_knee = \"l_knee\"\n[[joint]]\nname = \"l_knee\"\nid = 14\nmodel = \"XM430-W350\"\n",
            models.join("robotis_op3.nomesh.urdf").display()
        ),
    )
    .unwrap();
    // Relative description: copy the URDF beside the profile, run from elsewhere.
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::copy(
        models.join("robotis_op3.nomesh.urdf"),
        dir.join("sub/op3.urdf"),
    )
    .unwrap();
    std::fs::write(
        dir.join("sub/rel.toml"),
        "[robot]\ndescription = \"op3.urdf\"\n[[joint]]\nname = \"l_knee\"\nid = 14\nmodel = \"XM430-W350\"\n",
    )
    .unwrap();
    let elsewhere = scratch("profile-elsewhere");
    let rel = dir.join("sub/rel.toml");
    let (ok, out, err) = run(&["model", "info", rel.to_str().unwrap()], &elsewhere);
    assert!(ok, "{err}");
    assert!(out.contains("robotis_op3"), "{out}");
    // A role and a servo naming a joint the description lacks are refused, naming the
    // profile's line (the servo's joint is checked first).
    std::fs::write(
        dir.join("bad.toml"),
        "[robot]\ndescription = \"sub/op3.urdf\"\n[roles]\nleft_knee = \"knee\"\n[[joint]]\nname = \"knee\"\nid = 14\nmodel = \"XM430-W350\"\n",
    )
    .unwrap();
    let (ok, _, err) = run(&["model", "info", "bad.toml"], &dir);
    assert!(!ok);
    assert!(
        err.contains(
            "bad.toml line 5: joint \"knee\" (servo id 14) is not a joint of \"robotis_op3\""
        ),
        "{err}"
    );
}

/// Served OP3 (its OpenCR at id 200 on 2.0): the bus tip-over reads the IMU and
/// starts leaning (it used to stop with "no [[board]]").
#[test]
fn the_bus_tipover_reads_the_served_opencr() {
    let (mut server, pty) = serve(&[
        "--map",
        "builtin:op3",
        "--catch-falls",
        "--realtime-factor",
        "8",
        "--no-timing",
    ]);
    let out = Command::new(bin())
        .args([
            "experiment",
            "tipover",
            "--port",
            &pty,
            "--map",
            "builtin:op3",
            "--directions",
            "forward",
            "--yes",
        ])
        .stdin(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The first creep takes a few seconds of wall time at x8; then stop it.
    std::thread::sleep(std::time::Duration::from_secs(12));
    let pid = out.id();
    let _ = Command::new("kill")
        .args(["-INT", &pid.to_string()])
        .status();
    let o = out.wait_with_output().unwrap();
    let _ = server.kill();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("no [[board]]"), "{err}");
    assert!(err.contains("leaning forward"), "{err}");
    assert!(
        !err.contains("board \"trunk_imu\""),
        "the board answered: {err}"
    );
}

#[test]
fn link_scan_out_drafts_a_profile_that_loads_back() {
    let dir = scratch("scan");
    let (mut server, pty) = serve(&[
        "--map",
        "builtin:op3",
        "--servo-model",
        "ideal",
        "--no-timing",
    ]);
    let out = dir.join("op3.toml");
    let (ok, _, err) = run(
        &[
            "link",
            "scan",
            "--port",
            &pty,
            "--protocol",
            "2",
            "--ids",
            "1-200",
            "--robot",
            "builtin:op3",
            "--out",
            out.to_str().unwrap(),
        ],
        &dir,
    );
    assert!(ok, "{err}");
    assert!(
        err.contains("guessed: the servos are builtin:op3's"),
        "{err}"
    );
    let m = twinloop_link::RobotMapping::load(&out).unwrap();
    assert_eq!(m.joints.len(), 20);
    assert_eq!(m.boards[0].kind.name, "OpenCR");
    assert_eq!(m.role("left_ankle_roll"), Some("l_ank_roll"));
    // Against a description no built-in profile fits: joints by id, to fill in.
    let other = dir.join("other.toml");
    let (ok, _, err) = run(
        &[
            "link",
            "scan",
            "--port",
            &pty,
            "--protocol",
            "2",
            "--ids",
            "1-200",
            "--robot",
            "builtin:km20",
            "--out",
            other.to_str().unwrap(),
        ],
        &dir,
    );
    let _ = server.kill();
    assert!(ok, "{err}");
    assert!(
        err.contains("no built-in profile has these 20 servos"),
        "{err}"
    );
    let m = twinloop_link::RobotMapping::load(&other).unwrap();
    assert_eq!(m.joints[0].name, "id1");
    assert_eq!(m.boards[0].link, "torso");
    let text = std::fs::read_to_string(&other).unwrap();
    assert!(text.contains("# Joints of \"km20\":"), "{text}");
}
