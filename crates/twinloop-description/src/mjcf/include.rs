//! `<include file="...">`: MuJoCo splices the children of the included file's
//! `<mujoco>` element in place of the `<include>`. Paths are relative to the
//! directory of the main model file; included files may include others.

use crate::error::DescriptionError;
use crate::xml::{error_at, parse_xml, read_text, required};
use roxmltree::{Document, Node};
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

/// The text of every file that `root`'s top-level `<include>`s bring in, depth
/// first in document order (the order [`splice`] consumes them).
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
    for inc in root
        .children()
        .filter(|c| c.is_element() && c.tag_name().name() == "include")
    {
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
            chain.push(path);
            collect(inner, Some(dir), chain, out, budget)?;
            chain.pop();
        }
        out[slot].1 = text;
    }
    Ok(())
}

/// The children of `root` with every `<include>` replaced by the children of the
/// file it names (`docs`, parsed from [`read_includes`]'s texts in its order).
pub(crate) fn splice<'a, 'i>(
    root: Node<'a, 'i>,
    docs: &'a [Document<'i>],
    next: &mut usize,
    out: &mut Vec<Node<'a, 'i>>,
) {
    for c in root.children().filter(Node::is_element) {
        if c.tag_name().name() == "include" {
            let doc = &docs[*next];
            *next += 1;
            splice(doc.root_element(), docs, next, out);
        } else {
            out.push(c);
        }
    }
}
