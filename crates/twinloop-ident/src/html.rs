//! The HTML report of a static identification, with the seed's plots: GCOM distance
//! per pose before and after (seed 004, Fig. 5) and the residual base forces and
//! torques over time (its Fig. 6).

use crate::static_ident::{StaticResult, Suggestion};
use crate::validate::ResidualSeries;
use twinloop_report::{Plot, Report, SeriesStyle};

fn mm(x: f64) -> String {
    format!("{:.2}", x * 1e3)
}

/// The static-identification sections: summary, Fig. 5, link table, identifiability.
pub fn static_sections(r: &mut Report, res: &StaticResult, suggestions: &[Suggestion]) {
    gcom_section(r, res);
    link_table_section(r, res);
    identifiability_section(r, res);
    suggestions_section(r, suggestions);
}

/// GCOM to CoP distance per pose before and after (seed 004, Fig. 5).
fn gcom_section(r: &mut Report, res: &StaticResult) {
    r.heading("GCOM distance per pose (seed 004, Fig. 5)");
    r.paragraph(format!(
        "Distance between the model's ground-projected CoM and the measured centre of pressure for \
         each of the {} poses: prior model mean {} mm (std {}, max {}), identified model mean {} mm \
         (std {}, max {}). Seed 004 reports 9.2 mm (std 2.3) -> 0.6 mm (std 0.4) on REEM-C.",
        res.poses,
        mm(res.before.mean),
        mm(res.before.std),
        mm(res.before.max),
        mm(res.after.mean),
        mm(res.after.std),
        mm(res.after.max)
    ));
    let x: Vec<f64> = (1..=res.poses).map(|k| k as f64).collect();
    let before: Vec<f64> = res.gcom_distance_before.iter().map(|d| d * 1e3).collect();
    let after: Vec<f64> = res.gcom_distance_after.iter().map(|d| d * 1e3).collect();
    r.plot(
        &Plot::new("GCOM to CoP distance", "pose", "distance (mm)")
            .series("prior model", &x, &before, SeriesStyle::Bars)
            .series("identified model", &x, &after, SeriesStyle::Points),
    );
}

/// The identified masses and CoMs per link, with the prior (seed 004, eq 9).
fn link_table_section(r: &mut Report, res: &StaticResult) {
    r.heading("Masses and centres of mass");
    r.paragraph(format!(
        "Total mass: measured {:.3} kg (seed 004, eq 9), prior {:.3} kg; {:.3} kg on links kept \
         fixed. CoM in the link frame, mm. 'determined' is how much of the mass / first moment the \
         poses decide (1) rather than the prior (0).",
        res.total_mass, res.prior_total_mass, res.fixed_mass
    ));
    let header = [
        "link",
        "prior kg",
        "kg",
        "± kg",
        "prior CoM (mm)",
        "CoM (mm)",
        "determined m / mc",
        "at bound",
    ]
    .map(String::from)
    .to_vec();
    let v3 = |c: [f64; 3]| format!("{:.1} {:.1} {:.1}", c[0] * 1e3, c[1] * 1e3, c[2] * 1e3);
    let rows = res
        .links
        .iter()
        .map(|l| {
            vec![
                l.name.clone(),
                format!("{:.4}", l.prior_mass),
                format!("{:.4}", l.mass),
                format!("{:.4}", l.mass_std),
                v3(l.prior_com),
                v3(l.com),
                format!(
                    "{:.2} / {:.2} {:.2} {:.2}",
                    l.mass_determined,
                    l.first_moment_determined[0],
                    l.first_moment_determined[1],
                    l.first_moment_determined[2]
                ),
                l.at_bounds.join(", "),
            ]
        })
        .collect();
    r.table(header, rows);
}

