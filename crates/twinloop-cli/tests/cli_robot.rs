//! `twinloop model list|export` as a user runs it.

use std::path::Path;
use std::process::{Command, Output};

fn twinloop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .output()
        .expect("the twinloop binary runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).unwrap()
}

#[test]
fn list_names_both_robots() {
    let o = twinloop(&["model", "list"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.starts_with("NAME"), "{text}");
    let km20 = text.lines().find(|l| l.starts_with("km20")).unwrap();
    assert!(
        km20.contains(" 20 ") && km20.contains("3.336") && km20.contains("18 RX-28, 2 RX-64"),
        "{km20}"
    );
    let lab17 = text.lines().find(|l| l.starts_with("lab17")).unwrap();
    assert!(
        lab17.contains(" 17 ") && lab17.contains("1.65") && lab17.contains("17 LD-2015"),
        "{lab17}"
    );

    let o = twinloop(&["model", "list", "--json", "-"]);
    assert_eq!(o.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["name"], "km20");
    assert_eq!(v[0]["dof"], 20);
    assert!((v[0]["total_mass"].as_f64().unwrap() - 3.336).abs() < 1e-12);
    let knee = v[0]["servos"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["joint"] == "l_knee")
        .unwrap();
    assert_eq!(knee["servo"], "RX-64");
    assert_eq!(knee["stall_torque"], 5.3);
    assert_eq!(v[1]["name"], "lab17");
}

#[test]
fn export_writes_a_urdf_that_model_info_and_lint_accept() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    for (name, dof, mass) in [("builtin:km20", 20, 3.336), ("builtin:lab17", 17, 1.65)] {
        let file = dir.join(format!("{}.urdf", name.replace(':', "_")));
        let f = file.to_str().unwrap();
        let o = twinloop(&["model", "export", name, "--out", f]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        assert!(stdout(&o).starts_with("wrote "), "{}", stdout(&o));
        let o = twinloop(&["model", "info", "--json", "-", f]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["dof"], dof);
        assert!((v["total_mass"].as_f64().unwrap() - mass).abs() < 1e-12);
        let o = twinloop(&["model", "lint", f]);
        assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    }
}

#[test]
fn export_refuses_an_unknown_robot() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("nope.urdf");
    let o = twinloop(&[
        "model",
        "export",
        "builtin:km21",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("km21") && e.contains("km20, lab17"), "{e}");
    assert!(!out.exists());
    let o = twinloop(&[
        "model",
        "export",
        "builtin:km20",
        "--out",
        "/no/such/dir/km20.urdf",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("/no/such/dir/km20.urdf"),
        "{}",
        stderr(&o)
    );
}

/// BXI Elf2's free joint has an armature and damping (from its `<default>` class) that
/// URDF cannot carry: the export says so on stderr, once each, and in the file.
#[test]
fn export_warns_that_urdf_cannot_carry_the_free_joint_armature() {
    let src =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/bxi_elf2/mjcf/elf2_dof25.xml");
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("elf2_export.urdf");
    let o = twinloop(&[
        "model",
        "export",
        src.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let e = stderr(&o);
    assert_eq!(e.lines().count(), 2, "{e}");
    assert!(
        e.contains(
            "warning: the floating base's armature 0.01 (the MJCF free joint's) is not written"
        ),
        "{e}"
    );
    assert!(
        e.contains("warning: the floating base's damping 0.1 "),
        "{e}"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("<!-- the floating base's armature 0.01"),
        "{text}"
    );
}

#[test]
fn help_teaches() {
    let o = twinloop(&["model", "export", "--help"]);
    let h = stdout(&o);
    assert!(
        h.contains("twinloop model export builtin:km20 --out km20.urdf"),
        "{h}"
    );
    assert!(h.contains("Exit code"), "{h}");
    let o = twinloop(&["model", "list", "--help"]);
    assert!(stdout(&o).contains("builtin:NAME"));
}
