//! twinloop-ident: identification experiments and estimators.
//!
//! Seed 004 (REEM-C: static identification of link masses and CoMs) end to end:
//!
//! | piece | module |
//! |---|---|
//! | static-pose data (configuration + measured CoP per pose) | [`poses`] |
//! | the virtual force plate: stable poses in the seed's six categories | [`plate`] |
//! | feet, soles, legs, arms, torso read from the description | [`anatomy`] |
//! | Levenberg-Marquardt inverse kinematics on weighted tasks | [`ik`] |
//! | static identification of masses and CoMs (seed eq 8-9) | [`static_ident`], [`qp`] |
//! | IK marker fitting (seed eq 7) | [`markers`] |
//! | zero-phase Butterworth smoothing | [`filter`] |
//! | inverse-dynamics residual of the base, squat motion (seed 3.4) | [`validate`] |
//! | HTML report with the seed's Fig. 5 and Fig. 6 | [`html`] |
//! | errors naming file, row and field | [`error`] |

pub mod anatomy;
pub mod error;
pub mod filter;
pub mod html;
pub mod ik;
pub mod markers;
pub mod plate;
pub mod poses;
pub mod qp;
pub mod static_ident;
pub mod validate;

pub use error::IdentError;
pub use poses::{
    PoseCategory, StaticPose, parse_static_poses, read_static_poses, write_static_poses,
};
pub use static_ident::{StaticOptions, StaticResult, adapted_robot, identify_static};
