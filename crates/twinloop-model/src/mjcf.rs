//! MJCF reader (placeholder).
use crate::error::ModelError;
use crate::robot::Robot;
use roxmltree::Document;

pub(crate) fn from_document(doc: &Document) -> Result<Robot, ModelError> {
    Err(crate::load::error_at(
        doc.root_element(),
        "MJCF is not supported yet",
    ))
}
