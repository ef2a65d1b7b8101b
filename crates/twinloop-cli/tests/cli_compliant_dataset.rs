//! `experiment compliant-walk` (seed 002 section 4) through the binary: the CSV, the JSON summary,
//! a fall and bad input.

use std::process::Command;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-cli-dataset-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn coman_urdf() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/coman/coman.urdf").to_string()
}

fn run(extra: &[&str], out: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["experiment", "compliant-walk", "--robot", &coman_urdf()])
        .args(extra)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn dataset_writes_the_seed_columns_and_a_summary() {
    let (out, json) = (tmp("walk.csv"), tmp("walk.json"));
    let json_arg = json.to_str().unwrap().to_string();
    let o = run(&["--duration", "3", "--json", &json_arg], &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,xr,zr,x,z,phase"));
    assert_eq!(lines.count(), 3000);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["summary"]["samples"], 3000);
    assert!(v["summary"]["rms_x"].as_f64().unwrap() < 0.01);
    assert!(v["seconds_per_simulated_second"].as_f64().unwrap() > 0.0);
    assert!(String::from_utf8_lossy(&o.stdout).contains("CoM tracking"));
}

#[test]
fn dataset_says_when_the_robot_falls_and_names_bad_input() {
    // The seed's K_s = 100 on the full robot: k_j < m g Zc, it falls (exit 1).
    let o = run(&["--duration", "4", "--k-series", "100"], &tmp("fall.csv"));
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("fell at t ="));
    let o = run(&["--k-series=-5"], &tmp("bad.csv"));
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--k-series"));
    assert!(String::from_utf8_lossy(&o.stderr).contains("out of range"));
    let o = run(
        &["--step-length", "0.3", "--duration", "3"],
        &tmp("far.csv"),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("reach"));
}
