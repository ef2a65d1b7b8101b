//! `twinloop identify arx|ss` run as a user runs it, on the synthetic records of
//! tools/oracle/sysid_reference.py (crates/twinloop-sysid/tests/data).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../twinloop-sysid/tests/data")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("sysid-{}-{name}", std::process::id()))
}

fn twinloop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .output()
        .expect("the twinloop binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn read_json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn arx_json_equals_numpy_and_report_is_written() {
    let (json, html) = (scratch("arx.json"), scratch("arx.html"));
    let o = twinloop(&[
        "identify",
        "arx",
        "--data",
        path(&data("synthetic_est.csv")),
        "--inputs",
        "u*",
        "--outputs",
        "y1,y2,y3,y4,y5,y6",
        "--na",
        "2",
        "--nb",
        "2",
        "--nk",
        "1",
        // numpy's reference is on the raw records, means kept.
        "--no-detrend",
        "--json",
        path(&json),
        "--report",
        path(&html),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = read_json(&json);
    let reference: Value =
        serde_json::from_str(&std::fs::read_to_string(data("reference.json")).unwrap()).unwrap();
    let case = &reference["arx"][0];
    assert_eq!(case["na"], 2);
    for key in ["A", "B"] {
        let ours = v[key].as_array().unwrap();
        let theirs = case[key].as_array().unwrap();
        assert_eq!(ours.len(), 2);
        for (a, b) in ours.iter().zip(theirs) {
            let (a, b) = (matrix(a), matrix(b));
            assert_eq!(a.len(), 6);
            assert_eq!(a[0].len(), if key == "A" { 6 } else { 10 });
            for (ra, rb) in a.iter().zip(&b) {
                for (x, y) in ra.iter().zip(rb) {
                    assert!((x - y).abs() < 1e-9, "{key}: {x} vs {y}");
                }
            }
        }
    }
    assert_eq!(v["kind"], "arx");
    assert_eq!(v["fit_percent"]["simulation"].as_array().unwrap().len(), 6);
    assert_eq!(v["fit_percent"]["prediction"].as_array().unwrap().len(), 6);
    assert_eq!(v["fit_percent"]["data"], "estimation");
    assert_eq!(v["hankel_singular_values"].as_array().unwrap().len(), 12);
    assert!(
        v["residual_tests"]["autocorrelation"]
            .as_array()
            .unwrap()
            .len()
            == 6
    );
    assert!((v["data"]["sample_time"].as_f64().unwrap() - 0.01).abs() < 1e-12);
    assert_eq!(v["frequency_response"]["frequency_unit"], "rad/s");
    let h = std::fs::read_to_string(&html).unwrap();
    for needle in [
        "<svg",
        "Hankel singular values",
        "Singular values",
        "Residual autocorrelation",
        "FIT",
    ] {
        assert!(h.contains(needle), "report lacks {needle}");
    }
}

#[test]
fn state_space_pem_json() {
    let json = scratch("ss.json");
    let o = twinloop(&[
        "identify",
        "ss",
        "--data",
        path(&data("synthetic_est.csv")),
        "--val",
        path(&data("synthetic_val.csv")),
        "--inputs",
        "u*",
        "--outputs",
        "y*",
        "--order",
        "6",
        "--method",
        "pem",
        "--json",
        path(&json),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("residual tests: pass"), "{out}");
    let v = read_json(&json);
    assert_eq!(v["kind"], "state-space");
    assert_eq!(v["method"], "pem");
    for (k, shape) in [
        ("A", (6, 6)),
        ("B", (6, 10)),
        ("C", (6, 6)),
        ("D", (6, 10)),
        ("K", (6, 6)),
    ] {
        let m = matrix(&v[k]);
        assert_eq!((m.len(), m[0].len()), shape, "{k}");
    }
    assert_eq!(v["fit_percent"]["data"], "validation");
    let hsv = v["hankel_singular_values"].as_array().unwrap();
    assert_eq!(hsv.len(), 6);
    assert!(v["residual_tests"]["pass"].as_bool().unwrap());
    let pem = &v["pem"];
    assert!(pem["final_cost"].as_f64().unwrap() <= pem["initial_cost"].as_f64().unwrap());
    assert_eq!(v["stages"][0]["name"], "n4sid");
    assert!(v["stability"]["stable"].as_bool().unwrap());
    assert!(v["warnings"].as_array().unwrap().is_empty());
}

#[test]
fn state_space_simulation_focus_keeps_k_zero_and_a_inside_the_radius() {
    let json = scratch("ss_oe.json");
    let o = twinloop(&[
        "identify",
        "ss",
        "--data",
        path(&data("synthetic_est.csv")),
        "--inputs",
        "u*",
        "--outputs",
        "y*",
        "--order",
        "6",
        "--focus",
        "simulation",
        "--max-pole-radius",
        "0.99",
        "--json",
        path(&json),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = read_json(&json);
    assert_eq!(v["focus"], "simulation");
    for row in matrix(&v["K"]) {
        assert!(row.iter().all(|&k| k == 0.0), "K must stay zero: {row:?}");
    }
    let pem = &v["pem"];
    assert!(pem["final_cost"].as_f64().unwrap() <= pem["initial_cost"].as_f64().unwrap());
    assert!(v["stability"]["spectral_radius"].as_f64().unwrap() < 0.99);
}

#[test]
fn nan_row_names_file_line_row_and_column() {
    let text = std::fs::read_to_string(data("synthetic_est.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Data row 42 is file line 43; put a comment line before it (line numbers shift).
    let mut cells: Vec<String> = lines[42].split(',').map(String::from).collect();
    cells[12] = "NaN".to_string(); // y2
    lines[42] = cells.join(",");
    lines.insert(5, "# a comment".to_string());
    let bad = scratch("nan.csv");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let o = twinloop(&[
        "identify",
        "arx",
        "--data",
        path(&bad),
        "--inputs",
        "u*",
        "--outputs",
        "y*",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains(&format!("{}:44: data row 42", bad.display())),
        "{e}"
    );
    assert!(e.contains("output \"y2\""), "{e}");
    assert!(!e.contains("panicked"), "{e}");
}

#[test]
fn bad_columns_and_constant_inputs_are_clear_errors() {
    let o = twinloop(&[
        "identify",
        "arx",
        "--data",
        path(&data("synthetic_est.csv")),
        "--inputs",
        "u1,q9",
        "--outputs",
        "y1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("no column named \"q9\""),
        "{}",
        stderr(&o)
    );
    // A constant input column.
    let text = std::fs::read_to_string(data("synthetic_est.csv")).unwrap();
    let mut out = String::new();
    for (i, l) in text.lines().enumerate() {
        let mut c: Vec<&str> = l.split(',').collect();
        if i > 0 {
            c[3] = "0.5"; // u3
        }
        out.push_str(&c.join(","));
        out.push('\n');
    }
    let bad = scratch("const.csv");
    std::fs::write(&bad, out).unwrap();
    let o = twinloop(&[
        "identify",
        "ss",
        "--data",
        path(&bad),
        "--inputs",
        "u*",
        "--outputs",
        "y*",
        "--order",
        "4",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("input \"u3\" is constant"),
        "{}",
        stderr(&o)
    );
    // A record of one sample: refused by the record itself, naming the file.
    let one_row: String = text.lines().take(2).map(|l| format!("{l}\n")).collect();
    let short = scratch("one_row.csv");
    std::fs::write(&short, one_row).unwrap();
    let o = twinloop(&[
        "identify",
        "arx",
        "--data",
        path(&short),
        "--inputs",
        "u*",
        "--outputs",
        "y*",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("one_row.csv: 1 samples"), "{e}");
    assert!(e.contains("at least 2"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    // Fewer samples than parameters.
    let o = twinloop(&[
        "identify",
        "arx",
        "--data",
        path(&data("synthetic_est.csv")),
        "--inputs",
        "u*",
        "--outputs",
        "y*",
        "--na",
        "60",
        "--nb",
        "60",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("parameters per output"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn help_teaches() {
    for cmd in ["arx", "ss"] {
        let o = twinloop(&["identify", cmd, "--help"]);
        assert_eq!(o.status.code(), Some(0));
        let h = String::from_utf8_lossy(&o.stdout);
        for needle in [
            "Example",
            "fit_percent",
            "hankel_singular_values",
            "--inputs",
            "residual_tests",
        ] {
            assert!(h.contains(needle), "identify {cmd} --help lacks {needle}");
        }
    }
}
