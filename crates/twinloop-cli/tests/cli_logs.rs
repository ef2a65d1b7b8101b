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

/// Every column of `a` is in `b` with the same values, bit for bit (`t` to the ns;
/// a read the recording missed is NaN in both).
fn same_rows(a: &Table, b: &Table) {
    assert_eq!(a.rows.len(), b.rows.len());
    for (i, c) in a.columns.iter().enumerate() {
        let j = b.column_index(c).unwrap_or_else(|| panic!("no column {c}"));
        for (ra, rb) in a.rows.iter().zip(&b.rows) {
            if c == "t" {
                assert!((ra[i] - rb[j]).abs() <= 0.5e-9, "t {} vs {}", ra[i], rb[j]);
            } else if !(ra[i].is_nan() && rb[j].is_nan()) {
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
fn link_record_on_the_served_km20_as_mcap_and_csv_holds_the_same_rows() {
    let (mut server, pty) = served::serve(&["--robot", "builtin:km20", "--no-timing"]);
    let (csv, mcap) = (tmp("rec.csv"), tmp("rec.mcap"));
    // One recording written to both: every row read goes to each file.
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
        s(&csv),
        "--out",
        s(&mcap),
    ]);
    server.kill().unwrap();
    server.wait().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    let rows: usize = err.split(" rows").next().unwrap().parse().unwrap();
    assert!(rows >= 3, "{err}");
    let a = Table::read(&csv).unwrap();
    let b = read_log(&mcap, &ReadOptions::default()).unwrap();
    assert_eq!(a.columns, b.columns);
    assert_eq!((a.rows.len(), b.rows.len()), (rows, rows));
    same_rows(&a, &b);
    // The mapping's robot rides along for the viewers.
    let info = ok(&["log", "info", s(&mcap), "--robot", "builtin:km20"]);
    assert!(
        info.contains("/robot_description  std_msgs/msg/String  1 messages"),
        "{info}"
    );
    // The same path twice is refused before the bus is touched.
    let o = twinloop(&[
        "link",
        "record",
        "--port",
        "/nonexistent",
        "--map",
        "builtin:km20",
        "--duration",
        "0.1",
        "--out",
        s(&csv),
        "--out",
        s(&csv),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(e.contains("given twice"), "{e}");
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
    let v = python::mcap_readback(&py, &mcap);
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

/// The MCAP of a CSV table (`t` to the ns, every other value bit for bit): the same
/// data as a log, as a team's recorder would hand it over.
fn as_mcap(csv: &Path) -> PathBuf {
    let table = Table::read(csv).unwrap();
    let mcap = csv.with_extension("mcap");
    write_mcap(&mcap, &table, None, "pelvis").unwrap();
    mcap
}

/// `args` (with `{in}`/`{in2}` for the inputs and `{json}` for the answer) run on
/// the CSVs and on their MCAPs: the JSON answers are the same, but for the inputs'
/// names and the run times.
fn same_answer(args: &[&str], inputs: &[PathBuf]) {
    let logs: Vec<PathBuf> = inputs.iter().map(|p| as_mcap(p)).collect();
    let mut answers = Vec::new();
    for (k, files) in [inputs, &logs[..]].into_iter().enumerate() {
        let json = tmp(&format!("answer-{}-{k}.json", args[1]));
        let args: Vec<String> = args
            .iter()
            .map(|a| match *a {
                "{in}" => s(&files[0]).to_string(),
                "{in2}" => s(&files[1]).to_string(),
                "{json}" => s(&json).to_string(),
                a => a.to_string(),
            })
            .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        ok(&args);
        let mut text = std::fs::read_to_string(&json).unwrap();
        for f in files {
            text = text.replace(s(f), "INPUT");
        }
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        strip_times(&mut v);
        answers.push(v);
    }
    assert_eq!(answers[0], answers[1], "{args:?}");
}

/// Drop the run times (`*seconds*` keys) anywhere in a JSON answer.
fn strip_times(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|k, _| !k.contains("seconds"));
            m.values_mut().for_each(strip_times);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_times),
        _ => {}
    }
}

#[test]
fn identify_arx_and_ss_answer_the_same_from_an_mcap_as_from_its_csv() {
    // The synthetic records of tools/oracle/sysid_reference.py, `t` at 10 ms.
    let csv = tmp("sysid_est.csv");
    std::fs::copy(
        root().join("crates/twinloop-sysid/tests/data/synthetic_est.csv"),
        &csv,
    )
    .unwrap();
    let csv = vec![csv];
    let common = ["--data", "{in}", "--inputs", "u*", "--outputs", "y1,y2,y3"];
    same_answer(
        &[
            &["identify", "arx"][..],
            &common,
            &["--na", "2", "--nb", "2", "--nk", "1", "--json", "{json}"],
        ]
        .concat(),
        &csv,
    );
    same_answer(
        &[
            &["identify", "ss"][..],
            &common,
            &["--order", "4", "--method", "n4sid", "--json", "{json}"],
        ]
        .concat(),
        &csv,
    );
}

/// Two simulated leans of km20: the robot's run (`robot` added: 200 g on the torso
/// for a robot unlike its model) and the simulation's (`NAME-a.csv`, `NAME-b.csv`:
/// a file per test, the tests run at once).
fn two_leans(name: &str, robot: &[&str]) -> [PathBuf; 2] {
    let runs = [tmp(&format!("{name}-a.csv")), tmp(&format!("{name}-b.csv"))];
    for (run, extra) in runs.iter().zip([robot, &[]]) {
        let mut args = vec![
            "experiment",
            "lean",
            "--robot",
            "builtin:km20",
            "--amplitude",
            "3",
            "--ramp",
            "2",
            "--hold",
            "0.5",
            "--settle",
            "0.5",
            "--out",
            s(run),
        ];
        args.extend_from_slice(extra);
        ok(&args);
    }
    runs
}

#[test]
fn validate_lean_answers_the_same_from_mcaps_as_from_their_csvs() {
    let runs = two_leans("lean", &[]);
    same_answer(
        &[
            "validate",
            "lean",
            "--robot-run",
            "{in}",
            "--sim-run",
            "{in2}",
            "--json",
            "{json}",
        ],
        &runs,
    );
}

#[test]
fn validate_residual_answers_the_same_from_mcaps_as_from_their_csvs() {
    // h1's squat on the force plate: its configuration is the motion, its plate
    // columns the wrench.
    let squat = tmp("squat.csv");
    let h1 = root().join("models/unitree_h1/h1.urdf");
    let prior = root().join("models/unitree_h1/variants/h1_2025-06_a3b70ca.urdf");
    ok(&[
        "experiment",
        "squat",
        "--robot",
        s(&h1),
        "--out",
        s(&squat),
        "--duration",
        "1",
        "--rest",
        "0.2",
        "--rate",
        "100",
    ]);
    same_answer(
        &[
            "validate",
            "residual",
            "--robot",
            s(&prior),
            "--compare",
            s(&h1),
            "--motion",
            "{in}",
            "--plate",
            "{in}",
            "--out",
            s(&tmp("res.csv")),
            "--json",
            "{json}",
        ],
        &[squat],
    );
}

/// An RX-28 with parameters `truth` on a pendulum through the standard excitation,
/// sampled every 2 ms +- 0.4 ms, times on whole ns (what an MCAP stamp holds),
/// written as `experiment servo --out` writes it, as `NAME.csv` (its comment lines)
/// and `NAME.mcap` (the format `twinloop` registers; the lines its note). Returns
/// the two logs, the load file and the log.
fn servo_logs(
    truth: &twinloop_actuator::ServoParams,
    name: &str,
) -> (PathBuf, PathBuf, PathBuf, twinloop_actuator::log::ServoLog) {
    use twinloop_actuator::log::LogWriter;
    use twinloop_actuator::synthetic::synthetic_log;
    use twinloop_actuator::{Excitation, Load, Pendulum, ServoType};
    let pendulum = Pendulum {
        mass: 0.5,
        length: 0.15,
        arm_inertia: 0.002,
    };
    let load = tmp("servo-load.toml");
    std::fs::write(&load, "mass = 0.5\nlength = 0.15\narm_inertia = 0.002\n").unwrap();
    let mut log = synthetic_log(
        truth,
        &Load::from(pendulum),
        &Excitation::standard(ServoType::Rx28, 0.5),
        2e-3,
        4e-4,
        7,
    );
    let ns = |t: f64| (t * 1e9).round() / 1e9;
    log.t.iter_mut().for_each(|t| *t = ns(*t));
    log.t_goal.iter_mut().for_each(|t| *t = ns(*t));
    twinloop_io::sink::register_recording_format("mcap", twinloop_logs::open_mcap_recording);
    let (csv, mcap) = (tmp(&format!("{name}.csv")), tmp(&format!("{name}.mcap")));
    for path in [&csv, &mcap] {
        let mut w = LogWriter::create(path, ServoType::Rx28, "id 3 on test").unwrap();
        for r in 0..log.len() {
            let values = [
                log.t[r],
                log.goal[r],
                log.t_goal[r],
                log.q[r],
                log.v[r],
                f64::NAN,
                f64::NAN,
                log.voltage[r],
                40.0,
            ];
            w.write(&values, &log.firmware[r]).unwrap();
        }
        w.finish().unwrap();
    }
    (csv, mcap, load, log)
}

#[test]
fn identify_servo_answers_the_same_from_an_mcap_log_as_from_its_csv() {
    use twinloop_actuator::{ModelLevel, ServoType, datasheet};
    let truth = datasheet::defaults(ServoType::Rx28, ModelLevel::M1);
    let (csv, mcap, load, _) = servo_logs(&truth, "servo");
    let mut answers = Vec::new();
    for path in [&csv, &mcap] {
        let out = ok(&[
            "identify",
            "servo",
            "--data",
            s(path),
            "--load",
            s(&load),
            "--json",
            "-",
        ]);
        let mut v: serde_json::Value = serde_json::from_str(&out).unwrap();
        strip_times(&mut v);
        let text = v.to_string().replace(s(path), "LOG");
        answers.push(text);
    }
    assert_eq!(answers[0], answers[1]);
    // The servo and its id came from the MCAP's note.
    assert!(answers[1].contains("RX-28"), "{}", answers[1]);
}

/// RMS of `a - b`.
fn rms(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / n).sqrt()
}

#[test]
fn identify_servo_mcap_holds_the_log_the_start_s_and_the_fit_s_replays_and_the_fitted_file() {
    use twinloop_actuator::params::{FRICTION_BASE, RESISTANCE};
    use twinloop_actuator::{ModelLevel, ServoType, datasheet};
    let test =
        "identify_servo_mcap_holds_the_log_the_start_s_and_the_fit_s_replays_and_the_fitted_file";
    let Some(py) = python::python_with("mcap, mcap_ros2", test) else {
        return;
    };
    // A servo unlike its datasheet (the fit's start): more friction, a hotter coil.
    let mut truth = datasheet::defaults(ServoType::Rx28, ModelLevel::M1);
    truth.values[FRICTION_BASE] *= 1.6;
    truth.values[RESISTANCE] *= 1.3;
    let (csv, _, load, log) = servo_logs(&truth, "servo-fit");
    let (mcap, toml) = (tmp("servo-result.mcap"), tmp("servo-fitted.toml"));
    let args = [
        "identify",
        "servo",
        "--data",
        s(&csv),
        "--load",
        s(&load),
        "--out",
        s(&toml),
        "--mcap",
        s(&mcap),
    ];
    ok(&args);
    let v = python::mcap_readback(&py, &mcap);
    let topics = &v["topics"];
    let n = log.len();
    for topic in ["/measured", "/prior", "/adapted"] {
        assert_eq!(topics[topic]["count"], n, "{topic}");
    }
    // The measured signals are the log's, to the bit.
    for i in 0..n {
        assert_eq!(
            topics["/measured"]["rows"][i],
            serde_json::json!([
                "goal,q,v",
                hex_bits(log.goal[i]),
                hex_bits(log.q[i]),
                hex_bits(log.v[i])
            ]),
            "row {i}"
        );
    }
    // The fitted parameters' replay is nearer the log than the datasheet's.
    let column = |topic: &str| -> Vec<f64> {
        (0..n)
            .map(|i| from_hex(&topics[topic]["rows"][i][1]))
            .collect()
    };
    let (prior, fitted) = (
        rms(&column("/prior"), &log.q),
        rms(&column("/adapted"), &log.q),
    );
    assert!(
        fitted < 0.5 * prior,
        "fitted {fitted} rad RMS, start {prior}"
    );
    assert_eq!(topics["/adapted"]["rows"][0][0], "adapted.q");
    // The fitted file attached is the one --out wrote; the provenance.
    let written = std::fs::read_to_string(&toml).unwrap();
    assert_eq!(
        v["attachments"],
        serde_json::json!([{"name": "fitted.toml", "media_type": "application/toml", "text": written}])
    );
    let meta = &v["metadata"];
    assert_eq!(meta["twinloop"]["command"], "identify servo");
    let line: Vec<String> =
        serde_json::from_str(meta["twinloop"]["command_line"].as_str().unwrap()).unwrap();
    assert_eq!(line[1..], args.map(str::to_string));
    for input in [&csv, &load] {
        assert_eq!(meta["twinloop.inputs"][s(input)], python_sha256(&py, input));
    }
    // twinloop's own reader gives the same table: the log's times and values.
    let topics: Vec<twinloop_logs::TopicSpec> = ["/measured", "/prior", "/adapted"]
        .iter()
        .map(|t| t.parse().unwrap())
        .collect();
    let table = read_log(&mcap, &ReadOptions { topics, dt: None }).unwrap();
    assert_eq!(table.rows.len(), n);
    let (q, q1) = (
        table.column_index("q").unwrap(),
        table.column_index("adapted.q").unwrap(),
    );
    for (i, row) in table.rows.iter().enumerate() {
        assert!(
            (row[0] - log.t[i]).abs() <= 0.5e-9,
            "t {} vs {}",
            row[0],
            log.t[i]
        );
        assert_eq!(row[q].to_bits(), log.q[i].to_bits(), "q row {i}");
    }
    let adapted: Vec<f64> = table.rows.iter().map(|r| r[q1]).collect();
    assert_eq!(rms(&adapted, &log.q), fitted);
}

/// The readback script's Float64MultiArray rows of `topic`: value `j` of each row.
fn array_column(v: &serde_json::Value, topic: &str, j: usize) -> Vec<f64> {
    v["topics"][topic]["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| from_hex(&r[1 + j]))
        .collect()
}

#[test]
fn validate_residual_mcap_holds_the_plate_and_each_model_s_prediction_of_it() {
    let test = "validate_residual_mcap_holds_the_plate_and_each_model_s_prediction_of_it";
    let Some(py) = python::python_with("mcap, mcap_ros2", test) else {
        return;
    };
    // h1's squat on the force plate, generated by h1 itself; the prior variant is
    // the model under test, h1 the one compared with.
    let squat = tmp("squat-mcap.csv");
    let h1 = root().join("models/unitree_h1/h1.urdf");
    let prior = root().join("models/unitree_h1/variants/h1_2025-06_a3b70ca.urdf");
    ok(&[
        "experiment",
        "squat",
        "--robot",
        s(&h1),
        "--out",
        s(&squat),
        "--duration",
        "1",
        "--rest",
        "0.2",
        "--rate",
        "100",
    ]);
    let (mcap, res) = (tmp("residual.mcap"), tmp("res-mcap.csv"));
    let args = [
        "validate",
        "residual",
        "--robot",
        s(&prior),
        "--compare",
        s(&h1),
        "--motion",
        s(&squat),
        "--out",
        s(&res),
        "--mcap",
        s(&mcap),
    ];
    ok(&args);
    let v = python::mcap_readback(&py, &mcap);
    let table = Table::read(&squat).unwrap();
    let n = table.rows.len();
    for topic in ["/joint_states", "/measured", "/model", "/compare"] {
        assert_eq!(v["topics"][topic]["count"], n, "{topic}");
    }
    assert_eq!(v["topics"]["/robot_description"]["count"], 1);
    let plate = ["grf.fx", "grf.fy", "grf.fz", "cop.x", "cop.y", "grf.tz"];
    assert_eq!(v["topics"]["/measured"]["rows"][0][0], plate.join(","));
    // The plate's readings are the squat file's, to the bit; the model the squat was
    // made with predicts the vertical force nearer them than the prior does.
    let mut errors = Vec::new();
    for (j, c) in plate.iter().enumerate() {
        let i = table.column_index(c).unwrap();
        let file: Vec<f64> = table.rows.iter().map(|r| r[i]).collect();
        let measured = array_column(&v, "/measured", j);
        for k in 0..n {
            assert_eq!(measured[k].to_bits(), file[k].to_bits(), "{c} row {k}");
        }
        errors.push([
            rms(&array_column(&v, "/model", j), &file),
            rms(&array_column(&v, "/compare", j), &file),
        ]);
    }
    let [prior_fz, h1_fz] = errors[2];
    assert!(
        h1_fz < 0.1 * prior_fz,
        "grf.fz: h1 {h1_fz} N, prior {prior_fz} N"
    );
    let meta = &v["metadata"];
    assert_eq!(meta["twinloop"]["command"], "validate residual");
    for input in [&prior, &h1, &squat] {
        assert_eq!(meta["twinloop.inputs"][s(input)], python_sha256(&py, input));
    }
    assert_eq!(v["attachments"][0]["name"], "model.urdf");
    // twinloop's own reader: the same plate readings at the file's times.
    let topics = ["/measured", "/model"].map(|t| t.parse().unwrap()).to_vec();
    let back = read_log(&mcap, &ReadOptions { topics, dt: None }).unwrap();
    assert_eq!(back.rows.len(), n);
    let (fz, fz_model) = (
        back.column_index("grf.fz").unwrap(),
        back.column_index("model.grf.fz").unwrap(),
    );
    let i = table.column_index("grf.fz").unwrap();
    for (a, b) in table.rows.iter().zip(&back.rows) {
        assert!((a[0] - b[0]).abs() <= 0.5e-9, "t {} vs {}", a[0], b[0]);
        assert_eq!(a[i].to_bits(), b[fz].to_bits());
    }
    let model: Vec<f64> = back.rows.iter().map(|r| r[fz_model]).collect();
    let file: Vec<f64> = table.rows.iter().map(|r| r[i]).collect();
    assert_eq!(rms(&model, &file), prior_fz);
    eprintln!("grf.fz RMS from the plate: prior {prior_fz} N, h1 {h1_fz} N; all {errors:?}");
}

#[test]
fn validate_lean_mcap_holds_the_robot_s_torques_and_the_simulation_s_at_its_samples() {
    let test = "validate_lean_mcap_holds_the_robot_s_torques_and_the_simulation_s_at_its_samples";
    let Some(py) = python::python_with("mcap, mcap_ros2", test) else {
        return;
    };
    let [robot, sim] = two_leans("lean-mcap", &["--add-mass", "0.2@torso:0,0,0.03"]);
    let (mcap, json) = (tmp("lean-result.mcap"), tmp("lean-result.json"));
    let args = [
        "validate",
        "lean",
        "--robot-run",
        s(&robot),
        "--sim-run",
        s(&sim),
        "--json",
        s(&json),
        "--mcap",
        s(&mcap),
    ];
    ok(&args);
    let v = python::mcap_readback(&py, &mcap);
    let c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let table = Table::read(&robot).unwrap();
    let n = v["topics"]["/measured"]["count"].as_u64().unwrap() as usize;
    assert_eq!(n, c["samples"].as_u64().unwrap() as usize);
    assert_eq!(v["topics"]["/model"]["count"], n);
    let label = v["topics"]["/measured"]["rows"][0][0]
        .as_str()
        .unwrap()
        .to_string();
    let names: Vec<&str> = label.split(',').collect();
    // The robot's torques are its run's, to the bit, from its first row the
    // shifted simulation covers; the simulation's differ from them by the
    // comparison's own RMS.
    let t_start = c["t_start"].as_f64().unwrap();
    let first = table.rows.iter().position(|r| r[0] >= t_start).unwrap();
    let rows = &table.rows[first..first + n];
    for joint in c["joints"].as_array().unwrap() {
        let name = joint["joint"].as_str().unwrap();
        let j = names
            .iter()
            .position(|c| *c == format!("tau.{name}"))
            .unwrap();
        let i = table.column_index(&format!("tau:{name}")).unwrap();
        let file: Vec<f64> = rows.iter().map(|r| r[i]).collect();
        let measured = array_column(&v, "/measured", j);
        for k in 0..n {
            assert_eq!(measured[k].to_bits(), file[k].to_bits(), "{name} row {k}");
        }
        let d = rms(&array_column(&v, "/model", j), &file);
        let want = joint["torque_rms"].as_f64().unwrap();
        assert!(
            (d - want).abs() <= 1e-12 * want.max(1.0),
            "{name}: {d} vs {want}"
        );
    }
    let meta = &v["metadata"];
    assert_eq!(meta["twinloop"]["command"], "validate lean");
    for input in [&robot, &sim] {
        assert_eq!(meta["twinloop.inputs"][s(input)], python_sha256(&py, input));
    }
    // twinloop's own reader: the same torques at the run's times.
    let topics = ["/measured", "/model"].map(|t| t.parse().unwrap()).to_vec();
    let back = read_log(&mcap, &ReadOptions { topics, dt: None }).unwrap();
    assert_eq!(back.rows.len(), n);
    let name = c["joints"][0]["joint"].as_str().unwrap();
    let (i, j) = (
        table.column_index(&format!("tau:{name}")).unwrap(),
        back.column_index(&format!("tau.{name}")).unwrap(),
    );
    for (a, b) in rows.iter().zip(&back.rows) {
        assert!((a[0] - b[0]).abs() <= 0.5e-9, "t {} vs {}", a[0], b[0]);
        assert_eq!(a[i].to_bits(), b[j].to_bits());
    }
}

/// `csv` written by the reference Python libraries as a team's recorder would
/// (tools/oracle/logs_reference.py --from-csv): an MCAP (`mcap-ros2-support`) and a
/// rosbag2 folder with MCAP storage (`rosbags`), beside it. None (skipped) without
/// them, a failure under TWINLOOP_REQUIRE_ORACLES=1.
fn reference_logs(csv: &Path, test: &str) -> Option<[PathBuf; 2]> {
    let py = python::python_with("mcap_ros2, rosbags", test)?;
    let stem = csv.file_stem().unwrap().to_str().unwrap();
    let mcap = csv.with_file_name(format!("{stem}-ref.mcap"));
    let bag = csv.with_file_name(format!("{stem}-bag"));
    let out = Command::new(&py)
        .arg(root().join("tools/oracle/logs_reference.py"))
        .args(["--from-csv", s(csv), s(&mcap), s(&bag)])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some([mcap, bag])
}

/// Two JSON answers agree: the same keys and strings, numbers within `tol`
/// (relative to their size, at least absolute).
fn close_json(a: &serde_json::Value, b: &serde_json::Value, tol: f64, at: &str) {
    use serde_json::Value;
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys = |m: &serde_json::Map<String, Value>| m.keys().cloned().collect::<Vec<_>>();
            assert_eq!(keys(x), keys(y), "{at}");
            for (k, v) in x {
                close_json(v, &y[k], tol, &format!("{at}.{k}"));
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}");
            for (k, (u, v)) in x.iter().zip(y).enumerate() {
                close_json(u, v, tol, &format!("{at}[{k}]"));
            }
        }
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= tol * x.abs().max(1.0), "{at}: {x} vs {y}");
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

/// `args` (`{in}` the input, `{json}` the answer) run on each of `inputs`: the
/// answers of the later ones agree with the first's to `tol` (the inputs' names
/// and run times aside). Returns the first answer.
fn same_answers(args: &[&str], inputs: &[PathBuf], tol: f64) -> serde_json::Value {
    let mut answers: Vec<serde_json::Value> = Vec::new();
    for (k, input) in inputs.iter().enumerate() {
        let json = tmp(&format!("answers-{}-{}-{k}.json", args[0], args[1]));
        let args: Vec<String> = args
            .iter()
            .map(|a| a.replace("{in}", s(input)).replace("{json}", s(&json)))
            .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        ok(&args);
        let text = std::fs::read_to_string(&json)
            .unwrap()
            .replace(s(input), "INPUT");
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        strip_times(&mut v);
        if let Some(first) = answers.first() {
            close_json(first, &v, tol, &format!("{args:?}"));
        }
        answers.push(v);
    }
    answers.remove(0)
}

/// `adapt --lean` takes the robot's lean as a CSV, as its MCAP (twinloop's writer)
/// and as a rosbag2 folder and an MCAP the reference Python libraries wrote: the
/// same answer to 1e-12. Its `--mcap` holds the lean after the fall angles: the
/// robot's torques to the bit on `/lean/measured`, each model's replay on
/// `/lean/prior` and `/lean/adapted`, whose RMS from them is the check's own.
#[test]
fn adapt_lean_answers_the_same_from_logs_and_its_mcap_holds_the_lean_torques() {
    let test = "adapt_lean_answers_the_same_from_logs_and_its_mcap_holds_the_lean_torques";
    let mass = "0.3@torso:0.04,0.02,0.05";
    let tip = tmp("adapt-lean-tip.json");
    ok(&[
        "experiment",
        "tipover",
        "--robot",
        "builtin:km20",
        "--add-mass",
        mass,
        "--json",
        s(&tip),
    ]);
    let run = tmp("adapt-lean-run.csv");
    ok(&[
        "experiment",
        "lean",
        "--robot",
        "builtin:km20",
        "--add-mass",
        mass,
        "--amplitude",
        "2",
        "--ramp",
        "2",
        "--hold",
        "0.5",
        "--settle",
        "0.5",
        "--out",
        s(&run),
    ]);
    // A log's own clock starts at its first message (docs/logs.md, Time); the
    // lean's first row is at 5 ms, so the CSV is put on that clock too: the same data.
    let mut table = Table::read(&run).unwrap();
    let lean = tmp("adapt-lean-robot.csv");
    let t0 = table.rows[0][0];
    let mut w = twinloop_io::CsvWriter::create(&lean, &table.columns).unwrap();
    for r in &mut table.rows {
        r[0] = ((r[0] - t0) * 1e9).round() / 1e9;
        w.write_row(r).unwrap();
    }
    w.finish().unwrap();
    let mut inputs = vec![lean.clone(), as_mcap(&lean)];
    inputs.extend(reference_logs(&lean, test).into_iter().flatten());
    let total = format!("{}", 3.336 + 0.3);
    let base = [
        "adapt",
        "--robot",
        "builtin:km20",
        "--tipover",
        s(&tip),
        "--total-mass",
        &total,
        "--lean",
        "{in}",
        "--json",
        "{json}",
    ];
    let answer = same_answers(&base, &inputs, 1e-12);
    // --mcap, from the rosbag2 folder when there is one.
    let mcap = tmp("adapt-lean-result.mcap");
    let args: Vec<&str> = base
        .iter()
        .map(|a| {
            if *a == "{in}" {
                s(inputs.last().unwrap())
            } else {
                a
            }
        })
        .filter(|a| !matches!(*a, "--json" | "{json}"))
        .chain(["--mcap", s(&mcap)])
        .collect();
    ok(&args);
    let topics = ["/lean/measured", "/lean/prior", "/lean/adapted"]
        .map(|t| t.parse().unwrap())
        .to_vec();
    let back = read_log(&mcap, &ReadOptions { topics, dt: None }).unwrap();
    let table = Table::read(&lean).unwrap();
    // The lean's clock starts a second after the fourth fall angle (t = 3 s): its
    // first row the replays cover is `first`.
    let first = table
        .rows
        .iter()
        .position(|r| (r[0] - table.rows[0][0] + 4.0 - back.rows[0][0]).abs() < 1e-9)
        .unwrap();
    let lean_checks = answer["lean"].as_array().unwrap();
    assert!(!lean_checks.is_empty());
    for l in lean_checks {
        let name = l["joint"].as_str().unwrap();
        let i = table.column_index(&format!("tau:{name}")).unwrap();
        let col = |c: String| back.column_index(&c).unwrap_or_else(|| panic!("no {c}"));
        let m = col(format!("tau.{name}"));
        let file: Vec<f64> = table.rows[first..first + back.rows.len()]
            .iter()
            .map(|r| r[i])
            .collect();
        let measured: Vec<f64> = back.rows.iter().map(|r| r[m]).collect();
        assert!(
            measured
                .iter()
                .zip(&file)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "{name}"
        );
        for (model, key) in [("prior", "before_rms"), ("adapted", "after_rms")] {
            let p = col(format!("{model}.tau.{name}"));
            let replay: Vec<f64> = back.rows.iter().map(|r| r[p]).collect();
            let (d, want) = (rms(&replay, &file), l[key].as_f64().unwrap());
            assert!(
                (d - want).abs() <= 1e-12 * want.max(1.0),
                "{name} {model}: {d} vs {want}"
            );
        }
    }
}

/// Two RX-28s, one at its datasheet's values and one with 1.6 times its friction, a
/// log each, given as CSVs and as MCAPs (`experiment servo --out X.mcap`'s writer)
/// with their ids (`--data 1=LOG`): `identify servo` fits them as a group with the
/// same answer from both. Its `--mcap` holds each servo on topics of its own: the
/// log to the bit on `/id1/measured`, and the group fit's replay closer to it than
/// the datasheet's for the servo that is not the datasheet's.
#[test]
fn identify_servo_of_several_servos_answers_the_same_from_mcaps_and_its_mcap_holds_each() {
    use twinloop_actuator::params::FRICTION_BASE;
    use twinloop_actuator::{ModelLevel, ServoType, datasheet};
    let sheet = datasheet::defaults(ServoType::Rx28, ModelLevel::M1);
    let mut rough = sheet.clone();
    rough.values[FRICTION_BASE] *= 1.6;
    let (csv1, mcap1, load, log1) = servo_logs(&sheet, "group-1");
    let (csv2, mcap2, _, log2) = servo_logs(&rough, "group-2");
    let mut answers = Vec::new();
    for (k, [a, b]) in [[&csv1, &csv2], [&mcap1, &mcap2]].into_iter().enumerate() {
        let result = tmp(&format!("group-result-{k}.mcap"));
        let (d1, d2) = (format!("1={}", s(a)), format!("2={}", s(b)));
        let out = ok(&[
            "identify",
            "servo",
            "--data",
            &d1,
            "--data",
            &d2,
            "--load",
            s(&load),
            "--shared",
            "none",
            "--mcap",
            s(&result),
            "--json",
            "-",
        ]);
        let text = out
            .replace(s(a), "LOG1")
            .replace(s(b), "LOG2")
            .replace(s(&result), "RESULT");
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        strip_times(&mut v);
        answers.push(v);
        let mut tables = Vec::new();
        for id in ["id1", "id2"] {
            let topics = ["measured", "prior", "adapted"]
                .map(|t| format!("/{id}/{t}").parse().unwrap())
                .to_vec();
            tables.push(read_log(&result, &ReadOptions { topics, dt: None }).unwrap());
        }
        for ((id, table), log) in ["id1", "id2"].iter().zip(&tables).zip([&log1, &log2]) {
            let col = |c: &str| table.column_index(c).unwrap_or_else(|| panic!("no {c}"));
            let q: Vec<f64> = table
                .rows
                .iter()
                .map(|r| r[col(&format!("{id}.q"))])
                .collect();
            assert_eq!(q.len(), log.len());
            assert!(
                q.iter()
                    .zip(&log.q)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{id}"
            );
            let replay = |m: &str| -> Vec<f64> {
                table
                    .rows
                    .iter()
                    .map(|r| r[col(&format!("{m}.{id}.q"))])
                    .collect()
            };
            let (before, after) = (rms(&replay("prior"), &q), rms(&replay("adapted"), &q));
            if *id == "id2" {
                assert!(
                    after < 0.5 * before,
                    "{id}: fitted {after} vs datasheet {before}"
                );
            }
        }
    }
    assert_eq!(answers[0], answers[1]);
}

/// `ik --frames` and `identify compliant --data --val` read a log as every other
/// command does (they parsed CSV text themselves before): marker frames of h1's
/// squat and a compliant walk, written as the reference libraries write logs (an
/// MCAP, a rosbag2 folder), give the CSV's answer: the same fitted angles to the
/// bit, the same fit to 1e-12.
#[test]
fn ik_and_identify_compliant_answer_the_same_from_reference_logs_as_from_csv() {
    let test = "ik_and_identify_compliant_answer_the_same_from_reference_logs_as_from_csv";
    let h1 = root().join("models/unitree_h1/h1.urdf");
    // Three markers on each of h1's moving links (a set like cli_ident.rs's).
    let mut toml = String::new();
    let links = [
        "pelvis",
        "torso_link",
        "left_hip_yaw_link",
        "left_hip_roll_link",
        "left_hip_pitch_link",
        "left_knee_link",
        "left_ankle_link",
        "right_hip_yaw_link",
        "right_hip_roll_link",
        "right_hip_pitch_link",
        "right_knee_link",
        "right_ankle_link",
        "left_shoulder_pitch_link",
        "left_shoulder_roll_link",
        "left_shoulder_yaw_link",
        "left_elbow_link",
        "right_shoulder_pitch_link",
        "right_shoulder_roll_link",
        "right_shoulder_yaw_link",
        "right_elbow_link",
    ];
    for link in links {
        for (k, p) in [[0.05, 0.0, -0.1], [0.0, 0.05, -0.05], [-0.05, -0.02, 0.05]]
            .iter()
            .enumerate()
        {
            toml += &format!(
                "[[marker]]\nname = \"{link}_{k}\"\nlink = \"{link}\"\nposition = [{}, {}, {}]\n\n",
                p[0], p[1], p[2]
            );
        }
    }
    let (markers, squat, frames) = (
        tmp("ik-markers.toml"),
        tmp("ik-squat.csv"),
        tmp("ik-frames.csv"),
    );
    std::fs::write(&markers, toml).unwrap();
    ok(&[
        "experiment",
        "squat",
        "--robot",
        s(&h1),
        "--out",
        s(&squat),
        "--duration",
        "1",
        "--rest",
        "0.2",
        "--rate",
        "50",
        "--markers",
        s(&markers),
        "--frames-out",
        s(&frames),
    ]);
    let Some(logs) = reference_logs(&frames, test) else {
        return;
    };
    let mut fitted = Vec::new();
    for (k, input) in std::iter::once(&frames).chain(&logs).enumerate() {
        let out = tmp(&format!("ik-out-{k}.csv"));
        ok(&[
            "ik",
            "--robot",
            s(&h1),
            "--markers",
            s(&markers),
            "--frames",
            s(input),
            "--out",
            s(&out),
        ]);
        fitted.push(Table::read(&out).unwrap());
    }
    for other in &fitted[1..] {
        same_rows(&fitted[0], other);
    }
    // A compliant walk: the seed's plant along a short ZMP reference.
    let (plant, reference, walk) = (tmp("c-plant.toml"), tmp("c-ref.csv"), tmp("c-walk.csv"));
    std::fs::write(
        &plant,
        "m = 32.053860196\ng = 9.81\nKxx = 440.91346363174296\nKxz = -2173.515375145169\n\
         Kzx = -2173.515375145169\nKzz = 60061.10789312922\nDxx = 14.527209046033501\n\
         Dxz = -3.3326729999481515\nDzx = -3.3326729999481515\nDzz = 667.4461329201686\n",
    )
    .unwrap();
    ok(&[
        "gait",
        "zmp",
        "--footsteps",
        "6",
        "--step-length",
        "0.03",
        "--tss",
        "0.5",
        "--out",
        s(&reference),
    ]);
    ok(&[
        "compliant",
        "simulate",
        "--reference",
        s(&reference),
        "--plant",
        s(&plant),
        "--table1",
        "--out",
        s(&walk),
    ]);
    let Some(logs) = reference_logs(&walk, test) else {
        return;
    };
    let inputs: Vec<PathBuf> = std::iter::once(walk.clone()).chain(logs).collect();
    same_answers(
        &[
            "identify",
            "compliant",
            "--data",
            "{in}",
            "--val",
            "{in}",
            "--plant",
            s(&plant),
            "--method",
            "lm",
            "--json",
            "{json}",
        ],
        &inputs,
        1e-12,
    );
}
