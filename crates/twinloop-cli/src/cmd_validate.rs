//! `twinloop validate residual`: the inverse-dynamics residual of the base on a
//! measured motion (seed 004, section 3.4); `twinloop validate lean`: a robot's lean
//! against a simulated one (seed 001, Figs 10-11).

use crate::common::hinges_only;
use crate::common::{JSON_HELP, emit, load_model, num, read_table};
use crate::error::{CliError, CliResult, Outcome};
use crate::residual_text::residual_table;
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use twinloop_dynamics::{BaseKind, Model};
use twinloop_experiments::lean::LeanRecord;
use twinloop_experiments::lean_validation::{
    LeanComparison, align_and_compare, read_lean_record, resample_at,
};
use twinloop_ident::IdentError;
use twinloop_ident::html::residual_sections;
use twinloop_ident::validate::{
    Motion, PLATE_COLUMNS, PlateSample, ResidualSeries, ResidualSummary, Smoothing,
    check_paired_times, parse_motion, read_plate, residual_wrench,
};
use twinloop_io::CsvWriter;
use twinloop_report::{Plot, Report, SeriesStyle};

#[derive(Subcommand, Debug)]
pub enum ValidateCommand {
    /// Residual base wrench by inverse dynamics (seed 004, section 3.4, Table 1)
    ///
    /// For a motion (configuration over time) and the force plate's ground reaction,
    /// computes the 6-D wrench at the floating base that the model cannot explain:
    /// inverse dynamics' base wrench minus the ground reaction, about the base origin,
    /// in world-aligned axes. Velocities and accelerations come from the configuration
    /// by a zero-phase Butterworth low-pass (--cutoff 10 Hz, as in the seed) and central
    /// differences. A perfect model leaves only the differentiation error; a model
    /// 10 kg too light leaves about 98 N in Fz.
    ///
    /// Example:
    ///   twinloop validate residual --robot adapted.urdf --motion squat.csv --out res.csv
    ///   twinloop validate residual --robot prior.urdf --compare adapted.urdf \
    ///       --motion traj.csv --plate squat.csv --out res.csv --report fig6.html
    ///
    /// Output: RES.csv with `t` and `res.fx res.fy res.fz` (N), `res.tx res.ty res.tz`
    /// (N m) per frame (with --compare, `cmp.*` for the second model), and on stdout
    /// the mean and standard deviation of |Fx| .. |Tz| (the seed's Table 1).
    #[command(verbatim_doc_comment)]
    Residual(ResidualArgs),
    /// A robot's lean against a simulated one: torque and angle RMS per joint (seed 001, Figs 10-11)
    ///
    /// Reads two runs of `twinloop experiment lean` (the robot's over its bus, the
    /// model's in the simulator; any CSV with `t` and `tau:<joint>` columns, `q:<joint>`
    /// and `goal:<joint>` optional), puts them on one time axis (both count from the
    /// start of the lean; the simulation is shifted by up to --max-shift s to match the
    /// measured, else the commanded, angles), interpolates the denser run linearly at
    /// the sparser run's samples over the span both cover, and gives per joint the
    /// RMS, mean and largest torque difference
    /// (robot minus simulation) and the RMS angle difference. Both runs must record the
    /// same joints and follow the same lean (give the simulated one the robot's
    /// --amplitude, --ramp and --hold).
    ///
    /// Example:
    ///   twinloop validate lean --robot-run robot.csv --sim-run sim.csv --json - --report lean.html
    ///
    /// Output: stdout a table per joint; --json FILE (- for stdout): shift_s, samples,
    /// t_start, t_end and per joint torque_rms, torque_mean, torque_max_abs, torque_rms_robot (N m)
    /// and angle_rms (rad); --report FILE.html: the table and, per joint, both runs'
    /// torque over time (the seed's Figs 10-11) and the ankle angles; with --robot,
    /// OUT_3d.html beside it: the lean in 3D, the simulation as a ghost.
    #[command(verbatim_doc_comment)]
    Lean(LeanArgs),
}

