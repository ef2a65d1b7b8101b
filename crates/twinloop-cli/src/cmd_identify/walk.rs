//! `twinloop identify walk`: seed 003's identification of a recorded walk: the
//! 24th-order ARX initial model, then ARX -> balanced reduction -> PEM.

use super::sysid::command_line;
use crate::common::{emit, read_table};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};
use twinloop_ident::walk_identification::{WalkIdOptions, WalkIdentification, identify_walk};
use twinloop_io::Table;
use twinloop_sysid::ArxOrders;
use twinloop_sysid::identify::{PemSummary, Stage};
use twinloop_sysid::json::{ArxModelJson, EvaluationJson, OffsetsJson, StateSpaceModelJson};
use twinloop_sysid::pem::OutputWeight;
use twinloop_sysid::report::{ReferenceFit, arx_report, seed_reference_fits, state_space_report};

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum WalkFocusArg {
    /// Output error (K = 0): the simulation error is minimised, as the seed compares models.
    Simulation,
    /// Innovations form (K estimated): the one-step prediction error is minimised.
    Prediction,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum WalkWeightArg {
    Identity,
    Noise,
}

#[derive(Args, Debug)]
pub struct WalkIdArgs {
    /// Estimation record from `twinloop experiment walk`.
    #[arg(long, value_name = "FILE.csv")]
    pub data: PathBuf,
    /// Validation record (the FIT is reported on it): e.g. --skip-samples 1000 --seed 2.
    #[arg(long, value_name = "FILE.csv")]
    pub val: Option<PathBuf>,
    /// ARX output lags (seed 003: 24).
    #[arg(long, default_value_t = 24)]
    pub na: usize,
    /// ARX input lags (12: the largest full-rank order on the periodic walk inputs).
    #[arg(long, default_value_t = 12, value_parser = crate::bounds::count)]
    pub nb: usize,
    /// ARX input delay in samples.
    #[arg(long, default_value_t = 1)]
    pub nk: usize,
    /// States of the final model (default: from the ARX's Hankel singular values).
    #[arg(long, value_parser = crate::bounds::count)]
    pub order: Option<usize>,
    /// Share of the Hankel-singular-value sum the default order keeps.
    #[arg(long, default_value_t = 0.9, value_parser = crate::common::positive)]
    pub hsv_energy: f64,
    /// What the prediction-error search minimises.
    #[arg(long, value_enum, default_value = "simulation")]
    pub focus: WalkFocusArg,
    /// Output weighting of the prediction-error cost: `noise` (default) divides by the
    /// initial model's error covariance (MATLAB's det criterion at the start), `identity`
    /// sums the squared errors.
    #[arg(long, value_enum, default_value = "noise")]
    pub weight: WalkWeightArg,
    /// Keep the means. By default the estimation record's mean is subtracted from every
    /// input and output (the same offsets from the validation record; the JSON's
    /// data.offsets says what was removed).
    #[arg(long)]
    pub no_detrend: bool,
    /// Iteration limit of the prediction-error search.
    #[arg(long, default_value_t = 100, value_parser = crate::bounds::count)]
    pub max_iter: usize,
    /// Largest pole radius the search may give A: a damping margin (0.999 at 40 ms: a 40 s
    /// time constant, longer than the record).
    #[arg(long, default_value_t = 0.999, value_parser = crate::common::positive)]
    pub max_pole_radius: f64,
    /// Write both models and their evaluations as JSON to FILE (-: to stdout, in place
    /// of the text).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// HTML report of the final state-space model (the seed's Figs. 53-55 and residuals).
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
    /// HTML report of the initial ARX model (the seed's Figs. 50-52 and residuals).
    #[arg(long, value_name = "OUT.html")]
    pub report_arx: Option<PathBuf>,
}

/// The estimation and validation records; the validation record must have the
/// estimation record's columns.
fn read_records(a: &WalkIdArgs) -> Result<(Table, Option<Table>), CliError> {
    let est = read_table(&a.data).map_err(|e| e.context("--data"))?;
    let val = match &a.val {
        Some(p) => Some(read_table(p).map_err(|e| e.context("--val"))?),
        None => None,
    };
    if let Some(v) = &val
        && v.columns != est.columns
    {
        return Err(CliError::new(format!(
            "--val {}: its columns differ from --data's",
            a.val
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        )));
    }
    Ok((est, val))
}

fn options(a: &WalkIdArgs) -> WalkIdOptions {
    WalkIdOptions {
        arx: ArxOrders {
            na: a.na,
            nb: a.nb,
            nk: a.nk,
        },
        order: a.order,
        hsv_energy: a.hsv_energy,
        output_error: matches!(a.focus, WalkFocusArg::Simulation),
        weight: match a.weight {
            WalkWeightArg::Identity => OutputWeight::Identity,
            WalkWeightArg::Noise => OutputWeight::InverseNoise,
        },
        detrend: !a.no_detrend,
        max_iterations: a.max_iter,
        max_pole_radius: a.max_pole_radius,
    }
}

pub fn run(a: &WalkIdArgs) -> CliResult {
    let (est, val) = read_records(a)?;
    let o = options(a);
    let bar = crate::progress::steps(a.max_iter);
    bar.set_message("prediction-error search");
    let id = identify_walk(
        &est.columns,
        &est.rows,
        val.as_ref().map(|v| v.rows.as_slice()),
        &o,
        &mut |p| {
            bar.set_position(p.iteration as u64);
            bar.set_message(format!("cost {:.4e}", p.cost));
        },
    )
    .map_err(|e| {
        // An option the library checks names itself by its field: say which option.
        let context = if e.to_string().starts_with("hsv_energy") {
            "--hsv-energy".to_string()
        } else {
            a.data.display().to_string()
        };
        CliError::from(e).context(context)
    });
    bar.finish_and_clear();
    let id = id?;
    let refs = seed_reference_fits();
    let ev_arx = id.validation.as_ref().unwrap_or(&id.estimation);
    if let Some(p) = &a.report_arx {
        let mut page = arx_report(&id.arx, ev_arx, &command_line(), &refs[..1]);
        walk_in_3d(p, a, &mut page)?;
        page.write(p)?;
    }
    if let Some(p) = &a.report {
        let mut page = state_space_report(&id.ss, ev_arx, &command_line(), &refs[1..]);
        walk_in_3d(p, a, &mut page)?;
        page.write(p)?;
    }
    let json = walk_json(a, &o, &id, &refs);
    emit(&summary(&o, &id, &refs), a.json.as_ref(), &json)?;
    Ok(Outcome::Ok)
}

/// The walk in 3D beside a report (`OUT_3d.html`): lab17 (the robot seed 003's
/// walk is written for) at the joint angles the record's inputs command, seed 003
/// eq 6 read backwards (joint = direction x `u:` offset, from the Table 2 trims),
/// the estimation run solid and the validation run as a ghost. The record has no
/// base pose: the robot walks in place.
fn walk_in_3d(
    report: &Path,
    a: &WalkIdArgs,
    page: &mut twinloop_report::Report,
) -> Result<(), CliError> {
    use twinloop_description::builtin::lab17;
    let as_angles = |path: &PathBuf| -> Result<(PathBuf, twinloop_io::Table), CliError> {
        let data = crate::common::read_table(path)?;
        let mut columns = Vec::new();
        let mut cols = Vec::new();
        for (i, c) in data.columns.iter().enumerate() {
            let angle = c
                .strip_prefix("u:")
                .and_then(|j| lab17::trim(j).map(|t| (j, t)));
            match (c.as_str(), angle) {
                ("t", _) => (columns.push(c.clone()), cols.push((i, None))),
                (_, Some((j, t))) => (columns.push(format!("q:{j}")), cols.push((i, Some(t)))),
                _ => (columns.push(c.clone()), cols.push((i, None))),
            };
        }
        let mut out = twinloop_io::Table::new(columns);
        for row in &data.rows {
            out.rows.push(
                cols.iter()
                    .map(|&(i, t)| match t {
                        Some(t) => {
                            lab17::joint_angle(t.joint, t.servo_deg + row[i]).unwrap_or(f64::NAN)
                        }
                        None => row[i],
                    })
                    .collect(),
            );
        }
        Ok((path.clone(), out))
    };
    let mut runs = vec![as_angles(&a.data)?];
    if let Some(v) = &a.val {
        runs.push(as_angles(v)?);
    }
    crate::replay3d::replay_tables(
        report,
        "builtin:lab17",
        &runs,
        "The walk in 3D on lab17: the joint angles its inputs command (seed 003 eq 6 read \
         backwards from the u: offsets and the Table 2 trims; the joints without an input \
         at 0), the estimation run solid, the validation run as a ghost. The record has \
         no base pose, so the robot walks in place; the gyro rates are in the plots.",
        page,
    );
    Ok(())
}

/// The table of FIT per output for both models beside the seed's.
fn summary(o: &WalkIdOptions, id: &WalkIdentification, refs: &[ReferenceFit]) -> String {
    use std::fmt::Write as _;
    let pct = |v: &Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.1}"));
    let mut s = String::new();
    let _ = writeln!(
        s,
        "inputs: {} ({} dropped as copies: {})",
        id.inputs.join(","),
        id.dropped.len(),
        id.dropped
            .iter()
            .map(|(d, c)| format!("{d} = {c}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        s,
        "final order: {}; PEM ({}): {}",
        id.order_reason,
        if o.output_error {
            "simulation focus, K = 0"
        } else {
            "prediction focus, K estimated"
        },
        id.ss
            .pem
            .as_ref()
            .map(|p| format!(
                "{} iterations, cost {:.4e} -> {:.4e} ({})",
                p.iterations, p.initial_cost, p.final_cost, p.termination
            ))
            .unwrap_or_default()
    );
    let _ = writeln!(
        s,
        "FIT % on the {} record (sim = simulation, pred = one-step prediction):",
        id.ss.evaluation.data
    );
    let _ = writeln!(
        s,
        "  {:<20} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8}",
        "output", "seed ARX", "ARX sim", "ARX pred", "seed SS", "SS sim", "SS pred"
    );
    let (af, sf) = (
        &id.arx.evaluation.fit_percent,
        &id.ss.evaluation.fit_percent,
    );
    for (k, name) in id.outputs.iter().enumerate() {
        let seed = |r: usize| {
            refs.get(r)
                .and_then(|r| r.values.get(k))
                .map_or("-".to_string(), |v| format!("{v:.0}"))
        };
        let _ = writeln!(
            s,
            "  {:<20} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8}",
            name,
            seed(0),
            pct(&af.simulation[k]),
            pct(&af.prediction[k]),
            seed(1),
            pct(&sf.simulation[k]),
            pct(&sf.prediction[k])
        );
    }
    s
}

#[derive(Serialize)]
struct WalkDataJson<'a> {
    estimation: String,
    validation: Option<String>,
    inputs: &'a [String],
    dropped_inputs: &'a [(String, String)],
    outputs: &'a [String],
    offsets: Option<OffsetsJson>,
}

#[derive(Serialize)]
struct WalkArxJson<'a> {
    orders: ArxOrders,
    #[serde(flatten)]
    model: ArxModelJson,
    #[serde(flatten)]
    evaluation: EvaluationJson<'a>,
}

