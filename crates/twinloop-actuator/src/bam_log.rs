//! Logs recorded by BAM's pendulum recorders (Rhoban, github.com/Rhoban/bam,
//! `bam/xl330/record.py`) read as our [`ServoLog`] and [`Pendulum`].
//!
//! BAM's log is one JSON object: the bench (`mass` kg at `length` m, optional
//! `arm_mass`), the firmware P gain `kp` (raw Position P Gain), the nominal supply
//! `vin`, the `motor` name, the `trajectory`, and `entries`, one per read cycle:
//!
//! | field | meaning (unit) | here |
//! |---|---|---|
//! | `timestamp` | s since the start, the middle of the cycle's reads | `t`, `t_goal` (below) |
//! | `position` | Present Position, rad, 0 hanging down | `q` |
//! | `speed` | Present Velocity, rad/s (optional) | `v` (0 where absent) |
//! | `goal_position` | the goal written this cycle, rad | `goal` |
//! | `input_volts` | Present Input Voltage, V (optional: `vin`) | `voltage` |
//! | `torque_enable` | Torque Enable written this cycle (optional: on) | `torque` |
//! | `load`, `temp`, `present_current` | not used (older XL330 logs: `load` is the raw Present PWM, 885 full, two's complement) | - |
//!
//! The same content may come as columns: a first line holding the JSON object
//! without `entries`, a second naming the entry fields, then one row per entry
//! (`torque_enable` as 1/0). The committed test logs are in that form (transcribed:
//! no network where they were copied).
//!
//! **Timing.** The recorder writes the goal, sleeps 1 ms, then reads five registers
//! (position first) and stamps the middle of the reads; with the torque off it only
//! reads. One bus transaction is taken as `a = (P - 1 ms) / 6` (one write and five
//! reads per cycle of median period `P` with the torque on; `P / 5` where it is
//! never on): the position was read `2.5 a` before the stamp, and the goal sent
//! `1 ms + a` before that. The fit's `sensing_delay` and `bus_delay` take what this estimate
//! misses.
//!
//! **What the logs lack** for our model: the I and D gains (taken as 0, the
//! factory's), Present Current (BAM's XL330 logs have none: the fit is position
//! only, so kt and R are determined only as kt/R and kt^2/R), the arm's own inertia
//! (no `arm_mass` in the XL330 logs: 0).

use crate::bench::Pendulum;
use crate::error::ActuatorError;
use crate::log::ServoLog;
use crate::servo_type::ServoType;
use serde_json::{Map, Value};
use std::path::Path;

/// The recorder's sleep between the goal write and the reads, s.
pub const RECORDER_SLEEP: f64 = 1e-3;

/// A BAM log as ours, with what it says about the bench.
#[derive(Debug, Clone, PartialEq)]
pub struct BamLog {
    pub log: ServoLog,
    pub load: Pendulum,
    /// Raw Position P Gain.
    pub kp: f64,
    pub trajectory: String,
}

/// Whether `path` holds a BAM log: a `.json` file, or a first line that is a JSON
/// object (the column form).
pub fn is_bam_log(path: &Path) -> bool {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        return true;
    }
    twinloop_io::input::read_to_string(path)
        .ok()
        .and_then(|t| t.lines().next().map(|l| l.trim_start().starts_with('{')))
        .unwrap_or(false)
}

/// The servo type of BAM's `motor` name, where we model it.
pub fn servo_of_motor(motor: &str) -> Option<ServoType> {
    match motor.to_ascii_lowercase().as_str() {
        "xl330" | "xl330-m288" | "xl330_m288" => Some(ServoType::Xl330M288),
        _ => None,
    }
}

/// Read a BAM log (JSON or its column form); `servo` overrides the type its `motor`
/// names.
pub fn read(path: &Path, servo: Option<ServoType>) -> Result<BamLog, ActuatorError> {
    let file = path.display().to_string();
    let text = twinloop_io::input::read_to_string(path)
        .map_err(|e| ActuatorError::new(&file, "", format!("cannot read: {e}")))?;
    parse(&text, &file, servo)
}

/// One entry's fields, in the order [`parse_entries`] fills them.
struct Entry {
    timestamp: f64,
    position: f64,
    speed: f64,
    goal: f64,
    volts: Option<f64>,
    torque: bool,
}

