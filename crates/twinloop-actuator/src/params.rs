//! One servo's parameters (SI units) and the TOML file that holds them:
//!
//! ```toml
//! [servo]
//! model = "RX-28"        # the servo type (ServoType::name)
//! friction = "m1"        # the model ladder's rung (ModelLevel)
//!
//! [params]               # SI, names below (PARAM_NAMES and `voltage`)
//! voltage = 18.5
//! kt = 1.947
//! ...
//!
//! [uncertainty]          # optional: one standard deviation per fitted parameter
//! kt = 0.01
//! ```

use crate::error::ActuatorError;
use crate::servo_type::ServoType;
use std::fmt::Write as _;

/// The rungs of the model ladder, after BAM's M1-M4: which friction terms exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum ModelLevel {
    /// Coulomb + viscous (what MuJoCo's frictionloss and damping express).
    M1,
    /// M1 + Stribeck (more friction near rest).
    M2,
    /// M1 + load-dependent Coulomb friction (proportional to the motor torque the
    /// gears carry).
    M3,
    /// M3 + Stribeck.
    M4,
}

impl ModelLevel {
    pub const ALL: [ModelLevel; 4] = [
        ModelLevel::M1,
        ModelLevel::M2,
        ModelLevel::M3,
        ModelLevel::M4,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ModelLevel::M1 => "m1",
            ModelLevel::M2 => "m2",
            ModelLevel::M3 => "m3",
            ModelLevel::M4 => "m4",
        }
    }

    pub fn parse(text: &str) -> Option<ModelLevel> {
        Self::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(text.trim()))
    }

    pub fn has_stribeck(self) -> bool {
        matches!(self, ModelLevel::M2 | ModelLevel::M4)
    }

    pub fn has_load_friction(self) -> bool {
        matches!(self, ModelLevel::M3 | ModelLevel::M4)
    }

    /// The parameters this rung has (indices into [`PARAM_NAMES`]).
    pub fn parameters(self) -> Vec<usize> {
        let mut p = vec![KT, RESISTANCE, ARMATURE, FRICTION_BASE, FRICTION_VISCOUS];
        if self.has_stribeck() {
            p.extend([FRICTION_STRIBECK, STRIBECK_VELOCITY]);
        }
        if self.has_load_friction() {
            p.push(LOAD_FRICTION);
        }
        p
    }
}

/// The identified parameters, in this order in [`ServoParams::values`]:
/// - `kt`: torque constant at the output shaft, N m/A (motor constant x gear ratio
///   x efficiency); also the back-EMF constant, V s/rad at the output;
/// - `resistance`: winding resistance, ohm;
/// - `armature`: rotor inertia x gear ratio^2 (+ gear inertias), kg m^2;
/// - `friction_base`: Coulomb friction, N m;
/// - `friction_viscous`: viscous friction, N m s/rad;
/// - `friction_stribeck`: extra friction at rest, N m (M2, M4);
/// - `stribeck_velocity`: speed at which it has fallen to 1/e, rad/s (M2, M4);
/// - `load_friction`: Coulomb friction per N m of motor torque, 1 (M3, M4);
/// - `backlash`: the gearbox's dead band, full width at the output, rad (any rung; 0:
///   none);
/// - `sensing_delay`: how old the position is that the loop acts on and the bus
///   reports, s (any rung);
/// - `bus_delay`: from a Goal Position write's sending to the loop using it, s (any
///   rung).
pub const PARAM_NAMES: [&str; N_PARAMS] = [
    "kt",
    "resistance",
    "armature",
    "friction_base",
    "friction_viscous",
    "friction_stribeck",
    "stribeck_velocity",
    "load_friction",
    "backlash",
    "sensing_delay",
    "bus_delay",
];
/// How many parameters a servo has (the friction ladder's eight, backlash and the two
/// delays).
pub const N_PARAMS: usize = 11;
pub const KT: usize = 0;
pub const RESISTANCE: usize = 1;
pub const ARMATURE: usize = 2;
pub const FRICTION_BASE: usize = 3;
pub const FRICTION_VISCOUS: usize = 4;
pub const FRICTION_STRIBECK: usize = 5;
pub const STRIBECK_VELOCITY: usize = 6;
pub const LOAD_FRICTION: usize = 7;
pub const BACKLASH: usize = 8;
pub const SENSING_DELAY: usize = 9;
pub const BUS_DELAY: usize = 10;
/// The parameters every rung may have (0: absent): the model is not smooth in them
/// (a dead band, delays resolved to the model's step), so CMA-ES fits them.
pub const NONSMOOTH: [usize; 3] = [BACKLASH, SENSING_DELAY, BUS_DELAY];
/// Largest delay a file may give, s: beyond it the servo would be unusable, and the
/// bench's history would grow without bound.
pub const MAX_DELAY: f64 = 0.1;

