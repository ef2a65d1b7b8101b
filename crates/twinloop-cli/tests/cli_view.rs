//! `--view` through the binary: `simulate --view` streams its state to the viewer
//! page (a real headless Chromium draws it, and the CoM the page computes from the
//! pose it received is the simulation's own), decimated to 90 states a second from
//! a 1 kHz run; a page that hangs up mid-stream leaves the simulation running to its
//! end; `--view` where there is nothing to show is a clear error.
//!
//! Without Chromium the browser test prints why and passes, unless
//! TWINLOOP_REQUIRE_ORACLES=1 (CI).

#[path = "../../twinloop-view/tests/support/chromium.rs"]
mod chromium;
#[path = "support/replay_check.rs"]
mod replay_check;
use replay_check::read_csv;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-cli-view-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// `simulate --view` for `seconds`, and the page's URL from its stderr; the rest of
/// stderr is collected by a thread.
fn simulate_view(out: &Path, seconds: &str) -> (Child, String, std::thread::JoinHandle<String>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "simulate",
            "--robot",
            "builtin:km20",
            "--duration",
            seconds,
            "--view",
            "--out",
        ])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    err.read_line(&mut line).unwrap();
    let url = line
        .trim()
        .strip_prefix("live view: ")
        .unwrap_or_else(|| panic!("first stderr line: {line:?}"))
        .to_string();
    let rest = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    (child, url, rest)
}

