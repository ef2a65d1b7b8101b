//! The squat's plate readings are finite in every frame, and on average the robot's weight.

use twinloop_description::builtin::resolve;
use twinloop_dynamics::Model;
use twinloop_ident::validate::{SquatOptions, squat_motion};

/// km20's default squat: its first and last moving frames once wrote NaN plate columns
/// (the base's rotation vector through a rotation matrix's acos, rounding above 1).
#[test]
fn km20_squat_plate_is_finite_and_weighs_the_robot() {
    let robot = resolve("builtin:km20").unwrap();
    let model = Model::from_description(&robot).unwrap();
    let motion = squat_motion(&robot, &model, &SquatOptions::default(), |_, _| {}).unwrap();
    let plate = motion.plate.as_ref().unwrap();
    for (k, s) in plate.iter().enumerate() {
        let all = s.force.iter().chain(s.cop.iter()).chain([&s.free_moment]);
        assert!(
            all.clone().all(|x| x.is_finite()),
            "frame {k} (t = {}): {:?}",
            motion.t[k],
            all.collect::<Vec<_>>()
        );
    }
    let weight = robot.total_mass() * twinloop_description::GRAVITY;
    let mean_fz = plate.iter().map(|s| s.force[2]).sum::<f64>() / plate.len() as f64;
    assert!(
        (mean_fz - weight).abs() < 1e-3 * weight,
        "{mean_fz} vs {weight}"
    );
}
