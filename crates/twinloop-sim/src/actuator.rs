//! Joint actuators. Each gives, for the current goal and joint state, the torque and
//! its local stiffness and damping, so the step can treat them implicitly: a stiff
//! servo stays stable at a 1 ms step whatever the link inertia behind it.

use twinloop_actuator::friction::budget;
use twinloop_actuator::motor::motor_torque;
use twinloop_actuator::params::N_PARAMS;
use twinloop_actuator::{LoopFamily, ServoType};

/// Torque `tau` at the current state and its linearisation: a small change `dq`, `dv`
/// changes the torque by `-k dq - d dv`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Drive {
    pub tau: f64,
    pub k: f64,
    pub d: f64,
}

/// A Dynamixel servo in joint mode: a DC motor driven by a proportional position loop
/// with a saturating PWM (seed 000's "P-controlled servo"). The duty cycle is
/// `clamp((|e| - margin) / slope)`, zero inside the compliance margin, and the output
/// torque is that of a DC motor, `duty * stall_torque - (stall_torque / no_load_speed) * v`:
/// the back-EMF term is why a servo at full duty runs at its no-load speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamixelServo {
    /// Stall torque at the supply voltage, N m (datasheet).
    pub stall_torque: f64,
    /// No-load speed at the supply voltage, rad/s (datasheet).
    pub no_load_speed: f64,
    /// The Max Torque register as a fraction of the stall torque (1.0 = 1023).
    pub torque_limit: f64,
    /// Error at which the duty reaches 100 %, rad (the compliance slope).
    pub compliance_slope: f64,
    /// Dead band around the goal, rad (the compliance margin).
    pub compliance_margin: f64,
    /// The gearbox's dead band, full width, rad (0: none). With one, the motor side
    /// is a body of its own ([`crate::backlash`]).
    pub backlash: f64,
    /// The motor side's inertia at the output (the armature), kg m^2: used with a
    /// backlash, where it sits on the motor side of the gap; without one the
    /// armature is the joint's ([`crate::servo_params`]).
    pub motor_inertia: f64,
    /// The gearbox's Coulomb friction on the motor side, N m: used with a backlash
    /// (without one it is the joint's friction).
    pub gear_friction: f64,
    /// The full model of a parameter file (`crate::servo_model`): the firmware on
    /// encoder counts, the motor, BAM's friction budget, the delays. `None`: the
    /// continuous loop above.
    pub full: Option<FullServo>,
}

/// What a parameter file adds to a [`DynamixelServo`] (`crate::servo_model` runs
/// it): the servo type (encoder counts, loop family), the motor and gearbox
/// parameters, and the loop's registers that the servo's `compliance_slope` and
/// `compliance_margin` do not say.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FullServo {
    pub servo: ServoType,
    /// Supply voltage, V.
    pub voltage: f64,
    /// `twinloop_actuator::params::PARAM_NAMES` order.
    pub values: [f64; N_PARAMS],
    /// RX Punch, MX(2.0)/X Position I and D Gain: raw register values.
    pub punch: f64,
    pub i_gain: f64,
    pub d_gain: f64,
    /// Profile Velocity (rad/s, 0: none) and Acceleration (rad/s^2, 0: none); RX
    /// Moving Speed as the velocity.
    pub profile_velocity: f64,
    pub profile_acceleration: f64,
}

impl FullServo {
    pub fn kt(&self) -> f64 {
        self.values[twinloop_actuator::params::KT]
    }

    pub fn resistance(&self) -> f64 {
        self.values[twinloop_actuator::params::RESISTANCE]
    }

    /// Back-EMF damping `kt^2 / R`, N m s/rad.
    pub fn emf_damping(&self) -> f64 {
        self.kt() * self.kt() / self.resistance()
    }

    /// The gearbox's viscous friction, N m s/rad.
    pub fn viscous(&self) -> f64 {
        self.values[twinloop_actuator::params::FRICTION_VISCOUS]
    }

    /// The motor side's drive behind a backlash at its speed `vm` for duty `duty`:
    /// the motor's torque less the gearbox's viscous friction (both on the motor
    /// side of the gap, as on the bench), implicit in both dampings.
    pub fn motor_side_drive(&self, duty: f64, vm: f64) -> Drive {
        Drive {
            tau: self.torque(duty, vm) - self.viscous() * vm,
            k: 0.0,
            d: self.emf_damping() + self.viscous(),
        }
    }

