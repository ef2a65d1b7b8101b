//! A robot standing on the floor on its servos: the one way every front end starts a
//! simulation that holds a pose (`twinloop simulate`, the tip-over study, the lean,
//! the virtual robot behind `serve`), so each refuses what cannot stand with the same
//! words.

use crate::actuator::{Actuator, DynamixelServo, servo_for_joint};
use crate::simulator::{SimConfig, SimError, Simulator};
use twinloop_description::Description;
use twinloop_dynamics::Model;

/// The pose a robot stands in: every one-degree joint at zero clamped into its
/// limits, other joints (a ball's quaternion) at their neutral configuration; joint
/// coordinates only (no floating base).
pub fn standing_pose(model: &Model) -> Vec<f64> {
    let mut q = model.neutral_configuration().split_off(model.q_offset);
    for i in 0..model.nbodies {
        if model.joint_types[i].nq() == 1 {
            q[model.idx_q[i] - model.q_offset] =
                0f64.clamp(model.lower_limits[i], model.upper_limits[i]);
        }
    }
    q
}

impl Simulator {
    /// `robot` standing on the floor in [`standing_pose`] with each joint driven by
    /// `servo(model, joint)` (a P servo; [`Simulator::standing_on_datasheet_servos`]
    /// takes each joint's own), returned with the pose. A robot with nothing to stand
    /// on (no collision primitive touches the floor: mesh-only feet) is refused,
    /// naming what is missing.
    pub fn standing_on_servos(
        robot: &Description,
        config: SimConfig,
        servo: &dyn Fn(&Model, usize) -> DynamixelServo,
    ) -> Result<(Simulator, Vec<f64>), SimError> {
        let mut sim = Simulator::new(robot, config)?;
        for i in 0..sim.model.nbodies {
            sim.actuators[i] = Actuator::Dynamixel(servo(&sim.model, i));
        }
        sim.check_can_stand()?;
        let pose = standing_pose(&sim.model);
        sim.place_on_ground(&pose)?;
        Ok((sim, pose))
    }

    /// Whether anything of the robot can touch the floor: an error naming what is
    /// missing when no collision primitive takes part in contact.
    pub fn check_can_stand(&self) -> Result<(), SimError> {
        if self.contact_points().is_empty() {
            return Err(SimError::Input(nothing_to_stand_on(self)));
        }
        Ok(())
    }

    /// [`Simulator::standing_on_servos`] with each joint's datasheet servo
    /// ([`servo_for_joint`]: a built-in robot's own, else one from the limits).
    pub fn standing_on_datasheet_servos(
        robot: &Description,
        config: SimConfig,
    ) -> Result<(Simulator, Vec<f64>), SimError> {
        let name = robot.name.clone();
        Simulator::standing_on_servos(robot, config, &|m, i| servo_for_joint(&name, m, i))
    }
}

/// Why `sim` cannot stand: the links whose only collision shapes are meshes, or, with
/// none, that no collision shape takes part in contact at all.
pub fn nothing_to_stand_on(sim: &Simulator) -> String {
    if sim.mesh_only_links.is_empty() {
        "the robot has no collision primitives that touch the floor (no <collision> box, \
         sphere, cylinder or capsule takes part in contact; in MJCF, a geom with contype and \
         conaffinity 0 that no <contact><pair> names does not collide); add <collision> \
         boxes to the feet"
            .into()
    } else {
        format!(
            "the robot has no collision primitives to stand on (mesh-only links: {}); \
             add <collision> boxes to the feet",
            sim.mesh_only_links.join(", ")
        )
    }
}
