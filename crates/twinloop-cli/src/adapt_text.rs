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
