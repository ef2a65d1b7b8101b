//! Batch dynamics over trajectory files: `kinematics`, `inverse-dynamics`,
//! `forward-dynamics`. One output row per input row; the `t` column is carried over.

use crate::progress;
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use twinloop_dynamics::{BaseKind, Data, Model};
use twinloop_io::{CsvWriter, IoError, Quantity, StateColumns, Table};

#[derive(Args, Debug)]
pub struct BatchArgs {
    /// Robot description (URDF, or MJCF by its <mujoco> root).
    #[arg(long, value_name = "FILE")]
    pub urdf: PathBuf,
    /// Input trajectory CSV (header row; columns named as in the README).
    #[arg(long, value_name = "IN.csv")]
    pub trajectory: PathBuf,
    /// Output CSV.
    #[arg(long, value_name = "OUT.csv")]
    pub out: PathBuf,
    /// Weld the root link to the world instead of adding a floating base
    /// (then no `base.*` columns are read or written).
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

pub fn load_model(path: &Path, fixed_base: bool) -> Result<Model, String> {
    let robot = twinloop_description::load(path).map_err(|e| e.to_string())?;
    let base = if fixed_base {
        BaseKind::Fixed
    } else {
        BaseKind::Floating
    };
    Model::from_description_with_base(&robot, base).map_err(|e| format!("{}: {e}", path.display()))
}

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {msg}");
    ExitCode::from(crate::common::EXIT_BAD_INPUT)
}

fn with_time(table: &Table, names: Vec<String>) -> (Option<usize>, Vec<String>) {
    let t = table.column_index("t");
    let mut cols = Vec::with_capacity(names.len() + 1);
    if t.is_some() {
        cols.push("t".to_string());
    }
    cols.extend(names);
    (t, cols)
}

/// Quaternions must be unit for the dynamics to mean anything: say which row is not.
fn check_quaternion(model: &Model, table: &Table, row: usize, q: &[f64]) -> Result<(), IoError> {
    if model.is_floating() {
        let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
        if (n - 1.0).abs() > 1e-6 {
            return Err(table.row_error(row, format!("base quaternion has norm {n}, not 1")));
        }
    }
    Ok(())
}

pub fn kinematics(args: KinematicsArgs) -> ExitCode {
    match kinematics_impl(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(e),
    }
}

fn kinematics_impl(args: &KinematicsArgs) -> Result<(), String> {
    let a = &args.batch;
    let model = load_model(&a.urdf, a.fixed_base)?;
    let table = Table::read(&a.trajectory).map_err(|e| e.to_string())?;
    let qc =
        StateColumns::find(&table, Quantity::Q, &model.q_names()).map_err(|e| e.to_string())?;
    let frames: Vec<usize> = if args.frames.is_empty() {
        (0..model.frames.len())
            .filter(|&k| model.frames[k].link.is_some())
            .collect()
    } else {
        args.frames
            .iter()
            .map(|n| {
                model
                    .frame_index(n)
                    .ok_or_else(|| format!("{}: no frame named \"{n}\"", a.urdf.display()))
            })
            .collect::<Result<_, _>>()?
    };
    let mut names = vec!["com.x".into(), "com.y".into(), "com.z".into()];
    for &k in &frames {
        let n = &model.frames[k].name;
        for s in ["x", "y", "z", "qx", "qy", "qz", "qw"] {
            names.push(format!("pose:{n}.{s}"));
        }
    }
    let (tcol, cols) = with_time(&table, names);
    let mut w = CsvWriter::create(&a.out, &cols).map_err(|e| e.to_string())?;
    let mut data = Data::new(&model);
    let mut q = vec![0.0; model.nq];
    let mut row = Vec::with_capacity(cols.len());
    let bar = progress::rows(table.rows.len());
    for (r, input) in table.rows.iter().enumerate() {
        qc.gather(input, &mut q);
        check_quaternion(&model, &table, r, &q).map_err(|e| e.to_string())?;
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
        w.write_row(&row).map_err(|e| e.to_string())?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    w.finish().map_err(|e| e.to_string())
}

pub fn inverse_dynamics(args: BatchArgs) -> ExitCode {
    match inverse_impl(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(e),
    }
}

fn inverse_impl(a: &BatchArgs) -> Result<(), String> {
    per_row(a, Quantity::A, Quantity::Tau, |m, d, q, v, x| {
        twinloop_dynamics::rnea(m, d, q, v, x)
    })
}

pub fn forward_dynamics(args: BatchArgs) -> ExitCode {
    match forward_impl(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(e),
    }
}

fn forward_impl(a: &BatchArgs) -> Result<(), String> {
    per_row(a, Quantity::Tau, Quantity::A, |m, d, q, v, x| {
        twinloop_dynamics::aba(m, d, q, v, x)
    })
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
    ) -> &'d nalgebra::DVector<f64>,
) -> Result<(), String> {
    let model = load_model(&a.urdf, a.fixed_base)?;
    let table = Table::read(&a.trajectory).map_err(|e| e.to_string())?;
    let find = |qty| crate::common::state_columns(&table, &model, qty).map_err(|e| e.to_string());
    let (qc, vc, xc) = (find(Quantity::Q)?, find(Quantity::V)?, find(input)?);
    let (tcol, cols) = with_time(
        &table,
        output.column_names(&crate::common::coordinate_names(&model, output)),
    );
    let mut w = CsvWriter::create(&a.out, &cols).map_err(|e| e.to_string())?;
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
        check_quaternion(&model, &table, r, &q).map_err(|e| e.to_string())?;
        row.clear();
        if let Some(t) = tcol {
            row.push(values[t]);
        }
        row.extend(f(&model, &mut data, &q, &v, &x).iter());
        w.write_row(&row).map_err(|e| e.to_string())?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    w.finish().map_err(|e| e.to_string())
}
