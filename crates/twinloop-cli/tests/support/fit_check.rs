//! A servo fit (`identify servo --json`) against the truth it was made from.

use twinloop_actuator::ServoParams;
use twinloop_actuator::params::{FRICTION_VISCOUS, KT, PARAM_NAMES, RESISTANCE};

/// Every parameter the fit says the data determines, and the motor's combinations
/// (kt/R, kt^2/R + viscous), checked against `truth`: each within `allowed(name)`
/// (relative) or three stated standard deviations. Prints each line; returns the
/// failures (prefixed by `label`) and how many were checked.
pub fn check_fit(
    label: &str,
    fit: &serde_json::Value,
    truth: &ServoParams,
    allowed: impl Fn(&str) -> f64,
) -> (Vec<String>, usize) {
    let mut failures = Vec::new();
    let mut checked = 0;
    let undetermined: Vec<&str> = fit["undetermined"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let mut check = |name: &str, want: f64, got: f64, sd: f64| {
        let err = got / want - 1.0;
        eprintln!(
            "  {name:34} truth {want:.5} fit {got:.5} sd {sd:.1e} err {:+.2} %",
            100.0 * err
        );
        checked += 1;
        if err.abs() > allowed(name) && (got - want).abs() > 3.0 * sd {
            failures.push(format!("{label}{name}: {got} vs {want} (sd {sd})"));
        }
    };
    for (name, v) in fit["params"].as_object().unwrap() {
        let i = PARAM_NAMES.iter().position(|n| n == name).unwrap();
        if undetermined.contains(&name.as_str()) {
            continue;
        }
        check(
            name,
            truth.values[i],
            v["value"].as_f64().unwrap(),
            v["sd"].as_f64().unwrap(),
        );
    }
    let (kt, r, b) = (
        truth.values[KT],
        truth.values[RESISTANCE],
        truth.values[FRICTION_VISCOUS],
    );
    for c in fit["combinations"].as_array().unwrap() {
        let want = if c["name"] == "kt/resistance" {
            kt / r
        } else {
            kt * kt / r + b
        };
        check(
            c["name"].as_str().unwrap(),
            want,
            c["value"].as_f64().unwrap(),
            c["sd"].as_f64().unwrap(),
        );
    }
    (failures, checked)
}