#[derive(Args, Debug)]
pub struct LeanArgs {
    /// The robot's lean (CSV of `experiment lean --port`).
    #[arg(long, value_name = "ROBOT.csv")]
    pub robot_run: PathBuf,
    /// The simulated lean (CSV of `experiment lean --robot`).
    #[arg(long, value_name = "SIM.csv")]
    pub sim_run: PathBuf,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// HTML report with a plot per joint.
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
    /// The robot both runs lean (a URDF or MJCF file, or builtin:NAME): with
    /// --report, the lean in 3D beside it (OUT_3d.html: the robot's run, the
    /// simulation as a ghost).
    #[arg(long, value_name = "ROBOT", requires = "report")]
    pub robot: Option<String>,
    /// Also write the result as one MCAP (docs/logs.md): the robot's torques and
    /// angles at its samples and the simulation's at the same times.
    #[arg(long, value_name = "RESULT.mcap")]
    pub mcap: Option<PathBuf>,
    /// Largest clock offset between the runs to look for, s (0: align on `t` as it is).
    #[arg(long, default_value_t = 0.5, value_name = "S", value_parser = crate::common::non_negative)]
    pub max_shift: f64,
}

#[derive(Args, Debug)]
pub struct ResidualArgs {
    /// Robot description to validate: a URDF or MJCF file, or builtin:NAME.
    #[arg(long, value_name = "ROBOT")]
    pub robot: String,
    /// A second description to compare with (e.g. the adapted one).
    #[arg(long, value_name = "ROBOT")]
    pub compare: Option<String>,
    /// Motion: t and q:* columns (plate columns too, unless --plate).
    #[arg(long, value_name = "TRAJ.csv")]
    pub motion: PathBuf,
    /// Plate readings (grf.fx grf.fy grf.fz cop.x cop.y grf.tz), one row per motion frame.
    #[arg(long, value_name = "PLATE.csv")]
    pub plate: Option<PathBuf>,
    /// Output CSV.
    #[arg(long, value_name = "RES.csv")]
    pub out: PathBuf,
    /// Low-pass cut-off, Hz.
    #[arg(long, default_value_t = 10.0, value_name = "HZ", value_parser = crate::common::positive)]
    pub cutoff: f64,
    /// Butterworth order (applied forwards and backwards).
    #[arg(long, default_value_t = 4, value_parser = crate::bounds::count)]
    pub filter_order: usize,
    /// Differentiate without smoothing (exact, noise-free data).
    #[arg(long)]
    pub no_smoothing: bool,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// HTML report (the seed's Fig. 6) to write, and beside it OUT_3d.html: the motion in 3D.
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
    /// Also write the result as one MCAP (docs/logs.md): the motion, the plate's
    /// readings and what each model says the plate should read.
    #[arg(long, value_name = "RESULT.mcap")]
    pub mcap: Option<PathBuf>,
}

pub fn run(cmd: ValidateCommand) -> CliResult {
    match cmd {
        ValidateCommand::Residual(a) => residual(&a),
        ValidateCommand::Lean(a) => lean(&a),
    }
}

fn lean(a: &LeanArgs) -> CliResult {
    let robot = read_lean_record(&read_table(&a.robot_run)?)?;
    let sim = read_lean_record(&read_table(&a.sim_run)?)?;
    let (rn, sn) = (
        a.robot_run.display().to_string(),
        a.sim_run.display().to_string(),
    );
    let c = align_and_compare(&robot, &sim, &rn, &sn, a.max_shift)?;
    let mut text = format!(
        "lean: {rn} (robot) against {sn} (simulation), {} samples over {:.2} .. {:.2} s, \
         simulation shifted by {:+.3} s\n\
         joint           torque rms   mean diff    max |diff|   robot rms    angle rms\n\
         \x20                    N m         N m          N m          N m          deg\n",
        c.samples, c.t_start, c.t_end, c.shift_s
    );
    for j in &c.joints {
        text.push_str(&format!(
            "{:<14} {:>11.4} {:>+11.4} {:>12.4} {:>12.4} {:>12}\n",
            j.joint,
            j.torque_rms,
            j.torque_mean,
            j.torque_max_abs,
            j.torque_rms_robot,
            j.angle_rms
                .map(|r| format!("{:.3}", r.to_degrees()))
                .unwrap_or_else(|| "-".into())
        ));
    }
    if let Some(p) = &a.mcap {
        write_lean_mcap(p, a, &robot, &sim, c.shift_s)?;
    }
    if let Some(p) = &a.report {
        let mut page = lean_report(&c, &robot, &sim, &rn, &sn);
        if let Some(spec) = &a.robot {
            crate::replay3d::motion_replay(
                p,
                spec,
                &[a.robot_run.clone(), a.sim_run.clone()],
                "The lean in 3D: the robot's run (solid) and the simulation's (blue ghost), each \
                 on its own clock (the ghost's offset slider lines them up; the comparison above \
                 shifted the simulation by the amount it names). Both stand where they started: \
                 the runs record the joints, not the base.",
                &mut page,
            );
        }
        page.write(p)?;
    }
    emit(&text, a.json.as_ref(), &c)?;
    Ok(Outcome::Ok)
}