pub fn parse(text: &str, file: &str, servo: Option<ServoType>) -> Result<BamLog, ActuatorError> {
    let (header, entries) = header_and_entries(text, file)?;
    let number = |key: &str| -> Result<f64, ActuatorError> {
        header
            .get(key)
            .and_then(Value::as_f64)
            .filter(|x| x.is_finite())
            .ok_or_else(|| ActuatorError::new(file, key, "missing or not a finite number"))
    };
    let mass = number("mass")?;
    let length = number("length")?;
    let kp = number("kp")?;
    let vin = number("vin").ok();
    if mass < 0.0 || length < 0.0 || kp < 0.0 {
        return Err(ActuatorError::new(file, "mass, length, kp", "must be >= 0"));
    }
    if let Some(a) = header.get("arm_mass").and_then(Value::as_f64)
        && a != 0.0
    {
        // Our pendulum is a point mass on a balanced arm: an arm's own weight would
        // pull with a torque the model does not have.
        return Err(ActuatorError::new(
            file,
            "arm_mass",
            format!("{a} kg: a heavy arm is not modelled (the bench's arm is balanced)"),
        ));
    }
    let motor = header.get("motor").and_then(Value::as_str).unwrap_or("");
    let servo = match servo.or_else(|| servo_of_motor(motor)) {
        Some(s) => s,
        None => {
            return Err(ActuatorError::new(
                file,
                "motor",
                format!(
                    "{motor:?}: no servo model (give --servo MODEL; known: {})",
                    ServoType::known_names()
                ),
            ));
        }
    };
    check_entries(&entries, file)?;
    let log = servo_log(&entries, file, servo, kp, vin)?;
    Ok(BamLog {
        log,
        load: Pendulum {
            mass,
            length,
            arm_inertia: 0.0,
        },
        kp,
        trajectory: header
            .get("trajectory")
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string(),
    })
}

/// The header object and the entries of a BAM log: one JSON object with `entries`,
/// or a JSON header line followed by columns.
fn header_and_entries(
    text: &str,
    file: &str,
) -> Result<(Map<String, Value>, Vec<Entry>), ActuatorError> {
    let first = text.lines().next().unwrap_or("");
    let whole_json = match serde_json::from_str::<Value>(text) {
        Ok(v) => Some(v),
        Err(_) if first.trim_start().starts_with('{') && text.lines().nth(1).is_some() => None,
        Err(e) => {
            return Err(ActuatorError::new(
                file,
                format!("line {}", e.line()),
                format!("not a BAM log: {e}"),
            ));
        }
    };
    Ok(match whole_json {
        Some(Value::Object(mut o)) => {
            let entries = match o.remove("entries") {
                Some(Value::Array(a)) => parse_json_entries(&a, file)?,
                _ => return Err(ActuatorError::new(file, "entries", "missing or not a list")),
            };
            (o, entries)
        }
        Some(_) => return Err(ActuatorError::new(file, "", "not a JSON object")),
        None => {
            let header: Map<String, Value> = serde_json::from_str(first).map_err(|e| {
                ActuatorError::new(file, "line 1", format!("not a JSON object: {e}"))
            })?;
            (header, parse_columns(text, file)?)
        }
    })
}

/// Enough entries, in time order.
fn check_entries(entries: &[Entry], file: &str) -> Result<(), ActuatorError> {
    if entries.len() < 10 {
        return Err(ActuatorError::new(
            file,
            "entries",
            format!("{} entries: too few to fit", entries.len()),
        ));
    }
    for (k, w) in entries.windows(2).enumerate() {
        if w[1].timestamp <= w[0].timestamp {
            return Err(ActuatorError::new(
                file,
                format!("entry {}, timestamp", k + 2),
                format!(
                    "{} does not increase (previous {})",
                    w[1].timestamp, w[0].timestamp
                ),
            ));
        }
    }
    Ok(())
}