/// "live view: N of M states sent ...": (N, M).
fn states_sent(stderr: &str) -> (usize, usize) {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("live view: ") && l.contains("states sent"))
        .unwrap_or_else(|| panic!("no summary in {stderr}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    (words[2].parse().unwrap(), words[4].parse().unwrap())
}

#[test]
fn the_live_page_draws_what_simulate_view_streams() {
    let Some(browser) = chromium::browser() else {
        return;
    };
    let out = tmp("browser.csv");
    let (mut child, url, stderr) = simulate_view(&out, "8");
    let camera = "camera=0.9,-1.5,0.5,0,0,0.25&snapshot=1&overlays=com";
    // The first page starts the run; on a loaded machine headless Chromium's virtual
    // time can run out before the first frame arrives, so a page that saw none looks
    // again while the 8 s run goes on.
    let mut status = serde_json::Value::Null;
    for _ in 0..3 {
        let dom = chromium::dump_dom(&browser, &format!("{url}?{camera}"));
        let text = chromium::element_text(&dom, "status").expect("no #status");
        status = serde_json::from_str(&chromium::unescape_html(text)).unwrap();
        if status["live"]["frames"].as_u64().is_some_and(|f| f >= 1) {
            break;
        }
    }
    assert_eq!(status["ready"], true, "{status}");
    assert_eq!(status["errors"].as_array().unwrap().len(), 0, "{status}");
    let frames = status["live"]["frames"].as_u64().unwrap_or(0);
    assert!(frames >= 1, "no live frames in three page loads: {status}");
    assert!(child.wait().unwrap().success());
    let stderr = stderr.join().unwrap();
    // 8 s at 1 kHz, decimated on the server to 90 a second (a little above the
    // screen's 60, so the page has a new state for nearly every frame).
    let (sent, offered) = states_sent(&stderr);
    assert_eq!(offered, 8001, "{stderr}");
    assert!((715..=725).contains(&sent), "{stderr}");
    // The page's CoM, from the pose it was sent, is the simulation's at that time.
    let t = status["live"]["t"].as_f64().unwrap();
    let (header, rows) = read_csv(&out);
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let row = rows
        .iter()
        // The CSV's time is written to the nanosecond (`clean_time`); the page's
        // is the stream's, unrounded.
        .find(|r| (r[0] - t).abs() < 1e-9)
        .unwrap_or_else(|| panic!("no row at t = {t}"));
    let seen = status["com"].as_array().unwrap();
    for (k, c) in ["com.x", "com.y", "com.z"].iter().enumerate() {
        let (page, sim) = (seen[k].as_f64().unwrap(), row[col(c)]);
        assert!(
            (page - sim).abs() < 1e-5,
            "{c} at t = {t}: page {page}, simulation {sim}"
        );
    }
}

/// Open `/live` by hand (the websocket handshake) and read `bytes` of its stream.
fn live_socket(url: &str, bytes: usize) -> TcpStream {
    let addr = url
        .trim_start_matches("http://")
        .trim_end_matches('/')
        .to_string();
    let mut s = TcpStream::connect(&addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(
        s,
        "GET /live HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    .unwrap();
    let mut got = vec![0u8; bytes];
    s.read_exact(&mut got).unwrap();
    assert!(
        got.starts_with(b"HTTP/1.1 101"),
        "{}",
        String::from_utf8_lossy(&got)
    );
    s
}

#[test]
fn a_page_that_hangs_up_leaves_the_simulation_running() {
    let out = tmp("hangup.csv");
    let (mut child, url, stderr) = simulate_view(&out, "1.5");
    // A page connects (the run starts), reads part of the stream and goes away
    // mid-frame; another comes and goes; the run goes on to its end.
    let first = live_socket(&url, 600);
    std::thread::sleep(Duration::from_millis(300));
    drop(first);
    let second = live_socket(&url, 2000);
    drop(second);
    assert!(child.wait().unwrap().success());
    let stderr = stderr.join().unwrap();
    let (_, offered) = states_sent(&stderr);
    assert_eq!(offered, 1501, "{stderr}");
    let (_, rows) = read_csv(&out);
    assert_eq!(rows.len(), 1501, "every step written");
    assert!((rows[1500][0] - 1.5).abs() < 1e-9);
}

#[test]
fn view_without_a_simulated_robot_is_an_error() {
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["serve", "--servo-model", "ideal", "--view"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--view shows the simulated robot"), "{err}");
}

/// The first stderr line of `child` that starts with "live view: ": the page's URL.
fn live_url(child: &mut Child) -> (String, BufReader<std::process::ChildStderr>) {
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    while err.read_line(&mut line).unwrap() > 0 {
        if let Some(url) = line.trim().strip_prefix("live view: ") {
            return (url.to_string(), err);
        }
        line.clear();
    }
    panic!("no live view URL on stderr");
}

#[test]
fn serve_view_and_link_record_view_stream_the_robot() {
    let bin = env!("CARGO_BIN_EXE_twinloop");
    let mut serve = Command::new(bin)
        .args(["serve", "--robot", "builtin:km20", "--view"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut pty = String::new();
    BufReader::new(serve.stdout.as_mut().unwrap())
        .read_line(&mut pty)
        .unwrap();
    let (url, serve_err) = live_url(&mut serve);
    // The simulation behind the bus, as it runs: joint states in JSON frames, with
    // the floating base's pose: standing as `simulate` stands the same robot.
    let mut page = live_socket(&url, 400);
    let mut more = vec![0u8; 4000];
    page.read_exact(&mut more).unwrap();
    let text = String::from_utf8_lossy(&more);
    assert!(text.contains("\"q\":["));
    let base: Vec<f64> = text
        .split("\"base\":[")
        .nth(1)
        .and_then(|b| b.split(']').next())
        .unwrap_or_else(|| panic!("no base pose in {text}"))
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(base.len(), 7, "{base:?}");
    let norm = base[3..].iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!((norm - 1.0).abs() < 1e-6, "{base:?}");
    let standing = tmp("standing.csv");
    let ok = Command::new(bin)
        .args([
            "simulate",
            "--robot",
            "builtin:km20",
            "--duration",
            "0.01",
            "--out",
        ])
        .arg(&standing)
        .status()
        .unwrap();
    assert!(ok.success());
    let (header, rows) = read_csv(&standing);
    let z = rows[0][header.iter().position(|c| c == "q:base.z").unwrap()];
    assert!(
        (base[2] - z).abs() < 0.005,
        "served base at z = {}, simulate stands it at {z}",
        base[2]
    );
    drop(page);
    // What a recording reads over that bus, as it reads it.
    let out = tmp("record.csv");
    let mut rec = Command::new(bin)
        .args([
            "link",
            "record",
            "--port",
            pty.trim(),
            "--map",
            "builtin:km20",
        ])
        .args(["--duration", "3", "--view", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (url, mut rec_err) = live_url(&mut rec);
    let mut page = live_socket(&url, 400);
    page.read_exact(&mut more).unwrap();
    assert!(String::from_utf8_lossy(&more).contains("\"q\":["));
    assert!(rec.wait().unwrap().success());
    let mut rest = String::new();
    rec_err.read_to_string(&mut rest).unwrap();
    let (sent, offered) = states_sent(&rest);
    // 3 s read at up to 100 Hz (slower when the machine is busy), decimated to 90 a
    // second on a grid (a 100 Hz source gives 90, not every other read: 50).
    let want = offered.min(270);
    assert!(
        offered > 30 && sent <= want + 2 && sent + want / 10 >= want,
        "{rest}"
    );
    let ok = Command::new("kill")
        .args(["-INT", &serve.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    assert!(serve.wait().unwrap().success());
    let mut rest = String::new();
    BufReader::new(serve_err).read_to_string(&mut rest).unwrap();
    states_sent(&rest);
}

/// Run the binary with `args`; it must succeed and make no 3D replay warning.
fn twinloop_ok(args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{args:?}: {err}");
    assert!(!err.contains("no 3D replay"), "{args:?}: {err}");
    err
}

/// The `--report` pages about a motion link to its 3D replay written beside them,
/// which opens offline in Chromium with the recordings named and nothing wrong.
#[test]
fn motion_reports_link_their_3d_replay() {
    let p = |n: &str| tmp(n).display().to_string();
    // The lean, validated: the robot's run and the simulation's as a ghost.
    twinloop_ok(&[
        "experiment",
        "lean",
        "--robot",
        "builtin:km20",
        "--out",
        &p("lean_a.csv"),
    ]);
    twinloop_ok(&[
        "experiment",
        "lean",
        "--robot",
        "builtin:km20",
        "--amplitude",
        "2",
        "--out",
        &p("lean_b.csv"),
    ]);
    twinloop_ok(&[
        "validate",
        "lean",
        "--robot-run",
        &p("lean_a.csv"),
        "--sim-run",
        &p("lean_b.csv"),
        "--report",
        &p("lean.html"),
        "--robot",
        "builtin:km20",
    ]);
    // The squat of seed 004 under the residual check, and the static poses.
    let h1 = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/unitree_h1/h1.urdf"
    );
    twinloop_ok(&[
        "experiment",
        "squat",
        "--robot",
        h1,
        "--out",
        &p("squat.csv"),
    ]);
    twinloop_ok(&[
        "validate",
        "residual",
        "--robot",
        h1,
        "--motion",
        &p("squat.csv"),
        "--out",
        &p("res.csv"),
        "--report",
        &p("res.html"),
    ]);
    twinloop_ok(&[
        "experiment",
        "static-poses",
        "--robot",
        "builtin:km20",
        "--count",
        "60",
        "--out",
        &p("poses.csv"),
    ]);
    twinloop_ok(&[
        "identify",
        "static",
        "--robot",
        "builtin:km20",
        "--poses",
        &p("poses.csv"),
        "--total-mass",
        "3.336",
        "--report",
        &p("static.html"),
    ]);
    // The lab17 walk of seed 003, identified: its joints from the u: offsets.
    twinloop_ok(&[
        "experiment",
        "walk",
        "--robot",
        "builtin:lab17",
        "--out",
        &p("walk.csv"),
    ]);
    twinloop_ok(&[
        "identify",
        "walk",
        "--data",
        &p("walk.csv"),
        "--report-arx",
        &p("walk.html"),
        "--max-iter",
        "2",
    ]);
    let browser = chromium::browser();
    for (report, names, moving) in [
        ("lean", vec!["lean_a.csv", "lean_b.csv"], "q:l_ank_pitch"),
        ("res", vec!["squat.csv"], "q:left_knee_joint"),
        ("static", vec!["poses.csv"], "q:l_knee"),
        ("walk", vec!["walk.csv"], "q:l_ank_roll"),
    ] {
        let html = std::fs::read_to_string(tmp(&format!("{report}.html"))).unwrap();
        let file = format!("{report}_3d.html");
        assert!(
            html.contains(&format!("<a href=\"{file}\">")),
            "{report}: no link"
        );
        let Some(browser) = &browser else { continue };
        let page = format!("file://{}?snapshot=1&t=1", tmp(&file).display());
        let dom = chromium::dump_dom(browser, &page);
        let status = chromium::element_text(&dom, "status").expect("no #status");
        let status: serde_json::Value =
            serde_json::from_str(&chromium::unescape_html(status)).unwrap();
        assert_eq!(status["ready"], true, "{report}: {status}");
        assert_eq!(
            status["errors"].as_array().unwrap().len(),
            0,
            "{report}: {status}"
        );
        let recs = status["recordings"].as_array().unwrap();
        let got: Vec<&str> = recs.iter().map(|r| r["name"].as_str().unwrap()).collect();
        assert_eq!(got, names, "{report}");
        for r in recs {
            let missing: Vec<&str> = r["missing"]
                .as_array()
                .unwrap()
                .iter()
                .map(|m| m.as_str().unwrap())
                .collect();
            assert!(
                !missing.contains(&moving),
                "{report}: {moving} missing: {r}"
            );
        }
    }
}

/// Every `"base":[x, y, z, qx, qy, qz, qw]` in a stretch of the live stream.
fn base_poses(text: &str) -> Vec<Vec<f64>> {
    text.split("\"base\":[")
        .skip(1)
        .filter_map(|b| {
            let v: Vec<f64> = b
                .split(']')
                .next()?
                .split(',')
                .map(|v| v.parse().ok())
                .collect::<Option<_>>()?;
            (v.len() == 7).then_some(v)
        })
        .collect()
}

/// A served robot whose servos power on limp falls, and `serve --view` shows its
/// base going down (the state sent is the simulator's, base pose and all).
#[test]
fn serve_view_shows_a_limp_robot_fall() {
    let mut serve = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        // A quarter of real time: the fall lasts seconds, after the page is there.
        .args(["serve", "--robot", "builtin:km20", "--torque-off", "--view"])
        .args(["--realtime-factor", "0.25"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (url, _err) = live_url(&mut serve);
    let mut page = live_socket(&url, 300);
    let mut seen = Vec::new();
    let start = std::time::Instant::now();
    let mut buf = vec![0u8; 8192];
    while start.elapsed() < Duration::from_secs(5) {
        let n = page.read(&mut buf).unwrap();
        seen.extend_from_slice(&buf[..n]);
    }
    let _ = Command::new("kill")
        .args(["-INT", &serve.id().to_string()])
        .status();
    let _ = serve.wait();
    let poses = base_poses(&String::from_utf8_lossy(&seen));
    assert!(poses.len() > 30, "{} base poses in 5 s", poses.len());
    let z: Vec<f64> = poses.iter().map(|p| p[2]).collect();
    let (first, lowest) = (z[0], z.iter().copied().fold(f64::INFINITY, f64::min));
    // km20's base stands at 0.27 m; limp, the robot folds to the ground.
    assert!(first > 0.2, "the base starts at z = {first}");
    assert!(
        lowest < 0.6 * first,
        "the base went from {first} only down to {lowest}"
    );
}

/// `twinloop view ARGS`, with its stdout's first line (the page's URL) and the rest
/// of its stderr collected by a thread.
struct View {
    child: Child,
    url: String,
    stderr: Option<std::thread::JoinHandle<String>>,
}

impl View {
    fn start(args: &[&str]) -> View {
        let mut child = Command::new(env!("CARGO_BIN_EXE_twinloop"))
            .arg("view")
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let mut err = child.stderr.take().unwrap();
        let stderr = std::thread::spawn(move || {
            let mut s = String::new();
            let _ = err.read_to_string(&mut s);
            s
        });
        View {
            child,
            url: line.trim_end().to_string(),
            stderr: Some(stderr),
        }
    }

    /// host:port of the URL.
    fn addr(&self) -> &str {
        self.url
            .strip_prefix("http://")
            .and_then(|a| a.strip_suffix('/'))
            .unwrap_or_else(|| panic!("not http://HOST:PORT/: {:?}", self.url))
    }

    /// Stop the server; what it wrote on stderr.
    fn stop(mut self) -> String {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.stderr.take().unwrap().join().unwrap()
    }
}

/// GET `path` from `addr`: (status code, body).
fn http_get(addr: &str, path: &str) -> (u16, String) {
    let (code, body) = http_get_bytes(addr, path);
    (code, String::from_utf8(body).unwrap())
}

/// GET `path` from `addr`: (status code, body's bytes).
fn http_get_bytes(addr: &str, path: &str) -> (u16, Vec<u8>) {
    let mut s = TcpStream::connect(addr).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut bytes = Vec::new();
    s.read_to_end(&mut bytes).unwrap();
    let code = std::str::from_utf8(&bytes[9..12]).unwrap().parse().unwrap();
    let head = bytes
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .map_or(bytes.len(), |i| i + 4);
    (code, bytes[head..].to_vec())
}

#[test]
fn view_opens_an_mcap_recording_as_it_opens_the_csv_of_the_same_run() {
    let (csv, mcap) = (tmp("view-run.csv"), tmp("view-run.mcap"));
    for out in [&csv, &mcap] {
        twinloop_ok(&[
            "simulate",
            "--robot",
            "builtin:km20",
            "--duration",
            "0.1",
            "--out",
            out.to_str().unwrap(),
        ]);
    }
    let v = View::start(&[
        "builtin:km20",
        csv.to_str().unwrap(),
        mcap.to_str().unwrap(),
    ]);
    // The same columns and the same samples sent to the page (column-major f32; the
    // MCAP's columns in the order of its topics, `t` rebuilt from nanoseconds).
    let info = |k: usize| -> serde_json::Value {
        let mut j: serde_json::Value =
            serde_json::from_str(&http_get(v.addr(), &format!("/recording/{k}.json")).1).unwrap();
        j.as_object_mut().unwrap().remove("name");
        j
    };
    let columns = |j: &serde_json::Value| -> Vec<String> {
        serde_json::from_value(j["columns"].clone()).unwrap()
    };
    let (a, b) = (info(0), info(1));
    let (ca, cb) = (columns(&a), columns(&b));
    let (mut sa, mut sb) = (ca.clone(), cb.clone());
    sa.sort();
    sb.sort();
    assert_eq!(sa, sb);
    for key in ["rows", "missing", "has_base"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    for key in ["t0", "t1"] {
        let (x, y) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
        assert!((x - y).abs() <= 0.5e-9, "{key}: {x} vs {y}");
    }
    let rows = a["rows"].as_u64().unwrap() as usize;
    let (da, db) = (
        http_get_bytes(v.addr(), "/recording/0.bin").1,
        http_get_bytes(v.addr(), "/recording/1.bin").1,
    );
    assert_eq!(
        (da.len(), db.len()),
        (ca.len() * rows * 4, ca.len() * rows * 4)
    );
    for (i, c) in ca.iter().enumerate() {
        let j = cb.iter().position(|x| x == c).unwrap();
        let (x, y) = (
            &da[i * rows * 4..][..rows * 4],
            &db[j * rows * 4..][..rows * 4],
        );
        if c == "t" {
            for (p, q) in x.chunks(4).zip(y.chunks(4)) {
                let f = |b: &[u8]| f32::from_le_bytes(b.try_into().unwrap());
                assert!((f(p) - f(q)).abs() <= 1e-6, "t: {} vs {}", f(p), f(q));
            }
        } else {
            assert_eq!(x, y, "column {c}");
        }
    }
    v.stop();
    // A log being written cannot be followed: said in one line, exit 2.
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["view", "builtin:km20", "--live", mcap.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("record to a CSV to follow it live"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn view_prints_its_loopback_url_on_a_free_port_or_the_one_asked_for() {
    // Two at once: each on a port of its own, chosen by the system.
    let (a, b) = (
        View::start(&["builtin:km20"]),
        View::start(&["builtin:km20"]),
    );
    for v in [&a, &b] {
        let port: u16 = v
            .addr()
            .strip_prefix("127.0.0.1:")
            .unwrap_or_else(|| panic!("not on 127.0.0.1: {}", v.url))
            .parse()
            .unwrap();
        assert_ne!(port, 0);
        let (code, body) = http_get(v.addr(), "/");
        assert_eq!(code, 200);
        assert!(body.contains("twinloop view"), "{body}");
    }
    assert_ne!(a.url, b.url);
    let stderr = a.stop();
    assert!(stderr.contains("serving km20"), "{stderr}");
    b.stop();
    // --port: a port known to be free a moment ago.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let v = View::start(&["builtin:km20", "--port", &port.to_string()]);
    assert_eq!(v.url, format!("http://127.0.0.1:{port}/"));
    assert_eq!(http_get(v.addr(), "/scene.json").0, 200);
    v.stop();
}

/// The joint names of the served scene, in the order of the live state's `q`.
fn scene_joints(addr: &str) -> Vec<String> {
    let (_, body) = http_get(addr, "/scene.json");
    let scene: serde_json::Value = serde_json::from_str(&body).unwrap();
    scene["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["name"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn view_live_sends_the_newest_row_of_a_growing_csv_to_a_page() {
    let csv = tmp("growing.csv");
    std::fs::write(&csv, "t,q:l_knee,q:head_pan\n0,0.25,-0.5\n").unwrap();
    let v = View::start(&["builtin:km20", "--live", csv.to_str().unwrap()]);
    let joints = scene_joints(v.addr());
    let (knee, head) = (
        joints.iter().position(|j| j == "l_knee").unwrap(),
        joints.iter().position(|j| j == "head_pan").unwrap(),
    );
    // The page's side: a websocket client on /live.
    let stream = TcpStream::connect(v.addr()).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    let (mut ws, _) = tungstenite::client(format!("ws://{}/live", v.addr()), stream).unwrap();
    let mut next = || loop {
        match ws.read().unwrap() {
            tungstenite::Message::Text(t) => {
                break serde_json::from_str::<serde_json::Value>(t.as_str()).unwrap();
            }
            _ => continue,
        }
    };
    let first = next();
    assert_eq!(first["t"], 0.0, "{first}");
    assert_eq!(first["q"][knee], 0.25, "{first}");
    assert_eq!(first["q"][head], -0.5, "{first}");
    // A joint the file does not have is not known (null), not 0.
    let other = (0..joints.len()).find(|&k| k != knee && k != head).unwrap();
    assert!(first["q"][other].is_null(), "{first}");
    // Rows written later reach the page: the newest one.
    let mut f = std::fs::OpenOptions::new().append(true).open(&csv).unwrap();
    write!(f, "0.5,0.5,-0.25\n1,0.75,0\n").unwrap();
    f.flush().unwrap();
    let last = loop {
        let m = next();
        if m["t"] == 1.0 {
            break m;
        }
        assert!(m["t"].as_f64().unwrap() < 1.0, "{m}");
    };
    assert_eq!(last["q"][knee], 0.75, "{last}");
    assert_eq!(last["q"][head], 0.0, "{last}");
    drop(ws);
    // The page went away; the server still answers.
    assert_eq!(http_get(v.addr(), "/scene.json").0, 200);
    v.stop();
}

#[test]
fn view_export_writes_one_file_and_names_missing_meshes_on_stderr() {
    let out = tmp("km20_export.html");
    let csv = tmp("export_run.csv");
    std::fs::write(&csv, "t,q:l_knee\n0,0.1\n1,0.2\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["view", "builtin:km20"])
        .arg(&csv)
        .arg("--export")
        .arg(&out)
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{stderr}");
    assert_eq!(stdout.trim(), format!("wrote {}", out.display()));
    // The recording lacks joint columns: said on stderr.
    assert!(
        stderr.contains("warning: export_run.csv: 19 of the robot's joint columns are missing"),
        "{stderr}"
    );
    let html = std::fs::read_to_string(&out).unwrap();
    assert!(html.contains("window.TWINLOOP_EMBED = "));
    assert!(html.contains("\"name\":\"export_run.csv\""));
    assert!(
        !html.contains("src=\"vendor/"),
        "a file the export needs is left outside"
    );
    // A description with a missing mesh: a warning naming it.
    let robot = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../twinloop-view/tests/data/mesh_robot/urdf/robot.urdf"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["view", robot, "--export"])
        .arg(tmp("mesh_robot.html"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let warning = stderr
        .lines()
        .find(|l| l.contains("hand.stl"))
        .unwrap_or_else(|| panic!("no warning about hand.stl: {stderr}"));
    assert!(
        warning.starts_with("warning: mesh \"../meshes/hand.stl\" of link hand: file not found")
            && warning.ends_with("drawn as its collision primitive or inertia box (orange)"),
        "{warning}"
    );
}

/// The mesh test robot with every mesh behind `package://pkg/`, in a folder of its own
/// (so no folder above it is called pkg).
fn packaged_robot() -> PathBuf {
    let src = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../twinloop-view/tests/data/mesh_robot/urdf/robot.urdf"
    );
    let text = std::fs::read_to_string(src)
        .unwrap()
        .replace("package://mesh_robot/", "package://pkg/")
        .replace("../meshes/cube.stl", "package://pkg/meshes/cube.stl")
        .replace("../meshes/hand.stl", "package://pkg/meshes/cube.stl");
    let path = tmp("packaged.urdf");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn simulate_view_finds_package_meshes_through_package_dir() {
    let robot = packaged_robot();
    let pkg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../twinloop-view/tests/data/mesh_robot"
    );
    for with in [true, false] {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_twinloop"));
        cmd.args(["simulate", "--robot"])
            .arg(&robot)
            .args(["--duration", "1", "--view", "--out"])
            .arg(tmp("packaged.csv"));
        if with {
            cmd.arg("--package-dir").arg(format!("pkg={pkg}"));
        }
        let mut child = cmd
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (url, _err) = live_url(&mut child);
        let addr = url.trim_start_matches("http://").trim_end_matches('/');
        let (_, body) = http_get(addr, "/scene.json");
        let _ = child.kill();
        let _ = child.wait();
        let scene: serde_json::Value = serde_json::from_str(&body).unwrap();
        let found = scene["meshes"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| m["url"].is_string())
            .count();
        if with {
            assert_eq!(found, 2, "{scene}");
            assert_eq!(scene["warnings"], serde_json::json!([]), "{scene}");
        } else {
            assert_eq!(found, 0, "{scene}");
            assert!(
                scene["warnings"]
                    .to_string()
                    .contains("give --package-dir pkg=DIR"),
                "{scene}"
            );
        }
    }
    // --package-dir says where --view's meshes are: alone it is an error.
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args([
            "simulate",
            "--robot",
            "builtin:km20",
            "--package-dir",
            "a=b",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--view"));
}
