//! The documentation's examples run as written (issue 17): every line of every ```sh
//! block of README.md and docs/*.md runs, in order, each file in its own temporary
//! folder holding the repository's `models/`, `examples/` (the small inputs the
//! examples name) and `crates/`, with this build's `twinloop` first on PATH. A line
//! must exit 0, or exactly the code its comment announces ("(exit 1)": then exit 0
//! fails too, so an example of a failing check cannot pass by finding nothing). A line
//! ending in `&` starts a server in the background: it runs until its first line of
//! output (the address it serves) and is stopped after the file. `cd DIR` moves the
//! later lines of the file. A `/tmp/NAME` path (the virtual bus of `twinloop serve`) is
//! made private to the file's folder, so that two files run side by side. `cargo run --release -p twinloop-cli -- ARGS` is the same
//! program as `twinloop ARGS` and runs as that.
//!
//! Not run, and listed in the output: `cargo test` (this test is part of it), `cargo
//! build` (the binary is built), other `cargo run` lines (they build another program),
//! and a block right after an HTML comment `<!-- not run by tests: WHY -->` (a robot on a
//! serial adapter, say). Every other block must run: a line that needs hardware and is
//! not so marked fails here. A fenced block that is not labelled `sh` but holds a
//! command line (`twinloop`, `cargo`, `python3`, `bash`, ...) fails
//! `command_blocks_are_labelled_sh`: an unlabelled example would never run.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// What marks a block the tests do not run; the reason follows it.
const NOT_RUN: &str = "<!-- not run by tests:";

/// One command line of a ```sh block: its 1-based line number, the text (`\`
/// continuations joined), and why it is not run (a marked block), if it is not.
#[derive(Debug, PartialEq)]
struct ShLine {
    n: usize,
    text: String,
    not_run: Option<String>,
}

/// The command lines of the ```sh blocks of a Markdown text.
fn sh_lines(markdown: &str) -> Vec<ShLine> {
    let mut out = Vec::new();
    let mut in_block = false;
    let mut not_run: Option<String> = None;
    let mut last_text = "";
    let mut pending: Option<(usize, String)> = None;
    for (i, line) in markdown.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            let opens = !in_block && trimmed == "```sh";
            not_run = if opens {
                last_text
                    .strip_prefix(NOT_RUN)
                    .map(|r| r.trim_end_matches("-->").trim().to_string())
            } else {
                None
            };
            in_block = opens;
            last_text = trimmed;
            continue;
        }
        if !in_block {
            if !trimmed.is_empty() {
                last_text = trimmed;
            }
            continue;
        }
        if pending.is_none() && (trimmed.is_empty() || trimmed.starts_with('#')) {
            continue;
        }
        let (n, mut text) = pending.take().unwrap_or((i + 1, String::new()));
        text.push_str(trimmed.trim_end_matches('\\').trim_end());
        if trimmed.ends_with('\\') {
            text.push(' ');
            pending = Some((n, text));
        } else {
            out.push(ShLine {
                n,
                text,
                not_run: not_run.clone(),
            });
        }
    }
    out
}

/// The programs a documented command line starts with (after any `NAME=VALUE`
/// environment settings and a `$ ` prompt).
const COMMANDS: &[&str] = &[
    "twinloop", "cargo", "python3", "python", "bash", "sh", "pip", "pip3", "maturin", "cd",
    "export", "git", "curl", "mkdir", "printf", "echo", "cp", "mv", "rm",
];

/// Whether a line of a fenced block reads as a command line.
fn is_command(line: &str) -> bool {
    let line = line.trim();
    let line = line.strip_prefix("$ ").unwrap_or(line);
    let first = line
        .split_whitespace()
        .find(|w| !w.contains('=') || w.starts_with('-'))
        .unwrap_or("");
    COMMANDS.contains(&first)
}

