//! `twinloop identify static`: link masses and CoMs from static poses on a force
//! plate (seed 004, eq 8-9).

use crate::common::hinges_only;
use crate::common::{JSON_HELP, emit, load_model};
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use crate::residual_text::residual_table;
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::Instant;
use twinloop_description::Description;
use twinloop_dynamics::{BaseKind, Data, Model, ground_projected_com};
use twinloop_ident::html::{residual_sections, static_sections};
use twinloop_ident::static_ident::{
    StaticProblem, StaticWorkspace, Suggestion, assemble, candidate_poses, solve, suggest_poses,
};
use twinloop_ident::validate::{ResidualSeries, Smoothing, parse_motion, residual_wrench};
use twinloop_ident::{
    StaticOptions, StaticPose, StaticResult, adapted_robot, identify_static, parse_static_poses,
};
use twinloop_io::{CsvWriter, Quantity};
use twinloop_report::Report;

#[derive(Args, Debug)]
pub struct IdentifyStaticArgs {
    /// The prior description (CAD model): starting point and regulariser. A URDF or
    /// MJCF file, or builtin:NAME.
    #[arg(long, value_name = "ROBOT")]
    pub robot: String,
    /// Static poses: configuration and measured CoP per row.
    #[arg(long, value_name = "poses.csv")]
    pub poses: PathBuf,
    /// The robot's mass on a scale, kg (seed 004, eq 9).
    #[arg(long, value_name = "KG", value_parser = crate::common::positive)]
    pub total_mass: f64,
    /// Links to identify, comma-separated (default: every link with mass).
    #[arg(long, value_delimiter = ',', value_name = "LINKS")]
    pub links: Vec<String>,
    /// CoP noise per axis the regulariser assumes, m (0: exact data, prior only where
    /// the data see nothing).
    #[arg(long, default_value_t = 0.001, value_name = "M", value_parser = crate::common::non_negative)]
    pub cop_sigma: f64,
    /// How far a CoM may leave its link's geometry box, m.
    #[arg(long, default_value_t = 0.03, value_name = "M", value_parser = crate::common::non_negative)]
    pub com_margin: f64,
    /// The adapted description to write (URDF).
    #[arg(long, value_name = "ADAPTED.urdf")]
    pub out: Option<PathBuf>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// One MCAP of the result: per pose (one a second) the configuration, the
    /// measured CoP (cop.x cop.y) and the prior's and adapted model's CoM over the
    /// ground (prior.cop.*, adapted.cop.*), the adapted URDF attached, the provenance.
    #[arg(long, value_name = "RESULT.mcap")]
    pub mcap: Option<PathBuf>,
    /// HTML report to write.
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
    /// A validation motion with plate columns (from `experiment squat` or a
    /// recording): the residual base wrench of prior and adapted models is reported.
    #[arg(long, value_name = "MOTION.csv")]
    pub squat: Option<PathBuf>,
    /// How many further poses to suggest (from the virtual force plate on the prior).
    #[arg(long, default_value_t = 5)]
    pub suggest: usize,
    /// Where to write the suggested poses (category and configuration, no CoP).
    #[arg(long, value_name = "SUGGESTED.csv")]
    pub suggest_out: Option<PathBuf>,
    /// Repeat the fit (regressor and constrained solve) N times and print the median time.
    #[arg(long, value_name = "N")]
    pub time: Option<usize>,
    /// Seed of the candidate poses the suggestions are drawn from.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
}

fn mm(x: f64) -> String {
    format!("{:.3}", x * 1e3)
}

/// The prior and adapted models' residuals on the --squat motion.
type Validation = (ResidualSeries, ResidualSeries);

