//! `twinloop dynamics kinematics|inverse|forward`: batch rigid-body dynamics over a
//! trajectory file. One output row per input row; the `t` column is carried over.

use crate::common::{ROBOT_HELP, load_model};
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use crate::units::read_trajectory;
use clap::{Args, Subcommand};
use std::path::PathBuf;
use twinloop_dynamics::{BaseKind, Data, Model};
use twinloop_io::{CsvWriter, IoError, Quantity, StateColumns, Table};

#[derive(Subcommand, Debug)]
pub enum DynamicsCommand {
    /// Forward kinematics over a trajectory: CoM and frame poses per row
    ///
    /// Reads the q: columns of each row and writes com.x, com.y, com.z and, for each
    /// frame (every link by default), pose:<frame>.x .y .z .qx .qy .qz .qw in the world.
    ///
    /// Example:
    ///   twinloop dynamics kinematics --robot robot.urdf --trajectory walk.csv --out poses.csv
    ///
    /// Output: OUT.csv, one row per input row (t carried over); exit code 2 names the
    /// file, row and column of bad input.
    #[command(verbatim_doc_comment)]
    Kinematics(KinematicsArgs),
    /// Inverse dynamics (RNEA) over a trajectory: the torques that produce it
    ///
    /// Reads q:, v: and a: columns and writes tau:<joint> per joint and, for a floating
    /// base, tau:base.fx .. tau:base.tz: the wrench the base would need (base frame).
    ///
    /// Example:
    ///   twinloop dynamics inverse --robot robot.urdf --trajectory squat.csv --out tau.csv
    ///
    /// Output: OUT.csv. For a robot moving freely under gravity the base wrench should
    /// be zero; what is left is what the model cannot explain.
    #[command(verbatim_doc_comment)]
    Inverse(BatchArgs),
    /// Forward dynamics (ABA) over a trajectory: the accelerations torques produce
    ///
    /// Reads q:, v: and tau: columns (tau:base.* is an external wrench on the base,
    /// usually zero).
    ///
    /// Example:
    ///   twinloop dynamics forward --robot robot.urdf --trajectory cmd.csv --out acc.csv
    ///
    /// Output: OUT.csv with a:<joint> and a:base.vx .. a:base.wz per row.
    #[command(verbatim_doc_comment)]
    Forward(BatchArgs),
}

#[derive(Args, Debug)]
pub struct BatchArgs {
    #[arg(long, value_name = "ROBOT", help = ROBOT_HELP)]
    pub robot: String,
    /// Input trajectory CSV (header row; columns named as in the README).
    #[arg(long, value_name = "IN.csv")]
    pub trajectory: PathBuf,
    /// Output CSV.
    #[arg(long, value_name = "OUT.csv")]
    pub out: PathBuf,
    /// Weld the root link to the world instead of adding a floating base
    /// (then no `base.*` columns are read or written). As in Pinocchio, the fixed-base
    /// model has no body for the root link: its mass is left out of `com.*` (5-7 cm off
    /// on km20 and OP3). For the whole robot's CoM with the root where --fixed-base puts
    /// it, leave --fixed-base off and add the columns q:base.x,q:base.y,q:base.z = 0,
    /// q:base.qx,q:base.qy,q:base.qz = 0, q:base.qw = 1.
    #[arg(long)]
    pub fixed_base: bool,
}

#[derive(Args, Debug)]
pub struct KinematicsArgs {
    #[command(flatten)]
    pub batch: BatchArgs,
    /// Frames to report, comma-separated (default: every link).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub frames: Vec<String>,
}

pub fn run(cmd: DynamicsCommand) -> CliResult {
    match cmd {
        DynamicsCommand::Kinematics(a) => kinematics(&a),
        DynamicsCommand::Inverse(a) => per_row(&a, Quantity::A, Quantity::Tau, |m, d, q, v, x| {
            Ok(twinloop_dynamics::rnea(m, d, q, v, x))
        }),
        DynamicsCommand::Forward(a) => per_row(&a, Quantity::Tau, Quantity::A, |m, d, q, v, x| {
            // A singular mass matrix is refused naming the joint, not written as NaN.
            twinloop_dynamics::try_aba(m, d, q, v, x)
        }),
    }?;
    Ok(Outcome::Ok)
}

fn base_kind(fixed: bool) -> BaseKind {
    if fixed {
        BaseKind::Fixed
    } else {
        BaseKind::Floating
    }
}

fn with_time(table: &Table, names: Vec<String>) -> Result<(Option<usize>, Vec<String>), IoError> {
    let t = table.column_index("t");
    // The time is copied to the output: a NaN there is as wrong as one in q.
    table.check_finite(t.as_slice())?;
    let mut cols = Vec::with_capacity(names.len() + 1);
    if t.is_some() {
        cols.push("t".to_string());
    }
    cols.extend(names);
    Ok((t, cols))
}

