//! twinloop-dynamics: floating-base rigid-body dynamics with Pinocchio's conventions.
//!
//! A [`Model`] is compiled once from a description; a [`Data`] holds every buffer
//! the algorithms write. After `Data::new`, none of the algorithms allocates.
//!
//! Conventions (docs/architecture.md, "Conventions"): q = [x, y, z, qx, qy, qz, qw, joints], v = [base
//! linear, base angular (base frame), joints]; a ball joint has 4 q entries (its
//! quaternion x, y, z, w) and 3 v entries (angular velocity in its child frame); gravity (0, 0, -9.81) unless the
//! description sets one (MJCF `<option gravity>`); joint armature from the
//! description on the mass-matrix diagonal; spatial vectors
//! linear part first.
//!
//! | algorithm | function |
//! |---|---|
//! | forward kinematics | [`forward_kinematics`], [`frames_forward_kinematics`] |
//! | CoM, CoM Jacobian, ground-projected CoM | [`center_of_mass`], [`jacobian_center_of_mass`], [`ground_projected_com`] |
//! | joint and frame Jacobians | [`compute_joint_jacobians`], [`frame_jacobian`] |
//! | inverse dynamics (RNEA) | [`rnea`], [`nonlinear_effects`], [`generalized_gravity`] |
//! | mass matrix (CRBA) | [`crba`] |
//! | one kinematics pass, then CRBA and the bias forces on it (a simulator step) | [`kinematics_pass`], [`crba_from_kinematics`], [`nonlinear_effects_from_kinematics`], [`crba_and_bias_from_kinematics`] (both at once, RNEA in base coordinates) |
//! | forward dynamics (ABA) | [`aba`], [`try_aba`] (refuses a singular mass matrix naming the joint) |
//! | invertible mass matrix | [`check_mass_matrix`] |
//! | regressors | [`joint_torque_regressor`], [`static_com_regressor`] |

pub mod aba;
pub mod batch;
pub mod center_of_mass;
pub mod configuration;
pub mod crba;
pub mod data;
mod joint;
pub mod kinematics;
pub mod model;
pub mod regressor;
pub mod rnea;
pub mod singular;

pub use aba::{aba, aba_with_forces};
pub use batch::{
    BatchData, aba_batch, center_of_mass_batch, crba_batch, rnea_batch, try_aba_batch,
};
pub use center_of_mass::{center_of_mass, ground_projected_com, jacobian_center_of_mass};
pub use crba::{crba, crba_and_bias_from_kinematics, crba_from_kinematics};
pub use data::Data;
pub use kinematics::{
    ReferenceFrame, compute_joint_jacobians, forward_kinematics, frame_jacobian,
    frames_forward_kinematics, kinematics_pass, update_frame_placements,
};
pub use model::{BASE, BaseKind, FrameInfo, JointOrder, JointType, LinkInfo, Model};
pub use regressor::{
    body_parameters, joint_torque_regressor, link_parameters, link_static_parameters,
    link_to_body_parameter_map, parameter_block_of_link, static_com_regressor,
};
pub use rnea::{generalized_gravity, nonlinear_effects, nonlinear_effects_from_kinematics, rnea};
pub use singular::{SingularJoint, check_mass_matrix, try_aba};
