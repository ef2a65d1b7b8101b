//! For the tests that check twinloop's files with the reference libraries
//! (twinloop-logs' `python_readback`, the CLI's `cli_logs` and `cli_adapt`, which
//! include this file): a Python that imports some modules ($TWINLOOP_PYTHON, else
//! the repository's .venv, else python3; None, skip with a note, when none imports
//! them; with TWINLOOP_REQUIRE_ORACLES=1, set by .ci/run, that fails the test
//! instead), and an MCAP read back by `mcap` + `mcap-ros2-support`.
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The repository: two folders above any crate's manifest.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A Python that imports `modules`, or skip (fail under TWINLOOP_REQUIRE_ORACLES=1).
pub fn python_with(modules: &str, test: &str) -> Option<String> {
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
            .args(["-c", &format!("import {modules}")])
            .stderr(Stdio::null())
            .status()
        {
            Ok(s) if s.success() => return Some(py),
            Ok(_) => notes.push(format!("{py}: cannot import {modules}")),
            Err(e) => notes.push(format!("{py}: {e}")),
        }
    }
    let why = notes.join("; ");
    assert!(
        std::env::var("TWINLOOP_REQUIRE_ORACLES").as_deref() != Ok("1"),
        "TWINLOOP_REQUIRE_ORACLES=1 but no Python with {modules}: {why}"
    );
    eprintln!("SKIPPED {test}: {why}; pip install the versions .ci/run pins to run it");
    None
}

/// What the reference libraries read from the MCAP at `path`
/// (tools/oracle/logs_readback.py: `mcap` + `mcap-ros2-support`): topics with their
/// schemas, counts and decoded rows (f64 as their bits in hex), attachments and
/// metadata. `py` is a Python that imports `mcap, mcap_ros2` ([`python_with`]).
pub fn mcap_readback(py: &str, path: &Path) -> serde_json::Value {
    let out = Command::new(py)
        .arg(repo().join("tools/oracle/logs_readback.py"))
        .arg(path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "logs_readback.py {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}
