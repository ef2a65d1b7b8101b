//! twinloop-ident: the estimators that fit a model to what was measured.
//!
//! | estimator | seed | module |
//! |---|---|---|
//! | CoM from the tip-over angles: the seed's geometric method and the exact rigid-body method | 000 eq 8-13 | [`tipover`]; the simulated study that runs the experiment and checks them: [`tipover_study`] |
//! | an added (or removed) mass (mass, host link, position) from the tip-over angles and the prior model, and the checks it passes before a model is written | 000 III, V.B | [`adapt`], [`adapt_checks`]; the arms as places: [`arms`] |
//! | the three-mass LIPM from the fall angles by a 5-10-5 perceptron trained on simulated changes | 000 V.C | [`ann`] (the network), [`ann_data`] (the changes), [`ann_adapt`] (training and evaluation) |
//! | static identification of link masses and CoMs (below) | 004 | [`static_ident`] |
//! | the compliant compact model's 8 corrections (LM, CMA-ES, PoWER), identifiability | 002 section 4 | [`compliant_fit`] |
//! | a walk record to MIMO ARX and state-space models | 003 section 7 | [`walk_identification`] |
//!
//! Seed 004 (REEM-C: static identification of link masses and CoMs) end to end:
//!
//! | piece | module |
//! |---|---|
//! | static-pose data (configuration + measured CoP per pose) | [`poses`] |
//! | the virtual force plate: stable poses in the seed's six categories | [`plate`] |
//! | feet, soles, legs, arms, torso read from the description | [`anatomy`] |
//! | static identification of masses and CoMs (seed eq 8-9) | [`static_ident`], [`qp`] |
//! | IK marker fitting (seed eq 7) | [`markers`] |
//! | zero-phase Butterworth smoothing | [`filter`] |
//! | inverse-dynamics residual of the base, squat motion (seed 3.4) | [`validate`] |
//! | HTML report with the seed's Fig. 5 and Fig. 6 | [`html`] |
//! | errors naming file, row and field | [`error`] |

pub mod adapt;
pub mod adapt_checks;
pub mod anatomy;
pub mod ann;
pub mod ann_adapt;
pub mod ann_data;
pub mod ann_report;
pub mod arms;
pub mod compliant_fit;
pub mod error;
pub mod fall_angle_fit;
pub mod filter;
pub mod html;
pub mod markers;
pub mod plate;
pub mod poses;
pub mod qp;
pub mod static_ident;
pub mod tipover;
pub mod tipover_bus;
pub mod tipover_study;
pub mod validate;
pub mod walk_identification;

pub use error::IdentError;
pub use poses::{
    PoseCategory, StaticPose, parse_static_poses, read_static_poses, write_static_poses,
};
pub use static_ident::{StaticOptions, StaticResult, adapted_robot, identify_static};
pub use tipover::{
    ExactEstimate, FeetMass, FrontalLever, SEED_000_CONSTANTS, SeedAngles, SeedConstants,
    SeedEstimate, TipAngles, exact_method, feet_mass, frontal_lever, frontal_tip_angles,
    sagittal_tip_angles, seed_method, seed_method_sagittal_angles, tip_angles,
};
pub use walk_identification::{WalkIdOptions, WalkIdentification, identify_walk};
