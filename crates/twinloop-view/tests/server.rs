//! The viewer's server over real sockets: it serves its own files and the meshes
//! the description names, nothing else (no path traversal), and a client that
//! hangs up mid-answer leaves it running.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::time::Duration;
use twinloop_view::{Content, Recording, Scene, Server};

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(rel)
}

fn mesh_robot_content(recordings: usize) -> Content {
    let path = data("mesh_robot/urdf/robot.urdf");
    let robot = twinloop_description::load(&path).unwrap();
    let scene = Scene::new(&robot, Some(&path), &[]);
    let mut table = twinloop_io::Table::new(vec!["t".into(), "q:shoulder".into()]);
    for k in 0..50_000 {
        table
            .rows
            .push(vec![k as f64 * 1e-3, (k as f64 * 1e-3).sin()]);
    }
    let recordings = (0..recordings)
        .map(|_| Recording::from_table(&table, Path::new("swing.csv"), &scene.info).unwrap())
        .collect();
    Content {
        scene,
        recordings,
        live: None,
    }
}

fn start(content: Content) -> SocketAddr {
    let server = Server::bind("127.0.0.1:0", content).unwrap();
    let addr = server.addr();
    std::thread::spawn(move || server.run());
    addr
}

/// A raw GET (no client-side normalisation of the path): status code and body.
fn get(addr: SocketAddr, path: &str) -> (u16, Vec<u8>) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut all = Vec::new();
    s.read_to_end(&mut all).unwrap();
    let head_end = all.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let head = String::from_utf8_lossy(&all[..head_end]).to_string();
    let code = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    (code, all[head_end + 4..].to_vec())
}

