//! The pendulum bench (BAM's): one servo swinging a mass on an arm, angle 0 hanging
//! down. [`Bench::step`] is the whole model in one place: sensing, firmware, motor,
//! friction and the pendulum's motion.

use crate::error::ActuatorError;
use crate::firmware::Firmware;
use crate::friction::budget;
use crate::motor::motor_torque;
use crate::params::{FRICTION_VISCOUS, ServoParams};
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
        let text = std::fs::read_to_string(path)
            .map_err(|e| ActuatorError::new(&file, "", format!("cannot read: {e}")))?;
        Self::parse(&text, &file)
    }

    pub fn parse(text: &str, file: &str) -> Result<Pendulum, ActuatorError> {
        let mut doc: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| ActuatorError::new(file, "", e.message().to_string()))?;
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

/// A servo on the bench: parameters, firmware, and the state.
#[derive(Debug, Clone)]
pub struct Bench {
    pub params: ServoParams,
    pub load: Pendulum,
    pub firmware: Firmware,
    /// Goal Position, rad (already a whole number of counts when it came over a bus).
    pub goal: f64,
    pub torque_on: bool,
    /// Output angle (rad) and speed (rad/s).
    pub q: f64,
    pub v: f64,
    /// Last step's PWM duty, motor current (A) and motor torque (N m).
    pub duty: f64,
    pub current: f64,
    pub motor_torque: f64,
}

impl Bench {
    pub fn new(params: ServoParams, load: Pendulum) -> Bench {
        Bench {
            firmware: Firmware::new(params.servo),
            params,
            load,
            goal: 0.0,
            torque_on: false,
            q: 0.0,
            v: 0.0,
            duty: 0.0,
            current: 0.0,
            motor_torque: 0.0,
        }
    }

    /// Present Position as the encoder gives it: a whole number of counts, rad.
    pub fn sensed_position(&self) -> f64 {
        let r = self.params.servo.resolution();
        (self.q / r).round() * r
    }

    /// Advance `dt` seconds (one firmware cycle): the loop acts on the counts, the
    /// motor drives through the back-EMF, friction takes what it can to stop the
    /// output (`budget`), the rest moves the pendulum. Semi-implicit Euler, implicit
    /// in the linear damping (back-EMF and viscous), so a stiff servo stays stable.
    pub fn step(&mut self, dt: f64) {
        let p = &self.params;
        let r = p.servo.resolution();
        let (kt, res, volts) = (p.kt(), p.resistance(), p.voltage);
        self.duty = if self.torque_on {
            let error = (self.goal / r).round() - (self.q / r).round();
            self.firmware.duty(error)
        } else {
            0.0
        };
        // Torque off: the driver's bridge is open, no current flows, no back-EMF brake.
        let emf_damping = if self.torque_on { kt * kt / res } else { 0.0 };
        let drive = if self.torque_on {
            kt / res * self.duty * volts
        } else {
            0.0
        };
        let damping = emf_damping + p.values[FRICTION_VISCOUS];
        let inertia = p.armature() + self.load.inertia();
        let h = inertia + dt * damping;
        let free = (inertia * self.v + dt * (drive + self.load.gravity_torque(self.q))) / h;
        let (tau_m, _) = if self.torque_on {
            motor_torque(kt, res, volts, self.duty, self.v)
        } else {
            (0.0, 0.0)
        };
        let limit = budget(&p.values, self.v, tau_m);
        let stop = free * h / dt;
        let friction = stop.clamp(-limit, limit);
        self.v = free - dt * friction / h;
        self.q += dt * self.v;
        let (tau, current) = if self.torque_on {
            motor_torque(kt, res, volts, self.duty, self.v)
        } else {
            (0.0, 0.0)
        };
        self.motor_torque = tau;
        self.current = current;
    }
}
