//! `zmp` (seed 002, eq 12-13) through the binary: the file, its columns and bad input.

use std::process::Command;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-cli-compliant-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn zmp_writes_the_seed_gait() {
    let out = tmp("ref.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "gait",
            "zmp",
            "--step-length",
            "0.03",
            "--tss",
            "0.5",
            "--tdb",
            "0.2",
            "--footsteps",
            "4",
            "--com-height",
            "0.5",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,zmp.x,zmp.y,xr,yr,zr,vxr,vyr,axr,ayr,phase"
    );
    // 1 s standing + 0.2 + 4 * 0.5 + 4 * 0.2 + 1 s standing = 5 s at 1 kHz
    assert_eq!(lines.count(), 5001);
}

#[test]
fn zmp_names_bad_input() {
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["gait", "zmp", "--com-height=-1", "--out"])
        .arg(tmp("bad.csv"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    // Range-checked where the option is parsed: the message names the flag and range.
    assert!(String::from_utf8_lossy(&o.stderr).contains("--com-height"));
    assert!(String::from_utf8_lossy(&o.stderr).contains("out of range"));
}

fn coman_urdf() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/coman/coman.urdf").to_string()
}

#[test]
fn compliant_stiffness_writes_the_sagittal_entries() {
    let out = tmp("kc.json");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "compliant",
            "stiffness",
            "--robot",
            &coman_urdf(),
            "--support",
            "right",
            "--json",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    for key in ["Kxx", "Kxz", "Kzx", "Kzz", "Dxx", "Dxz", "Dzx", "Dzz"] {
        assert!(v["sagittal"][key].is_f64(), "missing {key}");
    }
    assert!(v["sagittal"]["Kzz"].as_f64().unwrap() > 0.0);
    assert_eq!(v["stiffness"].as_array().unwrap().len(), 6);
    assert!(String::from_utf8_lossy(&o.stdout).contains("K_C x-z"));
}

#[test]
fn compliant_stiffness_names_a_stretched_knee_and_bad_stiffness() {
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_twinloop"))
            .args(["compliant", "stiffness", "--robot", &coman_urdf()])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&["--knee-bend", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("knee"));
    let o = run(&["--k-series=-5"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--k-series"));
    assert!(String::from_utf8_lossy(&o.stderr).contains("out of range"));
    let o = run(&["--q", "NoSuchJoint=0.1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("NoSuchJoint"));
}

#[test]
fn compliant_simulate_rolls_the_compact_model_along_a_zmp_reference() {
    let (reference, kc, sim) = (tmp("sim_ref.csv"), tmp("sim_kc.json"), tmp("sim.csv"));
    let bin = env!("CARGO_BIN_EXE_twinloop");
    let ok = |o: std::process::Output| {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        o
    };
    ok(Command::new(bin)
        .args(["gait", "zmp", "--footsteps", "3", "--out"])
        .arg(&reference)
        .output()
        .unwrap());
    ok(Command::new(bin)
        .args(["compliant", "stiffness", "--robot", &coman_urdf(), "--json"])
        .arg(&kc)
        .output()
        .unwrap());
    ok(Command::new(bin)
        .args(["compliant", "simulate", "--table1", "--reference"])
        .arg(&reference)
        .arg("--plant")
        .arg(&kc)
        .arg("--out")
        .arg(&sim)
        .output()
        .unwrap());
    let text = std::fs::read_to_string(&sim).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,xr,zr,x,z,phase");
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    // at rest at the end: the CoM sits below the reference, carried by the spring
    assert!(last[4] < last[2] && last.iter().all(|v| v.is_finite()));
    let o = Command::new(bin)
        .args(["compliant", "simulate", "--params", "1,2", "--reference"])
        .arg(&reference)
        .arg("--plant")
        .arg(&kc)
        .arg("--out")
        .arg(tmp("bad.csv"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("10 comma-separated"));
}
