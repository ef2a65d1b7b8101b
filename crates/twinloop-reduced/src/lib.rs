//! twinloop-reduced: the reduced models, each written once.
//!
//! | model | seed | module |
//! |---|---|---|
//! | linear inverted pendulum, simulated and in closed form | seed 000 eq 1-3 | [`lipm`] |
//! | three-mass LIPM, masses derived from a full model | seed 000 eq 4-7 | [`three_mass`] |
//! | Cartesian stiffness and damping at the CoM, K_C = J^-T K_j J^-1 | seed 002 eq 7-8 | [`stiffness`] |
//! | compliant compact CoM model with its 8 corrections | seed 002 eq 9-11, 14-17 | [`compact`] |
//!
//! The estimators that use these models (the tip-over CoM methods, the compact
//! model's fit) live in twinloop-ident; the ZMP references built on the LIPM in
//! twinloop-gait. Every function that implements a seed equation says which. Bad input
//! is a [`ReducedError`] naming the field, never a panic.

pub mod compact;
pub mod error;
pub mod lipm;
pub mod stiffness;
pub mod three_mass;

pub use compact::{CompactModel, Corrections, SagittalCompliance, SagittalReference};
pub use error::ReducedError;
pub use lipm::{GRAVITY, Lipm, LipmInput, LipmPhase, LipmSample, LipmState};
pub use stiffness::{
    CartesianCompliance, JointCompliance, SupportLeg, cartesian_compliance, coman_crouch,
    support_leg_com_jacobian,
};
pub use three_mass::{
    LegMotion, Plane, PointMass, ThreeMassLipm, ThreeMassSample, ThreeMasses, ankle_midpoint,
    ankle_torque, com_relative_to_ankles,
};
