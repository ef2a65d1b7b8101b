//! A port that disappears mid-experiment (issue 17): the served virtual robot's pty or
//! TCP socket goes away in the middle of `experiment tipover --port`, `experiment lean
//! --port`, `experiment servo` (a limb of the held robot) and `link record`, as an unplugged USB adapter or a dropped network link
//! would. Each must end within a time limit with exit 2 and one `error:` line naming
//! the port, and the CSV it was recording must parse and hold every row the message
//! says was read.

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

/// How long a command may take to notice that its port is gone and stop.
const LIMIT: Duration = Duration::from_secs(20);

#[derive(Clone, Copy, Debug)]
enum Transport {
    Pty,
    Tcp,
}

/// `twinloop serve` km20 (the simulated robot; `extra` flags such as `--held`) on a
/// pty (behind the symlink `name`) or on a TCP port of the loopback; the child and
/// the port to hand to clients.
fn serve(transport: Transport, name: &str, extra: &[&str]) -> (Child, String) {
    let mut cmd = Command::new(bin());
    cmd.args(["serve", "--robot", "builtin:km20"]).args(extra);
    match transport {
        Transport::Pty => {
            let link = scratch(name);
            let _ = std::fs::remove_file(&link);
            cmd.arg("--link").arg(&link);
        }
        Transport::Tcp => {
            cmd.args(["--port", "tcp:127.0.0.1:0"]);
        }
    }
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.as_mut().unwrap())
        .read_line(&mut line)
        .unwrap();
    let port = match transport {
        Transport::Pty => scratch(name).to_str().unwrap().to_string(),
        Transport::Tcp => line.trim().to_string(),
    };
    (child, port)
}

/// Run `args` against a served robot, take the robot away after `after`, and check
/// how the command ends; `record` is the CSV it records. The robot is served with
/// `serve_extra` besides.
fn unplug_mid_run(
    transport: Transport,
    what: &str,
    serve_extra: &[&str],
    args: &[&str],
    after: Duration,
    record: &Path,
) {
    // One served robot at a time: each simulates km20 in real time, and two cores
    // running six would make "mid-experiment" a matter of luck.
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (mut server, port) = serve(
        transport,
        &format!("{what}-{transport:?}-link"),
        serve_extra,
    );
    let _ = std::fs::remove_file(record);
    // A second output (the lean's own CSV beside its raw record).
    let out = scratch(&format!("gone-{what}-{transport:?}-out.csv"));
    let _ = std::fs::remove_file(&out);
    let args: Vec<String> = args
        .iter()
        .map(|a| match *a {
            "{port}" => port.clone(),
            "{out}" => out.to_str().unwrap().to_string(),
            _ => a.to_string(),
        })
        .collect();
    let mut child = Command::new(bin())
        .args(&args)
        .arg(record)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(after);
    // Still running: the port goes away in the middle, not after the end.
    if child.try_wait().unwrap().is_some() {
        let mut err = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        panic!("{what} over {transport:?} ended before the port went away: {err}");
    }
    server.kill().unwrap();
    server.wait().unwrap();
    let t0 = Instant::now();
    let code = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s.code();
        }
        if t0.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "{what} over {transport:?}: still running {} s after its port went away",
                LIMIT.as_secs()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let took = t0.elapsed();
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    eprintln!(
        "{what} over {transport:?}: stopped {} ms after the port went away:\n{err}",
        took.as_millis()
    );
    assert_eq!(code, Some(2), "{what} over {transport:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{what} over {transport:?}: {err}");
    assert!(
        errors[0].contains(&port),
        "{what} over {transport:?}: the error does not name the port {port}: {}",
        errors[0]
    );
    // Every row read is in the file, which parses; the message says how many.
    let table = twinloop_io::Table::read(record)
        .unwrap_or_else(|e| panic!("{what} over {transport:?}: the record: {e}"));
    assert!(
        table.rows.len() >= 5,
        "{what} over {transport:?}: {} rows",
        table.rows.len()
    );
    assert!(
        err.contains(&format!("{} rows", table.rows.len())),
        "{what} over {transport:?}: the file has {} rows: {err}",
        table.rows.len()
    );
    if args.iter().any(|a| a == "{out}") {
        let t = twinloop_io::Table::read(&out)
            .unwrap_or_else(|e| panic!("{what} over {transport:?}: --out: {e}"));
        assert!(
            !t.rows.is_empty(),
            "{what} over {transport:?}: --out is empty"
        );
    }
}

