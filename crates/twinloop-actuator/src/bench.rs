//! The bench: one servo turning a load ([`Load`]): BAM's pendulum (a mass on an arm,
//! angle 0 hanging down) or a limb of a held robot. [`Bench::step`] is the whole
//! model in one place: sensing, firmware, motor, friction and the load's motion.

use crate::delay::Samples;
use crate::error::ActuatorError;
use crate::firmware::Firmware;
use crate::friction::budget;
use crate::load::Load;
use crate::motor::motor_torque;
use crate::params::{BACKLASH, BUS_DELAY, FRICTION_VISCOUS, SENSING_DELAY, ServoParams};
use std::path::Path;

/// Standard gravity, m/s^2 (the workspace's one value, twinloop_description::GRAVITY).
pub const GRAVITY: f64 = 9.81;

/// The load: a point mass at `length` from the axis on an arm of inertia
/// `arm_inertia` about it (the arm's own weight taken as balanced).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pendulum {
    /// kg.
    pub mass: f64,
    /// m, axis to the mass's centre.
    pub length: f64,
    /// kg m^2, the arm alone about the axis.
    pub arm_inertia: f64,
}

impl Pendulum {
    /// Inertia about the axis, without the servo's armature, kg m^2.
    pub fn inertia(&self) -> f64 {
        self.arm_inertia + self.mass * self.length * self.length
    }

    /// Gravity's torque at angle `q` (0 hanging down), N m.
    pub fn gravity_torque(&self, q: f64) -> f64 {
        -self.mass * GRAVITY * self.length * q.sin()
    }

    /// Read a LOAD.toml: `mass` (kg), `length` (m), `arm_inertia` (kg m^2).
    pub fn read(path: &Path) -> Result<Pendulum, ActuatorError> {
        let file = path.display().to_string();
        let text = twinloop_io::input::read_to_string(path)
            .map_err(|e| ActuatorError::new(&file, "", format!("cannot read: {e}")))?;
        Self::parse(&text, &file)
    }

    pub fn parse(text: &str, file: &str) -> Result<Pendulum, ActuatorError> {
        let mut doc: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| ActuatorError::toml(file, text, &e))?;
        let mut get = |key: &str| -> Result<f64, ActuatorError> {
            let v = doc.remove(key).ok_or_else(|| {
                ActuatorError::new(file, key, "missing (mass kg, length m, arm_inertia kg m^2)")
            })?;
            let x = crate::params::number(&v, "load", key, file)
                .map_err(|_| ActuatorError::new(file, key, "must be a number"))?;
            if !x.is_finite() || x < 0.0 {
                return Err(ActuatorError::new(
                    file,
                    key,
                    format!("{x} is not a finite number >= 0"),
                ));
            }
            Ok(x)
        };
        let p = Pendulum {
            mass: get("mass")?,
            length: get("length")?,
            arm_inertia: get("arm_inertia")?,
        };
        if let Some(k) = doc.keys().next() {
            return Err(ActuatorError::new(
                file,
                k.as_str(),
                "unknown field (mass, length, arm_inertia)",
            ));
        }
        if p.inertia() <= 0.0 {
            return Err(ActuatorError::new(
                file,
                "",
                "the load has no inertia (mass and length, or arm_inertia)",
            ));
        }
        Ok(p)
    }
}

impl From<Pendulum> for Load {
    /// A point mass `mass` at `length` on an arm of `arm_inertia`, hanging down at 0.
    fn from(p: Pendulum) -> Load {
        Load {
            inertia: p.inertia(),
            gravity_sin: -p.mass * GRAVITY * p.length,
            gravity_cos: 0.0,
            gravity_const: 0.0,
        }
    }
}

impl From<&Pendulum> for Load {
    fn from(p: &Pendulum) -> Load {
        Load::from(*p)
    }
}

