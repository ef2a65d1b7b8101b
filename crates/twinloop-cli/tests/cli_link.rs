//! `twinloop link ...` and `twinloop serve` as a user runs them: a virtual robot on
//! a pty, scanned, read and recorded by the CLI; interrupted and unplugged
//! recordings keep every row.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_twinloop")
}

fn twinloop(args: &[&str]) -> Output {
    Command::new(bin())
        .args(args)
        .output()
        .expect("the twinloop binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(name)
}

/// `twinloop serve` in the background; returns the child and the pty path.
fn serve(robot: &[&str], extra: &[&str]) -> (Child, String) {
    let mut child = Command::new(bin())
        .arg("serve")
        .args(robot)
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.as_mut().unwrap())
        .read_line(&mut line)
        .unwrap();
    (child, line.trim().to_string())
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
}

#[test]
fn link_scan_counts_the_imu_board_apart_from_the_servos() {
    // OP3: 20 XM430-W350 and the OpenCR at id 200 (issue 30 item 10: "21 servo(s)").
    let (mut server, pty) = serve(
        &["--map", "builtin:op3", "--servo-model", "ideal"],
        &["--no-timing"],
    );
    let o = twinloop(&[
        "link",
        "scan",
        "--port",
        &pty,
        "--protocol",
        "2",
        "--ids",
        "1-20,200",
    ]);
    let _ = server.kill();
    let _ = server.wait();
    let out = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        out.contains("20 servo(s) and 1 IMU board (OpenCR, id 200) found"),
        "{out}"
    );
    let board = out
        .lines()
        .find(|l| l.contains(" 200 "))
        .expect("id 200 listed");
    assert!(board.contains("OpenCR"), "{board}");
}

