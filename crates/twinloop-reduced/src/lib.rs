//! twinloop-reduced: the reduced models of seeds 000 and 001.
//!
//! - [`lipm`]: the linear inverted pendulum, seed 000 eq. 1-3, simulated (a fall from a
//!   lean, a walk from a ZMP input) and in closed form;
//! - [`three_mass`]: the three-mass LIPM, seed 000 eq. 4-7, with the three masses
//!   derived from a full [`twinloop_dynamics::Model`] ([`ThreeMasses::from_model`]) and
//!   simulated in either plane;
//! - [`tipover`]: the CoM from the angles at which the robot tips over: seed 000's
//!   geometric method (eq. 8-13) exactly as printed, and the exact rigid-body method.
//!
//! Every function that implements a seed equation says which. Bad input is a
//! [`ReducedError`] naming the field, never a panic.
//!
//! ```
//! use twinloop_reduced::tipover::{FeetMass, FrontalLever, exact_method, tip_angles};
//! let foot = twinloop_description::builtin::foot_geometry("km20").unwrap();
//! let com = [0.004, -0.002, 0.22];
//! let lever = FrontalLever { sin: 0.17, cos: 0.0 };
//! let feet = FeetMass { fraction: 0.11, x: -0.025, z: -0.011 };
//! let angles = tip_angles(com, &feet, &lever, &foot).unwrap();
//! let back = exact_method(&angles, &feet, &foot).unwrap();
//! assert!((back.com[2] - 0.22).abs() < 1e-12);
//! ```

pub mod error;
pub mod lipm;
pub mod three_mass;
pub mod tipover;

pub use error::ReducedError;
pub use lipm::{GRAVITY, Lipm, LipmInput, LipmSample};
pub use three_mass::{
    LegMotion, Plane, PointMass, ThreeMassLipm, ThreeMassSample, ThreeMasses, ankle_midpoint,
    ankle_torque, com_relative_to_ankles,
};
pub use tipover::{
    ExactEstimate, FeetMass, FrontalLever, SEED_000_CONSTANTS, SeedAngles, SeedConstants,
    SeedEstimate, TipAngles, exact_method, feet_mass, frontal_lever, frontal_tip_angles,
    sagittal_tip_angles, seed_method, seed_method_sagittal_angles, tip_angles,
};
pub use twinloop_description::builtin::FootGeometry;