#[test]
fn binds_to_loopback_and_serves_the_page_scene_and_named_meshes() {
    let addr = start(mesh_robot_content(1));
    assert!(addr.ip().is_loopback());
    let (code, body) = get(addr, "/");
    assert_eq!(code, 200);
    assert!(String::from_utf8_lossy(&body).contains("viewer.js"));
    assert_eq!(get(addr, "/vendor/twinloop-vendor.js").0, 200);
    let (code, scene) = get(addr, "/scene.json");
    assert_eq!(code, 200);
    let scene: serde_json::Value = serde_json::from_slice(&scene).unwrap();
    let meshes = scene["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 3, "{meshes:?}");
    // Found through a relative path and through package:// (the folder mesh_robot).
    assert_eq!(meshes[0]["url"], "mesh/0.stl");
    assert_eq!(meshes[1]["url"], "mesh/1.obj");
    assert!(meshes[2]["url"].is_null());
    assert!(
        meshes[2]["problem"]
            .as_str()
            .unwrap()
            .contains("file not found")
    );
    let (code, stl) = get(addr, "/mesh/0.stl");
    assert_eq!(code, 200);
    assert_eq!(
        stl,
        std::fs::read(data("mesh_robot/meshes/cube.stl")).unwrap()
    );
    assert_eq!(get(addr, "/mesh/1.obj").0, 200);
    // The served URDF names the meshes by number and draws the missing one as its
    // collision box.
    let (_, urdf) = get(addr, "/robot.urdf");
    let urdf = String::from_utf8(urdf).unwrap();
    assert!(urdf.contains("mesh/0.stl") && urdf.contains("mesh/1.obj"));
    assert!(!urdf.contains("hand.stl") && !urdf.contains("package://"));
    assert!(urdf.contains("box size=\"0.06 0.06 0.06\""), "{urdf}");
    // The recording: its facts and its column-major f32 data.
    let (code, info) = get(addr, "/recording/0.json");
    assert_eq!(code, 200);
    let info: serde_json::Value = serde_json::from_slice(&info).unwrap();
    assert_eq!(info["rows"], 50_000);
    let (_, bin) = get(addr, "/recording/0.bin");
    assert_eq!(bin.len(), 2 * 50_000 * 4);
    let q1 = f32::from_le_bytes(bin[(50_000 + 1) * 4..(50_000 + 2) * 4].try_into().unwrap());
    assert_eq!(q1, (1e-3f64).sin() as f32);
}

#[test]
fn nothing_outside_its_own_files_is_served() {
    let addr = start(mesh_robot_content(1));
    for path in [
        "/../Cargo.toml",
        "/mesh/../../Cargo.toml",
        "/mesh/..%2f..%2fCargo.toml",
        "/%2e%2e/Cargo.toml",
        "/%2e%2e%2fCargo.toml",
        "/mesh/%2e%2e/%2e%2e/meshes/cube.stl",
        "/vendor/../viewer.js",
        "/mesh/2.stl",
        "/mesh/0.obj",
        "/mesh/00.stl",
        "/mesh/0.stl/",
        "/meshes/cube.stl",
        "/tests/data/mesh_robot/meshes/cube.stl",
        "/recording/1.json",
        "/recording/-1.json",
        "/recording/0.csv",
        "/etc/passwd",
        "//etc/passwd",
        "/web/index.html",
        "/src/lib.rs",
    ] {
        assert_eq!(get(addr, path).0, 404, "{path}");
    }
    // Only GET and HEAD.
    let mut s = TcpStream::connect(addr).unwrap();
    write!(
        s,
        "POST /scene.json HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut head = String::new();
    s.read_to_string(&mut head).unwrap();
    assert!(head.starts_with("HTTP/1.1 404"), "{head}");
}

#[test]
fn a_client_that_hangs_up_mid_answer_leaves_the_server_running() {
    // 4 recordings of 400 kB each: answers larger than the socket buffers.
    let addr = start(mesh_robot_content(4));
    for round in 0..20 {
        let mut s = TcpStream::connect(addr).unwrap();
        write!(
            s,
            "GET /recording/{}.bin HTTP/1.1\r\nHost: x\r\n\r\n",
            round % 4
        )
        .unwrap();
        let mut some = [0u8; 256];
        let _ = s.read(&mut some).unwrap();
        drop(s); // gone with most of the answer unread
    }
    // And one that connects and says nothing at all.
    let idle = TcpStream::connect(addr).unwrap();
    let (code, body) = get(addr, "/scene.json");
    assert_eq!(code, 200);
    assert!(serde_json::from_slice::<serde_json::Value>(&body).is_ok());
    drop(idle);
    assert_eq!(get(addr, "/").0, 200);
}

#[test]
fn a_recording_says_which_joint_columns_it_lacks() {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let scene = Scene::new(&robot, None, &[]);
    let table =
        twinloop_io::Table::parse("t,q:l_knee,q:r_knee\n0,0.1,0.2\n0.01,0.1,0.2\n").unwrap();
    let rec = Recording::from_table(&table, Path::new("knees.csv"), &scene.info).unwrap();
    assert_eq!(rec.info.missing.len(), scene.info.joints.len() - 2);
    assert!(rec.info.missing.contains(&"q:l_hip_pitch".to_string()));
    assert!(!rec.info.has_base);
    let w = rec.warning().unwrap();
    assert!(
        w.starts_with("knees.csv: 18 of the robot's joint columns are missing"),
        "{w}"
    );
    // No time column, and time running backwards: errors naming the file and row.
    let no_t = twinloop_io::Table::parse("q:l_knee\n0\n").unwrap();
    let e = Recording::from_table(&no_t, Path::new("x.csv"), &scene.info).unwrap_err();
    assert!(e.to_string().contains("x.csv") && e.to_string().contains("\"t\""));
    // (Built in memory: a file like it is refused as it is read, by twinloop-io.)
    let in_memory = |rows: Vec<Vec<f64>>| twinloop_io::Table {
        rows,
        ..twinloop_io::Table::new(vec!["t".into(), "q:l_knee".into()])
    };
    let back = in_memory(vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.5, 0.0]]);
    let e = Recording::from_table(&back, Path::new("x.csv"), &scene.info).unwrap_err();
    assert_eq!(
        e.to_string(),
        "x.csv: column \"t\": data row 3: time decreases (the rows must be in time order)"
    );
    let nan = in_memory(vec![vec![0.0, 0.0], vec![f64::NAN, 0.0]]);
    let e = Recording::from_table(&nan, Path::new("x.csv"), &scene.info).unwrap_err();
    assert!(e.to_string().contains("not a finite number"), "{e}");
}

#[test]
fn op3_without_its_meshes_is_drawn_from_stand_ins_with_warnings() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/op3/robotis_op3.urdf");
    let robot = twinloop_description::load(&path).unwrap();
    let scene = Scene::new(&robot, Some(&path), &[]);
    assert_eq!(scene.info.meshes.len(), 21);
    assert!(scene.info.meshes.iter().all(|m| m.url.is_none()));
    // One grouped warning for the 21 meshes of the unknown package, not one per mesh.
    assert_eq!(scene.info.warnings.len(), 1, "{:?}", scene.info.warnings);
    assert!(
        scene.info.warnings[0].starts_with("21 meshes: ")
            && scene.info.warnings[0].contains("--package-dir op3_description=DIR"),
        "{}",
        scene.info.warnings[0]
    );
    // Every link with a mesh visual now has a box (its inertia box) instead.
    let served = twinloop_description::urdf::from_str(&scene.urdf).unwrap();
    for link in &served.links {
        for v in &link.visuals {
            assert!(
                matches!(v.geometry, twinloop_description::Geometry::Box { .. }),
                "{}: {:?}",
                link.name,
                v.geometry
            );
        }
    }
    assert_eq!(scene.info.joints.len(), 20);
}

