//! `<include file="...">`: MuJoCo splices the children of the included file's
//! `<mujoco>` element in place of the `<include>`, wherever it stands (a section
//! of `<mujoco>`, a `<body>`, a `<default>`, ...: MuJoCo's XML reference,
//! "include"; MS-Human-700 includes its legs inside `<body name="pelvis">`).
//! Paths are relative to the directory of the main model file; included files
//! may include others.

use crate::error::DescriptionError;
use crate::xml::{error_at, parse_xml, read_text, required};
use roxmltree::{Document, Node};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Deepest chain of files including files (a guard against runaway nesting).
const MAX_DEPTH: usize = 32;

/// Most `<include>`s one model may splice, counting a file each time it is
/// included: 10 000, hundreds of times what real models use (MuJoCo Menagerie's
/// largest use a handful), so that files including each other twice over, 30 deep
/// (2^30 copies), are refused at once instead of read for ever.
const MAX_INCLUDES: usize = 10_000;

/// What the includes read so far add up to: files spliced, and their bytes.
#[derive(Default)]
struct Budget {
    files: usize,
    bytes: u64,
}

/// The text of every file that the `<include>`s under `root` bring in (at any
/// depth, and those of the included files), depth first in document order (the
/// order [`Includes::new`] numbers them in).
pub(crate) fn read_includes(
    root: Node,
    dir: Option<&Path>,
) -> Result<Vec<(PathBuf, String)>, DescriptionError> {
    let mut out = Vec::new();
    collect(root, dir, &mut Vec::new(), &mut out, &mut Budget::default())?;
    Ok(out)
}

fn collect(
    root: Node,
    dir: Option<&Path>,
    chain: &mut Vec<PathBuf>,
    out: &mut Vec<(PathBuf, String)>,
    budget: &mut Budget,
) -> Result<(), DescriptionError> {
    for inc in root.descendants().filter(is_include) {
        let file = required(inc, "file")?;
        let Some(dir) = dir else {
            return Err(error_at(
                inc,
                "<include> needs the model's directory: read the model from its file",
            ));
        };
        let path = dir.join(file);
        if let Some(first) = chain.iter().position(|p| *p == path) {
            // Name the whole cycle: a.xml -> b.xml -> a.xml.
            let cycle: Vec<String> = chain[first..]
                .iter()
                .chain([&path])
                .map(|p| p.display().to_string())
                .collect();
            return Err(error_at(
                inc,
                format!("include cycle: {}", cycle.join(" -> ")),
            ));
        }
        if chain.len() >= MAX_DEPTH {
            return Err(error_at(
                inc,
                format!(
                    "{} is included {MAX_DEPTH} files deep, past the limit of {MAX_DEPTH}",
                    path.display()
                ),
            ));
        }
        budget.files += 1;
        if budget.files > MAX_INCLUDES {
            return Err(error_at(
                inc,
                format!(
                    "more than {MAX_INCLUDES} <include>s (counting a file each time it is \
                     included, here {}): files that include each other over and over",
                    path.display()
                ),
            ));
        }
        let text = read_text(&path).map_err(|e| {
            let what = format!(
                "cannot read the included file {}: {}",
                path.display(),
                e.message
            );
            error_at(inc, what)
        })?;
        // A file included many times over is bounded as one file is.
        budget.bytes += text.len() as u64;
        if budget.bytes > crate::xml::MAX_DESCRIPTION_BYTES {
            return Err(error_at(
                inc,
                format!(
                    "the included files add up to more than {} bytes",
                    crate::xml::MAX_DESCRIPTION_BYTES
                ),
            ));
        }
        let slot = out.len();
        out.push((path.clone(), String::new()));
        {
            let doc = parse_xml(&text).map_err(|e| e.in_file(&path))?;
            let inner = doc.root_element();
            if inner.tag_name().name() != "mujoco" {
                return Err(
                    error_at(inner, "an included file must have <mujoco> at its root")
                        .in_file(&path),
                );
            }
            chain.push(path.clone());
            // An error at an element of this file (an <include> in it) names it;
            // its documents are registered with xml_origin only once all are read.
            collect(inner, Some(dir), chain, out, budget).map_err(|e| e.in_file(&path))?;
            chain.pop();
        }
        out[slot].1 = text;
    }
    Ok(())
}

fn is_include(n: &Node) -> bool {
    n.is_element() && n.tag_name().name() == "include"
}

/// Which parsed file each `<include>` element brings in.
pub(crate) struct Includes<'a, 'i> {
    docs: &'a [Document<'i>],
    /// (address of the element's document, its node id) -> index into `docs`.
    at: HashMap<(usize, usize), usize>,
}

fn key(n: Node) -> (usize, usize) {
    (n.document() as *const Document as usize, n.id().get_usize())
}

impl<'a, 'i> Includes<'a, 'i> {
    /// `docs` parsed from [`read_includes`]'s texts for `root`, in its order.
    pub(crate) fn new(root: Node<'a, 'i>, docs: &'a [Document<'i>]) -> Self {
        let mut me = Includes {
            docs,
            at: HashMap::new(),
        };
        let mut next = 0;
        me.number(root, &mut next);
        me
    }

    /// Number the includes under `root` as [`collect`] read them: each before
    /// the includes of its own file.
    fn number(&mut self, root: Node<'a, 'i>, next: &mut usize) {
        for inc in root.descendants().filter(is_include) {
            let Some(doc) = self.docs.get(*next) else {
                return; // not read: read_includes failed before it
            };
            self.at.insert(key(inc), *next);
            *next += 1;
            self.number(doc.root_element(), next);
        }
    }

    /// The element children of `node`, each `<include>` replaced by the
    /// children of its file's `<mujoco>` (theirs in turn; read_includes bounds
    /// the depth). Without includes: exactly `node`'s element children.
    pub(crate) fn elements(&self, node: Node<'a, 'i>) -> Vec<Node<'a, 'i>> {
        let mut out = Vec::new();
        self.splice(node, &mut out);
        out
    }

    fn splice(&self, node: Node<'a, 'i>, out: &mut Vec<Node<'a, 'i>>) {
        for c in node.children().filter(Node::is_element) {
            match self.at.get(&key(c)) {
                Some(&d) if is_include(&c) => self.splice(self.docs[d].root_element(), out),
                _ => out.push(c),
            }
        }
    }

    /// `node` and every element below it, includes spliced in, in document order.
    pub(crate) fn descendants(&self, node: Node<'a, 'i>) -> Vec<Node<'a, 'i>> {
        let mut out = Vec::new();
        let mut stack = vec![node];
        while let Some(n) = stack.pop() {
            out.push(n);
            stack.extend(self.elements(n).into_iter().rev());
        }
        out
    }
}
