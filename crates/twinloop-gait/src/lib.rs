//! twinloop-gait: the gait layer.
//!
//! - [`sequence`]: seed 003's walking algorithm (section 6), the thirteen-stage joint
//!   coordination sequence A..N around the trims of its Table 2, as joint goals over
//!   time.
//! - [`dataset`]: the identification experiment of seed 003 (section 7) run on
//!   `lab17` in the simulator: the sequence on two-loop servos, an MPU-6050 gyro on
//!   each foot, inputs = the ten joint offsets (eq 6), outputs = the six foot rates.
//! - [`identify`]: section 7 on such a record: the 24th-order MIMO ARX initial model
//!   and the ARX -> balanced truncation -> prediction-error final state-space model.

pub mod dataset;
pub mod identify;
pub mod sequence;

pub use dataset::{DatasetOptions, WalkDataset, ld2015_two_loop, record_walk};
pub use identify::{WalkIdOptions, WalkIdentification, identify_walk};
pub use sequence::{
    GaitError, JointGoals, OFFSET_JOINTS, SEED_CYCLE_PERIOD, SEED_SAMPLE_TIME, SEED_SAMPLES,
    STAGES, SequenceOptions, Stage, offsets_at, stage_at, walking_sequence,
    walking_sequence_samples, walking_sequence_with,
};
