//! HTML reports with the seed's figures: measured vs simulated outputs (seed 003,
//! Figs 50 and 53), Hankel singular values (Figs 51, 54), singular values of the
//! frequency response (Figs 52, 55), and the residual correlations of section 8.

use crate::data::IoData;
use crate::identify::{ArxIdentification, Evaluation, Fit, StateSpaceIdentification};
use crate::resid::{CorrelationTest, ResidualTests};
use twinloop_report::{Plot, Report, SeriesStyle};

/// FIT values to print beside the model's, e.g. the seed's own results.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceFit {
    pub label: String,
    /// One value per output (percent).
    pub values: Vec<f64>,
}

/// The seed's FIT figures (seed 003, sections 8.1 and 8.2) for its six gyro
/// outputs in the order of its Fig. 50: left foot roll, pitch, yaw rate, then
/// right foot roll, pitch, yaw rate. Order the outputs the same way to compare.
pub fn seed_reference_fits() -> Vec<ReferenceFit> {
    vec![
        ReferenceFit {
            label: "seed initial ARX".to_string(),
            values: vec![56.0, 38.0, 35.0, 53.0, 17.0, 28.0],
        },
        ReferenceFit {
            label: "seed final state space".to_string(),
            values: vec![61.0, 48.0, 49.0, 59.0, 42.0, 55.0],
        },
    ]
}

/// `x` with `digits` significant digits, without float noise.
pub fn sig(x: f64, digits: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let r: f64 = format!("{x:.*e}", digits.saturating_sub(1))
        .parse()
        .unwrap_or(x);
    if (1e-4..1e6).contains(&r.abs()) {
        format!("{r}")
    } else {
        format!("{r:e}")
    }
}

fn pct(x: Option<f64>) -> String {
    x.map_or("-".to_string(), |v| format!("{v:.1}"))
}

fn fit_table(
    report: &mut Report,
    names: &[String],
    fit: &Fit,
    extra: &[(String, &Fit)],
    refs: &[ReferenceFit],
) {
    let mut header = vec![
        "output".to_string(),
        "FIT sim %".to_string(),
        format!("FIT {}-step %", fit.prediction_horizon),
        "eq 10 sim %".to_string(),
        format!("eq 10 {}-step %", fit.prediction_horizon),
    ];
    for (label, _) in extra {
        header.push(format!("{label}: FIT sim %"));
    }
    for r in refs {
        header.push(r.label.clone());
    }
    let rows = names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let mut row = vec![
                n.clone(),
                pct(fit.simulation[i]),
                pct(fit.prediction[i]),
                pct(fit.seed_eq10_simulation[i]),
                pct(fit.seed_eq10_prediction[i]),
            ];
            for (_, f) in extra {
                row.push(pct(f.simulation.get(i).copied().flatten()));
            }
            for r in refs {
                row.push(
                    r.values
                        .get(i)
                        .map_or("-".to_string(), |v| format!("{v:.0}")),
                );
            }
            row
        })
        .collect();
    report.table(header, rows);
}

fn time_axis(data: &IoData) -> (Vec<f64>, &'static str) {
    match data.sample_time {
        Some(ts) => ((0..data.len()).map(|k| k as f64 * ts).collect(), "time, s"),
        None => ((0..data.len()).map(|k| k as f64).collect(), "sample"),
    }
}

/// The four report sections for one evaluation, in the seed's figure order.
fn evaluation_sections(report: &mut Report, ev: &Evaluation, data: &IoData, fig: (u32, u32, u32)) {
    output_comparison_section(report, ev, data, fig.0);
    hankel_section(report, ev, fig.1);
    frequency_response_section(report, ev, fig.2);
    residual_section(report, ev);
}

