//! The official ROBOTIS SDK (PyPI `dynamixel-sdk` 4.1.0) doing what its example
//! programs do (indirect addressing, clear multi-turn, factory reset, Protocol 1.0
//! on X servos; tools/oracle/dynamixel_sdk_examples.py) against a virtual bus served
//! on a pty as `twinloop serve` serves it: the mapping's protocols and the line's
//! Baud Rate codes configured, wire time emulated at 1 Mbps.
//!
//! Skips, with a note, when Python or the SDK is missing; with
//! TWINLOOP_REQUIRE_ORACLES=1 (set by .ci/run) that fails instead. Python is
//! $TWINLOOP_PYTHON, else the repository's .venv, else python3.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use twinloop_link::servo::{ServeOptions, serve};
use twinloop_link::transport::PtyTransport;
use twinloop_link::{RobotMapping, VirtualBus};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A Python that imports `dynamixel_sdk`, or why there is none.
fn python_with_sdk() -> Result<String, String> {
    let mut candidates = Vec::new();
    if let Ok(p) = std::env::var("TWINLOOP_PYTHON") {
        candidates.push(p);
    }
    let venv = repo().join(".venv/bin/python");
    if venv.exists() {
        candidates.push(venv.to_string_lossy().into_owned());
    }
    candidates.push("python3".into());
    let mut notes = Vec::new();
    for py in candidates {
        match Command::new(&py)
            .args(["-c", "import dynamixel_sdk"])
            .stderr(Stdio::null())
            .status()
        {
            Ok(s) if s.success() => return Ok(py),
            Ok(_) => notes.push(format!("{py}: no dynamixel_sdk module")),
            Err(e) => notes.push(format!("{py}: {e}")),
        }
    }
    Err(notes.join("; "))
}

#[test]
fn official_sdk_examples_against_a_served_bus() {
    let py = match python_with_sdk() {
        Ok(py) => py,
        Err(why) => {
            assert!(
                std::env::var("TWINLOOP_REQUIRE_ORACLES").as_deref() != Ok("1"),
                "TWINLOOP_REQUIRE_ORACLES=1 but no Python with dynamixel-sdk: {why}"
            );
            eprintln!(
                "SKIPPED official_sdk_examples_against_a_served_bus: no Python with dynamixel-sdk \
                 ({why}); `pip install dynamixel-sdk==4.1.0` or set TWINLOOP_PYTHON to run it"
            );
            return;
        }
    };
    let oracle = repo().join("tools/oracle");
    let mapping = RobotMapping::load(oracle.join("sdk_examples_bus.toml")).unwrap();
    let mut pty = PtyTransport::open().unwrap();
    let path = pty.path().display().to_string();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let server = std::thread::spawn(move || {
        let mut bus = VirtualBus::with_tracking_model(&mapping.bus());
        mapping.configure(&mut bus, 1_000_000);
        let options = ServeOptions {
            emulate_baud: Some(1_000_000),
            stop_on_eof: false,
            ..Default::default()
        };
        serve(&mut bus, &mut pty, &options, &flag).unwrap();
    });
    let out = Command::new(&py)
        .arg(oracle.join("dynamixel_sdk_examples.py"))
        .args(["--port", &path])
        .current_dir(&oracle)
        .output()
        .unwrap();
    stop.store(true, Ordering::Relaxed);
    server.join().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "SDK examples failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains(" passed, 0 failed"), "{stdout}");
}