/// Quaternions must be unit for the dynamics to mean anything: say which row is not.
fn check_quaternion(model: &Model, table: &Table, row: usize, q: &[f64]) -> Result<(), IoError> {
    if model.is_floating() {
        let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
        if (n - 1.0).abs() > 1e-6 {
            return Err(table.row_error(row, format!("base quaternion has norm {n}, not 1")));
        }
    }
    for i in 0..model.nbodies {
        if model.joint_types[i] == twinloop_dynamics::JointType::Spherical {
            let iq = model.idx_q[i];
            let n = q[iq..iq + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
            if (n - 1.0).abs() > 1e-6 {
                let joint = &model.joint_names[i];
                return Err(table.row_error(
                    row,
                    format!(
                        "ball joint {joint}'s quaternion (q:{joint}.qx .. .qw) has norm {n}, not 1"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Which frames `kinematics` reports: the named ones, or every link.
fn report_frames(model: &Model, a: &KinematicsArgs) -> Result<Vec<usize>, CliError> {
    if a.frames.is_empty() {
        return Ok((0..model.frames.len())
            .filter(|&k| model.frames[k].link.is_some())
            .collect());
    }
    a.frames
        .iter()
        .map(|n| {
            model.frame_index(n).ok_or_else(|| {
                CliError::new(format!(
                    "--frames: {}: no frame named \"{n}\"",
                    a.batch.robot
                ))
            })
        })
        .collect()
}

fn kinematics(args: &KinematicsArgs) -> Result<(), CliError> {
    let a = &args.batch;
    let (_, model) = load_model(&a.robot, base_kind(a.fixed_base))?;
    let table = read_trajectory(&a.trajectory, &model)?;
    let qc = StateColumns::find(&table, Quantity::Q, &model.q_names())?;
    let frames = report_frames(&model, args)?;
    let mut names = vec!["com.x".into(), "com.y".into(), "com.z".into()];
    for &k in &frames {
        let n = &model.frames[k].name;
        for s in ["x", "y", "z", "qx", "qy", "qz", "qw"] {
            names.push(format!("pose:{n}.{s}"));
        }
    }
    let (tcol, cols) = with_time(&table, names)?;
    let mut w = CsvWriter::create(&a.out, &cols)?;
    let mut data = Data::new(&model);
    let mut q = vec![0.0; model.nq];
    let mut row = Vec::with_capacity(cols.len());
    let bar = progress::rows(table.rows.len());
    for (r, input) in table.rows.iter().enumerate() {
        qc.gather(input, &mut q);
        check_quaternion(&model, &table, r, &q)?;
        row.clear();
        if let Some(t) = tcol {
            row.push(input[t]);
        }
        let com = twinloop_dynamics::center_of_mass(&model, &mut data, &q);
        row.extend(com.iter());
        twinloop_dynamics::update_frame_placements(&model, &mut data);
        for &k in &frames {
            let x = data.o_m_f[k];
            row.extend(x.translation.iter());
            row.extend(twinloop_spatial::matrix_to_quaternion_xyzw(&x.rotation));
        }
        w.write_row(&row)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    w.finish()?;
    eprintln!(
        "wrote {}: {} rows of the centre of mass{}",
        a.out.display(),
        table.rows.len(),
        if frames.is_empty() {
            String::new()
        } else {
            format!(" and {} frame pose(s)", frames.len())
        }
    );
    Ok(())
}

/// Read q, v and one more quantity from each row, write what `f` computes from them.
fn per_row(
    a: &BatchArgs,
    input: Quantity,
    output: Quantity,
    mut f: impl for<'d> FnMut(
        &Model,
        &'d mut Data,
        &[f64],
        &[f64],
        &[f64],
    )
        -> Result<&'d nalgebra::DVector<f64>, twinloop_dynamics::SingularJoint>,
) -> Result<(), CliError> {
    let (_, model) = load_model(&a.robot, base_kind(a.fixed_base))?;
    let table = read_trajectory(&a.trajectory, &model)?;
    let find = |qty| crate::common::state_columns(&table, &model, qty);
    let (qc, vc, xc) = (find(Quantity::Q)?, find(Quantity::V)?, find(input)?);
    let (tcol, cols) = with_time(
        &table,
        output.column_names(&crate::common::coordinate_names(&model, output)),
    )?;
    let mut w = CsvWriter::create(&a.out, &cols)?;
    let mut data = Data::new(&model);
    let (mut q, mut v, mut x) = (
        vec![0.0; model.nq],
        vec![0.0; model.nv],
        vec![0.0; model.nv],
    );
    let mut row = Vec::with_capacity(cols.len());
    let bar = progress::rows(table.rows.len());
    for (r, values) in table.rows.iter().enumerate() {
        qc.gather(values, &mut q);
        vc.gather(values, &mut v);
        xc.gather(values, &mut x);
        check_quaternion(&model, &table, r, &q)?;
        row.clear();
        if let Some(t) = tcol {
            row.push(values[t]);
        }
        let out = f(&model, &mut data, &q, &v, &x)
            .map_err(|e| table.row_error(r, format!("{}: {e}", a.robot)))?;
        row.extend(out.iter());
        w.write_row(&row)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    w.finish()?;
    eprintln!(
        "wrote {}: {} rows of {} {} column(s)",
        a.out.display(),
        table.rows.len(),
        cols.len() - usize::from(tcol.is_some()),
        output.prefix()
    );
    Ok(())
}