/// The entries as a servo log: times moved back by the bus's transactions (the
/// position read 2.5 transactions before the stamp, the goal written one sleep and
/// a transaction before the read).
fn servo_log(
    entries: &[Entry],
    file: &str,
    servo: ServoType,
    kp: f64,
    vin: Option<f64>,
) -> Result<ServoLog, ActuatorError> {
    let transaction = transaction_time(entries);
    let mut log = ServoLog {
        file: file.to_string(),
        servo: Some(servo),
        torque: Some(Vec::with_capacity(entries.len())),
        ..Default::default()
    };
    for (k, e) in entries.iter().enumerate() {
        let t = e.timestamp - 2.5 * transaction;
        let t_goal = if k == 0 {
            t
        } else {
            t - RECORDER_SLEEP - transaction
        };
        log.t.push(t);
        log.t_goal.push(t_goal);
        log.q.push(e.position);
        log.v.push(e.speed);
        log.goal.push(e.goal);
        let volts = e.volts.or(vin).ok_or_else(|| {
            ActuatorError::new(
                file,
                format!("entry {}", k + 1),
                "no input_volts and no vin",
            )
        })?;
        log.voltage.push(volts);
        log.firmware.push([kp, 0.0, 0.0]);
        if let Some(torque) = log.torque.as_mut() {
            torque.push(e.torque);
        }
    }
    Ok(log)
}

/// One bus transaction, s: from the median period of cycles with the torque on (a
/// goal write, the sleep, five reads), else of cycles with it off (five reads).
fn transaction_time(entries: &[Entry]) -> f64 {
    let median = |torque: bool| {
        let mut gaps: Vec<f64> = entries
            .windows(2)
            .filter(|w| w[0].torque == torque && w[1].torque == torque)
            .map(|w| w[1].timestamp - w[0].timestamp)
            .collect();
        gaps.sort_by(f64::total_cmp);
        gaps.get(gaps.len() / 2).copied()
    };
    match (median(true), median(false)) {
        (Some(p), _) => ((p - RECORDER_SLEEP) / 6.0).max(0.0),
        (None, Some(p)) => p / 5.0,
        (None, None) => 0.0,
    }
}

fn parse_json_entries(entries: &[Value], file: &str) -> Result<Vec<Entry>, ActuatorError> {
    entries
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let field = |key: &str| -> Result<Option<f64>, ActuatorError> {
                match e.get(key) {
                    None | Some(Value::Null) => Ok(None),
                    Some(v) => v
                        .as_f64()
                        .filter(|x| x.is_finite())
                        .map(Some)
                        .ok_or_else(|| {
                            ActuatorError::new(
                                file,
                                format!("entry {}, {key}", k + 1),
                                "not a finite number",
                            )
                        }),
                }
            };
            let required = |key: &str| -> Result<f64, ActuatorError> {
                field(key)?.ok_or_else(|| {
                    ActuatorError::new(file, format!("entry {}, {key}", k + 1), "missing")
                })
            };
            let torque = match e.get("torque_enable") {
                None | Some(Value::Null) => true,
                Some(Value::Bool(b)) => *b,
                Some(v) => v.as_f64().map(|x| x != 0.0).ok_or_else(|| {
                    ActuatorError::new(
                        file,
                        format!("entry {}, torque_enable", k + 1),
                        "not true/false",
                    )
                })?,
            };
            Ok(Entry {
                timestamp: required("timestamp")?,
                position: required("position")?,
                speed: field("speed")?.unwrap_or(0.0),
                goal: required("goal_position")?,
                volts: field("input_volts")?,
                torque,
            })
        })
        .collect()
}

