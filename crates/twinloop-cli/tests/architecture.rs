//! The layering of docs/architecture.md, checked against the code: every crate's
//! dependencies (normal and dev) point only to crates listed above it in the page's
//! crate table, the "depends on" column lists exactly its normal twinloop
//! dependencies, and no crate has an import cycle between its source files. The two
//! front ends on top, the CLI and the Python package (python/src), are held to the
//! same: their dependencies are crates of the table, their files have no import
//! cycle, and both stay thin (the loop's workflows are called there, not written);
//! no CLI command module imports another.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The crate table of docs/architecture.md: (crate, documented dependencies), in order.
fn documented_layers() -> Vec<(String, BTreeSet<String>)> {
    let page = std::fs::read_to_string(repo().join("docs/architecture.md")).unwrap();
    let mut rows = Vec::new();
    for line in page.lines() {
        let Some(rest) = line.strip_prefix("| `twinloop-") else {
            continue;
        };
        let name = format!("twinloop-{}", &rest[..rest.find('`').unwrap()]);
        let deps_cell = line
            .trim_end_matches('|')
            .rsplit('|')
            .next()
            .unwrap()
            .trim();
        let deps = match deps_cell {
            "nothing" => BTreeSet::new(),
            "everything above" => rows
                .iter()
                .map(|(n, _): &(String, BTreeSet<String>)| n.clone())
                .collect(),
            cell => cell
                .split(',')
                .map(|d| format!("twinloop-{}", d.trim()))
                .collect(),
        };
        rows.push((name, deps));
    }
    rows
}

/// The twinloop crates a Cargo.toml names in [dependencies] and in [dev-dependencies].
fn manifest_dependencies(manifest: &Path) -> (BTreeSet<String>, BTreeSet<String>) {
    let text = std::fs::read_to_string(manifest).unwrap();
    let (mut normal, mut dev) = (BTreeSet::new(), BTreeSet::new());
    let mut section = String::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            section = line.to_string();
        } else if let Some(name) = line.split(['.', ' ', '=']).next()
            && name.starts_with("twinloop-")
        {
            match section.as_str() {
                "[dependencies]" => normal.insert(name.to_string()),
                "[dev-dependencies]" => dev.insert(name.to_string()),
                _ => false,
            };
        }
    }
    (normal, dev)
}

#[test]
fn crates_depend_only_on_crates_below_them_as_the_architecture_page_says() {
    let layers = documented_layers();
    assert!(layers.len() >= 15, "crate table not found: {layers:?}");
    let on_disk: BTreeSet<String> = std::fs::read_dir(repo().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let listed: BTreeSet<String> = layers.iter().map(|(n, _)| n.clone()).collect();
    assert_eq!(on_disk, listed, "crates on disk vs the page's table");
    let rank: BTreeMap<&str, usize> = layers
        .iter()
        .enumerate()
        .map(|(i, (n, _))| (n.as_str(), i))
        .collect();
    for (name, documented) in &layers {
        let (normal, dev) =
            manifest_dependencies(&repo().join("crates").join(name).join("Cargo.toml"));
        for d in normal.iter().chain(&dev) {
            assert!(
                rank[d.as_str()] < rank[name.as_str()],
                "{name} depends on {d}, which docs/architecture.md lists below it"
            );
        }
        if name != "twinloop-cli" {
            assert_eq!(
                &normal, documented,
                "{name}: Cargo.toml vs docs/architecture.md"
            );
        }
    }
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    walk(dir, &mut files);
    files.sort();
    files
}

/// A source file's code: comment lines dropped, and nothing from its first
/// `#[cfg(test)]` on (tests may reach anywhere in their crate).
fn code_of(file: &Path) -> String {
    let text = std::fs::read_to_string(file).unwrap();
    let text: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    text.split("#[cfg(test)]").next().unwrap().to_string()
}

/// Modules of one crate and the modules each one uses (`crate::m`, `super::m` from a
/// top-level module), by file: `src/a.rs` and `src/a/mod.rs` are module `a`, files
/// under `src/a/` belong to `a`.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let files = rust_files(src);
    let top = |p: &Path| -> Option<String> {
        let rel = p.strip_prefix(src).unwrap();
        let first = rel
            .components()
            .next()?
            .as_os_str()
            .to_string_lossy()
            .into_owned();
        let m = first.trim_end_matches(".rs").to_string();
        (m != "lib" && m != "main").then_some(m)
    };
    let modules: BTreeSet<String> = files.iter().filter_map(|p| top(p)).collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in &files {
        let Some(from) = top(f) else { continue };
        let text = code_of(f);
        let text = text.as_str();
        let nested = f.strip_prefix(src).unwrap().components().count() > 1;
        for m in &modules {
            if *m == from {
                continue;
            }
            let via_super = !nested && text.contains(&format!("super::{m}"));
            let via_crate = text.contains(&format!("crate::{m}::"))
                || text.contains(&format!("crate::{m};"))
                || text.contains(&format!("crate::{m}}}"))
                || text.contains(&format!("crate::{m},"))
                || text.contains(&format!("crate::{{{m}"));
            if via_super || via_crate {
                graph.entry(from.clone()).or_default().insert(m.clone());
            }
        }
    }
    graph
}

fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for m in g.get(n).into_iter().flatten() {
            match state.get(m.as_str()) {
                Some(1) => {
                    let i = stack.iter().position(|s| s == m).unwrap();
                    let mut c = stack[i..].to_vec();
                    c.push(m.clone());
                    return Some(c);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(m, g, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        if !state.contains_key(n)
            && let Some(c) = visit(n, graph, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

#[test]
fn no_crate_has_an_import_cycle_between_its_files() {
    for (name, _) in documented_layers() {
        let graph = module_graph(&repo().join("crates").join(&name).join("src"));
        if let Some(cycle) = find_cycle(&graph) {
            panic!("{name}: import cycle {}", cycle.join(" -> "));
        }
    }
}

#[test]
fn the_cycle_finder_finds_a_cycle() {
    let g: BTreeMap<String, BTreeSet<String>> = [
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec!["a"]),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.into_iter().map(String::from).collect()))
    .collect();
    assert_eq!(find_cycle(&g).unwrap(), ["a", "b", "c", "a"]);
    let mut acyclic = g.clone();
    acyclic.get_mut("c").unwrap().clear();
    assert!(find_cycle(&acyclic).is_none());
}

#[test]
fn the_python_package_depends_on_documented_crates_and_has_no_import_cycle() {
    let listed: BTreeSet<String> = documented_layers().into_iter().map(|(n, _)| n).collect();
    let (normal, dev) = manifest_dependencies(&repo().join("python/Cargo.toml"));
    for d in normal.iter().chain(&dev) {
        assert!(
            listed.contains(d),
            "python depends on {d}, which docs/architecture.md does not list"
        );
    }
    assert!(normal.contains("twinloop-loop"), "{normal:?}");
    let graph = module_graph(&repo().join("python/src"));
    assert!(!graph.is_empty(), "python/src: no module uses another");
    if let Some(cycle) = find_cycle(&graph) {
        panic!("python/src: import cycle {}", cycle.join(" -> "));
    }
}

/// What a front end must not write itself, and where it is written instead: the
/// steps of the tip-over over a bus, the protocol passes and standing a robot up.
const WORKFLOW_STEPS: [(&str, &str); 7] = [
    (
        "run_directions(",
        "fill a twinloop_loop::BusPlan and run it",
    ),
    (
        "bus_outcome(",
        "twinloop_loop::tipover_bus makes the report",
    ),
    ("BusTipoverOptions {", "fill a twinloop_loop::BusPlan"),
    (
        "BusProtocol {",
        "BusPlan::protocol keeps how a run measured",
    ),
    (
        "static_angles_at_onsets(",
        "twinloop_loop::protocol_bias runs the passes",
    ),
    (
        "Lockstep::new(",
        "twinloop_loop::tipover_bus::tipover_in_lockstep",
    ),
    (
        "contact_points().is_empty()",
        "Simulator::check_can_stand / standing_on_servos",
    ),
];

/// The workflow steps `files` write themselves, as `path: step (where it belongs)`.
fn workflow_steps_in(files: &[PathBuf]) -> Vec<String> {
    let mut found = Vec::new();
    for f in files {
        let code = code_of(f);
        for (step, instead) in WORKFLOW_STEPS {
            if code.contains(step) {
                found.push(format!("{}: {step} ({instead})", f.display()));
            }
        }
    }
    found
}

#[test]
fn the_cli_and_python_are_thin() {
    let mut files = rust_files(&repo().join("crates/twinloop-cli/src"));
    files.extend(rust_files(&repo().join("python/src")));
    assert!(files.len() > 20, "{files:?}");
    let found = workflow_steps_in(&files);
    assert!(
        found.is_empty(),
        "workflow written in a front end:\n{}",
        found.join("\n")
    );
    // The check sees a step where one is written.
    let probe = std::env::temp_dir().join(format!("twinloop-arch-probe-{}.rs", std::process::id()));
    std::fs::write(
        &probe,
        "fn f() { let o = BusTipoverOptions { creeps: 2 }; }\n",
    )
    .unwrap();
    let seen = workflow_steps_in(std::slice::from_ref(&probe));
    std::fs::remove_file(&probe).unwrap();
    assert_eq!(seen.len(), 1, "{seen:?}");
}

#[test]
fn no_cli_command_module_imports_another() {
    let graph = module_graph(&repo().join("crates/twinloop-cli/src"));
    let command = |m: &str| m.starts_with("cmd_");
    let crossing: Vec<String> = graph
        .iter()
        .filter(|(from, _)| command(from))
        .flat_map(|(from, to)| {
            to.iter()
                .filter(|m| command(m))
                .map(move |m| format!("{from} -> {m}"))
        })
        .collect();
    assert!(
        crossing.is_empty(),
        "CLI command modules importing one another (move the shared code to twinloop-loop \
         or a non-command module): {crossing:?}"
    );
    // The graph does see command modules' imports of shared modules.
    assert!(
        graph["cmd_demo"].contains("bus_args"),
        "{:?}",
        graph["cmd_demo"]
    );
}

/// The fuzz crate has its own lock file, built `--locked` in CI: a new path dependency of
/// a fuzzed crate must be written into it here, not discovered 25 minutes into CI.
#[test]
fn the_fuzz_lock_file_holds_every_dependency() {
    let out = std::process::Command::new(env!("CARGO"))
        .args(["metadata", "--locked", "--offline", "--format-version", "1"])
        .arg("--manifest-path")
        .arg(repo().join("fuzz/Cargo.toml"))
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "fuzz/Cargo.lock is out of date (run `cargo metadata --offline --manifest-path fuzz/Cargo.toml` and commit it): {}",
        String::from_utf8_lossy(&out.stderr)
    );
}