/// `--mcap`: at each of the robot's samples the simulation covers, the robot's
/// torques and angles (`tau.<joint>`, `q.<joint>`: `/measured`) and the
/// simulation's, shifted and interpolated as the comparison does (`model.` + the
/// names: `/model`).
fn write_lean_mcap(
    path: &Path,
    a: &LeanArgs,
    robot: &LeanRecord,
    sim: &LeanRecord,
    shift: f64,
) -> Result<(), CliError> {
    let (rows, at) = resample_at(sim, shift, &robot.t);
    // Joint k of the robot is joint ks of the simulation (checked the same set).
    let ks: Vec<usize> = robot
        .joints
        .iter()
        .map(|j| sim.joints.iter().position(|s| s == j).unwrap_or(0))
        .collect();
    let angles: Vec<usize> = (0..robot.joints.len())
        .filter(|&k| !robot.q[k].is_empty() && !at.q[ks[k]].is_empty())
        .collect();
    let mut measured: Vec<String> = robot.joints.iter().map(|j| format!("tau.{j}")).collect();
    measured.extend(angles.iter().map(|&k| format!("q.{}", robot.joints[k])));
    let model: Vec<String> = measured.iter().map(|c| format!("model.{c}")).collect();
    let columns = [vec!["t".to_string()], measured.clone(), model.clone()].concat();
    let mut table = twinloop_io::Table::new(columns);
    for (r, i) in rows.enumerate() {
        let mut row = vec![robot.t[i]];
        row.extend(robot.tau.iter().map(|y| y[i]));
        row.extend(angles.iter().map(|&k| robot.q[k][i]));
        row.extend(ks.iter().map(|&k| at.tau[k][r]));
        row.extend(angles.iter().map(|&k| at.q[ks[k]][r]));
        table.rows.push(row);
    }
    let result = crate::result_mcap::ResultLog {
        table,
        measured,
        predicted: vec![twinloop_logs::ArrayTopic {
            topic: "/model".into(),
            columns: model,
        }],
        robot: None,
        robot_file: "model.urdf",
        inputs: vec![
            a.robot_run.display().to_string(),
            a.sim_run.display().to_string(),
        ],
        files: Vec::new(),
        parts: Vec::new(),
    };
    crate::result_mcap::write(path, "validate lean", &result)
}