    /// The motor torque at duty `duty` and motor speed `v`, N m.
    pub fn torque(&self, duty: f64, v: f64) -> f64 {
        motor_torque(self.kt(), self.resistance(), self.voltage, duty, v).0
    }

    /// The gearbox's Coulomb budget at motor speed `v` carrying `tau_m` (seed: BAM's
    /// M1-M4 through `budget`).
    pub fn friction(&self, v: f64, tau_m: f64) -> f64 {
        budget(&self.values, v, tau_m)
    }

    /// The firmware's registers for `s`'s compliance slope and margin (RX) or the P
    /// gain that reaches full PWM at `compliance_slope` (MX(2.0)/X), with the file's
    /// punch or I and D gains.
    pub fn registers(&self, s: &DynamixelServo) -> [f64; 3] {
        let r = self.servo.resolution();
        match self.servo.family() {
            // The slope register in counts (a power of two; rounded, not truncated,
            // so 32 counts stays 32 after the trip through radians).
            LoopFamily::Compliance => [
                (s.compliance_slope / r).round(),
                (s.compliance_margin / r).round(),
                self.punch,
            ],
            LoopFamily::Pid => [
                self.servo.pwm_max() * self.servo.p_gain_divisor() / (s.compliance_slope / r),
                self.i_gain,
                self.d_gain,
            ],
        }
    }
}

/// One Dynamixel position unit of the 1024-count, 300-degree servos (RX, AX).
pub const RX_POSITION_UNIT: f64 = 300.0 / 1024.0 * std::f64::consts::PI / 180.0;

impl DynamixelServo {
    /// RX-28 at 18.5 V: stall 3.7 N m, no-load 85 rpm (the catalogue's EM-RX28 datasheet); default
    /// compliance slope 32 units and margin 1 unit (RX control table defaults).
    pub fn rx28() -> Self {
        let spec = twinloop_servos::ServoModel::Rx28.spec();
        DynamixelServo {
            stall_torque: spec.stall_torque,
            no_load_speed: spec.no_load_speed,
            torque_limit: 1.0,
            compliance_slope: 32.0 * RX_POSITION_UNIT,
            compliance_margin: RX_POSITION_UNIT,
            backlash: 0.0,
            motor_inertia: 0.0,
            gear_friction: 0.0,
            full: None,
        }
    }

    /// RX-64 at 18.5 V: stall 5.3 N m, no-load 64 rpm (the catalogue's EM-RX64 datasheet).
    pub fn rx64() -> Self {
        let spec = twinloop_servos::ServoModel::Rx64.spec();
        DynamixelServo {
            stall_torque: spec.stall_torque,
            no_load_speed: spec.no_load_speed,
            ..Self::rx28()
        }
    }

    /// A servo of given stall torque and no-load speed with RX defaults otherwise.
    pub fn with_rating(stall_torque: f64, no_load_speed: f64) -> Self {
        DynamixelServo {
            stall_torque,
            no_load_speed,
            ..Self::rx28()
        }
    }

    /// The loop's torque at output angle `q` and motor speed `v` (the same as the
    /// output's without a backlash; with one, the torque is on the motor side and
    /// `v` its speed: [`crate::backlash`]).
    pub fn drive(&self, goal: f64, q: f64, v: f64) -> Drive {
        let t = self.stall_torque * self.torque_limit;
        let b = self.stall_torque / self.no_load_speed;
        let e = goal - q;
        let beyond = e.abs() - self.compliance_margin;
        let (duty, k) = if beyond <= 0.0 {
            (0.0, 0.0)
        } else if beyond >= self.compliance_slope {
            (e.signum(), 0.0)
        } else {
            (
                e.signum() * beyond / self.compliance_slope,
                t / self.compliance_slope,
            )
        };
        // The PWM cannot drive the motor beyond the supply: clamp the total torque too.
        let tau = duty * t - b * v;
        let cap = self.stall_torque;
        if tau.abs() > cap {
            Drive {
                tau: cap * tau.signum(),
                k: 0.0,
                d: 0.0,
            }
        } else {
            Drive { tau, k, d: b }
        }
    }
}

