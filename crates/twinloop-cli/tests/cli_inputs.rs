//! Bad input through the binary: each case exits 2 (bad input) at once with one
//! line naming the place at fault, and good input that used to be cut or ignored
//! silently now runs as asked (issue 17).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-cli-inputs-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// Run the binary; every case must finish within `limit`: a hang is killed and
/// fails the test instead of blocking it.
fn twinloop(args: &[&str], limit: Duration) -> Output {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            let _ = child.wait();
            panic!("{args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Exit 2, one line on stderr containing every piece of `expected`.
fn assert_bad_input(o: &Output, expected: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expected {
        assert!(err.contains(e), "{e:?} not in {err}");
    }
}

/// A km20 standing for 0.1 s: a recording with q:*, v:*, and NaN centres of
/// pressure of any foot not in contact (columns the dynamics do not use).
fn km20_recording() -> PathBuf {
    // Made once per test process: tests run in parallel and share it.
    static MADE: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    MADE.get_or_init(|| {
        let out = tmp("stand.csv");
        let o = twinloop(
            &[
                "simulate",
                "--robot",
                "builtin:km20",
                "--duration",
                "0.05",
                "--hold",
                "--out",
                p(&out),
            ],
            Duration::from_secs(60),
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    })
    .clone()
}

/// Replace the cell of `column` in data row `row` (0-based) of a CSV.
fn with_cell(src: &Path, column: &str, row: usize, value: &str, dst: &Path) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let c = lines[0].split(',').position(|h| h == column).unwrap();
    let mut cells: Vec<String> = lines[row + 1].split(',').map(String::from).collect();
    cells[c] = value.to_string();
    lines[row + 1] = cells.join(",");
    std::fs::write(dst, lines.join("\n") + "\n").unwrap();
}

#[test]
fn a_non_finite_cell_in_dynamics_input_names_file_line_and_column() {
    let rec = km20_recording();
    // The recording as it is: the unused NaN cells are no error.
    let out = tmp("kin.csv");
    let o = twinloop(
        &[
            "dynamics",
            "kinematics",
            "--robot",
            "builtin:km20",
            "--trajectory",
            p(&rec),
            "--out",
            p(&out),
        ],
        Duration::from_secs(60),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (column, value, name) in [
        ("q:l_knee", "NaN", "nan.csv"),
        ("q:l_knee", "inf", "inf.csv"),
        ("q:l_knee", "-inf", "minf.csv"),
        ("t", "NaN", "nan-t.csv"),
    ] {
        let bad = tmp(name);
        with_cell(&rec, column, 2, value, &bad);
        let o = twinloop(
            &[
                "dynamics",
                "kinematics",
                "--robot",
                "builtin:km20",
                "--trajectory",
                p(&bad),
                "--out",
                p(&tmp("never.csv")),
            ],
            Duration::from_secs(60),
        );
        // Data row 3 is file line 4 (after the header).
        assert_bad_input(
            &o,
            &[
                &format!("{name}:4"),
                column,
                "data row 3",
                "not a finite number",
            ],
        );
    }
}

#[test]
fn a_trajectory_column_naming_no_joint_is_an_error_with_the_nearest_names() {
    let traj = tmp("typo.csv");
    std::fs::write(&traj, "t,q:l_kne\n0,0\n0.1,0.2\n").unwrap();
    let o = twinloop(
        &[
            "simulate",
            "--robot",
            "builtin:km20",
            "--trajectory",
            p(&traj),
            "--out",
            p(&tmp("never.csv")),
        ],
        Duration::from_secs(60),
    );
    assert_bad_input(&o, &["typo.csv", "\"q:l_kne\"", "did you mean q:l_knee"]);
    let nan = tmp("nan-goal.csv");
    std::fs::write(&nan, "t,q:l_knee\n0,0\n0.1,NaN\n").unwrap();
    let o = twinloop(
        &[
            "simulate",
            "--robot",
            "builtin:km20",
            "--trajectory",
            p(&nan),
            "--out",
            p(&tmp("never.csv")),
        ],
        Duration::from_secs(60),
    );
    assert_bad_input(&o, &["nan-goal.csv:3", "q:l_knee", "not a finite number"]);
}

fn last_time(csv: &Path) -> f64 {
    let text = std::fs::read_to_string(csv).unwrap();
    let last = text.lines().last().unwrap();
    last.split(',').next().unwrap().parse().unwrap()
}

#[test]
fn a_trajectory_runs_to_its_end_unless_duration_is_given() {
    // 2.5 s of goals: longer than the 2 s a simulation without a trajectory runs.
    let traj = tmp("long.csv");
    std::fs::write(&traj, "t,q:l_knee,q:r_knee\n0,0,0\n1.2,0.1,0.1\n2.5,0,0\n").unwrap();
    let out = tmp("long-out.csv");
    let o = twinloop(
        &[
            "simulate",
            "--robot",
            "builtin:km20",
            "--trajectory",
            p(&traj),
            "--dt",
            "0.002",
            "--every",
            "50",
            "--out",
            p(&out),
        ],
        Duration::from_secs(120),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!((last_time(&out) - 2.5).abs() < 1e-9, "{}", last_time(&out));
    let o = twinloop(
        &[
            "simulate",
            "--robot",
            "builtin:km20",
            "--trajectory",
            p(&traj),
            "--dt",
            "0.002",
            "--duration",
            "0.5",
            "--out",
            p(&out),
        ],
        Duration::from_secs(120),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!((last_time(&out) - 0.5).abs() < 1e-9, "{}", last_time(&out));
}

#[test]
fn numeric_options_out_of_range_are_usage_errors_not_hangs() {
    let json = tmp("never.json");
    let cases: Vec<Vec<&str>> = vec![
        vec![
            "experiment",
            "tipover",
            "--robot",
            "builtin:km20",
            "--ramp",
            "0",
        ],
        vec![
            "experiment",
            "tipover",
            "--robot",
            "builtin:km20",
            "--ramp=-0.5",
        ],
        vec![
            "experiment",
            "tipover",
            "--robot",
            "builtin:km20",
            "--ramp",
            "NaN",
        ],
        vec![
            "experiment",
            "tipover",
            "--robot",
            "builtin:km20",
            "--slow-ramp",
            "0",
        ],
        vec![
            "experiment",
            "tipover",
            "--robot",
            "builtin:km20",
            "--compliance-slope=-2",
        ],
        vec![
            "simulate",
            "--robot",
            "builtin:km20",
            "--dt",
            "0",
            "--out",
            "x.csv",
        ],
        vec![
            "simulate",
            "--robot",
            "builtin:km20",
            "--duration=-1",
            "--out",
            "x.csv",
        ],
        vec![
            "experiment",
            "lean",
            "--robot",
            "builtin:km20",
            "--dt",
            "inf",
        ],
        vec!["gait", "sequence", "--dt", "0", "--out", "x.csv"],
        vec!["gait", "sequence", "--cycles", "0", "--out", "x.csv"],
        vec!["bench", "sim", "--robot", "builtin:km20", "--rounds", "0"],
    ];
    for args in cases {
        // The option at fault is the last one given.
        let option = args
            .iter()
            .rev()
            .find(|a| a.starts_with("--") && **a != "--out")
            .unwrap()
            .split('=')
            .next()
            .unwrap();
        let mut a = args.clone();
        if a[1] == "tipover" {
            a.extend(["--json", p(&json)]);
        }
        let o = twinloop(&a, Duration::from_secs(10));
        assert_bad_input(&o, &[option, "out of range"]);
    }
    assert!(!json.exists());
}

#[test]
fn model_info_joints_lists_the_order_and_headers_the_csv_files_need() {
    let o = twinloop(
        &["model", "info", "builtin:km20", "--joints", "--json", "-"],
        Duration::from_secs(30),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let joints = info["joint_list"].as_array().unwrap();
    let k = &info["joints_by_kind"];
    let moving = k["revolute"].as_u64().unwrap()
        + k["continuous"].as_u64().unwrap()
        + k["prismatic"].as_u64().unwrap();
    assert_eq!(joints.len() as u64, moving);
    for j in joints {
        let (lo, hi) = (j["lower"].as_f64().unwrap(), j["upper"].as_f64().unwrap());
        assert!(lo < hi, "{j}");
    }
    // The state header is what a simulation writes: t and the q: columns, in order.
    let rec = std::fs::read_to_string(km20_recording()).unwrap();
    let written: Vec<&str> = rec.lines().next().unwrap().split(',').collect();
    let state: Vec<&str> = info["state_header"].as_str().unwrap().split(',').collect();
    assert_eq!(state[..], written[..state.len()]);
    assert!(!written[state.len()].starts_with("q:"));
    // The trajectory header, filled with zeros, is a trajectory simulate accepts.
    let header = info["trajectory_header"].as_str().unwrap();
    let n = header.split(',').count();
    let zeros = vec!["0"; n].join(",");
    let traj = tmp("from-header.csv");
    std::fs::write(&traj, format!("{header}\n{zeros}\n")).unwrap();
    let o = twinloop(
        &[
            "simulate",
            "--robot",
            "builtin:km20",
            "--trajectory",
            p(&traj),
            "--duration",
            "0.01",
            "--out",
            p(&tmp("h.csv")),
        ],
        Duration::from_secs(60),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The text lists every joint by name.
    let o = twinloop(
        &["model", "info", "builtin:km20", "--joints"],
        Duration::from_secs(30),
    );
    let text = String::from_utf8_lossy(&o.stdout);
    for j in joints {
        assert!(text.contains(j["name"].as_str().unwrap()), "{text}");
    }
    assert!(text.contains(header), "{text}");
}