fn live_content(feed: &twinloop_view::LiveFeed) -> Content {
    let mut c = mesh_robot_content(0);
    c.live = Some(feed.clone());
    c
}

fn live_socket(addr: SocketAddr) -> tungstenite::WebSocket<TcpStream> {
    let stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let (ws, _) = tungstenite::client::client(format!("ws://{addr}/live"), stream).unwrap();
    ws
}

/// The next state sent: (t, q).
fn next_state(ws: &mut tungstenite::WebSocket<TcpStream>) -> (f64, Vec<Option<f64>>) {
    loop {
        if let tungstenite::Message::Text(text) = ws.read().unwrap() {
            let v: serde_json::Value = serde_json::from_str(&text).unwrap();
            let q = v["q"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64())
                .collect();
            return (v["t"].as_f64().unwrap(), q);
        }
    }
}

#[test]
fn the_live_socket_sends_the_newest_state_decimated_and_survives_hang_ups() {
    let feed = twinloop_view::LiveFeed::new();
    let addr = start(live_content(&feed));
    let (_, scene) = get(addr, "/scene.json");
    let scene: serde_json::Value = serde_json::from_slice(&scene).unwrap();
    assert_eq!(scene["live"], true);
    let mut ws = live_socket(addr);
    // A 1 kHz source for 0.6 s of wall time, decimated to 60 Hz.
    let source = {
        let feed = feed.clone();
        std::thread::spawn(move || {
            let mut d = twinloop_view::Decimator::new(60.0);
            let start = std::time::Instant::now();
            let mut published = 0;
            for k in 0..600 {
                let t = k as f64 * 1e-3;
                while start.elapsed().as_secs_f64() < t {
                    std::thread::sleep(Duration::from_micros(200));
                }
                if d.admit(t) {
                    feed.publish(t, &[t.sin()], None);
                    published += 1;
                }
            }
            published
        })
    };
    let mut received = Vec::new();
    while received.last().is_none_or(|(t, _)| *t < 0.58) {
        received.push(next_state(&mut ws));
    }
    let published = source.join().unwrap();
    assert!((35..=37).contains(&published), "{published}");
    assert!(
        received.len() <= published && received.len() > published / 2,
        "{}",
        received.len()
    );
    for w in received.windows(2) {
        assert!(w[1].0 > w[0].0, "states out of order");
    }
    for (t, q) in &received {
        assert!((q[0].unwrap() - t.sin()).abs() < 1e-12, "{t}: {q:?}");
    }
    // A client that hangs up mid-stream, and one that never reads: the server and
    // the others go on.
    drop(ws);
    let stalled = live_socket(addr);
    let mut other = live_socket(addr);
    for k in 0..2000 {
        feed.publish(1.0 + k as f64 * 1e-3, &[f64::NAN], None);
    }
    // A new page first gets the state current when it connected, then the newest.
    let (mut t, mut q) = next_state(&mut other);
    if t < 1.0 {
        (t, q) = next_state(&mut other);
    }
    assert!(
        t > 1.0 && q[0].is_none(),
        "NaN arrives as null (not known): {t} {q:?}"
    );
    assert_eq!(get(addr, "/").0, 200);
    drop(stalled);
    feed.close();
}

#[test]
fn following_a_csv_as_it_is_written_publishes_its_newest_row() {
    let dir = std::env::temp_dir().join(format!("twinloop-view-follow-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("run.csv");
    let _ = std::fs::remove_file(&csv);
    let feed = twinloop_view::LiveFeed::new();
    let addr = start(live_content(&feed));
    let mut ws = live_socket(addr);
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let follower = {
        let (csv, feed, stop) = (csv.clone(), feed.clone(), stop.clone());
        std::thread::spawn(move || {
            let joints = ["shoulder".to_string()];
            twinloop_view::follow_csv(&csv, &joints, 1000.0, &feed, &|| {
                stop.load(std::sync::atomic::Ordering::Relaxed)
            })
        })
    };
    // The file appears after the follower started; rows come in pieces.
    std::thread::sleep(Duration::from_millis(100));
    let mut f = std::fs::File::create(&csv).unwrap();
    write!(f, "t,q:base.x,q:shoulder\n0,0,0.25\n0.5,0,0.").unwrap();
    f.flush().unwrap();
    let (t, q) = next_state(&mut ws);
    assert_eq!((t, q[0]), (0.0, Some(0.25)));
    std::thread::sleep(Duration::from_millis(50));
    writeln!(f, "75").unwrap();
    f.flush().unwrap();
    let (t, q) = next_state(&mut ws);
    assert_eq!(
        (t, q[0]),
        (0.5, Some(0.75)),
        "the half-written row waits for its end"
    );
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    follower.join().unwrap().unwrap();
    let _ = std::fs::remove_dir_all(dir);
}