pub fn run(a: &IdentifyStaticArgs) -> CliResult {
    let (robot, model) = load_model(&a.robot, BaseKind::Floating)?;
    hinges_only(&robot, &a.robot, "static identification")?;
    crate::units::total_mass("--total-mass", a.total_mass, &robot)?;
    let table = crate::units::read_trajectory(&a.poses, &model)?;
    let poses = parse_static_poses(&table, &model).map_err(|e| {
        if e.file.is_none() {
            e.in_file(&a.poses)
        } else {
            e
        }
    })?;
    let options = StaticOptions {
        links: (!a.links.is_empty()).then(|| a.links.clone()),
        cop_sigma: a.cop_sigma,
        com_margin: a.com_margin,
        ..StaticOptions::default()
    };
    let problem = StaticProblem::new(&robot, &model, a.total_mass, &options)?;
    let result = identify_static(&robot, &model, &poses, a.total_mass, &options).map_err(|e| {
        if e.option.as_deref() == Some("poses") {
            e.in_file(&a.poses)
        } else {
            e
        }
    })?;
    let timing = a
        .time
        .map(|n| median_fit_seconds(&model, &problem, &poses, n))
        .transpose()?;
    let adapted = adapted_robot(&robot, &result);
    if let Some(p) = &a.out {
        twinloop_description::urdf::write_file(&adapted, p)?;
    }
    if let Some(p) = &a.mcap {
        write_result_mcap(p, a, &model, &adapted, &poses)?;
    }
    let suggestions = suggestions(a, &robot, &model, &problem, &poses)?;
    if let Some(p) = &a.suggest_out {
        write_suggestions(p, &model, &suggestions)?;
    }
    let validation = match &a.squat {
        Some(m) => Some(validate_on_motion(m, &model, &adapted)?),
        None => None,
    };
    let json = serde_json::json!({
        "schema": "twinloop-static-identification/1",
        "prior": a.robot,
        "poses_file": a.poses.display().to_string(),
        "cop_sigma": a.cop_sigma,
        "com_margin": a.com_margin,
        "result": &result,
        "suggested_poses": &suggestions,
        "validation": validation.as_ref().map(|(p, q)| serde_json::json!({
            "motion": a.squat.as_ref().map(|m| m.display().to_string()),
            "prior": p.summary,
            "adapted": q.summary,
        })),
        "fit_seconds_median": timing,
    });
    if let Some(p) = &a.report {
        let mut r = Report::new(format!("Static identification of {}", model.name));
        r.preformatted(format!(
            "twinloop identify static --robot {} --poses {} --total-mass {}",
            a.robot,
            a.poses.display(),
            a.total_mass
        ));
        static_sections(&mut r, &result, &suggestions);
        if let Some((p0, p1)) = &validation {
            residual_sections(&mut r, &[("prior", p0), ("adapted", p1)]);
        }
        poses_in_3d(p, a, &mut r)?;
        r.write(p)?;
    }
    let text = summary(&model, &result, &suggestions, validation.as_ref(), timing);
    emit(&text, a.json.as_ref(), &json)?;
    Ok(Outcome::Ok)
}

/// `--mcap`: each pose a second, its configuration (on `/joint_states` and `/tf`),
/// the measured CoP and where the prior and the adapted model put the CoM over the
/// ground in it: the CoP a plate sees under a robot standing still (seed 004, eq 8).
fn write_result_mcap(
    path: &Path,
    a: &IdentifyStaticArgs,
    prior: &Model,
    adapted: &Description,
    poses: &[StaticPose],
) -> Result<(), CliError> {
    let adapted_model = Model::from_description_with_base(adapted, BaseKind::Floating)?;
    let q_columns = Quantity::Q.column_names(&prior.q_names());
    let names = |p: &str| vec![format!("{p}cop.x"), format!("{p}cop.y")];
    let (measured, prior_cols, adapted_cols) = (names(""), names("prior."), names("adapted."));
    let columns = [
        vec!["t".to_string()],
        q_columns,
        measured.clone(),
        prior_cols.clone(),
        adapted_cols.clone(),
    ]
    .concat();
    let mut table = twinloop_io::Table::new(columns);
    let (mut d0, mut d1) = (Data::new(prior), Data::new(&adapted_model));
    for (k, pose) in poses.iter().enumerate() {
        let c0 = ground_projected_com(prior, &mut d0, &pose.q);
        let c1 = ground_projected_com(&adapted_model, &mut d1, &pose.q);
        let mut row = vec![k as f64];
        row.extend_from_slice(&pose.q);
        row.extend([pose.cop[0], pose.cop[1], c0.x, c0.y, c1.x, c1.y]);
        table.rows.push(row);
    }
    let result = crate::result_mcap::ResultLog {
        table,
        measured,
        predicted: crate::result_mcap::prior_and_adapted(prior_cols, adapted_cols),
        robot: Some(adapted),
        robot_file: "adapted.urdf",
        inputs: vec![a.robot.clone(), a.poses.display().to_string()],
        files: Vec::new(),
        parts: Vec::new(),
    };
    crate::result_mcap::write(path, "identify static", &result)
}

