//! twinloop-compliant: the compliant humanoid COMAN of seed 002.
//!
//! | seed 002 | module |
//! |---|---|
//! | eq 12-13: ZMP reference and LIPM CoM reference | [`zmp`] |
//! | eq 7-8: Cartesian stiffness and damping at the CoM | [`stiffness`] |
//! | eq 9-11, 14-17: compact CoM model with corrections | [`compact`] |
//! | section 4: the COMAN walking dataset in the full simulator | [`walking`], [`walking_ik`] |
//! | section 4: fit of the corrections (LM, CMA-ES, PoWER), identifiability | [`fit`] |

pub mod compact;
pub mod fit;
pub mod stiffness;
pub mod walking;
pub mod walking_ik;
pub mod zmp;

pub use compact::{CompactModel, Corrections, SagittalCompliance, SagittalReference};
pub use stiffness::{
    CartesianCompliance, JointCompliance, SupportLeg, cartesian_compliance, coman_crouch,
    support_leg_com_jacobian,
};
pub use zmp::{Foot, GaitPlan, Phase, ZmpReference, ZmpSample};

/// A bad input, named.
#[derive(Debug, Clone, PartialEq)]
pub struct CompliantError(pub String);

impl std::fmt::Display for CompliantError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CompliantError {}

pub(crate) fn err<T>(message: impl Into<String>) -> Result<T, CompliantError> {
    Err(CompliantError(message.into()))
}
