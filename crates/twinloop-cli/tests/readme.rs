//! The README's examples run as written (issue 17): every line of every ```sh block
//! of README.md runs, in order, in a temporary folder holding the repository's
//! models, with this build's `twinloop` first on PATH. A non-zero exit fails the
//! test unless the line's comment announces it ("(exit 1)"). A line ending in `&`
//! starts a server in the background: it runs until its first line of output (the
//! address it serves) and is stopped after the block. `cargo run --release -p
//! twinloop-cli -- ARGS` is the same program as `twinloop ARGS` and runs as that.
//! Skipped, and listed in the output: `cargo test` (this test is part of it) and
//! lines that need hardware (a serial adapter).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The command lines of the ```sh blocks of a Markdown text, with their 1-based
/// line numbers; `\` continuations joined.
fn sh_lines(markdown: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_block = false;
    let mut pending: Option<(usize, String)> = None;
    for (i, line) in markdown.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            in_block = !in_block && trimmed == "```sh";
            continue;
        }
        if !in_block || (pending.is_none() && (trimmed.is_empty() || trimmed.starts_with('#'))) {
            continue;
        }
        let (n, mut text) = pending.take().unwrap_or((i + 1, String::new()));
        text.push_str(trimmed.trim_end_matches('\\').trim_end());
        if trimmed.ends_with('\\') {
            text.push(' ');
            pending = Some((n, text));
        } else {
            out.push((n, text));
        }
    }
    out
}

/// The command and its comment: the first ` #` outside quotes starts the comment.
fn split_comment(line: &str) -> (String, String) {
    let (mut single, mut double) = (false, false);
    let bytes: Vec<char> = line.chars().collect();
    for (k, &c) in bytes.iter().enumerate() {
        match c {
            '\'' if !double => single = !single,
            '"' if !single => double = !double,
            '#' if !single && !double && (k == 0 || bytes[k - 1].is_whitespace()) => {
                let cmd: String = bytes[..k].iter().collect();
                let comment: String = bytes[k + 1..].iter().collect();
                return (cmd.trim().to_string(), comment.trim().to_string());
            }
            _ => {}
        }
    }
    (line.trim().to_string(), String::new())
}

/// Why a line cannot run here, if it cannot.
fn skip_reason(cmd: &str) -> Option<&'static str> {
    if cmd.starts_with("cargo test") {
        return Some("the test suite itself (this test is part of it)");
    }
    if ["/dev/tty", "COM1", "--yes"]
        .iter()
        .any(|h| cmd.contains(h))
    {
        return Some("needs a robot on a serial adapter");
    }
    None
}

/// A shell running `cmd` in `dir` with `bin_dir` first on PATH.
fn shell(cmd: &str, dir: &Path, bin_dir: &Path) -> Command {
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut dirs = vec![bin_dir.to_path_buf()];
    dirs.extend(std::env::split_paths(&path));
    let mut c = Command::new("sh");
    c.arg("-c")
        .arg(cmd)
        .current_dir(dir)
        .env("PATH", std::env::join_paths(dirs).unwrap());
    c
}

/// Wait for `child`, killing it after `limit`; its exit code (None: killed).
fn wait_for(child: &mut Child, limit: Duration) -> Option<i32> {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status.code();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn every_readme_example_runs_as_written() {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let lines = sh_lines(&readme);
    assert!(lines.len() >= 10, "only {} README lines found", lines.len());
    let dir = std::env::temp_dir().join(format!("twinloop-readme-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::os::unix::fs::symlink(
        repo().join("models").canonicalize().unwrap(),
        dir.join("models"),
    )
    .unwrap();
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_twinloop"));
    let bin_dir = bin.parent().unwrap();
    let mut servers: Vec<Child> = Vec::new();
    let (mut failures, mut skipped, mut ran) = (Vec::new(), Vec::new(), 0);
    for (n, line) in &lines {
        let (cmd, comment) = split_comment(line);
        let cmd = cmd.replace("cargo run --release -p twinloop-cli -- ", "twinloop ");
        if let Some(why) = skip_reason(&cmd) {
            skipped.push(format!("README.md:{n}: {cmd} ({why})"));
            continue;
        }
        ran += 1;
        if let Some(server) = cmd.strip_suffix('&') {
            // `exec`: the server is the child, so killing the child stops it.
            let mut child = shell(&format!("exec {}", server.trim()), &dir, bin_dir)
                .stdout(Stdio::piped())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            let mut first = String::new();
            BufReader::new(child.stdout.as_mut().unwrap())
                .read_line(&mut first)
                .unwrap();
            if first.trim().is_empty() {
                failures.push(format!("README.md:{n}: `{cmd}` served nothing"));
            }
            servers.push(child);
            continue;
        }
        // stderr to a file: a pipe nobody reads while waiting could fill and block.
        let err_path = dir.join(format!(".stderr-{n}"));
        let mut child = shell(&cmd, &dir, bin_dir)
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&err_path).unwrap())
            .spawn()
            .unwrap();
        let code = wait_for(&mut child, Duration::from_secs(600));
        let err = std::fs::read_to_string(&err_path).unwrap_or_default();
        let announced = |c: i32| c == 0 || comment.contains(&format!("(exit {c})"));
        match code {
            Some(c) if announced(c) => {}
            Some(c) => failures.push(format!(
                "README.md:{n}: `{cmd}` exited {c}: {}",
                err.lines()
                    .find(|l| l.starts_with("error"))
                    .or(err.lines().last())
                    .unwrap_or("")
            )),
            None => failures.push(format!("README.md:{n}: `{cmd}` still running after 600 s")),
        }
    }
    for mut s in servers {
        let _ = s.kill();
        let _ = s.wait();
    }
    println!("{ran} README lines ran; skipped:");
    for s in &skipped {
        println!("  {s}");
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn sh_blocks_are_read_like_a_shell() {
    let md = "x\n```sh\n# note\na --b \\\n  c   # say (exit 1)\n\nd '#x'\n```\n```text\ne\n```\n";
    let lines = sh_lines(md);
    assert_eq!(
        lines,
        [
            (4, "a --b c   # say (exit 1)".to_string()),
            (7, "d '#x'".to_string())
        ]
    );
    assert_eq!(
        split_comment(&lines[0].1),
        ("a --b c".to_string(), "say (exit 1)".to_string())
    );
    assert_eq!(
        split_comment("d '#x'"),
        ("d '#x'".to_string(), String::new())
    );
}