/// A servo on the bench: parameters, firmware, and the state.
///
/// With a `backlash` the gearbox's last gear (the motor side, angle `qm` at the
/// output's scale, inertia the armature) and the output (angle `q`, the load) are two
/// bodies: inside the dead band each moves on its own; at its edge they move as one
/// while the motor side pushes the load, and meet in an inelastic impact. The encoder
/// is on the output (as on the Dynamixels: potentiometer or magnet on the output
/// shaft), so the loop sees the load's angle.
#[derive(Debug, Clone)]
pub struct Bench {
    /// Fixed at [`Bench::new`] (the step keeps what it needs of them worked out).
    params: ServoParams,
    /// What every step needs of `params` and `load`, worked out once.
    k: Constants,
    /// Fixed at [`Bench::new`], like `params`.
    load: Load,
    pub firmware: Firmware,
    /// Goal Position in force, rad (already a whole number of counts when it came over
    /// a bus).
    pub goal: f64,
    pub torque_on: bool,
    /// Output angle (rad) and speed (rad/s).
    pub q: f64,
    pub v: f64,
    /// The motor side's angle at the output's scale and speed (equal to `q`, `v`
    /// where the gap is closed).
    pub qm: f64,
    pub vm: f64,
    /// The bench's clock, s.
    pub t: f64,
    /// Last step's PWM duty, motor current (A) and motor torque (N m).
    pub duty: f64,
    pub current: f64,
    pub motor_torque: f64,
    /// (time, output angle) of the last `sensing_delay` seconds, oldest first.
    history: Samples,
    /// Goals sent but not yet in force: (time they take effect, goal).
    pending: Samples,
}

/// The parameters' terms the step uses, by the step's own expressions (so the same
/// bits as working them out in every step).
#[derive(Debug, Clone, Copy)]
struct Constants {
    kt: f64,
    resistance: f64,
    voltage: f64,
    armature: f64,
    /// `kt / resistance`: the drive per volt of the winding.
    drive: f64,
    /// `kt^2 / resistance + friction_viscous`, and `friction_viscous` alone (torque
    /// off: no back-EMF brake).
    damping_on: f64,
    damping_off: f64,
    /// Half the backlash, rad.
    half: f64,
    /// Armature and load together (the gap closed).
    engaged_inertia: f64,
}

impl Constants {
    fn new(p: &ServoParams, load: &Load) -> Constants {
        let (kt, res) = (p.kt(), p.resistance());
        Constants {
            kt,
            resistance: res,
            voltage: p.voltage,
            armature: p.armature(),
            drive: kt / res,
            damping_on: kt * kt / res + p.values[FRICTION_VISCOUS],
            damping_off: 0.0 + p.values[FRICTION_VISCOUS],
            half: 0.5 * p.values[BACKLASH],
            engaged_inertia: p.armature() + load.inertia,
        }
    }
}

impl Bench {
    pub fn new(params: ServoParams, load: impl Into<Load>) -> Bench {
        let load = load.into();
        Bench {
            firmware: Firmware::new(params.servo),
            k: Constants::new(&params, &load),
            params,
            load,
            goal: 0.0,
            torque_on: false,
            q: 0.0,
            v: 0.0,
            qm: 0.0,
            vm: 0.0,
            t: 0.0,
            duty: 0.0,
            current: 0.0,
            motor_torque: 0.0,
            history: Samples::with_capacity(256),
            pending: Samples::with_capacity(16),
        }
    }

    /// The servo's parameters (fixed for the bench's life).
    pub fn params(&self) -> &ServoParams {
        &self.params
    }

    /// What the servo turns (fixed for the bench's life).
    pub fn load(&self) -> &Load {
        &self.load
    }

    /// Put the output at `q`, `v` with the gap closed and no history (a log's first
    /// row).
    pub fn place(&mut self, q: f64, v: f64) {
        self.q = q;
        self.v = v;
        self.qm = q;
        self.vm = v;
        self.history.clear();
        self.pending.clear();
    }

    /// A Goal Position sent now: in force after the `bus_delay`.
    pub fn send_goal(&mut self, goal: f64) {
        let delay = self.params.values[BUS_DELAY];
        if delay <= 0.0 {
            self.goal = goal;
        } else {
            self.pending.push_back(self.t + delay, goal);
        }
    }