/// One plot per output: measured against simulated, titled with its FIT.
fn output_comparison_section(report: &mut Report, ev: &Evaluation, data: &IoData, fig: u32) {
    let (t, tl) = time_axis(data);
    report.subheading(format!(
        "Measured and simulated outputs ({} data; seed Fig. {fig})",
        ev.data
    ));
    report.paragraph(
        "The model is driven by the measured inputs alone from a zero state (no output feedback), \
         as MATLAB's compare does for simulation.",
    );
    for (i, name) in data.output_names.iter().enumerate() {
        let y: Vec<f64> = data.y.row(i).iter().copied().collect();
        let ys: Vec<f64> = ev.simulated.row(i).iter().copied().collect();
        let plot = Plot::new(
            format!("{name}: FIT {}%", pct(ev.fit_percent.simulation[i])),
            tl,
            name.clone(),
        )
        .line("measured", &t, &y)
        .series("simulated", &t, &ys, SeriesStyle::DashedLine);
        report.plot(&Plot {
            height: 220.0,
            ..plot
        });
    }
}

/// Hankel singular values with the suggested order, or why there are none.
fn hankel_section(report: &mut Report, ev: &Evaluation, fig: u32) {
    report.subheading(format!("Hankel singular values (seed Fig. {fig})"));
    match &ev.hankel_singular_values {
        Some(h) => {
            let x: Vec<f64> = (1..=h.len()).map(|k| k as f64).collect();
            let plot = Plot::new("Hankel singular values", "state", "singular value")
                .series("HSV", &x, h, SeriesStyle::Bars)
                .log_y();
            report.plot(&plot);
            if let Some(s) = &ev.order_suggestion {
                report.paragraph(format!(
                    "Largest gap after state {} (ratio {}): reducing to that order costs at most {} in the \
                     largest gain (balanced-truncation bound 2 x the sum of the discarded values).",
                    s.order,
                    sig(s.gap_ratio, 3),
                    sig(s.truncation_error_bound.get(s.order - 1).copied().unwrap_or(0.0), 4)
                ));
            }
        }
        None => {
            report.paragraph(
                "The model is unstable: it has no Gramians, hence no Hankel singular values.",
            );
        }
    }
}

/// Singular values of the frequency response, with peak, DC gain and bandwidth.
fn frequency_response_section(report: &mut Report, ev: &Evaluation, fig: u32) {
    let fr = &ev.frequency_response;
    report.subheading(format!(
        "Singular values of the frequency response (seed Fig. {fig})"
    ));
    let nsv = fr.sigma_db.iter().map(|r| r.len()).max().unwrap_or(0);
    let mut plot = Plot::new(
        "Singular values",
        format!("frequency, {}", fr.frequency_unit),
        "gain, dB",
    )
    .log_x();
    for s in 0..nsv {
        let (xs, ys): (Vec<f64>, Vec<f64>) = fr
            .frequency
            .iter()
            .zip(&fr.sigma_db)
            .filter_map(|(w, row)| row.get(s).map(|v| (*w, *v)))
            .filter(|(_, v)| v.is_finite())
            .unzip();
        plot = plot.line(format!("sigma {}", s + 1), &xs, &ys);
    }
    report.plot(&plot);
    report.paragraph(format!(
        "Peak gain {:.1} dB at {} {}; zero-frequency gain {}; bandwidth (largest singular value 3 dB \
         below its zero-frequency value) {}.",
        fr.peak_gain_db,
        sig(fr.peak_frequency, 4),
        fr.frequency_unit,
        fr.dc_gain_db.map_or("unbounded (pole at z = 1)".to_string(), |g| format!("{g:.1} dB")),
        fr.bandwidth
            .map_or("not reached below the Nyquist frequency".to_string(), |b| format!("{} {}", sig(b, 4), fr.frequency_unit))
    ));
}

/// Residual tests: summary, autocorrelation plot, worst cross-correlations, table.
fn residual_section(report: &mut Report, ev: &Evaluation) {
    let rt = &ev.residual_tests;
    report.subheading("Residual tests (seed section 8.1, eqs 11-12)");
    report.paragraph(format!(
        "One-step prediction errors on the {} data, {} samples, lags up to {}; dashed lines: 99 % band \
         +-{:.4}. {}",
        ev.data, rt.samples, rt.max_lag, rt.band_99, rt.summary
    ));
    residual_autocorrelation_plot(report, rt);
    residual_cross_correlation_plots(report, rt);
    residual_test_table(report, rt);
}

