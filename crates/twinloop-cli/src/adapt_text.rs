//! How the terminal words an adaptation's result, the same in `adapt` and `demo`:
//! the checks `adapt` holds the answer against (`twinloop_ident::adapt_checks`), in
//! the report's names.

use std::path::Path;
use twinloop_ident::adapt::AdaptReport;

/// The checks as the terminal says them: each failed one with its reason, and the
/// model at `out` (if one was asked for) not written.
pub fn checks_text(r: &AdaptReport, out: Option<&Path>) -> String {
    let mut t = String::new();
    let failed: Vec<_> = r.failed_checks().collect();
    if failed.is_empty() {
        if !r.checks.is_empty() {
            let names: Vec<&str> = r.checks.iter().map(|c| c.name.as_str()).collect();
            t += &format!("checks passed: {}\n", names.join(", "));
        }
        return t;
    }
    for c in failed {
        t += &format!("check FAILED: {}: {}\n", c.name, c.detail);
    }
    if let Some(out) = out {
        t += &format!(
            "{} not written: the result failed its checks (the JSON and report say which)\n",
            out.display()
        );
    }
    t
}

/// The `--check` line: the adapted model's simulated fall angles as the measured
/// ones are printed, to hundredths of a degree (not 15 digits: issue 30 item 10), and
/// their difference from the measured ones.
pub fn check_angles_text(check: &[f64; 4], measured: &[f64; 4]) -> String {
    let angles: Vec<String> = check.iter().map(|a| format!("{a:.2}")).collect();
    let diff: Vec<String> = check
        .iter()
        .zip(measured)
        .map(|(a, m)| format!("{:+.2}", a - m))
        .collect();
    format!(
        "adapted model's fall angles {} deg (model - measured {})\n",
        angles.join(" / "),
        diff.join(" / ")
    )
}

#[cfg(test)]
mod tests {
    use super::check_angles_text;

    #[test]
    fn adapt_check_prints_fall_angles_to_hundredths() {
        let line = check_angles_text(
            &[9.082031250000004, 22.4390625, 28.17399999999999, 28.193],
            &[9.0, 22.5, 28.17399999999999, 28.2],
        );
        assert_eq!(
            line,
            "adapted model's fall angles 9.08 / 22.44 / 28.17 / 28.19 deg (model - measured +0.08 / -0.06 / +0.00 / -0.01)\n"
        );
    }
}
