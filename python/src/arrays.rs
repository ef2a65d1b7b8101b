//! numpy at the edge: arguments read as float64 arrays and checked (shape, finite)
//! with errors that name the argument, and results handed back either as new arrays
//! or as read-only views into a `Data`.

use nalgebra::DMatrix;
use numpy::ndarray::{ArrayView1, ArrayView2, Dimension, ShapeBuilder};
use numpy::{
    PyArray, PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A float64 argument: borrowed from numpy when it is already a contiguous float64
/// array (no copy), else converted once.
pub struct Arg<'py> {
    name: &'static str,
    array: PyReadonlyArrayDyn<'py, f64>,
    copy: Option<Vec<f64>>,
}

/// One expected dimension: a fixed size named after what it counts (`nq`), or free
/// and named for the message (`N`, `nu`: each free dimension its own name, so that a
/// shape reads "(N, nu)", never "(N, N)").
#[derive(Clone, Copy)]
pub enum Dim {
    Is(usize, &'static str),
    Free(&'static str),
}

fn fmt_shape(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn fmt_expected(dims: &[Dim]) -> String {
    let parts: Vec<String> = dims
        .iter()
        .map(|d| match d {
            Dim::Is(n, "") => n.to_string(),
            Dim::Is(n, what) => format!("{what} = {n}"),
            Dim::Free(what) => what.to_string(),
        })
        .collect();
    if parts.len() == 1 {
        format!("({},)", parts[0])
    } else {
        format!("({})", parts.join(", "))
    }
}

impl<'py> Arg<'py> {
    /// Read `obj` as a float64 array with the given shape; every entry finite.
    pub fn new(obj: &Bound<'py, PyAny>, name: &'static str, dims: &[Dim]) -> PyResult<Arg<'py>> {
        let array = as_f64_array(obj, name)?;
        let ro = array
            .try_readonly()
            .map_err(|e| PyValueError::new_err(format!("{name}: cannot be read ({e})")))?;
        let shape = ro.shape().to_vec();
        let fits = shape.len() == dims.len()
            && shape.iter().zip(dims).all(|(&n, d)| match d {
                Dim::Is(m, _) => n == *m,
                Dim::Free(_) => true,
            });
        if !fits {
            return Err(PyValueError::new_err(format!(
                "{name}: expected shape {}, got {}",
                fmt_expected(dims),
                fmt_shape(&shape)
            )));
        }
        let copy = if ro.is_c_contiguous() {
            None
        } else {
            Some(ro.as_array().iter().copied().collect())
        };
        let arg = Arg {
            name,
            array: ro,
            copy,
        };
        arg.check_finite(&shape)?;
        Ok(arg)
    }

    pub fn slice(&self) -> &[f64] {
        match &self.copy {
            Some(v) => v,
            None => self.array.as_slice().expect("checked contiguous"),
        }
    }

    /// The array's shape.
    pub fn array_shape(&self) -> Vec<usize> {
        self.array.shape().to_vec()
    }

    /// Size of the first dimension (rows of a batch).
    pub fn rows(&self) -> usize {
        self.array.shape()[0]
    }

    fn check_finite(&self, shape: &[usize]) -> PyResult<()> {
        let Some(k) = self.slice().iter().position(|x| !x.is_finite()) else {
            return Ok(());
        };
        // Row-major index of the bad entry, for the message.
        let mut rest = k;
        let mut index = vec![0; shape.len()];
        for d in (0..shape.len()).rev() {
            index[d] = rest % shape[d];
            rest /= shape[d];
        }
        let idx: Vec<String> = index.iter().map(|i| i.to_string()).collect();
        Err(PyValueError::new_err(format!(
            "{}[{}] is {}: every entry must be finite",
            self.name,
            idx.join(", "),
            self.slice()[k]
        )))
    }
}

fn as_f64_array<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        return Ok(a.clone());
    }
    let py = obj.py();
    let numpy = py.import("numpy")?;
    // numpy would drop the imaginary part of complex numbers with only a warning.
    if let Ok(kind) = obj.getattr("dtype").and_then(|d| d.getattr("kind"))
        && kind.extract::<String>().is_ok_and(|k| k == "c")
    {
        return Err(PyValueError::new_err(format!(
            "{name}: complex numbers; expected real float64 values"
        )));
    }
    let converted = numpy
        .call_method1("asarray", (obj, "float64"))
        .map_err(|e| {
            PyValueError::new_err(format!("{name}: cannot be read as float64 numbers ({e})"))
        })?;
    converted
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|e| PyValueError::new_err(format!("{name}: not a float64 array ({e})")))
}

/// A read-only numpy view of a vector owned by `owner` (no copy; writing raises).
///
/// # Safety
/// `v` must live inside `owner` and never be reallocated while `owner` lives
/// (`Data` allocates its buffers once, in `Data::new`).
pub unsafe fn view_vector<'py>(owner: &Bound<'py, PyAny>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    let view = ArrayView1::from(v);
    // SAFETY: by the caller's contract the memory outlives the array, which keeps
    // `owner` alive as its base object.
    let array = unsafe { PyArray1::borrow_from_array(&view, owner.clone()) };
    array.readwrite().make_nonwriteable();
    array
}

/// A read-only numpy view of a column-major matrix owned by `owner`.
///
/// # Safety
/// As [`view_vector`].
pub unsafe fn view_matrix<'py>(
    owner: &Bound<'py, PyAny>,
    m: &DMatrix<f64>,
) -> Bound<'py, PyArray2<f64>> {
    let view = ArrayView2::from_shape((m.nrows(), m.ncols()).f(), m.as_slice())
        .expect("a DMatrix is column-major and dense");
    // SAFETY: as in view_vector.
    let array = unsafe { PyArray2::borrow_from_array(&view, owner.clone()) };
    array.readwrite().make_nonwriteable();
    array
}

/// `array` (a new copy) marked read-only: a property that hands out a copy must not
/// look like state that a write would change (rust-numpy#408's trap). Writing to it
/// raises ValueError; `np.array(x)` gives a writable copy.
pub fn read_only<'py, D: Dimension>(
    array: Bound<'py, PyArray<f64, D>>,
) -> Bound<'py, PyArray<f64, D>> {
    array.readwrite().make_nonwriteable();
    array
}

/// A read-only copy of a slice: [`read_only`] of a new 1-D array.
pub fn read_only_vector<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    read_only(PyArray1::from_slice(py, v))
}

/// A new (writable) numpy array of the given shape from row-major values.
pub fn new_array<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let flat = PyArray1::from_vec(py, values);
    Ok(flat.reshape(shape.to_vec())?.to_dyn().clone())
}

/// A copy of a column-major matrix as a new row-major numpy array.
pub fn matrix_copy<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    let (r, c) = (m.nrows(), m.ncols());
    let mut out = Vec::with_capacity(r * c);
    for i in 0..r {
        for j in 0..c {
            out.push(m[(i, j)]);
        }
    }
    PyArray1::from_vec(py, out)
        .reshape([r, c])
        .expect("r * c values")
}