    /// The output angle `sensing_delay` ago (linear between the bench's steps), rad:
    /// what the loop and Present Position see before the encoder's counts.
    pub fn sensed_angle(&self) -> f64 {
        let delay = self.params.values[SENSING_DELAY];
        if delay <= 0.0 {
            return self.q;
        }
        self.history.value_at(self.t - delay, (self.t, self.q))
    }

    /// Present Position as the encoder gives it: a whole number of counts, rad.
    pub fn sensed_position(&self) -> f64 {
        let r = self.params.servo.resolution();
        (self.sensed_angle() / r).round() * r
    }

    /// Advance `dt` seconds (one firmware cycle): goals whose bus delay has passed
    /// come into force, the loop acts on the sensed counts, the motor drives through
    /// the back-EMF, friction takes what it can to stop the motor side (`budget`),
    /// and the load moves with it or, inside the backlash, on its own. Semi-implicit
    /// Euler, implicit in the linear damping (back-EMF and viscous), so a stiff servo
    /// stays stable.
    pub fn step(&mut self, dt: f64) {
        // A goal coming into force inside the step splits it there, so the response
        // moves continuously with the bus delay (LM fits it).
        if let Some((t, _)) = self.pending.front() {
            let into = t - self.t;
            if into > 1e-9 && into < dt - 1e-9 {
                self.cycle(into);
                self.cycle(dt - into);
                return;
            }
        }
        self.cycle(dt);
    }

    fn cycle(&mut self, dt: f64) {
        while let Some((t, g)) = self.pending.front() {
            if t > self.t + 1e-9 {
                break;
            }
            self.goal = g;
            self.pending.pop_front();
        }
        self.duty = if self.torque_on {
            let sensed = self.sensed_angle();
            self.firmware.cycle(self.goal, sensed, dt)
        } else {
            0.0
        };
        let half = self.k.half;
        let delta = self.qm - self.q;
        // Engaged: the gap is closed on one side (within a nanoradian).
        let side = if half <= 0.0 {
            0.0
        } else if delta >= half - 1e-9 {
            1.0
        } else if delta <= -half + 1e-9 {
            -1.0
        } else {
            f64::NAN
        };
        let mut moved = false;
        // Gravity at the step's start angle: both branches below use it.
        let gravity = self.load.gravity_torque(self.q);
        if !side.is_nan() {
            let (v, vm) = (self.v, self.vm);
            let v_new = self.motor_side_step(dt, self.k.engaged_inertia, gravity);
            // The torque the motor side puts on the load must push it, not pull.
            let push = self.load.inertia * (v_new - v) / dt - gravity;
            if side == 0.0 || push * side >= 0.0 {
                self.v = v_new;
                self.vm = v_new;
                self.q += dt * v_new;
                self.qm = self.q + side * half;
                moved = true;
            } else {
                self.vm = vm; // undo: the gap opens this step
            }
        }
        if !moved {
            // Apart: the motor side alone on its armature, the load alone under gravity.
            let vm_new = self.motor_side_step(dt, self.k.armature, 0.0);
            self.vm = vm_new;
            self.v += dt * gravity / self.load.inertia;
            self.qm += dt * self.vm;
            self.q += dt * self.v;
            let delta = self.qm - self.q;
            if delta.abs() >= half {
                // The gap closes: an inelastic impact.
                let (jm, jl) = (self.k.armature, self.load.inertia);
                let common = (jm * self.vm + jl * self.v) / (jm + jl);
                self.vm = common;
                self.v = common;
                self.qm = self.q + half * delta.signum();
            }
        }
        let (tau, current) = if self.torque_on {
            let k = &self.k;
            motor_torque(k.kt, k.resistance, k.voltage, self.duty, self.vm)
        } else {
            (0.0, 0.0)
        };
        self.motor_torque = tau;
        self.current = current;
        self.t += dt;
        if self.params.values[SENSING_DELAY] > 0.0 {
            self.history.push_back(self.t, self.q);
            let keep = self.t - self.params.values[SENSING_DELAY] - 2.0 * dt;
            self.history.forget_before(keep);
        }
    }