const TIPOVER: &[&str] = &[
    "experiment",
    "tipover",
    "--port",
    "{port}",
    "--map",
    "builtin:km20",
    // A loaded test machine can be slow to answer: this test is about the port
    // going away, not about a servo's timeout.
    "--timeout-ms",
    "50",
    "--retries",
    "3",
    "--directions",
    "forward",
    "--ramp",
    "5",
    "--record",
];

const LEAN: &[&str] = &[
    "experiment",
    "lean",
    "--port",
    "{port}",
    "--map",
    "builtin:km20",
    // A loaded test machine can be slow to answer: this test is about the port
    // going away, not about a servo's timeout.
    "--timeout-ms",
    "50",
    "--retries",
    "3",
    "--amplitude",
    "3",
    "--ramp",
    "4",
    "--hold",
    "1",
    "--settle",
    "1",
    "--out",
    "{out}",
    "--record",
];

const RECORD: &[&str] = &[
    "link",
    "record",
    "--port",
    "{port}",
    "--map",
    "builtin:km20",
    // A loaded test machine can be slow to answer: this test is about the port
    // going away, not about a servo's timeout.
    "--timeout-ms",
    "50",
    "--retries",
    "3",
    "--duration",
    "60",
    "--out",
];

// The tip-over stands 1 s and settles 1 s before its ramp: 3 s in is mid-ramp. The
// lean stands and settles as long before its ramp.
#[test]
fn a_pty_that_disappears_mid_tipover_stops_it_naming_the_port() {
    let record = scratch("gone-tipover-pty.csv");
    unplug_mid_run(
        Transport::Pty,
        "tipover",
        &[],
        TIPOVER,
        Duration::from_secs(3),
        &record,
    );
}

#[test]
fn a_socket_that_disappears_mid_tipover_stops_it_naming_the_port() {
    let record = scratch("gone-tipover-tcp.csv");
    unplug_mid_run(
        Transport::Tcp,
        "tipover",
        &[],
        TIPOVER,
        Duration::from_secs(3),
        &record,
    );
}

#[test]
fn a_pty_that_disappears_mid_lean_stops_it_naming_the_port() {
    let record = scratch("gone-lean-pty.csv");
    unplug_mid_run(
        Transport::Pty,
        "lean",
        &[],
        LEAN,
        Duration::from_secs(3),
        &record,
    );
}

#[test]
fn a_socket_that_disappears_mid_lean_stops_it_naming_the_port() {
    let record = scratch("gone-lean-tcp.csv");
    unplug_mid_run(
        Transport::Tcp,
        "lean",
        &[],
        LEAN,
        Duration::from_secs(3),
        &record,
    );
}

#[test]
fn a_pty_that_disappears_mid_recording_stops_it_naming_the_port() {
    let record = scratch("gone-record-pty.csv");
    unplug_mid_run(
        Transport::Pty,
        "record",
        &[],
        RECORD,
        Duration::from_millis(1500),
        &record,
    );
}

#[test]
fn a_socket_that_disappears_mid_recording_stops_it_naming_the_port() {
    let record = scratch("gone-record-tcp.csv");
    unplug_mid_run(
        Transport::Tcp,
        "record",
        &[],
        RECORD,
        Duration::from_millis(1500),
        &record,
    );
}

/// A limb of the held robot (`serve --held`): the right hip swings the leg.
const SERVO: &[&str] = &[
    "experiment",
    "servo",
    "--port",
    "{port}",
    "--map",
    "builtin:km20",
    "--joint",
    "r_hip_pitch",
    // A loaded test machine can be slow to answer: this test is about the port
    // going away, not about a servo's timeout.
    "--timeout-ms",
    "50",
    "--retries",
    "3",
    "--out",
];

// The servo sequence starts at once (its first step is 0.8 rad): 2 s in is mid-run.
#[test]
fn a_pty_that_disappears_mid_servo_run_stops_it_naming_the_port() {
    let record = scratch("gone-servo-pty.csv");
    unplug_mid_run(
        Transport::Pty,
        "servo",
        &["--held"],
        SERVO,
        Duration::from_secs(2),
        &record,
    );
}

#[test]
fn a_socket_that_disappears_mid_servo_run_stops_it_naming_the_port() {
    let record = scratch("gone-servo-tcp.csv");
    unplug_mid_run(
        Transport::Tcp,
        "servo",
        &["--held"],
        SERVO,
        Duration::from_secs(2),
        &record,
    );
}
