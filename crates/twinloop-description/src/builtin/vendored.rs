//! Description files of real robots the repository ships (models/), compiled into
//! the binary so `builtin:NAME` works from any folder. Read with the same readers as
//! a file; their provenance is in each model folder's SOURCE.md.

use crate::{Description, DescriptionError};

/// ROBOTIS OP3: MuJoCo Menagerie's MJCF (models/op3/mjcf/op3.xml, byte for byte).
/// Its feet are boxes; its mesh assets are visual and collision shapes the dynamics
/// do not use.
pub const OP3: &str = "op3";
/// ROBOTIS Darwin-OP: models/darwin_op/robotis_op.feet.urdf (robotis_op_description's
/// URDF without meshes, with a sole box under each foot: SOURCE.md there).
pub const DARWIN_OP: &str = "darwin_op";

const OP3_MJCF: &str = include_str!("../../../../models/op3/mjcf/op3.xml");
const DARWIN_OP_URDF: &str = include_str!("../../../../models/darwin_op/robotis_op.feet.urdf");

/// The vendored robot `name`, `None` for another name. The texts are fixed, so a
/// reader error is a bug in a commit of this repository, reported as one.
pub fn read(name: &str) -> Option<Result<Description, DescriptionError>> {
    let (text, file) = match name {
        OP3 => (OP3_MJCF, "models/op3/mjcf/op3.xml"),
        DARWIN_OP => (DARWIN_OP_URDF, "models/darwin_op/robotis_op.feet.urdf"),
        _ => return None,
    };
    let read = if name == OP3 {
        crate::mjcf::from_str(text)
    } else {
        crate::urdf::from_str(text)
    };
    Some(read.map_err(|e| DescriptionError::new(format!("builtin:{name} ({file}): {e}"))))
}