/// The two-loop servo of seed 003: a speed loop inside a position loop, both
/// proportional. `w_ref = clamp(kp_position e, +-max_speed)`,
/// `tau = clamp(kv (w_ref - v), +-max_torque)`. With `kv >= 4 J kp_position` for the link
/// inertia J the step response has no overshoot; seed 003's servos settle in about
/// 200 ms, i.e. `kp_position` about 20 1/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoLoopServo {
    /// Position-loop gain, 1/s.
    pub kp_position: f64,
    /// Speed-loop gain, N m s/rad.
    pub kv: f64,
    pub max_speed: f64,
    pub max_torque: f64,
}

impl TwoLoopServo {
    pub fn drive(&self, goal: f64, q: f64, v: f64) -> Drive {
        let w = self.kp_position * (goal - q);
        let (w_ref, kq) = if w.abs() > self.max_speed {
            (self.max_speed * w.signum(), 0.0)
        } else {
            (w, self.kv * self.kp_position)
        };
        let tau = self.kv * (w_ref - v);
        if tau.abs() > self.max_torque {
            Drive {
                tau: self.max_torque * tau.signum(),
                k: 0.0,
                d: 0.0,
            }
        } else {
            Drive {
                tau,
                k: kq,
                d: self.kv,
            }
        }
    }
}

/// The series-elastic joint of seed 002 (eq 1-6): a motor of reflected inertia
/// `I_m = N^2 J_m` and damping `d_m = N^2 (D_m + K_tau K_bemf / R_m)` drives the link
/// through a spring `k_j = K_h K_s / (K_h + K_s)`. The motor position follows the goal
/// with a stiff PD loop (seed 002 assumption A1); the link feels only the spring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeriesElastic {
    /// Joint stiffness k_j, N m/rad (seed 002 eq 1-2).
    pub stiffness: f64,
    /// Damping in parallel with the spring, N m s/rad.
    pub spring_damping: f64,
    /// Reflected motor inertia I_m, kg m^2 (eq 5).
    pub motor_inertia: f64,
    /// Reflected motor damping d_m, N m s/rad (eq 6).
    pub motor_damping: f64,
    /// Motor position loop, N m/rad and N m s/rad.
    pub kp: f64,
    pub kd: f64,
    pub max_torque: f64,
    /// Motor state at the link side (eq 3): position and velocity.
    pub theta: f64,
    pub theta_dot: f64,
}

impl SeriesElastic {
    /// Joint stiffness of a harmonic drive `k_h` in series with a spring `k_s` (seed 002).
    pub fn series_stiffness(k_h: f64, k_s: f64) -> f64 {
        k_h * k_s / (k_h + k_s)
    }

    /// Reflected motor inertia and damping through a gear ratio `n` (seed 002, eq 5-6).
    pub fn reflected(n: f64, j_m: f64, d_m: f64, k_tau: f64, k_bemf: f64, r_m: f64) -> (f64, f64) {
        (n * n * j_m, n * n * (d_m + k_tau * k_bemf / r_m))
    }

    /// The torque on the link (eq 2's `k_j (theta - q)` plus spring damping).
    pub fn drive(&self, q: f64, v: f64) -> Drive {
        Drive {
            tau: self.stiffness * (self.theta - q) + self.spring_damping * (self.theta_dot - v),
            k: self.stiffness,
            d: self.spring_damping,
        }
    }

    /// Advance the motor (seed 002, eq 1) by `dt` with the link at `q`, `v`, linearly
    /// implicit in the motor's own stiffness and damping so a stiff loop stays stable.
    pub fn advance_motor(&mut self, goal: f64, q: f64, v: f64, dt: f64) {
        let e = goal - self.theta;
        let mut tau = self.kp * e - self.kd * self.theta_dot;
        let (mut kp, mut kd) = (self.kp, self.kd);
        if tau.abs() > self.max_torque {
            tau = self.max_torque * tau.signum();
            kp = 0.0;
            kd = 0.0;
        }
        let k = kp + self.stiffness;
        let d = kd + self.motor_damping + self.spring_damping;
        let force = tau
            - self.motor_damping * self.theta_dot
            - self.stiffness * (self.theta - q)
            - self.spring_damping * (self.theta_dot - v);
        let h = self.motor_inertia + dt * d + dt * dt * k;
        let dw = dt * (force - dt * k * self.theta_dot) / h;
        self.theta_dot += dw;
        self.theta += dt * self.theta_dot;
    }
}

