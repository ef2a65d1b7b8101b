//! The XML plumbing the URDF and MJCF readers share: reading the file, parsing
//! with positions, error locations that name the line, column and element, and
//! number parsing that rejects non-finite values. Its own module so that both
//! readers import it and [`crate::load`], which picks a reader, imports them.

use crate::description::Description;
use crate::error::DescriptionError;
use roxmltree::{Document, Node};
use std::path::Path;

/// The largest description file read, bytes (256 MiB): a 100 000-link chain in URDF
/// is 40 MB, the largest real description here (TALOS's MJCF) well under 1 MB.
pub const MAX_DESCRIPTION_BYTES: u64 = 256 << 20;

/// The file's text; errors name the path. Only a regular file of at most
/// [`MAX_DESCRIPTION_BYTES`] is read (`/dev/zero` would never end).
pub(crate) fn read_text(path: &Path) -> Result<String, DescriptionError> {
    let bytes = twinloop_io::input::read_bounded(path, MAX_DESCRIPTION_BYTES)
        .map_err(|e| DescriptionError::new(e.message).in_file(path))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let text = String::from_utf8_lossy(&e.as_bytes()[..at]).into_owned();
        let (line, column) = end_position(&text);
        DescriptionError::new("the file is not UTF-8 text")
            .at_line(line, column)
            .in_file(path)
    })?;
    Ok(late_declaration_blanked(text))
}

/// XML allows its `<?xml ...?>` declaration only at the very start; files with a
/// blank line before it are common and harmless (parsers such as Pinocchio's read
/// them). Blank such a declaration out with spaces, so every byte keeps its
/// place and errors keep their lines.
fn late_declaration_blanked(mut text: String) -> String {
    let start = text.len() - text.trim_start().len();
    if start > 0
        && text[start..].starts_with("<?xml")
        && let Some(end) = text[start..].find("?>")
    {
        let blank = " ".repeat(end + 2);
        text.replace_range(start..start + end + 2, &blank);
    }
    text
}

/// Parse XML; a syntax error becomes a [`DescriptionError`] at the place roxmltree reports.
pub(crate) fn parse_xml(text: &str) -> Result<Document<'_>, DescriptionError> {
    // DTDs stay refused (roxmltree's default): no description format uses them,
    // and entity expansion is a way to make a small file huge.
    Document::parse(text).map_err(|e| {
        use roxmltree::Error as E;
        let (line, column) = match e {
            // Errors of a text that stops too early: point at its end.
            E::UnclosedRootNode | E::UnexpectedEndOfStream => end_position(text),
            _ => {
                let p = e.pos();
                (p.row, p.col)
            }
        };
        let full = e.to_string();
        let suffix = format!(" at {}", e.pos());
        let message = full
            .strip_suffix(&suffix)
            .map(str::to_string)
            .unwrap_or_else(|| {
                // Some messages carry the position in the middle ("attribute 'x' at 1:2 is ...").
                full.replacen(&suffix, "", 1)
            });
        DescriptionError::new(format!("malformed XML: {message}")).at_line(line, column)
    })
}

/// 1-based line and column just past the end of `text`.
fn end_position(text: &str) -> (u32, u32) {
    let line = text.matches('\n').count() + 1;
    let last = text.rsplit('\n').next().unwrap_or("");
    let column = last.chars().count() + 1;
    (saturate(line), saturate(column))
}