/// The column form: line 1 the header object, line 2 the field names, then rows.
fn parse_columns(text: &str, file: &str) -> Result<Vec<Entry>, ActuatorError> {
    let mut lines = text.lines().enumerate().skip(1);
    let names: Vec<&str> = match lines.next() {
        Some((_, l)) => l.split(',').map(str::trim).collect(),
        None => return Err(ActuatorError::new(file, "line 2", "no column names")),
    };
    let col = |name: &str| names.iter().position(|n| *n == name);
    let need = |name: &str| {
        col(name).ok_or_else(|| ActuatorError::new(file, format!("column \"{name}\""), "missing"))
    };
    let (ts, pos, goal) = (
        need("timestamp")?,
        need("position")?,
        need("goal_position")?,
    );
    let (speed, volts, torque) = (col("speed"), col("input_volts"), col("torque_enable"));
    let mut out = Vec::new();
    for (n, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != names.len() {
            return Err(ActuatorError::new(
                file,
                format!("line {}", n + 1),
                format!("{} cells, {} columns", cells.len(), names.len()),
            ));
        }
        let num = |c: usize| -> Result<f64, ActuatorError> {
            match cells[c] {
                "true" => Ok(1.0),
                "false" => Ok(0.0),
                s => s
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        ActuatorError::new(
                            file,
                            format!("line {}, column \"{}\"", n + 1, names[c]),
                            format!("{s:?} is not a finite number"),
                        )
                    }),
            }
        };
        out.push(Entry {
            timestamp: num(ts)?,
            position: num(pos)?,
            speed: speed.map(num).transpose()?.unwrap_or(0.0),
            goal: num(goal)?,
            volts: volts.map(num).transpose()?,
            torque: torque.map(num).transpose()?.is_none_or(|x| x != 0.0),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first entries of BAM's `bam/data.bak/raw/2026-01-15_10h28m10.json`
    /// (commit af22604), verbatim.
    const EXCERPT: &str = r#"{"mass": 0.49, "length": 0.1, "kp": 100, "vin": 7.4, "motor": "xl330", "trajectory": "sin_sin", "entries": [{"position": -0.003067961575771161, "speed": 0.0, "load": 0, "input_volts": 7.3, "temp": 28, "timestamp": 0.003500699996948242, "goal_position": 7.864772933845965e-06, "torque_enable": true}, {"position": -0.003067961575771161, "speed": 0.0, "load": 2, "input_volts": 7.3, "temp": 28, "timestamp": 0.00870513916015625, "goal_position": 0.008397945709156108, "torque_enable": true}, {"position": -0.003067961575771161, "speed": 0.0, "load": 5, "input_volts": 7.3, "temp": 28, "timestamp": 0.013885021209716797, "goal_position": 0.016867017836179957, "torque_enable": true}, {"position": -0.003067961575771161, "speed": 0.0, "load": 7, "input_volts": 7.3, "temp": 28, "timestamp": 0.019139766693115234, "goal_position": 0.025789537432300887, "torque_enable": true}, {"position": -0.003067961575771161, "speed": 0.0, "load": 9, "input_volts": 7.4, "temp": 28, "timestamp": 0.024324893951416016, "goal_position": 0.034941842943236226, "torque_enable": true}, {"position": -0.003067961575771161, "speed": 0.0, "load": 12, "input_volts": 7.3, "temp": 28, "timestamp": 0.02950453758239746, "goal_position": 0.044263538351662586, "torque_enable": true}, {"position": -0.0015339807878858025, "speed": 0.023980823922402087, "load": 14, "input_volts": 7.3, "temp": 28, "timestamp": 0.03469586372375488, "goal_position": 0.05393964739515972, "torque_enable": true}, {"position": -0.0015339807878858025, "speed": 0.023980823922402087, "load": 17, "input_volts": 7.3, "temp": 28, "timestamp": 0.03989875316619873, "goal_position": 0.06377136136120944, "torque_enable": true}, {"position": -0.0015339807878858025, "speed": 0.023980823922402087, "load": 19, "input_volts": 7.3, "temp": 28, "timestamp": 0.04510617256164551, "goal_position": 0.07402625509044325, "torque_enable": true}, {"position": -0.0015339807878858025, "speed": 0.047961647844804174, "load": 21, "input_volts": 7.3, "temp": 28, "timestamp": 0.05036449432373047, "goal_position": 0.0843543079585837, "torque_enable": true}]}"#;

    #[test]
    fn reads_bam_json() {
        let b = parse(EXCERPT, "x.json", None).unwrap();
        assert_eq!(b.log.servo, Some(ServoType::Xl330M288));
        assert_eq!(b.log.len(), 10);
        assert_eq!(b.load.mass, 0.49);
        assert_eq!(b.load.length, 0.1);
        assert_eq!(b.kp, 100.0);
        assert_eq!(b.trajectory, "sin_sin");
        assert_eq!(b.log.firmware[3], [100.0, 0.0, 0.0]);
        assert_eq!(b.log.q[6], -0.0015339807878858025);
        assert_eq!(b.log.v[9], 0.047961647844804174);
        assert_eq!(b.log.voltage[4], 7.4);
        // Positions are whole encoder counts (4096 a turn).
        let r = ServoType::Xl330M288.resolution();
        for q in &b.log.q {
            assert!((q / r - (q / r).round()).abs() < 1e-9);
        }
        // Timing: periods of 5.2 ms, so one transaction about 0.7 ms; the read
        // 2.5 transactions before the stamp, the goal 1 ms and one transaction
        // before the read.
        let stamp = 0.00870513916015625;
        let a = (stamp - b.log.t[1]) / 2.5;
        assert!((a - 0.7e-3).abs() < 0.02e-3, "{a}");
        assert!((b.log.t[1] - b.log.t_goal[1] - (1e-3 + a)).abs() < 1e-12);
        assert!(b.log.torque.as_ref().unwrap().iter().all(|&t| t));
    }

    /// The XL330's loop drives `P/256` PWM units per count of error: the Present
    /// PWM the servo reported (`load`, raw) in the excerpt's entries, against our
    /// firmware at the logged goal and position (P/128 would give twice as much).
    #[test]
    fn xl330_pwm_is_p_over_256() {
        let b = parse(EXCERPT, "x.json", None).unwrap();
        let reported = [0.0, 2.0, 5.0, 7.0, 9.0, 12.0, 14.0, 17.0, 19.0, 21.0];
        let r = ServoType::Xl330M288.resolution();
        let mut fw = crate::firmware::Firmware::new(ServoType::Xl330M288);
        fw.registers = b.log.firmware[0];
        for (k, seen) in reported.iter().enumerate().skip(1) {
            let error = (b.log.goal[k] / r).round() - (b.log.q[k] / r).round();
            let pwm = fw.duty(error) * ServoType::Xl330M288.pwm_max();
            assert!(
                (pwm - seen).abs() <= 1.6,
                "entry {}: {pwm} against {seen}",
                k + 1
            );
        }
    }

    #[test]
    fn columns_read_as_json() {
        // The same entries in the column form give the same log.
        let json = parse(EXCERPT, "x", None).unwrap();
        let mut text = String::from(
            r#"{"mass": 0.49, "length": 0.1, "kp": 100, "vin": 7.4, "motor": "xl330", "trajectory": "sin_sin"}"#,
        );
        text.push_str("\ntimestamp,position,speed,goal_position,input_volts,torque_enable\n");
        for k in 0..json.log.len() {
            let l = &json.log;
            // Undo the timing to get the stamps back.
            let stamp = EXCERPT
                .split("\"timestamp\": ")
                .nth(k + 1)
                .and_then(|s| s.split(',').next())
                .unwrap();
            text.push_str(&format!(
                "{stamp},{},{},{},{},1\n",
                l.q[k], l.v[k], l.goal[k], l.voltage[k]
            ));
        }
        let cols = parse(&text, "x", None).unwrap();
        // serde_json's float parsing may differ from Rust's in the last bit.
        for (a, b) in cols.log.t.iter().zip(&json.log.t) {
            assert!((a - b).abs() < 1e-15, "{a} {b}");
        }
        assert_eq!(cols.log.q, json.log.q);
        assert_eq!(cols.log.goal, json.log.goal);
        assert_eq!(cols.load, json.load);
    }

    #[test]
    fn bad_input_names_the_place() {
        let e = parse(
            &EXCERPT.replace("\"motor\": \"xl330\"", "\"motor\": \"mx106\""),
            "f.json",
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("f.json") && e.contains("motor") && e.contains("mx106"),
            "{e}"
        );
        let e = parse(
            &EXCERPT.replacen("\"goal_position\": 0.008397", "\"goal\": 0.008397", 1),
            "f.json",
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("entry 2, goal_position") && e.contains("missing"),
            "{e}"
        );
        let e = parse(
            &EXCERPT.replace("0.00870513916015625", "0.001"),
            "f.json",
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("entry 2, timestamp"), "{e}");
        let e = parse("{\"mass\": 1}\nt\n1", "c.csv", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.csv") && e.contains("timestamp"), "{e}");
    }
}
