//! twinloop-description: the robot description layer.
//!
//! A [`Description`] holds links (mass, CoM, full inertia in a possibly rotated frame,
//! geometry), joints (revolute, continuous, prismatic, fixed, floating, planar,
//! mimic), limits and named frames, as the file said them. Readers: URDF (lossless
//! round trip) and the MJCF subset of the MuJoCo Menagerie humanoids. [`lint`]
//! checks the physical plausibility of the numbers.

pub mod builder;
pub mod builtin;
pub mod description;
pub mod error;
pub mod lint;
mod load;
pub mod mjcf;
pub mod tree;
pub mod urdf;
mod xml;
mod xml_origin;

pub use builder::{DescriptionBuilder, JointBuilder, LinkBuilder};
pub use description::*;
pub use error::{DescriptionError, Location};
pub use load::{Format, load, load_with_format};

/// Standard gravity, m/s^2: the 9.81 of every seed paper. World z is up, so the
/// gravity vector is (0, 0, -GRAVITY) unless a description says otherwise.
pub const GRAVITY: f64 = 9.81;
