//! twinloop-gait: references for walking and posing, each written once.
//!
//! - [`sequence`]: seed 003's walking algorithm (section 6), the thirteen-stage joint
//!   coordination sequence A..N around the trims of its Table 2, as joint goals over
//!   time.
//! - [`zmp`]: ZMP walking references and the LIPM CoM reference (seed 002, eq 12-13).
//! - [`ik`]: inverse kinematics over the full configuration by Levenberg-Marquardt on
//!   weighted tasks (feet, markers, CoM, posture); [`walking_ik`]: the whole-body
//!   walking IK (sole poses, CoM, pelvis orientation) on the same tasks.
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
