//! `twinloop serve` in the background, for the tests that drive a served robot.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};

/// Start `twinloop serve ARGS`; returns the child and the pty path it printed.
pub fn serve(args: &[&str]) -> (Child, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_twinloop"))
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