/// Fenced blocks not labelled `sh` that hold a command line: (1-based line of the
/// fence, its label, the first command line).
fn unlabelled_command_blocks(markdown: &str) -> Vec<(usize, String, String)> {
    let mut out = Vec::new();
    let mut open: Option<(usize, String)> = None;
    let mut found = false;
    for (i, line) in markdown.lines().enumerate() {
        let trimmed = line.trim();
        if let Some(label) = trimmed.strip_prefix("```") {
            match open {
                None => {
                    open = Some((i + 1, label.trim().to_string()));
                    found = false;
                }
                Some(_) => open = None,
            }
            continue;
        }
        if let Some((at, label)) = &open
            && label != "sh"
            && !found
            && is_command(trimmed)
        {
            found = true;
            out.push((*at, label.clone(), trimmed.to_string()));
        }
    }
    out
}

/// The exit code a line's comment announces ("(exit 1)"), if any.
fn announced_exit(comment: &str) -> Option<i32> {
    let rest = comment.split("(exit ").nth(1)?;
    rest.split(')').next()?.trim().parse().ok()
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

/// Why a (translated) line is not run here, if it is not.
fn skip_reason(cmd: &str) -> Option<&'static str> {
    if cmd.starts_with("cargo test") {
        return Some("the test suite itself (this test is part of it)");
    }
    if cmd.starts_with("cargo build") {
        return Some("the build (this test runs the built binary)");
    }
    if cmd.starts_with("cargo ") {
        return Some("builds and runs another program");
    }
    if cmd.starts_with("bash python/test.sh") {
        return Some("the Python package's test suite (CI runs it after this one)");
    }
    if cmd == "twinloop demo" {
        // Its 50-90 s on a live bus once, not twice: cli_demo.rs reads this line out
        // of README.md and runs it, adding only a seed, `--check` and where to write.
        return Some("run by cli_demo.rs's the_demo_finds_a_hidden_mass_over_the_bus");
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
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The longest any one documented line may take: the examples are sized to be tried,
/// and a hang must end. The longest were the README's demo (now run by cli_demo.rs):
/// under a minute on a quiet two-core machine, up to 100 s beside the other pages'
/// servers and builds (seen at load 5-10); the limit leaves any such line room.
const LINE_LIMIT: Duration = Duration::from_secs(150);

/// What running one Markdown file's lines gave.
#[derive(Default)]
struct Run {
    ran: usize,
    skipped: Vec<String>,
    failures: Vec<String>,
    /// Lines that took over 5 s: what to shrink when the test gets slow.
    slow: Vec<(f64, String)>,
}

/// A fresh folder with the repository's models, example inputs and crates linked in.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twinloop-docs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for sub in ["models", "examples", "crates"] {
        std::os::unix::fs::symlink(repo().join(sub).canonicalize().unwrap(), dir.join(sub))
            .unwrap();
    }
    dir
}

/// Start `cmd` (a line that ended in `&`) and wait for its first line of output.
fn start_server(cmd: &str, dir: &Path, bin_dir: &Path) -> (Child, bool) {
    // `exec`: the server is the child, so killing the child stops it.
    let mut child = shell(&format!("exec {cmd}"), dir, bin_dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.as_mut().unwrap())
        .read_line(&mut first)
        .unwrap();
    let served = !first.trim().is_empty();
    (child, served)
}