#[test]
fn plan_prints_the_wiretime_budget() {
    let o = twinloop(&[
        "link",
        "plan",
        "--servos",
        "20",
        "--protocol",
        "2",
        "--baud",
        "1000000",
    ]);
    assert!(o.status.success());
    let s = text(&o.stdout);
    assert!(
        s.contains("SYNC_READ") && s.contains("4.480") && s.contains("3.160"),
        "{s}"
    );
    let o = twinloop(&[
        "link",
        "plan",
        "--protocol",
        "1",
        "--return-delay-us",
        "500",
        "--json",
        "-",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["read_bytes"], 320);
    assert!((v[0]["wire_ms"].as_f64().unwrap() - 13.88).abs() < 1e-9);
}

#[test]
fn scan_read_and_record_a_served_robot() {
    // Stand-in servos, resting exactly at their centres (builtin:op3's description is
    // compiled in, so without this the robot would be simulated standing, its knees
    // bent a few counts by its weight).
    let (mut server, pty) = serve(
        &["--map", "builtin:op3", "--servo-model", "ideal"],
        &["--no-timing"],
    );
    let o = twinloop(&[
        "link",
        "scan",
        "--port",
        &pty,
        "--protocol",
        "2",
        "--json",
        "-",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // 20 XM430-W350 and the OpenCR at id 200 (model number 0x7400, no servo model).
    assert_eq!(v.as_array().unwrap().len(), 21);
    assert_eq!(v[0]["model"], "XM430-W350");
    assert_eq!(
        (v[20]["id"].as_u64(), v[20]["model_number"].as_u64()),
        (Some(200), Some(0x7400))
    );
    // The scan says what it does before the seconds it takes.
    assert!(
        text(&o.stderr).contains("scanning protocol 2.0, 253 id(s) (all)"),
        "{}",
        text(&o.stderr)
    );
    let o = twinloop(&[
        "link",
        "read",
        "--port",
        &pty,
        "--protocol",
        "2",
        "--id",
        "13",
        "present position",
        "model number",
    ]);
    let s = text(&o.stdout);
    assert!(
        s.contains("Present Position") && s.contains("2048") && s.contains("1020"),
        "{s}"
    );
    let o = twinloop(&[
        "link",
        "read",
        "--port",
        &pty,
        "--protocol",
        "2",
        "--id",
        "13",
        "goal speed",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("XM430-W350 has no register \"goal speed\""));

    let out = scratch("op3.csv");
    let o = twinloop(&[
        "link",
        "record",
        "--port",
        &pty,
        "--map",
        "builtin:op3",
        "--duration",
        "0.5",
        "--out",
        out.to_str().unwrap(),
        "--rate",
        "50",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let table = twinloop_io::Table::read(&out).unwrap();
    assert_eq!(table.columns.len(), 1 + 3 * 20);
    assert_eq!(table.columns[1], "q:r_sho_pitch");
    assert!(table.columns.contains(&"tau:head_tilt".to_string()));
    assert!(
        (20..=27).contains(&table.rows.len()),
        "{} rows at 50 Hz over 0.5 s",
        table.rows.len()
    );
    assert!(text(&o.stderr).contains(&format!("{} rows", table.rows.len())));
    server.kill().unwrap();
    server.wait().unwrap();
}

#[test]
fn interrupted_and_unplugged_recordings_keep_every_row() {
    let (mut server, pty) = serve(&["--robot", "builtin:km20"], &[]);
    // Ctrl-C: the recording stops cleanly, exit 0, every row in the file.
    let out = scratch("interrupted.csv");
    let rec = Command::new(bin())
        .args([
            "link",
            "record",
            "--port",
            &pty,
            "--map",
            "builtin:km20",
            "--duration",
            "60",
            "--out",
        ])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    signal(&rec, "-INT");
    let o = rec.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.contains("(interrupted)"), "{err}");
    // Below the 100 reads/s asked (20 servos, each waiting its Return Delay Time): the
    // recording says what limits its rate and how to raise it (issue 17).
    assert!(
        err.contains("the bus limits the rate") && err.contains("Return Delay Time"),
        "{err}"
    );
    let table = twinloop_io::Table::read(&out).unwrap();
    assert!(table.rows.len() >= 5, "{} rows", table.rows.len());
    assert!(err.contains(&format!("{} rows", table.rows.len())), "{err}");

    // The robot goes away mid-recording (an unplugged adapter): exit 2, the rows
    // read before are all there and the file parses.
    let out = scratch("unplugged.csv");
    let rec = Command::new(bin())
        .args([
            "link",
            "record",
            "--port",
            &pty,
            "--map",
            "builtin:km20",
            "--duration",
            "60",
            "--out",
        ])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    server.kill().unwrap();
    server.wait().unwrap();
    let t0 = Instant::now();
    let o = rec.wait_with_output().unwrap();
    assert!(t0.elapsed() < Duration::from_secs(10));
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.contains("recording stopped"), "{err}");
    let table = twinloop_io::Table::read(&out).unwrap();
    assert!(table.rows.len() >= 5);
    assert!(err.contains(&format!("{} rows", table.rows.len())), "{err}");
}

#[test]
fn bad_mapping_is_located() {
    let m = scratch("bad.toml");
    std::fs::write(&m, "[[joint]]\nname = \"a\"\nid = 1\nmodel = \"RX-99\"\n").unwrap();
    let o = twinloop(&["serve", "--map", m.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = text(&o.stderr);
    assert!(
        e.contains("bad.toml:4:9: joint \"a\": model: unknown model \"RX-99\""),
        "{e}"
    );
    let o = twinloop(&["link", "scan", "--port", "/nonexistent/ttyUSB9"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("/nonexistent/ttyUSB9"));
}

#[test]
fn serve_on_tcp() {
    let (mut server, addr) = serve(
        &["--map", "builtin:op3"],
        &["--port", "tcp:127.0.0.1:0", "--no-timing"],
    );
    assert!(addr.starts_with("tcp:127.0.0.1:"), "{addr}");
    let o = twinloop(&[
        "link",
        "scan",
        "--port",
        &addr,
        "--protocol",
        "2",
        "--ids",
        "1-5",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("5 servo(s) found"),
        "{}",
        text(&o.stdout)
    );
    server.kill().unwrap();
    server.wait().unwrap();
}

/// `twinloop serve --robot builtin:km20` is the physics simulation: a squat sent
/// over TCP bends the simulated knees, `link read` reports it, and the robot
/// stands (Present Load at the knees shows it carries its weight).
#[test]
fn serve_km20_simulated_on_tcp() {
    use twinloop_link::transport::{TcpTransport, Transport};
    use twinloop_link::{Client, ClientConfig, Protocol};
    let (mut server, addr) = serve(
        &["--robot", "builtin:km20"],
        &["--port", "tcp:127.0.0.1:0", "--no-timing"],
    );
    let a = 0.25f64;
    // RX units: 1024 over 300 degrees, centre 512; ids from the km20 mapping.
    let raw = |q: f64| ((512.0 + q / (300f64.to_radians() / 1024.0)).round() as u16).to_le_bytes();
    let goals = [
        (11u8, -a),
        (12, -a),
        (13, 2.0 * a),
        (14, 2.0 * a),
        (15, -a),
        (16, -a),
    ];
    {
        let t: Box<dyn Transport> =
            Box::new(TcpTransport::connect(addr.strip_prefix("tcp:").unwrap()).unwrap());
        let mut c = Client::with_config(
            t,
            ClientConfig {
                latency: Duration::from_millis(500),
                ..ClientConfig::default()
            },
        );
        let ids: Vec<u8> = goals.iter().map(|g| g.0).collect();
        let data: Vec<u8> = goals.iter().flat_map(|g| raw(g.1)).collect();
        c.sync_write(Protocol::V1, 30, 2, &ids, &data).unwrap();
        // The goal landed in the table.
        let mut b = [0u8; 2];
        c.read(Protocol::V1, 13, 30, &mut b).unwrap();
        assert_eq!(b, raw(2.0 * a));
    }
    std::thread::sleep(Duration::from_millis(1500));
    let o = twinloop(&[
        "link",
        "read",
        "--port",
        &addr,
        "--protocol",
        "1",
        "--id",
        "13",
        // The server's simulator thread runs in real time beside the other tests on a
        // shared machine: allow for scheduling, this test is about the physics.
        "--timeout-ms",
        "500",
        "--json",
        "-",
        "present position",
        "present load",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let knee = v["registers"][0]["value"].as_f64().unwrap();
    let load = v["registers"][1]["value"].as_f64().unwrap();
    assert!((knee - 2.0 * a).abs() < 0.1, "knee at {knee}: {v}");
    assert!(
        load.abs() > 0.02,
        "a bent knee under the robot's weight: {v}"
    );
    server.kill().unwrap();
    server.wait().unwrap();
}

#[test]
fn a_recording_with_a_mapping_no_servo_answers_stops_at_once() {
    // OP3's servos answer protocol 2.0 only; km20's mapping asks RX servos (1.0).
    let (mut server, pty) = serve(&["--map", "builtin:op3"], &["--no-timing"]);
    let out = scratch("nobody.csv");
    let start = Instant::now();
    let o = twinloop(&[
        "link",
        "record",
        "--port",
        &pty,
        "--map",
        "builtin:km20",
        "--duration",
        "60",
        "--timeout-ms",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    server.kill().unwrap();
    server.wait().unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        start.elapsed() < Duration::from_secs(30),
        "{:?}",
        start.elapsed()
    );
    assert!(err.contains("no servo of the mapping answered"), "{err}");
    assert!(
        err.contains("ids 1 (protocol 1.0), 2 (protocol 1.0)"),
        "{err}"
    );
    assert!(!out.exists(), "a file of NaN was left behind");
}
