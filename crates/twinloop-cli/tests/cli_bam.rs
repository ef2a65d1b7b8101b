//! `identify servo` on BAM's logs (real XL330 hardware, committed in
//! twinloop-actuator's tests/data/bam): the pendulum comes from the log, bad logs are
//! one-line errors naming the file and field.

use std::path::{Path, PathBuf};
use std::process::Command;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../twinloop-actuator/tests/data/bam")
        .join(name)
}

fn twinloop(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn identify_servo_reads_bam_logs() {
    let dir = std::env::temp_dir().join(format!("twinloop-cli-bam-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (sin, drop) = (
        data("2026-01-15_10h28m10.csv"),
        data("2026-01-15_10h28m49.csv"),
    );
    let json = dir.join("fit.json");
    let (code, out, err) = twinloop(&[
        "identify",
        "servo",
        "--model",
        "m3",
        "--data",
        sin.to_str().unwrap(),
        "--holdout",
        drop.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.starts_with("XL330-M288-T model m3"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // The same fit as crates/twinloop-actuator/tests/bam_xl330.rs's m3 from this
    // start: the stick-slip log fitted to about 14 mrad (m1: 41).
    let fit = v["fit_rms_mrad"].as_f64().unwrap();
    assert!(fit < 20.0, "{fit}");
    assert_eq!(v["heldout_rows"], 545);

    // A BAM log of a servo we do not model, and one whose arm has weight.
    let bad = dir.join("mx106.json");
    std::fs::write(
        &bad,
        r#"{"mass": 1.0, "length": 0.1, "kp": 32, "vin": 15, "motor": "mx106", "entries": []}"#,
    )
    .unwrap();
    let (code, _, err) = twinloop(&["identify", "servo", "--data", bad.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(
        err.starts_with(&format!("error: {}: motor: \"mx106\"", bad.display())),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    let heavy = dir.join("arm.json");
    std::fs::write(
        &heavy,
        r#"{"mass": 1.0, "arm_mass": 0.2, "length": 0.1, "kp": 32, "vin": 15, "motor": "xl330", "entries": []}"#,
    )
    .unwrap();
    let (code, _, err) = twinloop(&["identify", "servo", "--data", heavy.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(
        err.contains("arm_mass") && err.contains("not modelled"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
