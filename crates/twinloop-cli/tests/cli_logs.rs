//! Logs in and out through the command line (docs/logs.md): `.mcap` outputs hold the
//! rows a CSV output holds, identification answers the same from an MCAP as from
//! the CSV of the same data, `log info` lists a log, and bad selections are one-line
//! errors.

#[path = "support/served.rs"]
mod served;

#[path = "../../twinloop-logs/tests/support/python.rs"]
mod python;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use twinloop_io::Table;
use twinloop_logs::{ReadOptions, read_log, write_mcap};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("logs-{name}"))
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
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every column of `a` is in `b` with the same values, bit for bit (`t` to the ns).
fn same_rows(a: &Table, b: &Table) {
    assert_eq!(a.rows.len(), b.rows.len());
    for (i, c) in a.columns.iter().enumerate() {
        let j = b.column_index(c).unwrap_or_else(|| panic!("no column {c}"));
        for (ra, rb) in a.rows.iter().zip(&b.rows) {
            if c == "t" {
                assert!((ra[i] - rb[j]).abs() <= 0.5e-9, "t {} vs {}", ra[i], rb[j]);
            } else {
                assert_eq!(
                    ra[i].to_bits(),
                    rb[j].to_bits(),
                    "{c} at t={}: {} vs {}",
                    ra[0],
                    ra[i],
                    rb[j]
                );
            }
        }
    }
}

#[test]
fn simulate_out_mcap_holds_the_csv_rows_bit_for_bit() {
    let (csv, mcap) = (tmp("sim.csv"), tmp("sim.mcap"));
    for out in [&csv, &mcap] {
        ok(&[
            "simulate",
            "--robot",
            "builtin:km20",
            "--duration",
            "0.2",
            "--out",
            s(out),
        ]);
    }
    let a = Table::read(&csv).unwrap();
    let b = read_log(&mcap, &ReadOptions::default()).unwrap();
    assert_eq!(a.columns.len(), b.columns.len());
    same_rows(&a, &b);
    let info = ok(&["log", "info", s(&mcap), "--robot", "builtin:km20"]);
    assert!(
        info.contains("/robot_description  std_msgs/msg/String  1 messages"),
        "{info}"
    );
    assert!(info.contains("joints the robot lacks: none"), "{info}");
}

#[test]
fn identify_static_answers_the_same_from_an_mcap_as_from_its_csv() {
    // The force-plate poses of the identification tests, given a time column (one
    // pose a second) so they can be a log.
    let poses = Table::read(root().join("crates/twinloop-ident/tests/data/h1_poses.csv")).unwrap();
    let mut t = Table::new([vec!["t".to_string()], poses.columns.clone()].concat());
    t.rows = poses
        .rows
        .iter()
        .enumerate()
        .map(|(k, r)| [vec![k as f64], r.clone()].concat())
        .collect();
    let (csv, mcap) = (tmp("poses.csv"), tmp("poses.mcap"));
    t.write(&csv).unwrap();
    write_mcap(&mcap, &t, None, "pelvis").unwrap();
    let robot = root().join("models/unitree_h1/variants/h1_2025-06_a3b70ca.urdf");
    let mut answers = Vec::new();
    for p in [&csv, &mcap] {
        let json = tmp(&format!(
            "{}.json",
            p.extension().unwrap().to_str().unwrap()
        ));
        ok(&[
            "identify",
            "static",
            "--robot",
            s(&robot),
            "--poses",
            s(p),
            "--total-mass",
            "59.338",
            "--json",
            s(&json),
        ]);
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        v.as_object_mut()
            .unwrap()
            .retain(|k, _| k != "poses_file" && !k.contains("seconds"));
        answers.push(v);
    }
    assert_eq!(answers[0], answers[1]);
}

