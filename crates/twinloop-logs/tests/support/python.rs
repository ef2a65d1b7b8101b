//! A Python that imports some modules, for the tests that check twinloop's files
//! with the reference libraries (twinloop-logs' `python_readback`, the CLI's
//! `cli_logs`): $TWINLOOP_PYTHON, else the repository's .venv, else python3. None
//! (skip, with a note) when none imports them; with TWINLOOP_REQUIRE_ORACLES=1
//! (set by .ci/run) that fails the test instead.
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
