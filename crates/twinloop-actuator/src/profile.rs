//! The firmware's motion profile: the reference the position loop follows towards a
//! new goal (EM-XM430 "Profile Velocity(112)", "Profile Acceleration(108)": with
//! Profile Velocity 0 a step, with only Profile Velocity a rectangular velocity
//! profile, with both a trapezoidal one; EM-RX28 "Moving Speed(32)": the goal is
//! approached at that speed, 0 meaning as fast as the motor goes).

use crate::servo_type::{LoopFamily, ServoType};

/// rpm per unit of X/MX(2.0) Profile Velocity (EM-XM430).
pub const X_VELOCITY_UNIT_RPM: f64 = 0.229;
/// rev/min^2 per unit of X/MX(2.0) Profile Acceleration (EM-XM430).
pub const X_ACCELERATION_UNIT_RPM2: f64 = 214.577;
/// rpm per unit of RX Moving Speed (EM-RX28).
pub const RX_SPEED_UNIT_RPM: f64 = 0.111;

/// The profile's limits and the reference's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profile {
    /// rad/s; 0: no profile (the goal is the reference at once).
    pub velocity: f64,
    /// rad/s^2; 0: none (a rectangular velocity profile).
    pub acceleration: f64,
    /// The reference (rad) and its speed (rad/s); NaN until the first cycle.
    pub position: f64,
    pub speed: f64,
}

impl Default for Profile {
    fn default() -> Self {
        Profile {
            velocity: 0.0,
            acceleration: 0.0,
            position: f64::NAN,
            speed: 0.0,
        }
    }
}

impl Profile {
    /// The limits for raw register values: X/MX(2.0) Profile Velocity and Profile
    /// Acceleration, RX Moving Speed (`acceleration` unused).
    pub fn from_registers(servo: ServoType, velocity: f64, acceleration: f64) -> Profile {
        let mut p = Profile::default();
        p.set_velocity_register(servo, velocity);
        if servo.family() == LoopFamily::Pid {
            p.set_acceleration_register(acceleration);
        }
        p
    }

    /// Profile Velocity (X, MX(2.0)) or Moving Speed (RX), raw.
    pub fn set_velocity_register(&mut self, servo: ServoType, raw: f64) {
        let unit = match servo.family() {
            LoopFamily::Compliance => RX_SPEED_UNIT_RPM,
            LoopFamily::Pid => X_VELOCITY_UNIT_RPM,
        };
        self.velocity = raw.max(0.0) * unit * std::f64::consts::TAU / 60.0;
    }

    /// Profile Acceleration (X, MX(2.0)), raw.
    pub fn set_acceleration_register(&mut self, raw: f64) {
        self.acceleration =
            raw.max(0.0) * X_ACCELERATION_UNIT_RPM2 * std::f64::consts::TAU / 3600.0;
    }

    /// Start the reference again where the servo is (torque on, a reboot).
    pub fn restart(&mut self) {
        self.position = f64::NAN;
        self.speed = 0.0;
    }

    /// The reference for this cycle of `dt` towards `goal`, starting from `present`
    /// the first time: speed at most `velocity`, changed by at most `acceleration dt`,
    /// and braking so it stops at the goal (`|speed|` at most what braking at
    /// `acceleration` can stop within what is left).
    pub fn reference(&mut self, goal: f64, present: f64, dt: f64) -> f64 {
        if self.velocity <= 0.0 {
            self.position = goal;
            self.speed = 0.0;
            return goal;
        }
        if !self.position.is_finite() {
            self.position = present;
            self.speed = 0.0;
        }
        let left = goal - self.position;
        let mut want = left.signum() * self.velocity;
        if self.acceleration > 0.0 {
            // The speed from which braking at `acceleration` stops at the goal, for
            // steps that move by the new speed (`v^2 / 2a + v dt / 2 = |left|`).
            let h = 0.5 * self.acceleration * dt;
            let brake = -h + (h * h + 2.0 * self.acceleration * left.abs()).sqrt();
            want = left.signum() * self.velocity.min(brake);
            let dv = self.acceleration * dt;
            self.speed += (want - self.speed).clamp(-dv, dv);
        } else {
            self.speed = want;
        }
        let step = self.speed * dt;
        if left == 0.0 || (step * left.signum() >= left.abs()) {
            self.position = goal;
            self.speed = 0.0;
        } else {
            self.position += step;
        }
        self.position
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trapezoid_reaches_the_goal_at_the_analytic_time() {
        // 1 rad at 2 rad/s and 10 rad/s^2: 0.2 s up, 0.3 s cruise, 0.2 s down = 0.7 s.
        let mut p = Profile {
            velocity: 2.0,
            acceleration: 10.0,
            ..Default::default()
        };
        let dt = 1e-4;
        let mut t = 0.0;
        let mut top = 0.0f64;
        while p.reference(1.0, 0.0, dt) < 1.0 {
            t += dt;
            top = top.max(p.speed);
            assert!(t < 2.0);
        }
        assert!((t - 0.7).abs() < 3e-3, "{t}");
        assert!((top - 2.0).abs() < 1e-9);
        // Rectangular: 1 rad at 2 rad/s, 0.5 s.
        let mut r = Profile {
            velocity: 2.0,
            ..Default::default()
        };
        assert!((r.reference(1.0, 0.0, 0.1) - 0.2).abs() < 1e-12);
        // No profile: the goal.
        assert_eq!(Profile::default().reference(1.0, 0.0, 0.1), 1.0);
        // Registers: X Profile Velocity 100 = 22.9 rpm.
        let x = Profile::from_registers(ServoType::Xm430W350, 100.0, 10.0);
        assert!((x.velocity - 22.9 * std::f64::consts::TAU / 60.0).abs() < 1e-12);
        assert!((x.acceleration - 2145.77 * std::f64::consts::TAU / 3600.0).abs() < 1e-9);
    }
}
