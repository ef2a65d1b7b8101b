//! twinloop-ident: identification experiments and estimators.
//!
//! Seed 004 (REEM-C) in four pieces:
//!
//! | piece | module |
//! |---|---|
//! | static-pose data (configuration + measured CoP per pose) | [`poses`] |
//! | errors naming file, row and field | [`error`] |

pub mod anatomy;
pub mod error;
pub mod filter;
pub mod ik;
pub mod plate;
pub mod poses;
pub mod qp;
pub mod static_ident;

pub use error::IdentError;
pub use poses::{
    PoseCategory, StaticPose, parse_static_poses, read_static_poses, write_static_poses,
};