/// Run the ```sh lines of `file` (relative to the repository) in a fresh folder.
fn run_file(file: &str, bin_dir: &Path) -> Run {
    let text = std::fs::read_to_string(repo().join(file)).unwrap();
    let root = scratch(&file.replace('/', "_"));
    let mut dir = root.clone();
    let mut servers: Vec<Child> = Vec::new();
    let mut run = Run::default();
    for line in sh_lines(&text) {
        let n = line.n;
        let (cmd, comment) = split_comment(&line.text);
        let cmd = cmd
            .replace("cargo run --release -p twinloop-cli -- ", "twinloop ")
            .replace("/tmp/", &format!("{}/tmp-", root.display()));
        if let Some(why) = line.not_run.as_deref().or(skip_reason(&cmd)) {
            run.skipped.push(format!("{file}:{n}: {cmd} ({why})"));
            continue;
        }
        run.ran += 1;
        if let Some(to) = cmd.strip_prefix("cd ") {
            dir = dir.join(to.trim());
            continue;
        }
        if let Some(server) = cmd.strip_suffix('&') {
            let (child, served) = start_server(server.trim(), &dir, bin_dir);
            if !served {
                run.failures
                    .push(format!("{file}:{n}: `{cmd}` served nothing"));
            }
            servers.push(child);
            continue;
        }
        // stderr to a file: a pipe nobody reads while waiting could fill and block.
        let err_path = root.join(format!(".stderr-{n}"));
        let start = Instant::now();
        let mut child = shell(&cmd, &dir, bin_dir)
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&err_path).unwrap())
            .spawn()
            .unwrap();
        let code = wait_for(&mut child, LINE_LIMIT);
        let seconds = start.elapsed().as_secs_f64();
        if seconds > 5.0 {
            run.slow.push((seconds, format!("{file}:{n}")));
        }
        let err = std::fs::read_to_string(&err_path).unwrap_or_default();
        let expected = announced_exit(&comment).unwrap_or(0);
        match code {
            Some(c) if c == expected => {}
            Some(c) => run.failures.push(format!(
                "{file}:{n}: `{cmd}` exited {c}, not {expected}: {}",
                err.lines()
                    .find(|l| l.starts_with("error"))
                    .or(err.lines().last())
                    .unwrap_or("")
            )),
            None => run.failures.push(format!(
                "{file}:{n}: `{cmd}` still running after {} s",
                LINE_LIMIT.as_secs()
            )),
        }
    }
    for mut s in servers {
        let _ = s.kill();
        let _ = s.wait();
    }
    let _ = std::fs::remove_dir_all(&root);
    run
}

/// Whether a file's examples talk to a virtual bus in real time: a server started with
/// `&`, or the demo (its own bus inside).
fn drives_a_bus(file: &str) -> bool {
    let text = std::fs::read_to_string(repo().join(file)).unwrap();
    sh_lines(&text).iter().any(|l| {
        let (cmd, _) = split_comment(&l.text);
        cmd.ends_with('&') || cmd.contains(" demo")
    })
}

/// README.md and every docs/*.md with a ```sh block.
fn documented_files() -> Vec<String> {
    let mut files = vec!["README.md".to_string()];
    let mut docs: Vec<String> = std::fs::read_dir(repo().join("docs"))
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().into_string().unwrap();
            name.ends_with(".md").then(|| format!("docs/{name}"))
        })
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

