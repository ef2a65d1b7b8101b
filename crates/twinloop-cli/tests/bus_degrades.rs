//! A bus that degrades instead of breaking, and one owner per port (issue 28), as a
//! user meets them: the served robot's process stopped (SIGSTOP) for 3 s stops an
//! experiment within the silence window, naming a servo, every row kept; a host
//! stopped for half a second resumes; a second program on a port is told the port
//! is busy and by whom; a second TCP client is refused with a message.

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_twinloop")
}

fn scratch(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(name)
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// `twinloop serve` with `args`; the child and the first line it prints (the pty
/// path or tcp:ADDR).
fn serve(args: &[&str]) -> (Child, String) {
    let mut child = Command::new(bin())
        .arg("serve")
        .args(args)
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

fn signal(pid: u32, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &pid.to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill {sig} {pid}");
}

/// Wait for `child` at most `limit`; its exit code and stderr, and how long it took.
fn finish(mut child: Child, limit: Duration) -> (Option<i32>, String, Duration) {
    let t0 = Instant::now();
    let code = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s.code();
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let took = t0.elapsed();
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    (code, err, took)
}

/// The silence window (2 s, given: the default is 5) plus one read of km20's 21 servos that all
/// time out with their retries (21 x 3 x 10.2 ms): how long the host may take to
/// stop once the bus is silent. Checked against, with 0.5 s for a loaded machine.
const STOP_WITHIN: Duration = Duration::from_millis(2000 + 643 + 500);

#[test]
fn a_server_stopped_for_3_s_stops_the_tipover_naming_a_servo_with_every_row_kept() {
    let link = scratch("degrade-stopped-link");
    let _ = std::fs::remove_file(&link);
    let (mut server, _) = serve(&["--robot", "builtin:km20", "--link", link.to_str().unwrap()]);
    let record = scratch("degrade-stopped.csv");
    let _ = std::fs::remove_file(&record);
    let child = Command::new(bin())
        .args(["experiment", "tipover", "--port", link.to_str().unwrap()])
        .args(["--map", "builtin:km20", "--directions", "forward"])
        .args(["--ramp", "5", "--silence-window", "2", "--record"])
        .arg(&record)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Standing 1 s, the loop registers read and stiffened, settling 1 s, then the
    // ramp (5 deg/s to about 10 deg, then the creeps: seconds more): stop the server
    // mid-run, with room for a slow start on a loaded machine.
    std::thread::sleep(Duration::from_millis(4000));
    signal(server.id(), "-STOP");
    let stopped = Instant::now();
    let (code, err, _) = finish(child, Duration::from_secs(10));
    let took = stopped.elapsed();
    signal(server.id(), "-CONT");
    server.kill().unwrap();
    server.wait().unwrap();
    eprintln!("stopped {} ms after the server:\n{err}", took.as_millis());
    assert_eq!(code, Some(2), "{err}");
    assert!(took < STOP_WITHIN, "{took:?}: {err}");
    let last = err.lines().last().unwrap_or("");
    assert!(last.starts_with("error: servo id "), "{err}");
    assert!(last.contains("silence window (2 s)"), "{err}");
    assert!(last.contains("standing pose"), "{err}");
    // The retries and the missed reads are counted; every row is in the file, the
    // missed reads among them (NaN where a servo was silent).
    let bus = err.lines().find(|l| l.starts_with("bus: ")).expect(&err);
    let retries: u64 = bus
        .split(", ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(retries > 0, "{bus}");
    let table = twinloop_io::Table::read(&record).unwrap();
    assert!(err.contains(&format!("{} rows", table.rows.len())), "{err}");
    let q = table
        .columns
        .iter()
        .position(|c| c == "q:r_sho_pitch")
        .unwrap();
    let nan = table.rows.iter().filter(|r| r[q].is_nan()).count();
    assert!(nan >= 1, "{nan} NaN rows");
    assert!(table.rows.len() > nan + 20, "{} rows", table.rows.len());
}

#[test]
fn a_host_stopped_for_half_a_second_resumes() {
    let (mut server, pty) = serve(&["--robot", "builtin:km20"]);
    let out = scratch("degrade-host-paused.csv");
    let rec = Command::new(bin())
        .args(["link", "record", "--port", &pty, "--map", "builtin:km20"])
        .args(["--duration", "3", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1000));
    signal(rec.id(), "-STOP");
    std::thread::sleep(Duration::from_millis(500));
    signal(rec.id(), "-CONT");
    let (code, err, _) = finish(rec, Duration::from_secs(15));
    server.kill().unwrap();
    server.wait().unwrap();
    eprintln!("{err}");
    assert_eq!(code, Some(0), "{err}");
    let table = twinloop_io::Table::read(&out).unwrap();
    assert!(err.contains(&format!("{} rows", table.rows.len())), "{err}");
    // The rows on either side of the pause are half a second apart, and reads go on
    // after it.
    let gap = table
        .rows
        .windows(2)
        .map(|w| w[1][0] - w[0][0])
        .fold(0.0, f64::max);
    assert!(gap >= 0.45, "the longest gap between rows is {gap} s");
    let last = table.rows.last().unwrap()[0];
    assert!(last > 2.5, "the last row at {last} s");
    assert!(err.contains("bus: "), "{err}");
}

#[test]
fn a_second_link_read_on_a_port_is_told_it_is_busy_and_by_whom() {
    let (mut server, pty) = serve(&["--robot", "builtin:km20"]);
    // The first `link read` holds the port while it waits for a stopped server.
    signal(server.id(), "-STOP");
    let first = Command::new(bin())
        .args([
            "link",
            "read",
            "--port",
            &pty,
            "--protocol",
            "1",
            "--id",
            "1",
        ])
        .args(["--timeout-ms", "3000", "--retries", "0", "present position"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let o = Command::new(bin())
        .args([
            "link",
            "read",
            "--port",
            &pty,
            "--protocol",
            "1",
            "--id",
            "1",
        ])
        .arg("present position")
        .output()
        .unwrap();
    signal(server.id(), "-CONT");
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "port {pty} is busy: process {} (twinloop)",
            first.id()
        )),
        "{err}"
    );
    // The first one gets its reply once the server runs again.
    let o = first.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("Present Position"));
    // Both gone, the port is free.
    let o = Command::new(bin())
        .args([
            "link",
            "read",
            "--port",
            &pty,
            "--protocol",
            "1",
            "--id",
            "1",
        ])
        .arg("present position")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    server.kill().unwrap();
    server.wait().unwrap();
}

#[test]
fn a_second_tcp_client_is_refused_with_a_message() {
    let (mut server, addr) = serve(&[
        "--map",
        "builtin:op3",
        "--port",
        "tcp:127.0.0.1:0",
        "--no-timing",
    ]);
    let first = std::net::TcpStream::connect(addr.strip_prefix("tcp:").unwrap()).unwrap();
    // The server takes the first client before the second one comes.
    std::thread::sleep(Duration::from_millis(300));
    let read = || {
        Command::new(bin())
            .args([
                "link",
                "read",
                "--port",
                &addr,
                "--protocol",
                "2",
                "--id",
                "1",
            ])
            .arg("present position")
            .output()
            .unwrap()
    };
    let t0 = Instant::now();
    let o = read();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
    assert!(
        err.contains(&format!("{addr} is busy: another client (")),
        "{err}"
    );
    // The first client leaves: the next one is served.
    drop(first);
    let t0 = Instant::now();
    loop {
        let o = read();
        if o.status.success() {
            assert!(text(&o.stdout).contains("Present Position"));
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(5), "{}", text(&o.stderr));
        std::thread::sleep(Duration::from_millis(100));
    }
    server.kill().unwrap();
    server.wait().unwrap();
}