fn saturate(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

/// The element's name as written, prefix included (`xacro:grey`, `gazebo`).
pub(crate) fn qualified_name<'a>(node: Node<'a, '_>) -> &'a str {
    let text = node.document().input_text();
    let start = node.range().start + 1;
    let rest = text.get(start..).unwrap_or("");
    let end = rest
        .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
        .unwrap_or(rest.len());
    &rest[..end]
}

/// The exact source text of a node (an element with everything inside it).
pub(crate) fn source_text<'a>(node: Node<'a, '_>) -> &'a str {
    let text = node.document().input_text();
    text.get(node.range()).unwrap_or("")
}

/// `<joint name="l_knee">`, or `<origin>` for an element without a name.
pub(crate) fn describe(node: Node) -> String {
    let tag = qualified_name(node);
    match node.attribute("name") {
        Some(n) => format!("<{tag} name=\"{n}\">"),
        None => format!("<{tag}>"),
    }
}

/// The element and its ancestors up to the first one with a name, below the
/// document's root element: `<origin> in <visual> in <link name="base">`
/// (at most four ancestors).
pub(crate) fn element_path(node: Node) -> String {
    let mut parts = vec![describe(node)];
    if node.attribute("name").is_none() {
        let mut at = node.parent_element();
        while let Some(p) = at {
            if p.parent_element().is_none() {
                break; // the document's root element
            }
            if parts.len() > 4 {
                parts.push("...".to_string());
                break;
            }
            parts.push(describe(p));
            if p.attribute("name").is_some() {
                break;
            }
            at = p.parent_element();
        }
    }
    parts.join(" in ")
}

/// Line and column (1-based) of a byte offset in the document.
pub(crate) fn position(doc: &Document, byte: usize) -> (u32, u32) {
    let p = doc.text_pos_at(byte);
    (p.row, p.col)
}

/// An error located at an element.
pub(crate) fn error_at(node: Node, message: impl Into<String>) -> DescriptionError {
    let (line, column) = position(node.document(), node.range().start);
    let e = DescriptionError::new(message)
        .at_line(line, column)
        .at_element(element_path(node));
    // An element of an MJCF <include>d file: name that file.
    match crate::xml_origin::file_of(node.document()) {
        Some(file) => e.in_file(file),
        None => e,
    }
}

/// An error located at an attribute of an element (the element is named too).
pub(crate) fn error_at_attr(
    node: Node,
    attr: &str,
    message: impl Into<String>,
) -> DescriptionError {
    let start = node
        .attributes()
        .find(|a| a.name() == attr)
        .map_or(node.range().start, |a| a.range().start);
    let (line, column) = position(node.document(), start);
    let e = DescriptionError::new(message)
        .at_line(line, column)
        .at_element(element_path(node));
    match crate::xml_origin::file_of(node.document()) {
        Some(file) => e.in_file(file),
        None => e,
    }
}

/// A required attribute.
pub(crate) fn required<'a>(node: Node<'a, '_>, attr: &str) -> Result<&'a str, DescriptionError> {
    node.attribute(attr)
        .ok_or_else(|| error_at(node, format!("missing attribute \"{attr}\"")))
}

/// Shorten a value for an error message.
fn shown(value: &str) -> String {
    const MAX: usize = 40;
    if value.chars().count() <= MAX {
        value.to_string()
    } else {
        let head: String = value.chars().take(MAX).collect();
        format!("{head}...")
    }
}

/// One finite number from an attribute value.
pub(crate) fn parse_number(node: Node, attr: &str, value: &str) -> Result<f64, DescriptionError> {
    let word = value.trim();
    match word.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(error_at_attr(
            node,
            attr,
            format!("{attr}=\"{}\": the number is not finite", shown(value)),
        )),
        Err(_) => Err(error_at_attr(
            node,
            attr,
            format!("{attr}=\"{}\": not a number", shown(value)),
        )),
    }
}

/// Whitespace-separated finite numbers from an attribute value.
pub(crate) fn parse_numbers(
    node: Node,
    attr: &str,
    value: &str,
) -> Result<Vec<f64>, DescriptionError> {
    let mut out = Vec::new();
    for word in value.split_whitespace() {
        match word.parse::<f64>() {
            Ok(v) if v.is_finite() => out.push(v),
            Ok(_) => {
                return Err(error_at_attr(
                    node,
                    attr,
                    format!(
                        "{attr}=\"{}\": \"{}\" is not finite",
                        shown(value),
                        shown(word)
                    ),
                ));
            }
            Err(_) => {
                return Err(error_at_attr(
                    node,
                    attr,
                    format!(
                        "{attr}=\"{}\": \"{}\" is not a number",
                        shown(value),
                        shown(word)
                    ),
                ));
            }
        }
    }
    Ok(out)
}