#[test]
fn link_record_out_mcap_holds_what_the_csv_recording_holds() {
    let (mut server, pty) = served::serve(&["--robot", "builtin:km20", "--no-timing"]);
    let (csv, mcap) = (tmp("rec.csv"), tmp("rec.mcap"));
    let mut counts = Vec::new();
    for out in [&csv, &mcap] {
        let o = twinloop(&[
            "link",
            "record",
            "--port",
            &pty,
            "--map",
            "builtin:km20",
            "--duration",
            "0.3",
            "--rate",
            "50",
            "--out",
            s(out),
        ]);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(o.status.success(), "{err}");
        counts.push(
            err.split(" rows")
                .next()
                .unwrap()
                .rsplit(' ')
                .next()
                .unwrap()
                .parse::<usize>()
                .unwrap(),
        );
    }
    server.kill().unwrap();
    server.wait().unwrap();
    let a = Table::read(&csv).unwrap();
    let b = read_log(&mcap, &ReadOptions::default()).unwrap();
    assert_eq!(a.columns, b.columns);
    assert_eq!((a.rows.len(), b.rows.len()), (counts[0], counts[1]));
    // Two recordings of one robot standing still: in every row of both, every joint
    // where the CSV first read it, to a few encoder steps (RX-28: 0.005 rad); a read
    // a loaded machine missed is NaN in either format, as the recording says.
    for (i, c) in a.columns.iter().enumerate() {
        if !c.starts_with("q:") {
            continue;
        }
        let Some(pose) = a.rows.iter().map(|r| r[i]).find(|v| !v.is_nan()) else {
            continue;
        };
        let j = b.column_index(c).unwrap();
        let near = |v: f64| v.is_nan() || (v - pose).abs() < 0.02;
        for (x, y) in a.rows.iter().map(|r| r[i]).zip(b.rows.iter().map(|r| r[j])) {
            assert!(near(x) && near(y), "{c}: {x} {y} vs {pose}");
        }
    }
}

