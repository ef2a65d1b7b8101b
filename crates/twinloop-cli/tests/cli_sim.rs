//! `simulate` and `experiment tipover` through the binary: files written, fields present,
//! bad input named.

use std::process::Command;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-cli-sim-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn simulate_holds_km20_and_writes_every_column() {
    let out = tmp("hold.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "simulate",
            "--robot",
            "builtin:km20",
            "--duration",
            "0.2",
            "--hold",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    for c in [
        "t",
        "q:base.qw",
        "q:l_knee",
        "v:l_knee",
        "tau:l_knee",
        "com.z",
    ] {
        assert!(header.contains(&c), "missing {c}");
    }
    assert!(
        header
            .iter()
            .any(|h| h.starts_with("foot:") && h.ends_with(".fz"))
    );
    assert_eq!(
        text.lines().count(),
        1 + 201,
        "a row per 1 ms step, both ends"
    );
}

#[test]
fn tipover_json_has_the_issue_fields() {
    let json = tmp("tip.json");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "experiment",
            "tipover",
            "--robot",
            "builtin:km20",
            "--ramp",
            "2",
            "--json",
        ])
        .arg(&json)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for d in ["forward", "backward", "left", "right"] {
        for f in ["commanded_deg", "measured_deg", "time_s"] {
            assert!(v[d][f].as_f64().is_some_and(|x| x > 0.0), "{d}.{f}");
        }
    }
    for m in ["true", "seed_method", "exact_method"] {
        assert_eq!(v["com"][m].as_array().map(|a| a.len()), Some(3), "com.{m}");
    }
}

#[test]
fn bad_mass_and_unknown_robot_are_named() {
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "experiment",
            "tipover",
            "--robot",
            "builtin:km20",
            "--add-mass",
            "0.2@nolink:0,0,0",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nolink"));
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["simulate", "--robot", "builtin:nosuch", "--out"])
        .arg(tmp("x.csv"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("km20"),
        "lists the known robots"
    );
}

/// A robot whose legs hang from ball joints: it stands, and its quaternion columns
/// stay unit.
#[test]
fn simulate_writes_ball_joint_columns_with_unit_quaternions() {
    let xml = tmp("ballbot.xml");
    std::fs::write(
        &xml,
        r#"<mujoco model="ballbot"><worldbody>
  <body name="torso" pos="0 0 0.6"><freejoint/>
    <geom type="box" size="0.1 0.15 0.1" mass="5"/>
    <body name="leg_l" pos="0 0.08 -0.1"><joint name="hip_l" type="ball" damping="2"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.03" mass="1"/>
      <geom type="box" pos="0.01 0 -0.42" size="0.08 0.04 0.02" mass="0.2"/></body>
    <body name="leg_r" pos="0 -0.08 -0.1"><joint name="hip_r" type="ball" damping="2"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.03" mass="1"/>
      <geom type="box" pos="0.01 0 -0.42" size="0.08 0.04 0.02" mass="0.2"/></body>
  </body></worldbody></mujoco>"#,
    )
    .unwrap();
    let out = tmp("ballbot.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["simulate", "--robot"])
        .arg(&xml)
        .args(["--duration", "0.3", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| *h == n)
            .unwrap_or_else(|| panic!("{n}"))
    };
    let quat = ["qx", "qy", "qz", "qw"].map(|s| col(&format!("q:hip_l.{s}")));
    for c in ["v:hip_l.wx", "v:hip_r.wz"] {
        col(c);
    }
    for line in text.lines().skip(1) {
        let row: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let n: f64 = quat.iter().map(|&k| row[k] * row[k]).sum::<f64>().sqrt();
        assert!((n - 1.0).abs() < 1e-12, "|q:hip_l| = {n}");
    }
}

/// A run that succeeds says in one stderr line what it wrote, and its CSV's times
/// are the instants they stand for (issue 30 item 10: silent runs, and
/// `1.9999999999998905` for 2.0 from a time summed step by step).
#[test]
fn simulate_says_what_it_wrote_and_writes_clean_times() {
    let out = tmp("clean.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "simulate",
            "--robot",
            "builtin:km20",
            "--duration",
            "0.3",
            "--hold",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let said: Vec<&str> = err.lines().filter(|l| l.starts_with("wrote ")).collect();
    assert_eq!(said.len(), 1, "{err}");
    assert!(
        said[0].contains("clean.csv") && said[0].contains("301 rows") && said[0].contains("0.3 s"),
        "{err}"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    for (k, line) in text.lines().skip(1).enumerate() {
        let t = line.split(',').next().unwrap();
        // Every time is k ms written as the shortest decimal of k/1000.
        assert_eq!(t, format!("{:?}", k as f64 / 1000.0), "row {k}");
    }
    // dynamics kinematics on that file says what it wrote too.
    let kin = tmp("clean-kin.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "dynamics",
            "kinematics",
            "--robot",
            "builtin:km20",
            "--trajectory",
        ])
        .arg(&out)
        .arg("--out")
        .arg(&kin)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.lines().any(|l| l.starts_with("wrote ")
            && l.contains("clean-kin.csv")
            && l.contains("301 rows")),
        "{err}"
    );
}