/// The poses in 3D beside the report (`OUT_3d.html`), one a second in the file's
/// order, on the prior model: a slide show to look over what the plate saw.
fn poses_in_3d(report: &Path, a: &IdentifyStaticArgs, page: &mut Report) -> Result<(), CliError> {
    let poses = crate::common::read_table(&a.poses)?;
    let mut columns = vec!["t".to_string()];
    columns.extend(poses.columns.iter().filter(|c| *c != "t").cloned());
    let keep: Vec<usize> = (0..poses.columns.len())
        .filter(|&i| poses.columns[i] != "t")
        .collect();
    let mut shown = twinloop_io::Table::new(columns);
    for (k, row) in poses.rows.iter().enumerate() {
        shown.rows.push(
            std::iter::once(k as f64)
                .chain(keep.iter().map(|&i| row[i]))
                .collect(),
        );
    }
    crate::replay3d::replay_tables(
        report,
        &a.robot,
        &[(a.poses.clone(), shown)],
        "The poses on the prior model, one a second in the file's order (t is the pose's \
         row, from 0): step through them with the timeline, with the CoM, its ground \
         projection and the support polygon drawn.",
        page,
    );
    Ok(())
}

/// Median time of the fit (regressor and constrained solve) over `n` repeats.
fn median_fit_seconds(
    model: &Model,
    problem: &StaticProblem,
    poses: &[StaticPose],
    n: usize,
) -> Result<f64, CliError> {
    let mut ws = StaticWorkspace::new(model, problem, poses.len());
    let mut samples = Vec::with_capacity(n.max(1));
    for _ in 0..n.max(1) {
        let t0 = Instant::now();
        assemble(model, problem, poses, &mut ws);
        let fit = solve(problem, &ws)?;
        std::hint::black_box(&fit.x);
        samples.push(t0.elapsed().as_secs_f64());
    }
    samples.sort_by(f64::total_cmp);
    Ok(samples[samples.len() / 2])
}

/// The --suggest poses that would help most, from the virtual force plate on the prior.
fn suggestions(
    a: &IdentifyStaticArgs,
    robot: &Description,
    model: &Model,
    problem: &StaticProblem,
    poses: &[StaticPose],
) -> Result<Vec<Suggestion>, CliError> {
    if a.suggest == 0 {
        return Ok(Vec::new());
    }
    let bar = progress::steps(1);
    bar.set_message("candidate poses for suggestions");
    let mut suggestions = Vec::new();
    match candidate_poses(robot, model, 12, a.seed) {
        Ok(cands) => {
            let mut ws = StaticWorkspace::new(model, problem, poses.len());
            assemble(model, problem, poses, &mut ws);
            let fit = solve(problem, &ws)?;
            suggestions = suggest_poses(model, problem, &fit.gram, &cands, a.suggest);
        }
        Err(e) => eprintln!("note: no pose suggestions: {e}"),
    }
    bar.finish_and_clear();
    Ok(suggestions)
}

/// The suggested poses: category and configuration, no CoP.
fn write_suggestions(
    path: &std::path::Path,
    model: &Model,
    suggestions: &[Suggestion],
) -> Result<(), CliError> {
    let mut cols = vec!["category".to_string()];
    cols.extend(Quantity::Q.column_names(&model.q_names()));
    let mut w = CsvWriter::create(path, &cols)?;
    for s in suggestions {
        let mut row = vec![s.category as i32 as f64];
        row.extend_from_slice(&s.q);
        w.write_row(&row)?;
    }
    Ok(w.finish()?)
}

