//! `identify compliant` through the binary: known-truth recovery from data the compact model
//! makes itself (`gait zmp` -> `compliant simulate --table1`), the JSON, the report, and
//! bad input named.

use std::path::PathBuf;
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-cli-fit-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn twinloop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .output()
        .unwrap()
}

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// COMAN's x-z entries with the pelvis free (`compliant stiffness`, 0.5 rad crouch).
const MODEL: &str = "m = 32.053860196\ng = 9.81\nKxx = 440.91346363174296\nKxz = -2173.515375145169\nKzx = -2173.515375145169\nKzz = 60061.10789312922\nDxx = 14.527209046033501\nDxz = -3.3326729999481515\nDzx = -3.3326729999481515\nDzz = 667.4461329201686\n";

fn walk(name: &str, step_length: &str, tss: &str, noise: &str) -> PathBuf {
    let model = tmp("PLANT.toml");
    std::fs::write(&model, MODEL).unwrap();
    let reference = tmp(&format!("{name}.ref.csv"));
    let o = twinloop(&[
        "gait",
        "zmp",
        "--footsteps",
        "12",
        "--step-length",
        step_length,
        "--tss",
        tss,
        "--out",
        s(&reference),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = tmp(&format!("{name}.csv"));
    let o = twinloop(&[
        "compliant",
        "simulate",
        "--reference",
        s(&reference),
        "--plant",
        s(&model),
        "--table1",
        "--noise",
        noise,
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

#[test]
fn fit_recovers_table_1_and_validates_on_another_gait() {
    let train = walk("train", "0.03", "0.5", "0");
    let val = walk("val", "0.05", "0.4", "0");
    let (json, html) = (tmp("fit.json"), tmp("fit.html"));
    let o = twinloop(&[
        "identify",
        "compliant",
        "--data",
        s(&train),
        "--plant",
        s(&tmp("PLANT.toml")),
        "--method",
        "lm",
        "--val",
        s(&val),
        "--json",
        s(&json),
        "--report",
        s(&html),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let table1 = [
        ("alpha1", 0.9827),
        ("beta1", 1.0357),
        ("gamma1", 1.0560),
        ("epsilon1", 1.1335),
        ("alpha2", 0.9792),
        ("beta2", 0.9561),
        ("gamma2", 1.0072),
        ("epsilon2", 1.1053),
        ("eta1", 1.0),
        ("eta2", 1.0),
    ];
    for (name, want) in table1 {
        let got = v["params"][name].as_f64().unwrap();
        assert!((got - want).abs() < 1e-6, "{name}: {got} vs {want}");
    }
    let before = v["mse_before"].as_f64().unwrap();
    assert!(before > 1e-7 && v["mse_after"].as_f64().unwrap() < 1e-20);
    assert!(v["evaluations"].as_u64().unwrap() > 10);
    assert_eq!(v["identifiability"]["names"].as_array().unwrap().len(), 8);
    let g = &v["validation"][0];
    assert!(
        g["mse_before"].as_f64().unwrap() > 1e-7 && g["mse_after"].as_f64().unwrap() < 1e-20,
        "{g}"
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("<svg") && page.contains("Fig. 4") && page.contains("before"));
}

#[test]
fn bad_input_is_named() {
    let good = std::fs::read_to_string(walk("bad-base", "0.03", "0.5", "0")).unwrap();
    let model = tmp("PLANT.toml");
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    // NaN in x on the 11th data row (line 12)
    let mut cells: Vec<String> = lines[11].split(',').map(String::from).collect();
    cells[3] = "NaN".into();
    lines[11] = cells.join(",");
    let nan = tmp("nan.csv");
    std::fs::write(&nan, lines.join("\n")).unwrap();
    let o = twinloop(&[
        "identify",
        "compliant",
        "--data",
        s(&nan),
        "--plant",
        s(&model),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("nan.csv") && e.contains("line 12, column x"),
        "{e}"
    );
    // a gap: rows 100..110 missing
    let mut gap: Vec<&str> = good.lines().collect();
    gap.drain(100..110);
    let gapped = tmp("gap.csv");
    std::fs::write(&gapped, gap.join("\n")).unwrap();
    let o = twinloop(&[
        "identify",
        "compliant",
        "--data",
        s(&gapped),
        "--plant",
        s(&model),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("line 101, column t") && e.contains("gap"), "{e}");
    // non-positive stiffness
    let neg = tmp("neg.toml");
    std::fs::write(&neg, MODEL.replace("Kzz = 60061.10789312922", "Kzz = 0")).unwrap();
    let o = twinloop(&[
        "identify",
        "compliant",
        "--data",
        s(&nan),
        "--plant",
        s(&neg),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("neg.toml") && e.contains("Kzz"), "{e}");
    // a stretched knee: the support-leg Jacobian is singular
    let urdf = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/coman/coman.urdf");
    let knee = tmp("knee.toml");
    std::fs::write(&knee, format!("urdf = \"{urdf}\"\nknee_bend = 0.0\n")).unwrap();
    let o = twinloop(&[
        "identify",
        "compliant",
        "--data",
        s(&nan),
        "--plant",
        s(&knee),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("knee.toml") && e.contains("singular") && e.contains("knee"),
        "{e}"
    );
    // unknown parameter name
    let o = twinloop(&[
        "identify",
        "compliant",
        "--data",
        s(&nan),
        "--plant",
        s(&model),
        "--params",
        "alpha1,zeta",
    ]);
    assert_eq!(o.status.code(), Some(2));
}
