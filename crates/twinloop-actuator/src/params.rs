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
use std::path::Path;

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
/// - `load_friction`: Coulomb friction per N m of motor torque, 1 (M3, M4).
pub const PARAM_NAMES: [&str; 8] = [
    "kt",
    "resistance",
    "armature",
    "friction_base",
    "friction_viscous",
    "friction_stribeck",
    "stribeck_velocity",
    "load_friction",
];
pub const KT: usize = 0;
pub const RESISTANCE: usize = 1;
pub const ARMATURE: usize = 2;
pub const FRICTION_BASE: usize = 3;
pub const FRICTION_VISCOUS: usize = 4;
pub const FRICTION_STRIBECK: usize = 5;
pub const STRIBECK_VELOCITY: usize = 6;
pub const LOAD_FRICTION: usize = 7;

/// One servo's model: its type, rung, supply voltage and parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoParams {
    pub servo: ServoType,
    pub level: ModelLevel,
    /// Supply voltage, V (measured: Present Voltage).
    pub voltage: f64,
    /// [`PARAM_NAMES`] order; terms the rung lacks are 0.
    pub values: [f64; 8],
    /// One standard deviation per parameter, where a fit gave one.
    pub uncertainty: Option<[f64; 8]>,
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

    /// The same servo on another rung: terms the new rung lacks are zeroed, terms it
    /// adds start at the datasheet's values.
    pub fn with_level(&self, level: ModelLevel) -> ServoParams {
        let defaults = crate::datasheet::defaults(self.servo, level);
        let mut p = self.clone();
        p.level = level;
        p.uncertainty = None;
        for i in 0..PARAM_NAMES.len() {
            let has = level.parameters().contains(&i);
            let had = self.level.parameters().contains(&i);
            p.values[i] = match (has, had) {
                (false, _) => 0.0,
                (true, true) => self.values[i],
                (true, false) => defaults.values[i],
            };
        }
        p
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
        }
        Ok(())
    }

    /// Read a parameter file.
    pub fn read(path: &Path) -> Result<ServoParams, ActuatorError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| ActuatorError::new(&file, "", format!("cannot read: {e}")))?;
        Self::parse(&text, &file)
    }

    /// Parse a parameter file's text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<ServoParams, ActuatorError> {
        let doc: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| ActuatorError::new(file, "", e.message().to_string()))?;
        for key in doc.keys() {
            if !matches!(key.as_str(), "servo" | "params" | "uncertainty") {
                return Err(ActuatorError::new(
                    file,
                    format!("[{key}]"),
                    "unknown table (expected [servo], [params], [uncertainty])",
                ));
            }
        }
        let servo = table(&doc, "servo", file)?;
        let model = string(servo, "servo", "model", file)?;
        let servo_type = ServoType::parse(&model).ok_or_else(|| {
            ActuatorError::new(
                file,
                "[servo] model",
                format!(
                    "unknown servo {model:?} (known: {})",
                    ServoType::known_names()
                ),
            )
        })?;
        let level = match servo.get("friction") {
            None => ModelLevel::M1,
            Some(_) => {
                let f = string(servo, "servo", "friction", file)?;
                ModelLevel::parse(&f).ok_or_else(|| {
                    ActuatorError::new(
                        file,
                        "[servo] friction",
                        format!("unknown model {f:?} (m1, m2, m3, m4)"),
                    )
                })?
            }
        };
        let mut p = crate::datasheet::defaults(servo_type, level);
        let params = table(&doc, "params", file)?;
        for (key, value) in params {
            let v = number(value, "params", key, file)?;
            if key == "voltage" {
                p.voltage = v;
            } else if let Some(i) = PARAM_NAMES.iter().position(|n| n == key) {
                if !level.parameters().contains(&i) && v != 0.0 {
                    return Err(ActuatorError::new(
                        file,
                        format!("[params] {key}"),
                        format!(
                            "model {} has no {key} (use a richer friction model)",
                            level.name()
                        ),
                    ));
                }
                p.values[i] = v;
            } else {
                return Err(ActuatorError::new(
                    file,
                    format!("[params] {key}"),
                    format!(
                        "unknown parameter (known: voltage, {})",
                        PARAM_NAMES.join(", ")
                    ),
                ));
            }
        }
        if let Some(u) = doc.get("uncertainty") {
            let u = u
                .as_table()
                .ok_or_else(|| ActuatorError::new(file, "[uncertainty]", "must be a table"))?;
            let mut sd = [0.0; 8];
            for (key, value) in u {
                let i = PARAM_NAMES.iter().position(|n| n == key).ok_or_else(|| {
                    ActuatorError::new(file, format!("[uncertainty] {key}"), "unknown parameter")
                })?;
                sd[i] = number(value, "uncertainty", key, file)?;
            }
            p.uncertainty = Some(sd);
        }
        p.check(file)?;
        Ok(p)
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
        let used = self.level.parameters();
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

fn table<'a>(
    doc: &'a toml::Table,
    name: &str,
    file: &str,
) -> Result<&'a toml::Table, ActuatorError> {
    doc.get(name)
        .ok_or_else(|| ActuatorError::new(file, format!("[{name}]"), "missing table"))?
        .as_table()
        .ok_or_else(|| ActuatorError::new(file, format!("[{name}]"), "must be a table"))
}

fn string(t: &toml::Table, table: &str, key: &str, file: &str) -> Result<String, ActuatorError> {
    match t.get(key) {
        Some(toml::Value::String(s)) => Ok(s.clone()),
        Some(_) => Err(ActuatorError::new(
            file,
            format!("[{table}] {key}"),
            "must be a string",
        )),
        None => Err(ActuatorError::new(
            file,
            format!("[{table}] {key}"),
            "missing",
        )),
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