#[test]
fn every_documented_example_runs_as_written() {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_twinloop"));
    let bin_dir = bin.parent().unwrap();
    let files = documented_files();
    let start = Instant::now();
    // Files that drive a virtual bus in real time (a server, the demo) run one at a
    // time after the others, which run two at a time (CI has two cores): a bus
    // starved of CPU misses its reply deadlines. Each file's lines stay in order.
    let (live, batch): (Vec<&String>, Vec<&String>) = files.iter().partition(|f| drives_a_bus(f));
    let runs = std::sync::Mutex::new(Vec::new());
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(file) = batch.get(k) else { break };
                    let r = run_file(file, bin_dir);
                    runs.lock().unwrap().push(r);
                }
            });
        }
    });
    for file in live {
        let r = run_file(file, bin_dir);
        runs.lock().unwrap().push(r);
    }
    let (mut ran, mut skipped, mut failures, mut slow) = (0, Vec::new(), Vec::new(), Vec::new());
    for r in runs.into_inner().unwrap() {
        ran += r.ran;
        skipped.extend(r.skipped);
        failures.extend(r.failures);
        slow.extend(r.slow);
    }
    slow.sort_by(|a, b| b.0.total_cmp(&a.0));
    println!(
        "{ran} documented lines of {} files ran in {:.1} s; over 5 s:",
        files.len(),
        start.elapsed().as_secs_f64()
    );
    for (t, at) in &slow {
        println!("  {t:.1} s  {at}");
    }
    skipped.sort();
    println!("not run:");
    for s in &skipped {
        println!("  {s}");
    }
    assert!(ran >= 40, "only {ran} documented lines ran");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Every example in the documentation is in a ```sh block, so that the test above
/// runs it (or its block says why not).
#[test]
fn command_blocks_are_labelled_sh() {
    let mut failures = Vec::new();
    for file in documented_files() {
        let text = std::fs::read_to_string(repo().join(&file)).unwrap();
        for (at, label, line) in unlabelled_command_blocks(&text) {
            failures.push(format!(
                "{file}:{at}: a ```{label} block holds a command line, `{line}`: label it \
                 ```sh (and mark it `{NOT_RUN} WHY -->` if it cannot run here)"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn command_lines_and_exit_codes_are_recognised() {
    let md = "```\ntwinloop a\n```\n```text\nwarning: x\n```\n```toml\nk = 1\n```\n\
              ```text\nsome output\nWINDOW=1,2 python3 x.py\n```\n```sh\ntwinloop b\n```\n";
    assert_eq!(
        unlabelled_command_blocks(md),
        [
            (1, String::new(), "twinloop a".to_string()),
            (
                10,
                "text".to_string(),
                "WINDOW=1,2 python3 x.py".to_string()
            ),
        ]
    );
    assert!(is_command("$ cargo test") && !is_command("twinloopish") && !is_command(""));
    assert_eq!(announced_exit("finds it (exit 1)"), Some(1));
    assert_eq!(announced_exit("a usage error (exit 2), named"), Some(2));
    assert_eq!(announced_exit("no code here"), None);
}

#[test]
fn sh_blocks_are_read_like_a_shell() {
    let md = "x\n```sh\n# note\na --b \\\n  c   # say (exit 1)\n\nd '#x'\n```\n```text\ne\n```\n\
              <!-- not run by tests: needs a robot -->\n\n```sh\nf\n```\n```sh\ng\n```\n";
    let lines = sh_lines(md);
    let plain = |n: usize, t: &str| ShLine {
        n,
        text: t.to_string(),
        not_run: None,
    };
    assert_eq!(
        lines,
        [
            plain(4, "a --b c   # say (exit 1)"),
            plain(7, "d '#x'"),
            ShLine {
                n: 15,
                text: "f".to_string(),
                not_run: Some("needs a robot".to_string())
            },
            plain(18, "g"),
        ]
    );
    assert_eq!(
        split_comment(&lines[0].text),
        ("a --b c".to_string(), "say (exit 1)".to_string())
    );
    assert_eq!(
        split_comment("d '#x'"),
        ("d '#x'".to_string(), String::new())
    );
}

/// Issue 30 item 8: the README's line that installs the Python package builds the
/// optimised wheel (`maturin develop` without `--release` built a debug package that
/// ran OP3's tip-over in 384 s against 2 s) and installs it with pip, which works in
/// or outside a virtualenv.
#[test]
fn readme_python_line_builds_and_installs_the_release_wheel() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md"))
        .expect("README.md");
    let lines: Vec<&str> = readme
        .lines()
        .filter(|l| l.contains("maturin ") && !l.contains('`'))
        .collect();
    assert!(!lines.is_empty(), "no maturin command in README.md");
    for line in lines {
        assert!(!line.contains("maturin develop"), "{line}");
        assert!(line.contains("maturin build --release"), "{line}");
        assert!(line.contains("pip install dist/twinloop-"), "{line}");
    }
}
