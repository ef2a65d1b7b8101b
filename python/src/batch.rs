//! `<function>_batch`: one call over N rows of (N, nq) / (N, nv) arrays, looped in
//! Rust with the GIL released, the rows split over `threads` threads (each with its
//! own `Data` and a 6 x nv scratch matrix, so the loop allocates nothing per row).
//! RNEA, ABA, CRBA and the CoM run the batched algorithms instead, a thread's rows in
//! one call (`run_blocks`; docs/dynamics.md, Batched calls).

use crate::arrays::{Arg, Dim, new_array};
use crate::dynamics::reference_frame;
use crate::errors::value_error;
use crate::model::PyModel;
use nalgebra::DMatrix;
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use twinloop_dynamics::{self as dy, BatchData, Data, Model};

/// Threads to use: the caller's number, else every core.
pub fn thread_count(threads: Option<usize>) -> PyResult<usize> {
    match threads {
        Some(0) => Err(value_error("threads: must be at least 1")),
        Some(n) => Ok(n),
        None => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
    }
}

/// What one row computes: `Err` (a message) for a row it cannot, such as a singular
/// mass matrix in `aba_batch`.
pub type RowResult = Result<(), String>;

/// Run `row` on every row of the inputs (row-major, `widths[k]` values per row of
/// input k), writing `out_width` values per row, on `threads` threads. A row that
/// fails stops its thread; the error of the lowest failing row is returned, as
/// "row i: message" (the same row whatever the thread count).
pub fn run_rows<F>(
    model: &Model,
    inputs: &[&[f64]],
    widths: &[usize],
    n: usize,
    out_width: usize,
    threads: usize,
    row: F,
) -> Result<Vec<f64>, String>
where
    F: Fn(&Model, &mut Data, &mut DMatrix<f64>, &[&[f64]], &mut [f64]) -> RowResult + Sync,
{
    let mut out = vec![0.0; n * out_width];
    if n == 0 || out_width == 0 {
        return Ok(out);
    }
    let per_thread = n.div_ceil(threads.min(n));
    let failures: Vec<Option<(usize, String)>> = std::thread::scope(|s| {
        let handles: Vec<_> = out
            .chunks_mut(per_thread * out_width)
            .enumerate()
            .map(|(c, chunk)| {
                let row = &row;
                s.spawn(move || {
                    let mut data = Data::new(model);
                    let mut scratch = DMatrix::zeros(6, model.nv);
                    let mut args: Vec<&[f64]> = vec![&[]; inputs.len()];
                    for (k, o) in chunk.chunks_mut(out_width).enumerate() {
                        let i = c * per_thread + k;
                        for (a, (x, w)) in args.iter_mut().zip(inputs.iter().zip(widths)) {
                            *a = &x[i * w..(i + 1) * w];
                        }
                        if let Err(e) = row(model, &mut data, &mut scratch, &args, o) {
                            return Some((i, e));
                        }
                    }
                    None
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Some((0, "a batch thread failed unexpectedly".into())))
            })
            .collect()
    });
    // Chunks are in row order: the first failing chunk holds the lowest failing row.
    match failures.into_iter().flatten().next() {
        Some((i, e)) => Err(format!("row {i}: {e}")),
        None => Ok(out),
    }
}

/// What one thread computes on its block of rows: `Err((row in the block, message))`.
pub type BlockResult = Result<(), (usize, String)>;

/// [`run_rows`] for the batched algorithms (`twinloop_dynamics::batch`): each thread
/// gets one block of consecutive rows (a multiple of the lane count, so only the last
/// block has a partial lane group) and its own `BatchData`, and `block` computes them
/// all in one call. Errors as `run_rows`: the lowest failing row, "row i: message".
pub fn run_blocks<F>(
    model: &Model,
    inputs: &[&[f64]],
    widths: &[usize],
    n: usize,
    out_width: usize,
    threads: usize,
    block: F,
) -> Result<Vec<f64>, String>
where
    F: Fn(&Model, &mut BatchData, &[&[f64]], &mut [f64]) -> BlockResult + Sync,
{
    let mut out = vec![0.0; n * out_width];
    if n == 0 || out_width == 0 {
        return Ok(out);
    }
    let lanes = dy::batch::lanes::LANES;
    let per_thread = n.div_ceil(threads.min(n)).next_multiple_of(lanes);
    let failures: Vec<Option<(usize, String)>> = std::thread::scope(|s| {
        let handles: Vec<_> = out
            .chunks_mut(per_thread * out_width)
            .enumerate()
            .map(|(c, chunk)| {
                let block = &block;
                s.spawn(move || {
                    let mut bd = BatchData::new(model);
                    let (r0, r1) = (c * per_thread, c * per_thread + chunk.len() / out_width);
                    let args: Vec<&[f64]> = inputs
                        .iter()
                        .zip(widths)
                        .map(|(x, w)| &x[r0 * w..r1 * w])
                        .collect();
                    block(model, &mut bd, &args, chunk)
                        .err()
                        .map(|(i, e)| (r0 + i, e))
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Some((0, "a batch thread failed unexpectedly".into())))
            })
            .collect()
    });
    match failures.into_iter().flatten().next() {
        Some((i, e)) => Err(format!("row {i}: {e}")),
        None => Ok(out),
    }
}

/// Copy a column-major matrix into row-major `out`.
fn write_matrix(m: &DMatrix<f64>, out: &mut [f64]) {
    let c = m.ncols();
    for (j, col) in m.column_iter().enumerate() {
        for (i, x) in col.iter().enumerate() {
            out[i * c + j] = *x;
        }
    }
}

/// The inputs of a batch: Q (N, nq) then arrays (N, nv) with the same N.
fn batch_args<'py>(
    model: &Model,
    q: &Bound<'py, PyAny>,
    rest: &[(&Bound<'py, PyAny>, &'static str)],
) -> PyResult<(usize, Vec<Arg<'py>>)> {
    let qa = Arg::new(q, "Q", &[Dim::Free("N"), Dim::Is(model.nq, "nq")])?;
    let n = qa.rows();
    let mut args = vec![qa];
    for (x, name) in rest {
        args.push(Arg::new(
            x,
            name,
            &[Dim::Is(n, "N (rows of Q)"), Dim::Is(model.nv, "nv")],
        )?);
    }
    Ok((n, args))
}

/// The shared body of every batch function: check, release the GIL, run, wrap.
fn batch<'py, F>(
    py: Python<'py>,
    model: &PyModel,
    q: &Bound<'py, PyAny>,
    rest: &[(&Bound<'py, PyAny>, &'static str)],
    out_shape: &[usize],
    threads: Option<usize>,
    row: F,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>>
where
    F: Fn(&Model, &mut Data, &mut DMatrix<f64>, &[&[f64]], &mut [f64]) -> RowResult + Sync + Send,
{
    let m = &*model.inner;
    let threads = thread_count(threads)?;
    let (n, args) = batch_args(m, q, rest)?;
    let slices: Vec<&[f64]> = args.iter().map(|a| a.slice()).collect();
    let mut widths = vec![m.nq];
    widths.extend(std::iter::repeat_n(m.nv, rest.len()));
    let out_width: usize = out_shape.iter().product();
    let values = py
        .detach(|| run_rows(m, &slices, &widths, n, out_width, threads, row))
        .map_err(value_error)?;
    let mut shape = vec![n];
    shape.extend_from_slice(out_shape);
    new_array(py, values, &shape)
}

/// [`batch`] for the batched algorithms: `block` computes a thread's rows at once.
fn batch_blocks<'py, F>(
    py: Python<'py>,
    model: &PyModel,
    q: &Bound<'py, PyAny>,
    rest: &[(&Bound<'py, PyAny>, &'static str)],
    out_shape: &[usize],
    threads: Option<usize>,
    block: F,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>>
where
    F: Fn(&Model, &mut BatchData, &[&[f64]], &mut [f64]) -> BlockResult + Sync + Send,
{
    let m = &*model.inner;
    let threads = thread_count(threads)?;
    let (n, args) = batch_args(m, q, rest)?;
    let slices: Vec<&[f64]> = args.iter().map(|a| a.slice()).collect();
    let mut widths = vec![m.nq];
    widths.extend(std::iter::repeat_n(m.nv, rest.len()));
    let out_width: usize = out_shape.iter().product();
    let values = py
        .detach(|| run_blocks(m, &slices, &widths, n, out_width, threads, block))
        .map_err(value_error)?;
    let mut shape = vec![n];
    shape.extend_from_slice(out_shape);
    new_array(py, values, &shape)
}

/// A `#[pyfunction]` of `(model, Q, <arrays of nv columns>..., threads=None)` whose
/// rows `$driver` runs with `$work`: the one signature [`block_fn`] and [`batch_fn`]
/// share.
macro_rules! py_batch_fn {
    (
        $(#[$meta:meta])*
        fn $name:ident($($arg:ident),*) -> |$sm:ident| $shape:expr,
        $driver:ident, $work:expr
    ) => {
        $(#[$meta])*
        #[pyfunction]
        #[pyo3(signature = (model, Q, $($arg,)* threads = None))]
        #[allow(non_snake_case)]
        pub fn $name<'py>(
            model: &Bound<'py, PyModel>,
            Q: &Bound<'py, PyAny>,
            $($arg: &Bound<'py, PyAny>,)*
            threads: Option<usize>,
        ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
            let $sm = &*model.get().inner;
            let shape = $shape;
            $driver(
                model.py(),
                model.get(),
                Q,
                &[$(($arg, stringify!($arg))),*],
                &shape,
                threads,
                $work,
            )
        }
    };
}

/// A batch function on the batched algorithms (4 states per vector instruction;
/// `twinloop_dynamics::batch`): the same Python signature as [`batch_fn`]'s, the
/// block's body given all of a thread's rows.
macro_rules! block_fn {
    (
        $(#[$meta:meta])*
        fn $name:ident($($arg:ident),*) -> |$sm:ident| $shape:expr,
        |$m:ident, $bd:ident, $x:ident, $o:ident| $body:block
    ) => {
        py_batch_fn! {
            $(#[$meta])*
            fn $name($($arg),*) -> |$sm| $shape,
            batch_blocks, |$m, $bd, $x, $o| $body
        }
    };
}

/// A batch function of `(model, Q, <arrays of nv columns>..., threads=None)`: its
/// Python signature, the output shape per row (from the model) and the row's body.
macro_rules! batch_fn {
    (
        $(#[$meta:meta])*
        fn $name:ident($($arg:ident),*) -> |$sm:ident| $shape:expr,
        |$m:ident, $d:ident, $scratch:pat_param, $x:ident, $o:ident| $row:block
    ) => {
        py_batch_fn! {
            $(#[$meta])*
            fn $name($($arg),*) -> |$sm| $shape,
            batch, |$m, $d, $scratch, $x, $o| {
                let () = $row;
                Ok(())
            }
        }
    };
}

block_fn! {
    /// rnea over rows: Q (N, nq), V (N, nv), A (N, nv) -> tau (N, nv).
    fn rnea_batch(V, A) -> |m| [m.nv],
    |m, bd, x, o| {
        dy::rnea_batch(m, bd, x[0], x[1], x[2], o);
        Ok(())
    }
}

block_fn! {
    /// aba over rows: Q (N, nq), V (N, nv), TAU (N, nv) -> ddq (N, nv). A singular
    /// mass matrix raises ValueError naming the row and the joint, as `aba` does,
    /// never NaN accelerations.
    fn aba_batch(V, TAU) -> |m| [m.nv],
    |m, bd, x, o| {
        dy::try_aba_batch(m, bd, x[0], x[1], x[2], o).map_err(|e| (e.row, e.joint.to_string()))
    }
}

batch_fn! {
    /// nonlinear_effects over rows: Q (N, nq), V (N, nv) -> (N, nv).
    fn nonlinear_effects_batch(V) -> |m| [m.nv],
    |m, d, _, x, o| {
        o.copy_from_slice(dy::nonlinear_effects(m, d, x[0], x[1]).as_slice());
    }
}

block_fn! {
    /// crba over rows: Q (N, nq) -> M (N, nv, nv), full.
    fn crba_batch() -> |m| [m.nv, m.nv],
    |m, bd, x, o| {
        dy::crba_batch(m, bd, x[0], o);
        Ok(())
    }
}

block_fn! {
    /// center_of_mass over rows: Q (N, nq) -> (N, 3).
    fn center_of_mass_batch() -> |_m| [3],
    |m, bd, x, o| {
        dy::center_of_mass_batch(m, bd, x[0], o);
        Ok(())
    }
}

batch_fn! {
    /// jacobian_center_of_mass over rows: Q (N, nq) -> (N, 3, nv).
    fn jacobian_center_of_mass_batch() -> |m| [3, m.nv],
    |m, d, _, x, o| {
        write_matrix(dy::jacobian_center_of_mass(m, d, x[0]), o);
    }
}

batch_fn! {
    /// compute_joint_jacobians over rows: Q (N, nq) -> (N, 6, nv).
    fn compute_joint_jacobians_batch() -> |m| [6, m.nv],
    |m, d, _, x, o| {
        dy::compute_joint_jacobians(m, d, x[0]);
        write_matrix(&d.joint_jacobians, o);
    }
}

batch_fn! {
    /// joint_torque_regressor over rows: Q, V, A -> (N, nv, 10 * bodies).
    fn joint_torque_regressor_batch(V, A) -> |m| [m.nv, 10 * (m.nbodies + usize::from(m.is_floating()))],
    |m, d, _, x, o| {
        write_matrix(dy::joint_torque_regressor(m, d, x[0], x[1], x[2]), o);
    }
}

batch_fn! {
    /// static_com_regressor over rows: Q (N, nq) -> (N, 3, 4 * links).
    fn static_com_regressor_batch() -> |m| [3, 4 * m.links.len()],
    |m, d, _, x, o| {
        write_matrix(dy::static_com_regressor(m, d, x[0]), o);
    }
}

/// frame_jacobian over rows: Q (N, nq) -> (N, 6, nv).
#[pyfunction]
#[pyo3(signature = (model, Q, frame, reference = "LOCAL", threads = None))]
#[allow(non_snake_case)]
pub fn frame_jacobian_batch<'py>(
    model: &Bound<'py, PyModel>,
    Q: &Bound<'py, PyAny>,
    frame: &Bound<'py, PyAny>,
    reference: &str,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let pm = model.get();
    let nv = pm.inner.nv;
    let k = pm.frame_id(frame)?;
    let rf = reference_frame(reference)?;
    batch(
        model.py(),
        pm,
        Q,
        &[],
        &[6, nv],
        threads,
        move |m, d, jf, x, o| {
            dy::compute_joint_jacobians(m, d, x[0]);
            dy::frame_jacobian(m, d, k, rf, jf);
            write_matrix(jf, o);
            Ok(())
        },
    )
}