#[test]
fn a_topic_the_log_lacks_is_a_one_line_error_with_exit_2() {
    let mcap = tmp("traj.mcap");
    ok(&[
        "simulate",
        "--robot",
        "builtin:km20",
        "--duration",
        "0.05",
        "--out",
        s(&mcap),
    ]);
    let o = twinloop(&[
        "simulate",
        "--robot",
        "builtin:km20",
        "--trajectory",
        s(&mcap),
        "--topic",
        "/joint_state",
        "--out",
        s(&tmp("x.csv")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        e.starts_with(&format!(
            "error: {}: no message on topic /joint_state; the log holds /robot_description",
            mcap.display()
        )),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1, "{e}");
    // The right topic: the recorded joint positions are the trajectory.
    ok(&[
        "simulate",
        "--robot",
        "builtin:km20",
        "--trajectory",
        s(&mcap),
        "--topic",
        "/joint_states",
        "--out",
        s(&tmp("y.csv")),
    ]);
}

#[test]
fn a_logged_joint_the_robot_lacks_is_listed_and_refused() {
    // The reference log's joints: l_hip_pitch, l_knee (km20 has both) and
    // r_ankle_roll (km20's is r_ank_roll).
    let log = root().join("crates/twinloop-logs/tests/data/joints_zstd.mcap");
    let o = twinloop(&["log", "info", s(&log), "--robot", "builtin:km20"]);
    assert_eq!(o.status.code(), Some(1));
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        out.contains("joints the robot lacks: r_ankle_roll\n"),
        "{out}"
    );
    // A log of our own within km20's limits, with the same misnamed joint.
    let mut t = Table::new(vec!["t".into(), "q:l_knee".into(), "q:r_ankle_roll".into()]);
    t.rows = (0..5).map(|k| vec![k as f64 * 1e-3, 0.1, 0.0]).collect();
    let mine = tmp("misnamed.mcap");
    write_mcap(&mine, &t, None, "base").unwrap();
    let o = twinloop(&[
        "simulate",
        "--robot",
        "builtin:km20",
        "--trajectory",
        s(&mine),
        "--out",
        s(&tmp("k.csv")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        e.contains("misnamed.mcap") && e.contains("q:r_ankle_roll") && e.contains("q:r_ank_roll"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1, "{e}");
}

/// The SHA-256 of a file as Python's hashlib computes it.
fn python_sha256(py: &str, path: &Path) -> String {
    let o = Command::new(py)
        .args([
            "-c",
            "import hashlib,sys; print(hashlib.sha256(open(sys.argv[1],'rb').read()).hexdigest())",
        ])
        .arg(path)
        .output()
        .unwrap();
    String::from_utf8(o.stdout).unwrap().trim().to_string()
}

/// f64 bits as the readback script prints them.
fn hex_bits(x: f64) -> String {
    format!("{:016x}", x.to_bits())
}

fn from_hex(v: &serde_json::Value) -> f64 {
    f64::from_bits(u64::from_str_radix(v.as_str().unwrap(), 16).unwrap())
}

#[test]
fn identify_static_mcap_holds_the_measurement_both_models_predictions_and_the_adapted_urdf() {
    let test =
        "identify_static_mcap_holds_the_measurement_both_models_predictions_and_the_adapted_urdf";
    let Some(py) = python::python_with("mcap, mcap_ros2", test) else {
        return;
    };
    let poses = root().join("crates/twinloop-ident/tests/data/h1_poses.csv");
    let robot = root().join("models/unitree_h1/variants/h1_2025-06_a3b70ca.urdf");
    let (mcap, urdf, json) = (tmp("static.mcap"), tmp("static.urdf"), tmp("static.json"));
    let args = [
        "identify",
        "static",
        "--robot",
        s(&robot),
        "--poses",
        s(&poses),
        "--total-mass",
        "59.338",
        "--out",
        s(&urdf),
        "--json",
        s(&json),
        "--mcap",
        s(&mcap),
    ];
    ok(&args);
    let out = Command::new(&py)
        .arg(root().join("tools/oracle/logs_readback.py"))
        .arg(&mcap)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let table = Table::read(&poses).unwrap();
    let n = table.rows.len();
    let topics = &v["topics"];
    for topic in ["/joint_states", "/tf", "/measured", "/prior", "/adapted"] {
        assert_eq!(topics[topic]["count"], n, "{topic}");
    }
    assert_eq!(topics["/robot_description"]["count"], 1);
    // The measured CoP as the poses file gives it, to the bit; each model's CoM over
    // the ground as far from it as the identification's own distances say.
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let (cx, cy) = (
        table.column_index("cop.x").unwrap(),
        table.column_index("cop.y").unwrap(),
    );
    for (k, row) in table.rows.iter().enumerate() {
        let m = &topics["/measured"]["rows"][k];
        assert_eq!(
            m,
            &serde_json::json!(["cop.x,cop.y", hex_bits(row[cx]), hex_bits(row[cy])])
        );
        for (topic, key) in [
            ("/prior", "gcom_distance_before"),
            ("/adapted", "gcom_distance_after"),
        ] {
            let p = &topics[topic]["rows"][k];
            let d = (from_hex(&p[1]) - row[cx]).hypot(from_hex(&p[2]) - row[cy]);
            let want = result["result"][key][k].as_f64().unwrap();
            assert!((d - want).abs() < 1e-12, "{topic} pose {k}: {d} vs {want}");
        }
    }
    assert_eq!(topics["/prior"]["rows"][0][0], "prior.cop.x,prior.cop.y");
    // The adapted URDF attached is the one --out wrote; the provenance.
    let written = std::fs::read_to_string(&urdf).unwrap();
    assert_eq!(
        v["attachments"],
        serde_json::json!([{"name": "adapted.urdf", "media_type": "application/xml", "text": written}])
    );
    let meta = &v["metadata"];
    assert_eq!(meta["twinloop"]["command"], "identify static");
    assert_eq!(
        meta["twinloop"]["twinloop_version"],
        env!("CARGO_PKG_VERSION")
    );
    let line: Vec<String> =
        serde_json::from_str(meta["twinloop"]["command_line"].as_str().unwrap()).unwrap();
    assert_eq!(line[1..], args.map(str::to_string));
    for input in [&robot, &poses] {
        assert_eq!(
            meta["twinloop.inputs"][s(input)],
            python_sha256(&py, input),
            "{}",
            input.display()
        );
    }
}