/// Autocorrelation of each residual at positive lags, inside the 99 % band.
fn residual_autocorrelation_plot(report: &mut Report, rt: &ResidualTests) {
    let band = rt.band_99;
    let mut auto = Plot::new("Residual autocorrelation", "lag", "correlation")
        .hline(band, "99 %")
        .hline(-band, "-99 %");
    for a in &rt.autocorrelation {
        let (x, y): (Vec<f64>, Vec<f64>) = a
            .lags
            .iter()
            .zip(&a.correlation)
            .filter(|(l, _)| **l > 0)
            .map(|(l, c)| (*l as f64, *c))
            .unzip();
        auto = auto.series(a.residual.clone(), &x, &y, SeriesStyle::Points);
    }
    report.plot(&auto);
}

/// Output-output and residual-input cross-correlations: only the 4 lowest
/// p-values each, since all pairs would crowd the plot.
fn residual_cross_correlation_plots(report: &mut Report, rt: &ResidualTests) {
    let band = rt.band_99;
    fn worst(tests: &[CorrelationTest], n: usize) -> Vec<&CorrelationTest> {
        let mut v: Vec<&CorrelationTest> = tests.iter().collect();
        v.sort_by(|a, b| a.p_value.total_cmp(&b.p_value));
        v.truncate(n);
        v
    }
    for (title, tests) in [
        (
            "Residual cross-correlation between outputs (the 4 lowest p-values)",
            &rt.cross_correlation,
        ),
        (
            "Residual-input cross-correlation (the 4 lowest p-values)",
            &rt.input_correlation,
        ),
    ] {
        if tests.is_empty() {
            continue;
        }
        let mut p = Plot::new(title, "lag", "correlation")
            .hline(band, "99 %")
            .hline(-band, "-99 %");
        for t in worst(tests, 4) {
            let x: Vec<f64> = t.lags.iter().map(|l| *l as f64).collect();
            p = p.series(
                format!("{}~{}", t.residual, t.with),
                &x,
                &t.correlation,
                SeriesStyle::Points,
            );
        }
        report.plot(&p);
    }
}

/// Every output test, plus only the failed input tests (the passing ones are many
/// and say little).
fn residual_test_table(report: &mut Report, rt: &ResidualTests) {
    let mut rows = Vec::new();
    for t in rt.autocorrelation.iter().chain(&rt.cross_correlation) {
        rows.push(vec![
            if t.residual == t.with {
                format!("auto {}", t.residual)
            } else {
                format!("{} ~ {}", t.residual, t.with)
            },
            sig(t.statistic, 3),
            format!("{}", t.degrees_of_freedom),
            sig(t.p_value, 3),
            format!("{}", t.outside_band),
            if t.pass { "pass" } else { "fail" }.to_string(),
        ]);
    }
    let failed_inputs: Vec<&CorrelationTest> =
        rt.input_correlation.iter().filter(|t| !t.pass).collect();
    for t in failed_inputs {
        rows.push(vec![
            format!("{} ~ input {}", t.residual, t.with),
            sig(t.statistic, 3),
            format!("{}", t.degrees_of_freedom),
            sig(t.p_value, 3),
            format!("{}", t.outside_band),
            "fail".to_string(),
        ]);
    }
    report.table(
        vec![
            "test".to_string(),
            "statistic".to_string(),
            "dof".to_string(),
            "p-value".to_string(),
            "lags outside 99 %".to_string(),
            "verdict".to_string(),
        ],
        rows,
    );
}

fn warnings(report: &mut Report, w: &[String]) {
    if !w.is_empty() {
        report.heading("Warnings");
        for x in w {
            report.paragraph(x.clone());
        }
    }
}

