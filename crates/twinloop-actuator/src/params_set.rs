//! The parameter files of a whole robot: one file for every servo of its type
//! (`FILE.toml`), or one per servo (`ID=FILE.toml` by bus id, `JOINT=FILE.toml` by
//! joint name), as `serve --servo-params`, `simulate --servo-params` and
//! `experiment tipover --servo-params` take them.

use crate::error::ActuatorError;
use crate::params::ServoParams;
use crate::servo_type::ServoType;
use std::path::Path;

/// Which servo a per-servo file is for.
#[derive(Debug, Clone, PartialEq)]
pub enum ServoKey {
    Id(u8),
    Joint(String),
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct ServoParamsSet {
    /// (the argument as given, its parameters): for every servo of its type.
    pub all: Vec<(String, ServoParams)>,
    /// (key, the argument as given, its parameters): for one servo.
    pub each: Vec<(ServoKey, String, ServoParams)>,
}

/// One servo of the robot, as the set is asked about it.
#[derive(Debug, Clone, Copy)]
pub struct ServoSlot<'a> {
    pub id: Option<u8>,
    pub joint: &'a str,
    /// Its type where known (a mapping, a built-in robot's servo table).
    pub servo: Option<ServoType>,
}

impl ServoParamsSet {
    pub fn is_empty(&self) -> bool {
        self.all.is_empty() && self.each.is_empty()
    }

    /// Read `FILE`, `ID=FILE` or `JOINT=FILE` arguments (`option` names the flag in
    /// errors).
    pub fn read(args: &[String], option: &str) -> Result<ServoParamsSet, ActuatorError> {
        let mut set = ServoParamsSet::default();
        for a in args {
            // A key is text before '=' that is not a path (no '/').
            let (key, file) = match a.split_once('=') {
                Some((k, f)) if !k.is_empty() && !k.contains('/') => (Some(k), f),
                _ => (None, a.as_str()),
            };
            let p = ServoParams::read(Path::new(file))?;
            match key {
                None => set.all.push((a.clone(), p)),
                Some(k) => {
                    let key = match k.parse::<u8>() {
                        Ok(id) => ServoKey::Id(id),
                        Err(_) if k.chars().all(|c| c.is_ascii_digit()) => {
                            return Err(ActuatorError::new(option, a, "a servo id is 0-253"));
                        }
                        Err(_) => ServoKey::Joint(k.to_string()),
                    };
                    if set.each.iter().any(|(q, _, _)| *q == key) {
                        return Err(ActuatorError::new(
                            option,
                            a,
                            "that servo has a file already",
                        ));
                    }
                    set.each.push((key, a.clone(), p));
                }
            }
        }
        if let Some(t) = set
            .all
            .iter()
            .map(|(_, p)| p.servo)
            .find(|t| set.all.iter().filter(|(_, p)| p.servo == *t).count() > 1)
        {
            return Err(ActuatorError::new(
                option,
                "",
                format!("two files for every {t}: give one, or ID=FILE per servo"),
            ));
        }
        Ok(set)
    }

    /// The parameters for `slot`: its own file, else the file for every servo of
    /// its type (any, where the type is unknown), else none (the datasheet's).
    /// A file of another type than the servo's is an error naming both.
    pub fn for_servo(
        &self,
        slot: ServoSlot,
        option: &str,
    ) -> Result<Option<&ServoParams>, ActuatorError> {
        let own = self.each.iter().find(|(k, _, _)| match k {
            ServoKey::Id(id) => Some(*id) == slot.id,
            ServoKey::Joint(j) => j == slot.joint,
        });
        if let Some((_, arg, p)) = own {
            if let Some(t) = slot.servo
                && t != p.servo
            {
                return Err(ActuatorError::new(
                    option,
                    arg,
                    format!(
                        "parameters of {}, but servo{} (joint \"{}\") is {t}",
                        p.servo,
                        slot.id.map(|i| format!(" id {i}")).unwrap_or_default(),
                        slot.joint
                    ),
                ));
            }
            return Ok(Some(p));
        }
        Ok(self
            .all
            .iter()
            .find(|(_, p)| slot.servo.is_none_or(|t| t == p.servo))
            .map(|(_, p)| p))
    }

    /// After assigning `slots`: every file must have found a servo.
    pub fn check_used(&self, slots: &[ServoSlot], option: &str) -> Result<(), ActuatorError> {
        for (k, arg, _) in &self.each {
            let found = slots.iter().any(|s| match k {
                ServoKey::Id(id) => Some(*id) == s.id,
                ServoKey::Joint(j) => j == s.joint,
            });
            if !found {
                return Err(ActuatorError::new(
                    option,
                    arg,
                    "no servo of the robot has that id or joint",
                ));
            }
        }
        for (arg, p) in &self.all {
            if !slots.iter().any(|s| s.servo.is_none_or(|t| t == p.servo)) {
                let mut types: Vec<&str> = slots
                    .iter()
                    .filter_map(|s| s.servo.map(|t| t.name()))
                    .collect();
                types.sort();
                types.dedup();
                return Err(ActuatorError::new(
                    option,
                    arg,
                    format!(
                        "parameters of {}, but the robot has no such servo (its servos: {})",
                        p.servo,
                        types.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }
}
