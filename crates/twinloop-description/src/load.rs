//! Loading a description file of either format: the root element picks the reader.

use crate::description::Description;
use crate::error::DescriptionError;
use crate::xml::{error_at, parse_xml, read_text};
use std::path::Path;

/// Read a robot description, choosing the reader by the root element:
/// `<robot>` is URDF ([`crate::urdf`]), `<mujoco>` is MJCF ([`crate::mjcf`]).
/// Errors carry the file path.
pub fn load(path: impl AsRef<Path>) -> Result<Description, DescriptionError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    let result = parse_xml(&text).and_then(|doc| {
        let root = doc.root_element();
        match root.tag_name().name() {
            "robot" => crate::urdf::from_document(&doc),
            "mujoco" => crate::mjcf::from_document(&doc, path.parent()),
            other => Err(error_at(
                root,
                format!("root element is <{other}>: expected <robot> (URDF) or <mujoco> (MJCF)"),
            )),
        }
    });
    result.map_err(|e| e.in_file(path))
}