/// Rank, singular values against the noise, and the groups the poses do not decide.
fn identifiability_section(r: &mut Report, res: &StaticResult) {
    let id = &res.identifiability;
    r.heading("Identifiability");
    r.paragraph(format!(
        "{} parameters; rank {} (singular values above {:e} of the largest); {} above the noise \
         level {:.3e} kg m; condition number {:.3e} within the rank. {}",
        id.parameters,
        id.rank,
        crate::static_ident::RANK_TOLERANCE,
        id.well_determined,
        id.noise_level,
        id.condition_number,
        id.structural_explanation
    ));
    let k: Vec<f64> = (1..=id.singular_values.len()).map(|k| k as f64).collect();
    let sv: Vec<f64> = id
        .singular_values
        .iter()
        .map(|s| s.max(1e-12 * id.singular_values[0].max(1e-300)))
        .collect();
    r.plot(
        &Plot::new(
            "Singular values of the prior-scaled regressor",
            "index",
            "singular value (kg m)",
        )
        .series("singular value", &k, &sv, SeriesStyle::Bars)
        .hline(id.noise_level, "noise level")
        .log_y(),
    );
    if !id.welded.is_empty() {
        r.subheading(
            "Links welded to one body (only their sum is seen; the split stays at the prior)",
        );
        r.table(
            vec!["links".into()],
            id.welded.iter().map(|g| vec![g.join(", ")]).collect(),
        );
    }
    for (title, groups) in [
        (
            "Not excited by these poses (kept at the prior)",
            &id.unidentifiable,
        ),
        (
            "Excited below the noise (mostly prior)",
            &id.poorly_identified,
        ),
    ] {
        if groups.is_empty() {
            continue;
        }
        r.subheading(title);
        r.table(
            vec!["links".into(), "directions".into(), "why".into()],
            groups
                .iter()
                .map(|g| vec![g.links.join(", "), g.directions.to_string(), g.why.clone()])
                .collect(),
        );
    }
}

/// The poses that would raise the smallest singular value most.
fn suggestions_section(r: &mut Report, suggestions: &[Suggestion]) {
    if !suggestions.is_empty() {
        r.subheading("Poses that would help most");
        r.table(
            vec![
                "#".into(),
                "category".into(),
                "smallest singular value before -> after".into(),
            ],
            suggestions
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    vec![
                        (i + 1).to_string(),
                        s.category.name().to_string(),
                        format!(
                            "{:.3e} -> {:.3e}",
                            s.smallest_singular_value_before, s.smallest_singular_value_after
                        ),
                    ]
                })
                .collect(),
        );
    }
}

/// Residual base forces and torques over time for one or more models (seed 004,
/// Fig. 6, and Table 1 as a table).
pub fn residual_sections(r: &mut Report, runs: &[(&str, &ResidualSeries)]) {
    r.heading("Residual base wrench (seed 004, Fig. 6 and Table 1)");
    r.paragraph(
        "What inverse dynamics needs at the floating base beyond the measured ground reaction: zero \
         for a perfect model. World-aligned axes at the base origin. Seed 004 (REEM-C squat): Fz \
         103.02 N -> 2.68 N, Tx 5.66 -> 0.87 Nm, Ty 5.98 -> 1.35 Nm.",
    );
    let names = ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"];
    let mut rows = Vec::new();
    for (label, s) in runs {
        let mut row = vec![label.to_string()];
        for k in 0..6 {
            row.push(format!(
                "{:.3} [{:.3}]",
                s.summary.mean_abs[k], s.summary.std_abs[k]
            ));
        }
        rows.push(row);
    }
    let mut header = vec!["model".to_string()];
    header.extend(names.iter().map(|n| {
        if n.starts_with('F') {
            format!("|{n}| N")
        } else {
            format!("|{n}| Nm")
        }
    }));
    r.table(header, rows);
    for (title, unit, range) in [
        ("Residual forces", "N", 0..3),
        ("Residual torques", "Nm", 3..6),
    ] {
        let mut p = Plot::new(title, "t (s)", unit);
        for (label, s) in runs {
            for k in range.clone() {
                let y: Vec<f64> = s.wrench.iter().map(|w| w[k]).collect();
                p = p.line(format!("{} {label}", names[k]), &s.t, &y);
            }
        }
        r.plot(&p);
    }
}
