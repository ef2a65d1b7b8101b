//! The official ROBOTIS SDK (PyPI `dynamixel-sdk`) as a client of `twinloop serve`:
//! runs tools/oracle/dynamixel_sdk_conformance.py against a served virtual robot.
//! Skips, with a note, when Python or the SDK is missing, so `cargo test` needs
//! only Rust; with TWINLOOP_REQUIRE_ORACLES=1 (set by .ci/run) a missing SDK fails
//! the test instead, so CI cannot pass without running it. Python is
//! $TWINLOOP_PYTHON, else the repository's .venv, else python3.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

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
fn official_sdk_against_twinloop_serve() {
    let py = match python_with_sdk() {
        Ok(py) => py,
        Err(why) => {
            assert!(
                std::env::var("TWINLOOP_REQUIRE_ORACLES").as_deref() != Ok("1"),
                "TWINLOOP_REQUIRE_ORACLES=1 but no Python with dynamixel-sdk: {why}"
            );
            eprintln!(
                "SKIPPED official_sdk_against_twinloop_serve: no Python with dynamixel-sdk ({why}); \
                 `pip install dynamixel-sdk==4.1.0` or set TWINLOOP_PYTHON to run it"
            );
            return;
        }
    };
    let mut server = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["serve", "--map"])
        .arg(repo().join("tools/oracle/sdk_bus.toml"))
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut pty = String::new();
    BufReader::new(server.stdout.as_mut().unwrap())
        .read_line(&mut pty)
        .unwrap();
    let out = Command::new(&py)
        .arg(repo().join("tools/oracle/dynamixel_sdk_conformance.py"))
        .args(["--port", pty.trim()])
        .output()
        .unwrap();
    server.kill().unwrap();
    server.wait().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "SDK conformance failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains(" passed, 0 failed"), "{stdout}");
}
