//! The HTML report of a compact-model fit (seed 002, section 4 and Fig. 4).

use super::{Dataset, FitResult, Identifiability, PARAMETER_NAMES, Validation};
use twinloop_reduced::{CompactModel, Corrections, SagittalCompliance};
use twinloop_report::{Plot, Report, SeriesStyle, number};

/// At most about 3000 points per curve: the SVG stays light.
fn decimate(v: &[f64]) -> Vec<f64> {
    let stride = v.len().div_ceil(3000).max(1);
    v.iter().step_by(stride).copied().collect()
}

/// The HTML report of a fit: seed 002's Fig. 4 (CoM x and z, measured, before and
/// after), the model's error before and after, the parameters with their Cramer-Rao
/// standard deviations and correlations, and the other gaits' MSE. `data_name` and
/// `model_name` say where the data and the plant came from.
#[allow(clippy::too_many_arguments)]
pub fn fit_report(
    data_name: &str,
    model_name: &str,
    plant: &SagittalCompliance,
    start: &Corrections,
    data: &Dataset,
    r: &FitResult,
    ident: Option<&Identifiability>,
    validation: &[Validation],
) -> Report {
    let mut rep = Report::new("Compact compliant model fit (seed 002)");
    rep.paragraph(format!(
        "Data {} ({} samples), model {}, method {:?}: {} evaluations ({}). MSE {} m^2 before, {} m^2 after.",
        data_name,
        data.len(),
        model_name,
        r.method,
        r.evaluations,
        r.stop,
        number(r.mse_before),
        number(r.mse_after)
    ));
    trajectory_sections(&mut rep, plant, start, data, r);
    parameter_section(&mut rep, start, r, ident);
    if let Some(id) = ident {
        identifiability_section(&mut rep, id);
    }
    if !validation.is_empty() {
        validation_section(&mut rep, validation);
    }
    rep
}

/// The CoM trajectory of `plant` with corrections `c`, from the data's first sample.
fn rollout(plant: &SagittalCompliance, c: &Corrections, data: &Dataset) -> (Vec<f64>, Vec<f64>) {
    let m = CompactModel {
        plant: *plant,
        corrections: *c,
    };
    let (mut x, mut z) = (Vec::new(), Vec::new());
    m.rollout_unchecked(&data.reference, data.x[0], data.z[0], &mut x, &mut z);
    (x, z)
}

/// Seed 002's Fig. 4 (measured, before and after), then the model's error, which
/// shows what the overlapping curves hide.
fn trajectory_sections(
    rep: &mut Report,
    plant: &SagittalCompliance,
    start: &Corrections,
    data: &Dataset,
    r: &FitResult,
) {
    let (xb, zb) = rollout(plant, start, data);
    let (xa, za) = rollout(plant, &r.params, data);
    let t = decimate(&data.reference.t);
    rep.heading("Seed 002 Fig. 4: the model before and after the fit");
    for (axis, meas, before, after) in [("x", &data.x, &xb, &xa), ("z", &data.z, &zb, &za)] {
        rep.plot(
            &Plot::new(format!("CoM {axis}"), "t [s]", format!("{axis} [m]"))
                .series("measured", &t, &decimate(meas), SeriesStyle::Line)
                .series("before", &t, &decimate(before), SeriesStyle::DashedLine)
                .series("after", &t, &decimate(after), SeriesStyle::Line),
        );
    }
    rep.paragraph(
        "At walking scale the curves overlap; the model's error against the measurement shows the difference:",
    );
    for (axis, meas, before, after) in [("x", &data.x, &xb, &xa), ("z", &data.z, &zb, &za)] {
        let err = |m: &[f64]| -> Vec<f64> {
            decimate(
                &m.iter()
                    .zip(meas.iter())
                    .map(|(a, b)| a - b)
                    .collect::<Vec<_>>(),
            )
        };
        rep.plot(
            &Plot::new(
                format!("CoM {axis}: model minus measurement"),
                "t [s]",
                format!("error in {axis} [m]"),
            )
            .series("before", &t, &err(before), SeriesStyle::DashedLine)
            .series("after", &t, &err(after), SeriesStyle::Line),
        );
    }
}

/// Start and fitted value of every parameter, with its Cramer-Rao standard
/// deviation when it was estimated ("fixed" otherwise).
fn parameter_section(
    rep: &mut Report,
    start: &Corrections,
    r: &FitResult,
    ident: Option<&Identifiability>,
) {
    rep.heading("Parameters");
    let p = r.params.to_array();
    let s = start.to_array();
    let rows = (0..10)
        .map(|i| {
            let name = PARAMETER_NAMES[i];
            let fitted = ident.and_then(|id| Some((id, id.names.iter().position(|n| n == name)?)));
            let (std, flag) = match fitted {
                Some((id, k)) => {
                    let flag = if id.poorly_determined.iter().any(|n| n == name) {
                        "poorly determined"
                    } else {
                        ""
                    };
                    (number(id.std[k]), flag.to_string())
                }
                None => ("fixed".to_string(), String::new()),
            };
            vec![name.to_string(), number(s[i]), number(p[i]), std, flag]
        })
        .collect();
    rep.table(
        vec![
            "parameter".into(),
            "start".into(),
            "fitted".into(),
            "Cramer-Rao std".into(),
            "".into(),
        ],
        rows,
    );
}

/// Noise estimate, conditioning, weakest direction and the correlation matrix.
fn identifiability_section(rep: &mut Report, id: &Identifiability) {
    rep.paragraph(format!(
        "Noise standard deviation estimated from the residuals: {} m (variance {} m^2, \
         Cramer-Rao std of that variance {} m^2; the bounds use {} m). \
         Condition of the scaled Fisher information: {}. Least determined direction \
         (relative changes): {}.",
        number(id.noise_std_estimated),
        number(id.noise_std_estimated.powi(2)),
        number(id.noise_variance_std),
        number(id.noise_std),
        number(id.condition),
        id.names
            .iter()
            .zip(&id.weakest_direction)
            .map(|(n, v)| format!("{n} {}", number(*v)))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let mut header = vec![String::new()];
    header.extend(id.names.iter().cloned());
    let rows = id
        .names
        .iter()
        .zip(&id.correlation)
        .map(|(n, row)| {
            let mut r = vec![n.clone()];
            r.extend(row.iter().map(|v| format!("{v:.3}")));
            r
        })
        .collect();
    rep.subheading("Parameter correlation (Cramer-Rao covariance)");
    rep.table(header, rows);
}

/// MSE before and after the fit on the other gaits.
fn validation_section(rep: &mut Report, validation: &[Validation]) {
    rep.heading("Generalisation: other gaits");
    rep.table(
        vec![
            "data".into(),
            "samples".into(),
            "MSE before [m^2]".into(),
            "MSE after [m^2]".into(),
        ],
        validation
            .iter()
            .map(|v| {
                vec![
                    v.source.clone(),
                    v.samples.to_string(),
                    number(v.mse_before),
                    number(v.mse_after),
                ]
            })
            .collect(),
    );
}
