//! The bus side of the simulated robot: [`VirtualServoBackend`] over the shared
//! registers and snapshot. Nothing here steps the simulation.

use crate::shared::Shared;
use std::sync::Arc;
use twinloop_link::servo::ServoMeasurement;
use twinloop_link::{BoardAxes, ImuSample, Item, ServoModel, VirtualServoBackend};

/// Moves the bus's servos by handing their registers to the simulator thread and
/// answers from the simulator's latest snapshot.
pub struct SimServoBackend {
    pub(crate) shared: Arc<Shared>,
    /// Each servo's model (bus order), to read its registers' units.
    pub(crate) models: Vec<ServoModel>,
    /// The boards after the servos (bus order): how each sits in the IMU's link.
    pub(crate) boards: Vec<BoardAxes>,
}

impl VirtualServoBackend for SimServoBackend {
    fn set_torque_enabled(&mut self, servo: usize, enabled: bool) {
        let mut r = self
            .shared
            .registers
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        r[servo].torque_on = enabled;
    }

    fn set_goal_position(&mut self, servo: usize, position: f64) {
        self.shared.heard();
        let mut r = self
            .shared
            .registers
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        r[servo].goal = position;
    }

    fn measure(&self, servo: usize) -> ServoMeasurement {
        self.shared.heard();
        let s = self
            .shared
            .snapshot
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        s.servos[servo]
    }

    /// Time runs on the simulator's thread.
    fn step(&mut self, _dt: f64) {}

    /// The simulated trunk IMU (the link the board is on), turned onto the board's
    /// axes; the bus quantises it into the board's counts.
    fn board_imu(&self, board: usize) -> Option<ImuSample> {
        let axes = self.boards.get(board.checked_sub(self.models.len())?)?;
        let s = self
            .shared
            .snapshot
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        let imu = s.state.imu?;
        Some(ImuSample {
            gyro: axes.link_to_board(imu.gyro),
            accel: axes.link_to_board(imu.accel),
        })
    }

    fn register_written(&mut self, servo: usize, item: Item, raw: i32) {
        let model = self.models[servo];
        let mut r = self
            .shared
            .registers
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        r[servo].set(model, item, raw);
    }
}