/// Exactly `N` finite numbers from an attribute value.
pub(crate) fn parse_array<const N: usize>(
    node: Node,
    attr: &str,
    value: &str,
) -> Result<[f64; N], DescriptionError> {
    let v = parse_numbers(node, attr, value)?;
    <[f64; N]>::try_from(v.as_slice()).map_err(|_| {
        error_at_attr(
            node,
            attr,
            format!(
                "{attr}=\"{}\": expected {N} numbers, found {}",
                shown(value),
                v.len()
            ),
        )
    })
}

/// An optional attribute holding one finite number.
pub(crate) fn opt_number(node: Node, attr: &str) -> Result<Option<f64>, DescriptionError> {
    node.attribute(attr)
        .map(|v| parse_number(node, attr, v))
        .transpose()
}

/// An optional attribute holding exactly `N` numbers.
pub(crate) fn opt_array<const N: usize>(
    node: Node,
    attr: &str,
) -> Result<Option<[f64; N]>, DescriptionError> {
    node.attribute(attr)
        .map(|v| parse_array::<N>(node, attr, v))
        .transpose()
}

/// The elements a robot's links and joints were read from, to place the errors
/// found after parsing by [`Description::validate`] (in the file each is in: an
/// MJCF body may come from an `<include>`d file).
pub(crate) struct Places<'a, 'i> {
    /// The document's root element (for errors about the whole robot).
    pub robot: Node<'a, 'i>,
    pub links: Vec<Node<'a, 'i>>,
    pub joints: Vec<Node<'a, 'i>>,
}

/// [`Description::validate`], with the error given the line of the element it names
/// (for a duplicate name: the second element that has it).
pub(crate) fn validate_placed(
    robot: &Description,
    places: &Places,
) -> Result<(), DescriptionError> {
    let Err(mut e) = robot.validate() else {
        return Ok(());
    };
    let element = e.location.element.clone().unwrap_or_default();
    let name_in = |prefix: &str| {
        element
            .strip_prefix(prefix)
            .and_then(|s| s.strip_suffix("\">"))
            .map(str::to_string)
    };
    let duplicate = e.message.starts_with("duplicate");
    let pick = |names: Vec<&str>, name: &str| -> Option<usize> {
        let mut hits = names
            .iter()
            .enumerate()
            .filter(|(_, n)| **n == name)
            .map(|(i, _)| i);
        let first = hits.next();
        if duplicate {
            hits.next().or(first)
        } else {
            first
        }
    };
    let node = if let Some(name) = name_in("<joint name=\"") {
        let names = robot.joints.iter().map(|j| j.name.as_str()).collect();
        pick(names, &name).and_then(|i| places.joints.get(i).copied())
    } else if let Some(name) = name_in("<link name=\"") {
        let names = robot.links.iter().map(|l| l.name.as_str()).collect();
        pick(names, &name).and_then(|i| places.links.get(i).copied())
    } else if let Some(n) = element
        .strip_prefix("link #")
        .and_then(|s| s.parse::<usize>().ok())
    {
        n.checked_sub(1).and_then(|i| places.links.get(i).copied())
    } else {
        None
    };
    let node = node.unwrap_or_else(|| {
        if e.location.element.is_none() {
            e.location.element = Some(describe(places.robot));
        }
        places.robot
    });
    let (line, column) = position(node.document(), node.range().start);
    let e = e.at_line(line, column);
    match crate::xml_origin::file_of(node.document()) {
        Some(file) => Err(e.in_file(file)),
        None => Err(e),
    }
}