#[derive(Serialize)]
struct WalkStateSpaceJson<'a> {
    order: usize,
    order_reason: &'a str,
    focus: &'static str,
    weight: &'static str,
    #[serde(flatten)]
    model: StateSpaceModelJson,
    spectral_radius: Option<f64>,
    #[serde(flatten)]
    evaluation: EvaluationJson<'a>,
    stages: &'a [Stage],
    pem: &'a Option<PemSummary>,
    warnings: &'a [String],
}

#[derive(Serialize)]
struct SeedFitJson {
    initial: Option<Vec<f64>>,
    #[serde(rename = "final")]
    final_: Option<Vec<f64>>,
}

#[derive(Serialize)]
struct WalkJson<'a> {
    kind: &'static str,
    data: WalkDataJson<'a>,
    arx: WalkArxJson<'a>,
    state_space: WalkStateSpaceJson<'a>,
    seed_fit_percent: SeedFitJson,
}

fn walk_json<'a>(
    a: &WalkIdArgs,
    o: &WalkIdOptions,
    id: &'a WalkIdentification,
    refs: &[ReferenceFit],
) -> WalkJson<'a> {
    WalkJson {
        kind: "seed003_walk_identification",
        data: WalkDataJson {
            estimation: a.data.display().to_string(),
            validation: a.val.as_ref().map(|p| p.display().to_string()),
            inputs: &id.inputs,
            dropped_inputs: &id.dropped,
            outputs: &id.outputs,
            offsets: OffsetsJson::new(id.offsets.as_ref()),
        },
        arx: WalkArxJson {
            orders: o.arx,
            model: ArxModelJson::new(&id.arx),
            evaluation: EvaluationJson::new(
                &id.arx.evaluation,
                &id.arx.estimation_fit,
                id.arx.estimation_prediction_cost,
            ),
        },
        state_space: WalkStateSpaceJson {
            order: id.order,
            order_reason: &id.order_reason,
            focus: if o.output_error {
                "simulation"
            } else {
                "prediction"
            },
            weight: match a.weight {
                WalkWeightArg::Identity => "identity",
                WalkWeightArg::Noise => "inverse_noise",
            },
            model: StateSpaceModelJson::new(&id.ss.model),
            spectral_radius: id.ss.model.spectral_radius(),
            evaluation: EvaluationJson::new(
                &id.ss.evaluation,
                &id.ss.estimation_fit,
                id.ss.estimation_prediction_cost,
            ),
            stages: &id.ss.stages,
            pem: &id.ss.pem,
            warnings: &id.ss.warnings,
        },
        seed_fit_percent: SeedFitJson {
            initial: refs.first().map(|r| r.values.clone()),
            final_: refs.get(1).map(|r| r.values.clone()),
        },
    }
}
