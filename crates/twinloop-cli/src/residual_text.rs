//! The residual base wrench as the terminal prints it (seed 004's Table 1), for
//! `validate` and `identify static`.

use twinloop_ident::validate::ResidualSummary;

/// The seed's Table 1: mean [std] of |Fx| .. |Tz| per model.
pub fn residual_table(rows: &[(&str, &ResidualSummary)]) -> String {
    let mut t = String::from(
        "model          |Fx| N         |Fy| N         |Fz| N         |Tx| Nm        |Ty| Nm        |Tz| Nm\n",
    );
    for (name, s) in rows {
        t.push_str(&format!("{name:<10}"));
        for k in 0..6 {
            t.push_str(&format!(" {:>7.3} [{:>5.3}]", s.mean_abs[k], s.std_abs[k]));
        }
        t.push('\n');
    }
    t
}
