//! The layering of docs/architecture.md, checked against the code: every crate's
//! dependencies (normal and dev) point only to crates listed above it in the page's
//! crate table, the "depends on" column lists exactly its normal twinloop
//! dependencies, and no crate has an import cycle between its source files.

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

/// Modules of one crate and the modules each one uses (`crate::m`, `super::m` from a
/// top-level module), by file: `src/a.rs` and `src/a/mod.rs` are module `a`, files
/// under `src/a/` belong to `a`.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
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
    walk(src, &mut files);
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
        let text = std::fs::read_to_string(f).unwrap();
        let text: String = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        // Tests may reach anywhere in their crate.
        let text = text.split("#[cfg(test)]").next().unwrap();
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