/// The residual base wrench of the prior and the adapted model on a motion.
fn validate_on_motion(
    motion_file: &std::path::Path,
    model: &Model,
    adapted: &Description,
) -> Result<Validation, CliError> {
    let table = crate::units::read_trajectory(motion_file, model)?;
    let motion = parse_motion(&table, model).map_err(|e| {
        if e.file.is_none() {
            e.in_file(motion_file)
        } else {
            e
        }
    })?;
    let adapted_model = Model::from_description(adapted)?;
    let prior_res = residual_wrench(model, &motion, Some(Smoothing::default()))
        .map_err(|e| e.in_file(motion_file))?;
    let adapted_res = residual_wrench(&adapted_model, &motion, Some(Smoothing::default()))
        .map_err(|e| e.in_file(motion_file))?;
    Ok((prior_res, adapted_res))
}

/// What stdout says: the fit, its identifiability, the links, suggestions, validation.
fn summary(
    model: &Model,
    result: &StaticResult,
    suggestions: &[Suggestion],
    validation: Option<&Validation>,
    timing: Option<f64>,
) -> String {
    let id = &result.identifiability;
    let mut t = format!(
        "static identification of {} from {} poses (seed 004, eq 8-9)\n\
         total mass: measured {:.3} kg, prior {:.3} kg, {:.3} kg on {} links kept fixed\n\
         GCOM to CoP distance (mm): before mean {} std {} max {}  ->  after mean {} std {} max {}\n\
         identifiability: {} parameters, rank {}, {} above the noise ({:.2e} kg m), condition number {:.3e}\n\
         \x20 {} directions no static pose can determine (kept at the prior)\n",
        model.name,
        result.poses,
        result.total_mass,
        result.prior_total_mass,
        result.fixed_mass,
        result.fixed_links.len(),
        mm(result.before.mean),
        mm(result.before.std),
        mm(result.before.max),
        mm(result.after.mean),
        mm(result.after.std),
        mm(result.after.max),
        id.parameters,
        id.rank,
        id.well_determined,
        id.noise_level,
        id.condition_number,
        id.structural_null,
    );
    for g in &id.welded {
        t.push_str(&format!(
            "  welded to one body (only their sum is seen): {}\n",
            g.join(", ")
        ));
    }
    for g in &id.unidentifiable {
        t.push_str(&format!(
            "  not excited by these poses ({} directions): {}\n",
            g.directions,
            g.links.join(", ")
        ));
    }
    t.push_str("\nlink                              prior kg        kg   ± kg   CoM (mm, link frame)        determined m\n");
    for l in &result.links {
        t.push_str(&format!(
            "{:<32} {:>9.4} {:>9.4} {:>6.3}   {:>7.1} {:>7.1} {:>7.1}   {:>5.2}{}\n",
            l.name,
            l.prior_mass,
            l.mass,
            l.mass_std,
            l.com[0] * 1e3,
            l.com[1] * 1e3,
            l.com[2] * 1e3,
            l.mass_determined,
            if l.at_bounds.is_empty() {
                String::new()
            } else {
                format!("  at {}", l.at_bounds.join(", "))
            }
        ));
    }
    if !suggestions.is_empty() {
        t.push_str("\nposes that would help most (smallest singular value before -> after):\n");
        for (i, s) in suggestions.iter().enumerate() {
            t.push_str(&format!(
                "  {}. {:<6} {:.3e} -> {:.3e}\n",
                i + 1,
                s.category.name(),
                s.smallest_singular_value_before,
                s.smallest_singular_value_after
            ));
        }
    }
    if let Some((p0, p1)) = validation {
        t.push_str(
            "\nresidual base wrench on the motion, mean [std] of |.| (seed 004, Table 1):\n",
        );
        t.push_str(&residual_table(&[
            ("prior", &p0.summary),
            ("adapted", &p1.summary),
        ]));
    }
    if let Some(s) = timing {
        t.push_str(&format!(
            "\nfit time (regressor + constrained solve), median: {:.3} ms\n",
            s * 1e3
        ));
    }
    t
}
