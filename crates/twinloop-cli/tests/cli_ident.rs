//! The seed-004 commands run as a user runs them: `experiment static-poses`,
//! `identify static`, `experiment squat`, `ik`, `validate residual`.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn data(name: &str) -> PathBuf {
    root().join("crates/twinloop-ident/tests/data").join(name)
}

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("ident-{name}"))
}

fn twinloop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .output()
        .expect("the twinloop binary runs")
}

fn ok(args: &[&str]) -> String {
    let o = twinloop(args);
    assert!(
        o.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

fn fails(args: &[&str]) -> String {
    let o = twinloop(args);
    assert_eq!(o.status.code(), Some(2), "{args:?} should fail with 2");
    String::from_utf8(o.stderr).unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const H1: &str = "models/unitree_h1/h1.urdf";
const H1_PRIOR: &str = "models/unitree_h1/variants/h1_2025-06_a3b70ca.urdf";

fn m(rel: &str) -> String {
    root().join(rel).to_str().unwrap().to_string()
}

#[test]
fn help_teaches_each_command() {
    for cmd in [
        vec!["experiment", "static-poses"],
        vec!["experiment", "squat"],
        vec!["identify", "static"],
        vec!["ik"],
        vec!["validate", "residual"],
    ] {
        let mut args = cmd.clone();
        args.push("--help");
        let h = ok(&args);
        assert!(h.contains("Example"), "{cmd:?}: {h}");
        assert!(h.contains("Output"), "{cmd:?}: {h}");
        assert!(h.contains("seed 004"), "{cmd:?}: {h}");
    }
}

#[test]
fn force_plate_poses() {
    let out = tmp("plate.csv");
    let text = ok(&[
        "experiment",
        "static-poses",
        "--robot",
        &m(H1),
        "--count",
        "12",
        "--categories",
        "arm,torso",
        "--cop-noise",
        "0.001",
        "--seed",
        "2",
        "--out",
        s(&out),
    ]);
    assert!(
        text.contains("12 poses") && text.contains("arm") && text.contains("torso"),
        "{text}"
    );
    let csv = std::fs::read_to_string(&out).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert!(
        header.starts_with("category,q:base.x") && header.ends_with("cop.x,cop.y"),
        "{header}"
    );
    assert_eq!(lines.count(), 12);
    let e = fails(&[
        "experiment",
        "static-poses",
        "--robot",
        &m(H1),
        "--categories",
        "arm,kneel",
        "--out",
        s(&out),
    ]);
    assert!(e.contains("--categories") && e.contains("kneel"), "{e}");
    let e = fails(&[
        "experiment",
        "static-poses",
        "--robot",
        &m(H1),
        "--hold",
        "waist",
        "--out",
        s(&out),
    ]);
    assert!(e.contains("--hold") && e.contains("waist"), "{e}");
}

/// The committed poses and the Pinocchio + SciPy answer for them: the command's JSON
/// must agree, and the adapted URDF must differ from the prior only in the identified
/// links' mass and inertial origin.
#[test]
fn identify_static_matches_reference_and_writes_urdf() {
    let (json, urdf, html) = (tmp("r.json"), tmp("adapted.urdf"), tmp("report.html"));
    let text = ok(&[
        "identify",
        "static",
        "--robot",
        &m(H1_PRIOR),
        "--poses",
        s(&data("h1_poses.csv")),
        "--total-mass",
        "59.338",
        "--out",
        s(&urdf),
        "--json",
        s(&json),
        "--report",
        s(&html),
        "--suggest",
        "2",
    ]);
    assert!(
        text.contains("GCOM to CoP distance") && text.contains("identifiability"),
        "{text}"
    );
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let want: Value =
        serde_json::from_str(&std::fs::read_to_string(data("h1_static_reference.json")).unwrap())
            .unwrap();
    let links = got["result"]["links"].as_array().unwrap();
    for (w, g) in want["links"].as_array().unwrap().iter().zip(links) {
        assert_eq!(w["name"], g["name"]);
        assert!((w["mass"].as_f64().unwrap() - g["mass"].as_f64().unwrap()).abs() < 1e-6);
    }
    assert_eq!(got["suggested_poses"].as_array().unwrap().len(), 2);
    assert!(got["result"]["identifiability"]["rank"].as_u64().unwrap() > 0);
    // The adapted description: same robot but the identified inertials' mass and xyz.
    let prior = twinloop_description::load(root().join(H1_PRIOR)).unwrap();
    let adapted = twinloop_description::load(&urdf).unwrap();
    let mut restored = adapted.clone();
    for l in links {
        let name = l["name"].as_str().unwrap();
        let a = adapted.link(name).unwrap().inertial.unwrap();
        // (serde_json's default float parser can be off by an ulp.)
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-15 * x.abs().max(1e-300) * 4.0;
        assert!(close(a.mass, l["mass"].as_f64().unwrap()));
        for k in 0..3 {
            assert!(
                close(a.origin.xyz[k], l["com"][k].as_f64().unwrap()),
                "{name} {k}"
            );
        }
        let p = prior.link(name).unwrap().inertial.unwrap();
        assert_eq!(a.inertia, p.inertia, "{name}: inertia must stay");
        assert_eq!(a.origin.rpy(), p.origin.rpy());
        *restored.link_mut(name).unwrap().inertial.as_mut().unwrap() = p;
    }
    assert_eq!(
        restored, prior,
        "nothing but the identified inertials may change"
    );
    let report = std::fs::read_to_string(&html).unwrap();
    assert!(
        report.contains("Fig. 5") && report.contains("<svg"),
        "report"
    );
}

#[test]
fn identify_static_errors_name_the_field() {
    let poses = data("h1_poses.csv");
    let e = fails(&[
        "identify",
        "static",
        "--robot",
        &m(H1_PRIOR),
        "--poses",
        s(&poses),
        "--total-mass",
        "20",
        "--links",
        "torso_link",
    ]);
    assert!(
        e.contains("--total-mass") && e.contains("kept fixed"),
        "{e}"
    );
    // A NaN in a pose row and an unknown joint column.
    let text = std::fs::read_to_string(&poses).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let col = lines[0]
        .split(',')
        .position(|c| c == "q:left_knee_joint")
        .unwrap();
    let mut cells: Vec<String> = lines[3].split(',').map(String::from).collect();
    cells[col] = "NaN".into();
    lines[3] = cells.join(",");
    let bad = tmp("nan.csv");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let e = fails(&[
        "identify",
        "static",
        "--robot",
        &m(H1_PRIOR),
        "--poses",
        s(&bad),
        "--total-mass",
        "59.3",
    ]);
    assert!(
        e.contains("nan.csv") && e.contains("data row 3") && e.contains("q:left_knee_joint"),
        "{e}"
    );
    let renamed = tmp("unknown.csv");
    std::fs::write(
        &renamed,
        text.replacen("q:torso_joint", "q:waist_yaw_joint", 1),
    )
    .unwrap();
    let e = fails(&[
        "identify",
        "static",
        "--robot",
        &m(H1_PRIOR),
        "--poses",
        s(&renamed),
        "--total-mass",
        "59.3",
    ]);
    assert!(
        e.contains("q:waist_yaw_joint") && e.contains("not a joint"),
        "{e}"
    );
    // Too few poses.
    let few = tmp("few.csv");
    std::fs::write(&few, text.lines().take(11).collect::<Vec<_>>().join("\n")).unwrap();
    let e = fails(&[
        "identify",
        "static",
        "--robot",
        &m(H1_PRIOR),
        "--poses",
        s(&few),
        "--total-mass",
        "59.3",
    ]);
    assert!(
        e.contains("few.csv") && e.contains("--poses") && e.contains("at least"),
        "{e}"
    );
}

/// Squat with markers, IK back to a trajectory, inverse-dynamics residual of prior
/// and truth on it.
#[test]
fn squat_markers_ik_and_residual() {
    let markers = tmp("markers.toml");
    let mut toml = String::new();
    for (link, pts) in [
        (
            "pelvis",
            vec![
                [0.1, 0.08, 0.0],
                [0.1, -0.08, 0.0],
                [-0.08, 0.0, 0.05],
                [0.0, 0.1, -0.05],
            ],
        ),
        (
            "torso_link",
            vec![[0.1, 0.1, 0.3], [0.1, -0.1, 0.3], [-0.1, 0.0, 0.4]],
        ),
        (
            "left_hip_pitch_link",
            vec![[0.05, 0.0, -0.1], [0.0, 0.05, -0.2], [-0.05, 0.0, -0.15]],
        ),
        (
            "right_hip_pitch_link",
            vec![[0.05, 0.0, -0.1], [0.0, -0.05, -0.2], [-0.05, 0.0, -0.15]],
        ),
        (
            "left_knee_link",
            vec![[0.05, 0.0, -0.1], [0.0, 0.05, -0.2], [-0.05, 0.0, -0.25]],
        ),
        (
            "right_knee_link",
            vec![[0.05, 0.0, -0.1], [0.0, -0.05, -0.2], [-0.05, 0.0, -0.25]],
        ),
        (
            "left_ankle_link",
            vec![
                [0.15, 0.0, -0.05],
                [-0.05, 0.02, -0.05],
                [0.05, -0.02, -0.03],
            ],
        ),
        (
            "right_ankle_link",
            vec![
                [0.15, 0.0, -0.05],
                [-0.05, -0.02, -0.05],
                [0.05, 0.02, -0.03],
            ],
        ),
        (
            "left_hip_yaw_link",
            vec![[0.0, 0.05, 0.0], [-0.05, 0.0, 0.05]],
        ),
        (
            "right_hip_yaw_link",
            vec![[0.0, -0.05, 0.0], [-0.05, 0.0, 0.05]],
        ),
        (
            "left_hip_roll_link",
            vec![[0.05, 0.05, 0.0], [0.0, 0.03, -0.05]],
        ),
        (
            "right_hip_roll_link",
            vec![[0.05, -0.05, 0.0], [0.0, -0.03, -0.05]],
        ),
        (
            "left_shoulder_pitch_link",
            vec![[0.05, 0.05, 0.0], [0.0, 0.05, -0.05]],
        ),
        (
            "right_shoulder_pitch_link",
            vec![[0.05, -0.05, 0.0], [0.0, -0.05, -0.05]],
        ),
        (
            "left_shoulder_roll_link",
            vec![[0.05, 0.0, -0.1], [0.0, 0.05, -0.15]],
        ),
        (
            "right_shoulder_roll_link",
            vec![[0.05, 0.0, -0.1], [0.0, -0.05, -0.15]],
        ),
        (
            "left_shoulder_yaw_link",
            vec![[0.05, 0.0, -0.15], [0.0, 0.05, -0.2]],
        ),
        (
            "right_shoulder_yaw_link",
            vec![[0.05, 0.0, -0.15], [0.0, -0.05, -0.2]],
        ),
        (
            "left_elbow_link",
            vec![[0.15, 0.0, 0.0], [0.2, 0.03, -0.03]],
        ),
        (
            "right_elbow_link",
            vec![[0.15, 0.0, 0.0], [0.2, -0.03, -0.03]],
        ),
    ] {
        for (k, p) in pts.iter().enumerate() {
            toml.push_str(&format!(
                "[[marker]]\nname = \"{link}_{k}\"\nlink = \"{link}\"\nposition = [{}, {}, {}]\n\n",
                p[0], p[1], p[2]
            ));
        }
    }
    std::fs::write(&markers, toml).unwrap();
    let (squat, frames, traj, res) = (
        tmp("squat.csv"),
        tmp("frames.csv"),
        tmp("traj.csv"),
        tmp("res.csv"),
    );
    let text = ok(&[
        "experiment",
        "squat",
        "--robot",
        &m(H1),
        "--out",
        s(&squat),
        "--duration",
        "1.5",
        "--rest",
        "0.3",
        "--rate",
        "100",
        "--markers",
        s(&markers),
        "--frames-out",
        s(&frames),
    ]);
    assert!(text.contains("frames of a squat"), "{text}");
    let text = ok(&[
        "ik",
        "--robot",
        &m(H1),
        "--markers",
        s(&markers),
        "--frames",
        s(&frames),
        "--out",
        s(&traj),
    ]);
    assert!(text.contains("frames fitted"), "{text}");
    // The fit reproduces the squat's configuration.
    let read = |p: &Path| -> (Vec<String>, Vec<Vec<f64>>) {
        let t = std::fs::read_to_string(p).unwrap();
        let mut l = t.lines();
        let h: Vec<String> = l.next().unwrap().split(',').map(String::from).collect();
        (
            h,
            l.map(|r| r.split(',').map(|x| x.parse().unwrap()).collect())
                .collect(),
        )
    };
    let (hs, rs) = read(&squat);
    let (ht, rt) = read(&traj);
    let k = hs.iter().position(|c| c == "q:left_knee_joint").unwrap();
    let kt = ht.iter().position(|c| c == "q:left_knee_joint").unwrap();
    for (a, b) in rs.iter().zip(&rt) {
        assert!((a[k] - b[kt]).abs() < 1e-7, "{} vs {}", a[k], b[kt]);
    }
    let text = ok(&[
        "validate",
        "residual",
        "--robot",
        &m(H1_PRIOR),
        "--compare",
        &m(H1),
        "--motion",
        s(&traj),
        "--plate",
        s(&squat),
        "--out",
        s(&res),
    ]);
    assert!(
        text.contains("|Fz| N") && text.contains("h1.urdf"),
        "{text}"
    );
    let (hr, rr) = read(&res);
    assert_eq!(
        hr[0..7],
        [
            "t", "res.fx", "res.fy", "res.fz", "res.tx", "res.ty", "res.tz"
        ]
    );
    let mean_fz = |col: usize| rr.iter().map(|r| r[col].abs()).sum::<f64>() / rr.len() as f64;
    // 7.7 kg missing in the prior: about 76 N; the truth explains the plate.
    assert!(mean_fz(3) > 70.0, "{}", mean_fz(3));
    assert!(mean_fz(9) < 1.0, "{}", mean_fz(9));
    // Without plate columns the command says which are missing.
    let e = fails(&[
        "validate",
        "residual",
        "--robot",
        &m(H1),
        "--motion",
        s(&traj),
        "--out",
        s(&res),
    ]);
    assert!(e.contains("grf.fz"), "{e}");
}
