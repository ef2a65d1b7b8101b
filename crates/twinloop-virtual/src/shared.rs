//! What the bus thread and the simulator thread share: the servos' registers
//! (bus -> simulator) and the latest measurements (simulator -> bus). Both are
//! sized once; updating them copies numbers in place.

use crate::drive::DriveRegisters;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;
use twinloop_link::servo::ServoMeasurement;
use twinloop_robot::RobotState;

/// The simulation as last published.
#[derive(Debug, Clone, Default)]
pub struct Snapshot {
    /// Simulated time, s.
    pub time: f64,
    /// Per servo (bus order), in the servo's own angle and units.
    pub servos: Vec<ServoMeasurement>,
    /// The whole simulated robot: joint positions, velocities and torques in the
    /// simulator's joint order, trunk IMU, feet.
    pub state: RobotState,
    /// Height of the floating base above the ground, m.
    pub base_height: f64,
    /// The simulator's whole configuration (`Model::q_names` order: the floating
    /// base's pose first, when it has one): what a viewer draws.
    pub q: Vec<f64>,
    /// Steps taken since the start.
    pub steps: u64,
    /// How far simulated time lags the wall clock, s (0 when the simulator keeps up).
    pub behind_s: f64,
    /// Set once if the simulation stopped (it diverged); it then stays frozen.
    pub error: Option<String>,
}

impl Snapshot {
    /// Copy `src` into `self` reusing `self`'s buffers (no allocation once the
    /// vectors have their sizes; `Clone::clone_from` of a derived `Clone` would
    /// allocate the feet's names).
    pub fn copy_from(&mut self, src: &Snapshot) {
        self.time = src.time;
        self.servos.clone_from(&src.servos);
        self.base_height = src.base_height;
        self.q.clone_from(&src.q);
        self.steps = src.steps;
        self.behind_s = src.behind_s;
        if src.error.is_some() && self.error.is_none() {
            self.error.clone_from(&src.error);
        }
        let (d, s) = (&mut self.state, &src.state);
        d.time = s.time;
        d.positions.clone_from(&s.positions);
        d.velocities.clone_from(&s.velocities);
        d.efforts.clone_from(&s.efforts);
        d.imu = s.imu;
        d.feet
            .resize_with(s.feet.len(), twinloop_robot::FootSensor::default);
        for (a, b) in d.feet.iter_mut().zip(&s.feet) {
            if a.name != b.name {
                a.name.clone_from(&b.name);
            }
            a.force = b.force;
            a.cop = b.cop;
        }
    }
}

pub(crate) struct Shared {
    pub registers: Mutex<Vec<DriveRegisters>>,
    pub snapshot: Mutex<Snapshot>,
    pub stop: AtomicBool,
    /// When the bus last served the host (a servo read or a goal written), in
    /// nanoseconds since `epoch`: the tether of [`crate::VirtualRobotOptions::tether_s`].
    pub epoch: Instant,
    pub last_heard_ns: AtomicU64,
}

impl Shared {
    pub fn new(registers: Vec<DriveRegisters>) -> Shared {
        Shared {
            registers: Mutex::new(registers),
            snapshot: Mutex::new(Snapshot::default()),
            stop: AtomicBool::new(false),
            epoch: Instant::now(),
            last_heard_ns: AtomicU64::new(0),
        }
    }

    /// The host was just served.
    pub fn heard(&self) {
        let ns = self.epoch.elapsed().as_nanos() as u64;
        self.last_heard_ns.store(ns, Ordering::Relaxed);
    }

    /// Wall-clock seconds since the host was last served.
    pub fn silence_s(&self) -> f64 {
        let now = self.epoch.elapsed().as_nanos() as u64;
        now.saturating_sub(self.last_heard_ns.load(Ordering::Relaxed)) as f64 * 1e-9
    }
}

/// Winding temperature after `dt` seconds: a first-order thermal model driven by
/// copper loss, which goes with the square of the torque. At a continuous
/// `load` (torque over stall torque) the temperature settles at
/// `ambient + rise_at_stall * load^2` with time constant `tau` (s).
///
/// The constants the virtual robot uses ([`AMBIENT_C`], [`RISE_AT_STALL_K`],
/// [`THERMAL_TAU_S`]) are assumptions, not datasheet values: ROBOTIS publishes no
/// thermal data for RX/X servos. They are chosen so a servo held at stall reaches
/// the factory Temperature Limit (80 C) in about 80 s (a guess of the right order,
/// not a measurement) and an idle one stays at ambient.
pub fn thermal_step(temperature: f64, load: f64, dt: f64) -> f64 {
    let target = AMBIENT_C + RISE_AT_STALL_K * load * load;
    target + (temperature - target) * (-dt / THERMAL_TAU_S).exp()
}

/// Ambient temperature, C.
pub const AMBIENT_C: f64 = 25.0;
/// Steady temperature rise held at stall, K.
pub const RISE_AT_STALL_K: f64 = 100.0;
/// Thermal time constant, s.
pub const THERMAL_TAU_S: f64 = 100.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thermal_steps_compose_to_the_first_order_solution() {
        // Held at stall from ambient for 80 s in 1 ms steps vs the closed form.
        let mut t = AMBIENT_C;
        for _ in 0..80_000 {
            t = thermal_step(t, 1.0, 1e-3);
        }
        let exact = AMBIENT_C + RISE_AT_STALL_K * (1.0 - (-80.0 / THERMAL_TAU_S).exp());
        assert!((t - exact).abs() < 1e-6, "{t} vs {exact}");
        // ~80 C: the RX factory Temperature Limit.
        assert!((t - 80.0).abs() < 0.5, "{t}");
        // Idle stays at ambient; load sign does not matter.
        assert_eq!(thermal_step(AMBIENT_C, 0.0, 1.0), AMBIENT_C);
        assert_eq!(thermal_step(40.0, -0.5, 0.1), thermal_step(40.0, 0.5, 0.1));
    }
}
