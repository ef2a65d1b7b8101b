//! The simulator as a [`twinloop_robot::Robot`]: experiments run on it unchanged.

use crate::simulator::Simulator;
use twinloop_robot::{Robot, RobotError, RobotState};

impl Robot for Simulator {
    fn joint_names(&self) -> &[String] {
        &self.model.joint_names
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn read(&mut self, state: &mut RobotState) -> Result<(), RobotError> {
        self.read_sensors(state);
        Ok(())
    }

    fn command_positions(&mut self, goals: &[f64]) -> Result<(), RobotError> {
        if goals.len() != self.goals.len() {
            return Err(RobotError::new(format!(
                "{} goals given, the robot has {} joints",
                goals.len(),
                self.goals.len()
            )));
        }
        for (i, g) in goals.iter().enumerate() {
            if !g.is_finite() {
                return Err(RobotError::at_joint(
                    &self.model.joint_names[i],
                    "goal is not finite",
                ));
            }
        }
        self.goals.copy_from_slice(goals);
        Ok(())
    }

    fn advance(&mut self, dt: f64) -> Result<(), RobotError> {
        let n = (dt / self.config.dt).round().max(0.0) as u64;
        for _ in 0..n {
            self.step().map_err(|e| RobotError::new(e.to_string()))?;
        }
        Ok(())
    }
}
