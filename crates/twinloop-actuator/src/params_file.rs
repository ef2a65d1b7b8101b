//! Reading a parameter file (the format is in [`crate::params`]): unknown tables or
//! keys, a term the rung lacks, a bad number are errors naming the file and
//! `[table] key`; parameters the file leaves out take the datasheet's values.

use crate::datasheet;
use crate::error::ActuatorError;
use crate::params::{ModelLevel, PARAM_NAMES, ServoParams, number};
use crate::servo_type::ServoType;
use std::path::Path;

impl ServoParams {
    /// The same servo on another rung: terms the new rung lacks are zeroed, terms it
    /// adds start at the datasheet's values.
    pub fn with_level(&self, level: ModelLevel) -> ServoParams {
        let defaults = datasheet::defaults(self.servo, level);
        let mut p = self.clone();
        p.level = level;
        p.uncertainty = None;
        for i in 0..PARAM_NAMES.len() {
            if crate::params::NONSMOOTH.contains(&i) {
                continue; // every rung has them: kept
            }
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

    /// Read a parameter file.
    pub fn read(path: &Path) -> Result<ServoParams, ActuatorError> {
        let file = path.display().to_string();
        let text = twinloop_io::input::read_to_string(path)
            .map_err(|e| ActuatorError::new(&file, "", format!("cannot read: {e}")))?;
        Self::parse(&text, &file)
    }

    /// Parse a parameter file's text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<ServoParams, ActuatorError> {
        let doc: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| ActuatorError::toml(file, text, &e))?;
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
        let mut p = datasheet::defaults(servo_type, level);
        let params = table(&doc, "params", file)?;
        for (key, value) in params {
            let v = number(value, "params", key, file)?;
            if key == "voltage" {
                p.voltage = v;
            } else if let Some(i) = PARAM_NAMES.iter().position(|n| n == key) {
                let any_rung = crate::params::NONSMOOTH.contains(&i);
                if !any_rung && !level.parameters().contains(&i) && v != 0.0 {
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
            let mut sd = [0.0; crate::params::N_PARAMS];
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