/// A report of an ARX identification (`data` is the record the evaluation used).
pub fn arx_report(
    id: &ArxIdentification,
    data: &IoData,
    command: &str,
    refs: &[ReferenceFit],
) -> Report {
    let o = id.model.orders();
    let mut r = Report::new(format!("ARX model na={} nb={} nk={}", o.na, o.nb, o.nk));
    if !command.is_empty() {
        r.preformatted(command.to_string());
    }
    let (ny, nu) = (id.model.ny(), id.model.nu());
    r.paragraph(format!(
        "MIMO ARX with full {ny}x{ny} A matrices, {nu} inputs, {ny} outputs: {} parameters per output, estimated \
         by least squares (Householder QR) as MATLAB's arx. Prediction cost (mean squared one-step error) {} \
         on the estimation data, {} on the {} data.",
        o.parameters_per_output(ny, nu),
        sig(id.estimation_prediction_cost, 6),
        sig(id.evaluation.prediction_cost, 6),
        id.evaluation.data
    ));
    r.heading("FIT per output");
    r.paragraph(
        "FIT = 100 (1 - |y - yhat| / |y - mean y|) as MATLAB's compare (higher is better); eq 10 is the seed's \
         |y - yhat| / |y| x 100 (an error, lower is better).",
    );
    fit_table(
        &mut r,
        &data.output_names,
        &id.evaluation.fit_percent,
        &[],
        refs,
    );
    r.heading("Evaluation");
    evaluation_sections(&mut r, &id.evaluation, data, (50, 51, 52));
    warnings(&mut r, &id.evaluation.warnings);
    r
}

/// A report of a state-space identification (`data` is the record the evaluation used).
pub fn state_space_report(
    id: &StateSpaceIdentification,
    data: &IoData,
    command: &str,
    refs: &[ReferenceFit],
) -> Report {
    let mut r = Report::new(format!(
        "State-space model of order {} ({})",
        id.model.n(),
        id.method.name()
    ));
    if !command.is_empty() {
        r.preformatted(command.to_string());
    }
    r.paragraph(format!(
        "Innovations form x(k+1) = A x + B u + K e, y = C x + D u + e with {} states, {} inputs, {} outputs. \
         Prediction cost {} on the estimation data, {} on the {} data.",
        id.model.n(),
        id.model.nu(),
        id.model.ny(),
        sig(id.estimation_prediction_cost, 6),
        sig(id.evaluation.prediction_cost, 6),
        id.evaluation.data
    ));
    r.heading("FIT per output");
    r.paragraph(
        "FIT = 100 (1 - |y - yhat| / |y - mean y|) as MATLAB's compare (higher is better); eq 10 is the seed's \
         |y - yhat| / |y| x 100 (an error, lower is better). Earlier stages of the route are shown beside.",
    );
    let extra: Vec<(String, &Fit)> = id
        .stages
        .iter()
        .map(|s| (s.name.clone(), &s.fit_percent))
        .collect();
    fit_table(
        &mut r,
        &data.output_names,
        &id.evaluation.fit_percent,
        &extra,
        refs,
    );
    if let Some(p) = &id.pem {
        r.heading("Prediction-error search");
        r.paragraph(format!(
            "{} iterations over {} free parameters; cost {} -> {}; {}.",
            p.iterations,
            p.free_parameters,
            sig(p.initial_cost, 6),
            sig(p.final_cost, 6),
            p.termination
        ));
        let x: Vec<f64> = (0..p.cost_history.len()).map(|k| k as f64).collect();
        r.plot(
            &Plot::new("Prediction cost per iteration", "iteration", "cost").line(
                "cost",
                &x,
                &p.cost_history,
            ),
        );
    }
    if let Some(h) = &id.arx_hankel_singular_values {
        r.heading(
            "Hankel singular values of the ARX model (with its noise inputs) before the reduction",
        );
        let x: Vec<f64> = (1..=h.len()).map(|k| k as f64).collect();
        r.plot(
            &Plot::new("ARX Hankel singular values", "state", "singular value")
                .series("HSV", &x, h, SeriesStyle::Bars)
                .log_y(),
        );
    }
    if let Some(s) = &id.subspace_singular_values {
        r.heading("Subspace singular values (order selection)");
        let x: Vec<f64> = (1..=s.len()).map(|k| k as f64).collect();
        r.plot(
            &Plot::new(
                "Singular values of the weighted projection",
                "index",
                "singular value",
            )
            .series("sv", &x, s, SeriesStyle::Bars)
            .log_y(),
        );
    }
    r.heading("Evaluation");
    evaluation_sections(&mut r, &id.evaluation, data, (53, 54, 55));
    warnings(&mut r, &id.warnings);
    r
}
