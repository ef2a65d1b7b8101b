//! twinloop-gait: references for walking and posing, each written once.
//!
//! - [`sequence`]: seed 003's walking algorithm (section 6), the thirteen-stage joint
//!   coordination sequence A..N around the trims of its Table 2, as joint goals over
//!   time.
//! - [`zmp`]: ZMP walking references and the LIPM CoM reference (seed 002, eq 12-13).
//! - [`ik`]: the inverse kinematics over the full configuration, on weighted tasks
//!   (points, directions, frame poses and orientations, CoM, posture), by
//!   Levenberg-Marquardt or damped least squares; [`walking_ik`]: its walking
//!   configuration (both sole poses, CoM, pelvis orientation over base and legs).
//!
//! The experiments that walk a robot on these references (seed 003's lab17 dataset,
//! seed 002's COMAN walk) live in twinloop-experiments; the identification of a walk
//! record in twinloop-ident.

pub mod error;
pub mod ik;
pub mod sequence;
pub mod walking_ik;
pub mod zmp;

pub use error::GaitError;
pub use sequence::{
    JointGoals, OFFSET_JOINTS, SEED_CYCLE_PERIOD, SEED_SAMPLE_TIME, SEED_SAMPLES, STAGES,
    SequenceOptions, Stage, offsets_at, stage_at, walking_sequence, walking_sequence_samples,
    walking_sequence_with,
};
pub use zmp::{Foot, GaitPlan, Phase, ZmpReference, ZmpSample};