/// One servo's model: its type, rung, supply voltage and parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoParams {
    pub servo: ServoType,
    pub level: ModelLevel,
    /// Supply voltage, V (measured: Present Voltage).
    pub voltage: f64,
    /// [`PARAM_NAMES`] order; terms the rung lacks are 0.
    pub values: [f64; N_PARAMS],
    /// One standard deviation per parameter, where a fit gave one.
    pub uncertainty: Option<[f64; N_PARAMS]>,
}

impl ServoParams {
    pub fn kt(&self) -> f64 {
        self.values[KT]
    }
    pub fn resistance(&self) -> f64 {
        self.values[RESISTANCE]
    }
    pub fn armature(&self) -> f64 {
        self.values[ARMATURE]
    }

    /// Check every number: finite, positive where it must be.
    pub fn check(&self, file: &str) -> Result<(), ActuatorError> {
        let bad =
            |name: &str, msg: String| ActuatorError::new(file, format!("[params] {name}"), msg);
        if !(self.voltage.is_finite() && self.voltage > 0.0) {
            return Err(bad(
                "voltage",
                format!("{} is not a positive voltage", self.voltage),
            ));
        }
        for (i, &v) in self.values.iter().enumerate() {
            let name = PARAM_NAMES[i];
            if !v.is_finite() || v < 0.0 {
                return Err(bad(name, format!("{v} is not a finite number >= 0")));
            }
            let needs_positive = matches!(i, KT | RESISTANCE | ARMATURE)
                || (i == STRIBECK_VELOCITY && self.level.has_stribeck());
            if needs_positive && v <= 0.0 {
                return Err(bad(name, format!("{v} must be > 0")));
            }
            if matches!(i, SENSING_DELAY | BUS_DELAY) && v > MAX_DELAY {
                return Err(bad(
                    name,
                    format!("{v} s is above the {MAX_DELAY} s a servo allows"),
                ));
            }
            if i == BACKLASH && v > 0.2 {
                return Err(bad(
                    name,
                    format!("{v} rad of dead band: more than 11 deg, not a servo"),
                ));
            }
        }
        Ok(())
    }

    /// The file's text; `comment` (if any) goes first as `#` lines.
    pub fn to_toml(&self, comment: &str) -> String {
        let mut s = String::new();
        for line in comment.lines() {
            let _ = writeln!(s, "# {line}");
        }
        let _ = writeln!(
            s,
            "[servo]\nmodel = \"{}\"\nfriction = \"{}\"\n",
            self.servo.name(),
            self.level.name()
        );
        let _ = writeln!(s, "[params]\nvoltage = {:?}", self.voltage);
        let mut used = self.level.parameters();
        // Backlash and delays only where the servo has them (or a fit estimated them).
        used.extend(
            NONSMOOTH.iter().filter(|&&i| {
                self.values[i] != 0.0 || self.uncertainty.is_some_and(|u| u[i] != 0.0)
            }),
        );
        for &i in &used {
            let _ = writeln!(s, "{} = {:?}", PARAM_NAMES[i], self.values[i]);
        }
        if let Some(u) = &self.uncertainty {
            let _ = writeln!(s, "\n[uncertainty]");
            for &i in &used {
                let _ = writeln!(s, "{} = {:?}", PARAM_NAMES[i], u[i]);
            }
        }
        s
    }
}

/// A TOML number (integer or float) as f64.
pub(crate) fn number(
    v: &toml::Value,
    table: &str,
    key: &str,
    file: &str,
) -> Result<f64, ActuatorError> {
    match v {
        toml::Value::Float(x) => Ok(*x),
        toml::Value::Integer(i) => Ok(*i as f64),
        _ => Err(ActuatorError::new(
            file,
            format!("[{table}] {key}"),
            "must be a number",
        )),
    }
}