/// A servo for a joint from its description limits: the effort limit as the stall
/// torque and the velocity limit as the no-load speed where they look like ratings;
/// placeholders (OP3's 1000 N m and 100 rad/s) and missing limits fall back to an
/// XM430-class servo (4.1 N m, 46 rpm) scaled to the robot's mass (per 3.2 kg, OP3's).
/// Position loop: full duty at 0.19 rad, no dead band (X-series PID; 5.1 stall/rad is
/// the gain of the Menagerie OP3).
pub fn servo_from_limits(effort: f64, velocity: f64, robot_mass: f64) -> DynamixelServo {
    let real = |x: f64, max: f64| x.is_finite() && x > 0.0 && x < max;
    let scale = (robot_mass / 3.2).max(1.0);
    let stall = if real(effort, 999.0) {
        effort
    } else {
        4.1 * scale
    };
    let speed = if real(velocity, 99.0) {
        velocity
    } else {
        46.0 * std::f64::consts::TAU / 60.0
    };
    let mut s = DynamixelServo::with_rating(stall, speed);
    s.compliance_slope = 0.19;
    s.compliance_margin = 0.0;
    s
}

/// The servo of joint `i`: a built-in robot's own (its datasheet rating, RX defaults
/// otherwise), else one derived from the description's limits
/// ([`servo_from_limits`]).
pub fn servo_for_joint(
    robot_name: &str,
    model: &twinloop_dynamics::Model,
    i: usize,
) -> DynamixelServo {
    match twinloop_description::builtin::servo_of_joint(robot_name, &model.joint_names[i]) {
        Some(spec) => DynamixelServo::with_rating(spec.stall_torque, spec.no_load_speed),
        None => servo_from_limits(
            model.effort_limits[i],
            model.velocity_limits[i],
            model.total_mass,
        ),
    }
}

/// What drives a joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Actuator {
    /// Nothing: the joint is free (its URDF damping still acts).
    Passive,
    /// The commanded value is a torque, N m (or N for a prismatic joint).
    Torque,
    Dynamixel(DynamixelServo),
    TwoLoop(TwoLoopServo),
    SeriesElastic(SeriesElastic),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dynamixel_runs_at_no_load_speed_at_full_duty() {
        let s = DynamixelServo::rx28();
        let d = s.drive(1.0, 0.0, s.no_load_speed);
        assert!(d.tau.abs() < 1e-12);
        let stall = s.drive(1.0, 0.0, 0.0);
        assert!((stall.tau - 3.7).abs() < 1e-12);
        // Inside the margin: no torque at rest.
        assert_eq!(s.drive(0.5 * RX_POSITION_UNIT, 0.0, 0.0).tau, 0.0);
        // On the slope, the linearisation predicts the torque change.
        let e = 10.0 * RX_POSITION_UNIT;
        let a = s.drive(e, 0.0, 0.1);
        let b = s.drive(e, 1e-6, 0.1 + 1e-6);
        assert!(((b.tau - a.tau) - (-a.k * 1e-6 - a.d * 1e-6)).abs() < 1e-12);
    }

    #[test]
    fn two_loop_saturates_speed_then_torque() {
        let s = TwoLoopServo {
            kp_position: 20.0,
            kv: 1.0,
            max_speed: 5.0,
            max_torque: 2.0,
        };
        assert_eq!(s.drive(0.1, 0.0, 0.0).tau, 2.0);
        let d = s.drive(0.01, 0.0, 0.0);
        assert!((d.tau - 0.2).abs() < 1e-12 && d.k == 20.0 && d.d == 1.0);
        let far = s.drive(10.0, 0.0, 4.5);
        assert!((far.tau - 0.5).abs() < 1e-12 && far.k == 0.0);
    }

    #[test]
    fn series_stiffness_of_coman_joints() {
        // Seed 002: K_h about 8000, K_s about 100 N m/rad: k_j just under K_s.
        let k = SeriesElastic::series_stiffness(8000.0, 100.0);
        assert!((k - 800000.0 / 8100.0).abs() < 1e-9 && k < 100.0);
    }
}