    /// The motor side's new speed after `dt` with `inertia` on it (armature, plus
    /// the load where engaged) and an external torque `external`: the drive through
    /// the back-EMF, the friction budget stopping what it can (BAM's formulation),
    /// implicit in the linear damping. Writes `self.vm`.
    fn motor_side_step(&mut self, dt: f64, inertia: f64, external: f64) -> f64 {
        let k = &self.k;
        let (kt, res, volts) = (k.kt, k.resistance, k.voltage);
        // Torque off: the driver's bridge is open, no current flows, no back-EMF brake.
        let (damping, drive) = if self.torque_on {
            (k.damping_on, k.drive * self.duty * volts)
        } else {
            (k.damping_off, 0.0)
        };
        let h = inertia + dt * damping;
        let free = (inertia * self.vm + dt * (drive + external)) / h;
        let tau_m = if self.torque_on {
            motor_torque(kt, res, volts, self.duty, self.vm).0
        } else {
            0.0
        };
        let limit = budget(&self.params.values, self.vm, tau_m);
        let stop = free * h / dt;
        // max/min, not clamp: a diverging trial's NaN reaches the fit's cost, not a panic.
        let friction = stop.max(-limit).min(limit);
        self.vm = free - dt * friction / h;
        self.vm
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::datasheet::defaults;
    use crate::{ModelLevel, ServoType};

    /// With Profile Velocity and Acceleration the servo follows the trapezoid: 1 rad
    /// at 2 rad/s and 10 rad/s^2 takes 0.7 s (0.2 s up, 0.3 s cruising, 0.2 s
    /// down), so halfway in time the reference is halfway there and the output
    /// cruises at 2 rad/s (behind by the loop's velocity lag), and after the end it
    /// is at the goal.
    #[test]
    fn the_servo_follows_its_profile() {
        let p = defaults(ServoType::Xm430W350, ModelLevel::M1);
        let load = Pendulum {
            mass: 0.1,
            length: 0.05,
            arm_inertia: 0.0,
        };
        let mut b = Bench::new(p, load);
        b.firmware.registers[0] = 3000.0; // stiff: small lag
        b.firmware.profile.velocity = 2.0;
        b.firmware.profile.acceleration = 10.0;
        b.torque_on = true;
        b.send_goal(1.0);
        let dt = 2.5e-4;
        let at = |b: &mut Bench, t: f64| {
            while b.t < t - 1e-12 {
                b.step(dt);
            }
            b.q
        };
        let count = ServoType::Xm430W350.resolution();
        let half = at(&mut b, 0.35);
        assert!((b.firmware.profile.position - 0.5).abs() < 2e-3);
        assert!((b.v - 2.0).abs() < 0.05, "{}", b.v);
        assert!(half < 0.5 && half > 0.5 - 30.0 * count, "{half}");
        let end = at(&mut b, 0.75);
        assert!((end - 1.0).abs() < 3.0 * count, "{end}");
        // Without a profile the servo is nearly there at that time already.
        let mut fast = Bench::new(defaults(ServoType::Xm430W350, ModelLevel::M1), load);
        fast.firmware.registers[0] = 3000.0;
        fast.torque_on = true;
        fast.send_goal(1.0);
        let q = at(&mut fast, 0.35);
        assert!(q > 0.9, "{q}");
    }

    #[test]
    fn a_pendulum_is_a_load() {
        let p = Pendulum {
            mass: 0.5,
            length: 0.15,
            arm_inertia: 0.001,
        };
        let l = Load::from(p);
        for q in [-2.0, -0.3, 0.0, 0.7, 3.0] {
            assert!((l.gravity_torque(q) - p.gravity_torque(q)).abs() < 1e-14);
        }
        assert_eq!(l.inertia, p.inertia());
    }
}
