//! Loading a description file of either format: the root element picks the reader.

use crate::description::Description;
use crate::error::DescriptionError;
use crate::xml::{error_at, parse_xml, read_text};
use std::path::Path;

/// The format a description file was read as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Urdf,
    Mjcf,
}

/// Read a robot description, choosing the reader by the root element:
/// `<robot>` is URDF ([`crate::urdf`]), `<mujoco>` is MJCF ([`crate::mjcf`]).
/// Errors carry the file path.
pub fn load(path: impl AsRef<Path>) -> Result<Description, DescriptionError> {
    load_with_format(path).map(|(d, _)| d)
}

/// As [`load`], also saying which format the file was (the Python package numbers
/// a URDF's joints as Pinocchio's URDF parser does, an MJCF's in file order).
pub fn load_with_format(path: impl AsRef<Path>) -> Result<(Description, Format), DescriptionError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    let result = parse_xml(&text).and_then(|doc| {
        let root = doc.root_element();
        match root.tag_name().name() {
            "robot" => crate::urdf::from_document(&doc).map(|d| (d, Format::Urdf)),
            "mujoco" => crate::mjcf::from_document(&doc, path.parent()).map(|d| (d, Format::Mjcf)),
            other => Err(error_at(
                root,
                format!("root element is <{other}>: expected <robot> (URDF) or <mujoco> (MJCF)"),
            )),
        }
    });
    result.map_err(|e| e.in_file(path))
}
