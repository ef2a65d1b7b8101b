//! URDF: reader and lossless writer.
//!
//! Reading keeps everything a URDF says: links (inertial, any number of visuals
//! and collisions, inline materials), joints with all their optional parts,
//! top-level materials, the attributes of `<robot>`, and — verbatim, at their
//! place in the document — everything that is not URDF: `<gazebo>`,
//! `<transmission>`, `<sensor>`, `<mujoco>` and other top-level tags become
//! [`Extension`](crate::Extension)s, unknown children of `<link>` and `<joint>`
//! go to their `extra`. Writing gives back a file that reads as an equal
//! [`Description`](crate::Description).
//!
//! Writing also covers what only code or MJCF produce: a
//! [`Frame`](crate::Frame) is written as a massless `<link>` plus a fixed
//! `<joint name="<frame>_frame_joint">` (so it reads back as a link), and a
//! capsule as a cylinder with a comment; a ball joint as three revolute joints, and
//! every `<limit>` with the `effort` and `velocity` other tools require (see
//! [`to_string`]).
//!
//! What is not kept: XML comments, the interleaving of `<visual>` and
//! `<collision>` inside a link (visuals are written first), unknown attributes
//! (e.g. `dont_collapse` on a joint, `scale` on a `<box>`, `name` on a
//! `<geometry>`) and unknown children of `<visual>`, `<collision>`,
//! `<geometry>` and `<inertial>`.
//!
//! ```
//! let robot = twinloop_description::urdf::from_str(r#"
//!   <robot name="r">
//!     <link name="a"/>
//!     <link name="b"><inertial><mass value="1.5"/>
//!       <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
//!     <joint name="j" type="revolute"><parent link="a"/><child link="b"/>
//!       <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="2" velocity="3"/></joint>
//!   </robot>"#).unwrap();
//! let text = twinloop_description::urdf::to_string(&robot);
//! assert_eq!(twinloop_description::urdf::from_str(&text).unwrap(), robot);
//! ```

mod read;
mod schema;
mod write;

pub(crate) use read::from_document;
pub use read::{from_str, read_file};
pub use write::{
    UNKNOWN_LIMIT, UNLIMITED_SLIDE, to_string, to_string_exact, unwritable, write_file,
};