/// The report: the table, then per joint both runs' torque over time and the angles.
fn lean_report(
    c: &LeanComparison,
    robot: &LeanRecord,
    sim: &LeanRecord,
    robot_name: &str,
    sim_name: &str,
) -> Report {
    let mut r = Report::new("Lean validation (seed 001, section F)");
    r.paragraph(format!(
        "Robot: {robot_name}. Simulation: {sim_name}, shifted by {} s. {} samples of the \
         sparser run over {} .. {} s; differences are robot minus simulation.",
        num(c.shift_s),
        c.samples,
        num(c.t_start),
        num(c.t_end)
    ));
    let rows = c
        .joints
        .iter()
        .map(|j| {
            vec![
                j.joint.clone(),
                num(j.torque_rms),
                num(j.torque_mean),
                num(j.torque_max_abs),
                num(j.torque_rms_robot),
                j.angle_rms.map(|x| num(x.to_degrees())).unwrap_or_default(),
            ]
        })
        .collect();
    r.table(
        [
            "joint",
            "torque RMS (N m)",
            "mean diff (N m)",
            "max |diff| (N m)",
            "robot RMS (N m)",
            "angle RMS (deg)",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    );
    let sim_t: Vec<f64> = sim.t.iter().map(|t| t + c.shift_s).collect();
    for (k, name) in robot.joints.iter().enumerate() {
        let ks = sim.joints.iter().position(|j| j == name).unwrap_or(k);
        r.subheading(name.clone());
        r.plot(
            &Plot::new(format!("{name}: torque"), "t (s)", "torque (N m)")
                .line("simulation", &sim_t, &sim.tau[ks])
                .series("robot", &robot.t, &robot.tau[k], SeriesStyle::Points),
        );
        if !robot.q[k].is_empty() && !sim.q[ks].is_empty() {
            let deg = |v: &[f64]| v.iter().map(|x| x.to_degrees()).collect::<Vec<_>>();
            r.plot(
                &Plot::new(format!("{name}: angle"), "t (s)", "angle (deg)")
                    .line("simulation", &sim_t, &deg(&sim.q[ks]))
                    .series("robot", &robot.t, &deg(&robot.q[k]), SeriesStyle::Points),
            );
        }
    }
    r
}

fn residual(a: &ResidualArgs) -> CliResult {
    let (robot, model) = load_model(&a.robot, BaseKind::Floating)?;
    hinges_only(&robot, &a.robot, "validation")?;
    let motion = read_motion_and_plate(a, &model)?;
    let smoothing = (!a.no_smoothing).then_some(Smoothing {
        cutoff_hz: a.cutoff,
        order: a.filter_order,
    });
    let file = a.plate.as_ref().unwrap_or(&a.motion);
    let res = residual_wrench(&model, &motion, smoothing).map_err(|e| e.in_file(file))?;
    let cmp = match &a.compare {
        Some(c) => {
            let (r2, m2) = load_model(c, BaseKind::Floating)?;
            hinges_only(&r2, c, "validation")?;
            Some(residual_wrench(&m2, &motion, smoothing).map_err(|e| e.in_file(file))?)
        }
        None => None,
    };
    write_residuals(&a.out, &res, cmp.as_ref())?;
    if let Some(p) = &a.mcap {
        write_residual_mcap(p, a, &robot, &model, &motion, &res, cmp.as_ref())?;
    }
    let label0 = label(&a.robot);
    let label1 = a.compare.as_deref().map(label).unwrap_or_default();
    let mut runs = vec![(label0.as_str(), &res)];
    if let Some(c) = &cmp {
        runs.push((label1.as_str(), c));
    }
    if let Some(p) = &a.report {
        let mut r = Report::new(format!("Residual base wrench of {}", model.name));
        residual_sections(&mut r, &runs);
        crate::replay3d::motion_replay(
            p,
            &a.robot,
            std::slice::from_ref(&a.motion),
            "The motion in 3D, with the CoM, the support polygon and, when the motion file \
             has the plate's columns, the centre of pressure and the ground reaction.",
            &mut r,
        );
        r.write(p)?;
    }
    let rows: Vec<(&str, &ResidualSummary)> = runs.iter().map(|(n, r)| (*n, &r.summary)).collect();
    let json = serde_json::json!({
        "schema": "twinloop-residual/1",
        "motion": a.motion.display().to_string(),
        "smoothing": smoothing.map(|s| serde_json::json!({"cutoff_hz": s.cutoff_hz, "order": s.order})),
        "models": rows.iter().map(|(n, s)| serde_json::json!({"model": n, "summary": s})).collect::<Vec<_>>(),
    });
    let text = format!(
        "residual base wrench over {} frames written to {} (world axes at the base origin)\n\
         mean [std] of the absolute values (seed 004, Table 1):\n{}",
        res.t.len(),
        a.out.display(),
        residual_table(&rows)
    );
    emit(&text, a.json.as_ref(), &json)?;
    Ok(Outcome::Ok)
}

/// The file name a model is shown by (builtin:NAME as it is).
fn label(spec: &str) -> String {
    if spec.starts_with("builtin:") {
        return spec.to_string();
    }
    Path::new(spec)
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default()
}

/// The motion, with the plate readings of --plate when given.
fn read_motion_and_plate(a: &ResidualArgs, model: &Model) -> Result<Motion, CliError> {
    let table = crate::units::read_trajectory(&a.motion, model)?;
    let mut motion = parse_motion(&table, model).map_err(|e| {
        if e.file.is_none() {
            e.in_file(&a.motion)
        } else {
            e
        }
    })?;
    if let Some(p) = &a.plate {
        let table = read_table(p)?;
        check_paired_times(&motion.t, &table).map_err(|e| e.in_file(p).option("--plate"))?;
        motion.plate = read_plate(&table).map_err(|e| e.in_file(p))?;
        if motion.plate.is_none() {
            return Err(IdentError::new(
                "no plate columns (grf.fx grf.fy grf.fz cop.x cop.y grf.tz)",
            )
            .in_file(p)
            .into());
        }
    }
    Ok(motion)
}

/// `--mcap`: per frame the configuration (`/joint_states`, `/tf`), the plate's
/// readings as measured and as each model predicts them: its inverse dynamics'
/// base wrench, the ground reaction the motion needs (`/model`, `/compare`).
fn write_residual_mcap(
    path: &Path,
    a: &ResidualArgs,
    robot: &twinloop_description::Description,
    model: &Model,
    motion: &Motion,
    res: &ResidualSeries,
    cmp: Option<&ResidualSeries>,
) -> Result<(), CliError> {
    let plate = motion.plate.as_deref().unwrap_or_default();
    let named = |p: &str| {
        PLATE_COLUMNS
            .iter()
            .map(|c| format!("{p}{c}"))
            .collect::<Vec<_>>()
    };
    let q_columns = twinloop_io::Quantity::Q.column_names(&model.q_names());
    let (measured, by_model, by_compare) = (named(""), named("model."), named("compare."));
    let mut columns = [
        vec!["t".to_string()],
        q_columns,
        measured.clone(),
        by_model.clone(),
    ]
    .concat();
    if cmp.is_some() {
        columns.extend(by_compare.iter().cloned());
    }
    let readings = |p: &PlateSample| {
        [
            p.force[0],
            p.force[1],
            p.force[2],
            p.cop[0],
            p.cop[1],
            p.free_moment,
        ]
    };
    let mut table = twinloop_io::Table::new(columns);
    // residual_wrench checked one plate reading per frame.
    for (k, reading) in plate.iter().enumerate() {
        let mut row = vec![motion.t[k]];
        row.extend_from_slice(&motion.q[k]);
        row.extend(readings(reading));
        row.extend(readings(&res.predicted[k]));
        if let Some(c) = cmp {
            row.extend(readings(&c.predicted[k]));
        }
        table.rows.push(row);
    }
    let topic = |t: &str, columns: Vec<String>| twinloop_logs::ArrayTopic {
        topic: t.into(),
        columns,
    };
    let mut predicted = vec![topic("/model", by_model)];
    if cmp.is_some() {
        predicted.push(topic("/compare", by_compare));
    }
    let inputs = [Some(a.robot.clone()), a.compare.clone()]
        .into_iter()
        .flatten()
        .chain(
            [&Some(a.motion.clone()), &a.plate]
                .into_iter()
                .flatten()
                .map(|p| p.display().to_string()),
        )
        .collect();
    let result = crate::result_mcap::ResultLog {
        table,
        measured,
        predicted,
        robot: Some(robot),
        robot_file: "model.urdf",
        inputs,
        files: Vec::new(),
        parts: Vec::new(),
    };
    crate::result_mcap::write(path, "validate residual", &result)
}

/// `t`, `res.*` and, with a second model, `cmp.*` per frame.
fn write_residuals(
    out: &Path,
    res: &ResidualSeries,
    cmp: Option<&ResidualSeries>,
) -> Result<(), CliError> {
    let names = ["fx", "fy", "fz", "tx", "ty", "tz"];
    let mut cols = vec!["t".to_string()];
    cols.extend(names.iter().map(|n| format!("res.{n}")));
    if cmp.is_some() {
        cols.extend(names.iter().map(|n| format!("cmp.{n}")));
    }
    let mut w = CsvWriter::create(out, &cols)?;
    let mut row = Vec::with_capacity(cols.len());
    for k in 0..res.t.len() {
        row.clear();
        row.push(res.t[k]);
        row.extend_from_slice(&res.wrench[k]);
        if let Some(c) = cmp {
            row.extend_from_slice(&c.wrench[k]);
        }
        w.write_row(&row)?;
    }
    Ok(w.finish()?)
}
