//! The dynamics functions, called as Pinocchio's are: `(model, data, q, ...)`, results
//! written into `data` and returned as read-only views of it.

use crate::arrays::{Arg, Dim, view_matrix, view_vector};
use crate::errors::value_error;
use crate::model::{PyData, PyModel};
use nalgebra::DMatrix;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use twinloop_dynamics as dy;
use twinloop_dynamics::ReferenceFrame;

/// The argument checks every function shares: data made for this model, q of
/// length nq, the velocity-like arguments of length nv, all finite.
pub struct Checked<'py> {
    pub q: Arg<'py>,
    pub rest: Vec<Arg<'py>>,
}

pub fn check<'py>(
    model: &PyModel,
    data: &PyData,
    q: &Bound<'py, PyAny>,
    nv_args: &[(&Bound<'py, PyAny>, &'static str)],
) -> PyResult<Checked<'py>> {
    data.check_model(model)?;
    let m = &model.inner;
    let q = Arg::new(q, "q", &[Dim::Is(m.nq, "nq")])?;
    let rest = nv_args
        .iter()
        .map(|(x, name)| Arg::new(x, name, &[Dim::Is(m.nv, "nv")]))
        .collect::<PyResult<Vec<_>>>()?;
    Ok(Checked { q, rest })
}

pub fn reference_frame(name: &str) -> PyResult<ReferenceFrame> {
    match name.to_ascii_uppercase().as_str() {
        "LOCAL" => Ok(ReferenceFrame::Local),
        "WORLD" => Ok(ReferenceFrame::World),
        "LOCAL_WORLD_ALIGNED" => Ok(ReferenceFrame::LocalWorldAligned),
        _ => Err(value_error(format!(
            "reference: \"{name}\" is not LOCAL, WORLD or LOCAL_WORLD_ALIGNED"
        ))),
    }
}

fn vec_out<'py>(
    data: &Bound<'py, PyData>,
    f: impl Fn(&PyData) -> &[f64],
) -> Bound<'py, PyArray1<f64>> {
    let this = data.borrow();
    // SAFETY: the slice is a buffer of the Data object, allocated once in Data::new.
    unsafe { view_vector(data.as_any(), f(&this)) }
}

fn mat_out<'py>(
    data: &Bound<'py, PyData>,
    f: impl Fn(&PyData) -> &DMatrix<f64>,
) -> Bound<'py, PyArray2<f64>> {
    let this = data.borrow();
    // SAFETY: as in vec_out.
    unsafe { view_matrix(data.as_any(), f(&this)) }
}

/// Forward kinematics: body placements in `data.oMi` (q: (nq,)).
#[pyfunction]
pub fn forward_kinematics(
    model: &Bound<'_, PyModel>,
    data: &Bound<'_, PyData>,
    q: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let mut d = data.borrow_mut();
    let c = check(model.get(), &d, q, &[])?;
    dy::forward_kinematics(&model.get().inner, &mut d.data, c.q.slice());
    Ok(())
}

/// Forward kinematics and frame placements (`data.oMf`).
#[pyfunction]
pub fn frames_forward_kinematics(
    model: &Bound<'_, PyModel>,
    data: &Bound<'_, PyData>,
    q: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let mut d = data.borrow_mut();
    let c = check(model.get(), &d, q, &[])?;
    dy::frames_forward_kinematics(&model.get().inner, &mut d.data, c.q.slice());
    Ok(())
}

/// A dynamics function of `(model, data, q, <arrays of length nv>...)` whose result
/// lives in `data` and is returned as a read-only view of it: the Python signature,
/// the computation on the checked slices, and the view (`vec_out` or `mat_out`).
macro_rules! data_fn {
    (
        $(#[$meta:meta])*
        fn $name:ident($($arg:ident),*) -> $out:ident $ret:ty,
        |$m:ident, $d:ident, $q:ident| $body:block => |$dv:ident| $view:expr
    ) => {
        $(#[$meta])*
        #[pyfunction]
        pub fn $name<'py>(
            model: &Bound<'py, PyModel>,
            data: &Bound<'py, PyData>,
            q: &Bound<'py, PyAny>,
            $($arg: &Bound<'py, PyAny>,)*
        ) -> PyResult<Bound<'py, $ret>> {
            {
                let mut data_ref = data.borrow_mut();
                let c = check(model.get(), &data_ref, q, &[$(($arg, stringify!($arg))),*])?;
                // `check` made one checked array per argument, in order.
                let [$($arg),*] = &c.rest[..] else {
                    return Err(value_error("internal: the checked arguments do not match"));
                };
                $(let $arg = $arg.slice();)*
                let $m = &*model.get().inner;
                let $d = &mut data_ref.data;
                let $q = c.q.slice();
                $body
            }
            Ok($out(data, |$dv| $view))
        }
    };
}

data_fn! {
    /// Centre of mass (3,), world frame, m: `data.com`.
    fn center_of_mass() -> vec_out PyArray1<f64>,
    |m, d, q| {
        d.com = dy::center_of_mass(m, d, q);
    } => |x| x.data.com.as_slice()
}

data_fn! {
    /// CoM Jacobian (3, nv), world frame: `data.Jcom` (also sets `data.com`).
    fn jacobian_center_of_mass() -> mat_out PyArray2<f64>,
    |m, d, q| {
        dy::jacobian_center_of_mass(m, d, q);
    } => |x| &x.data.com_jacobian
}

data_fn! {
    /// World-frame joint Jacobians (6, nv), rows linear then angular: `data.J`.
    fn compute_joint_jacobians() -> mat_out PyArray2<f64>,
    |m, d, q| {
        dy::compute_joint_jacobians(m, d, q);
    } => |x| &x.data.joint_jacobians
}

/// Jacobian (6, nv) of a frame (name or index) in `reference` ("LOCAL", "WORLD" or
/// "LOCAL_WORLD_ALIGNED"), after compute_joint_jacobians at q (Pinocchio's
/// computeFrameJacobian). A new array.
#[pyfunction]
#[pyo3(signature = (model, data, q, frame, reference = "LOCAL"))]
pub fn frame_jacobian<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
    frame: &Bound<'py, PyAny>,
    reference: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = model.get();
    let k = m.frame_id(frame)?;
    let rf = reference_frame(reference)?;
    let mut d = data.borrow_mut();
    let c = check(m, &d, q, &[])?;
    dy::compute_joint_jacobians(&m.inner, &mut d.data, c.q.slice());
    let mut j = DMatrix::zeros(6, m.inner.nv);
    dy::frame_jacobian(&m.inner, &d.data, k, rf, &mut j);
    Ok(crate::arrays::matrix_copy(data.py(), &j))
}

data_fn! {
    /// Inverse dynamics (RNEA): tau (nv,) = M(q) a + C(q, v) v + g(q): `data.tau`.
    /// q: (nq,), v and a: (nv,) (rad/s, rad/s^2; base velocity in the base frame).
    fn rnea(v, a) -> vec_out PyArray1<f64>,
    |m, d, q| {
        dy::rnea(m, d, q, v, a);
    } => |x| x.data.tau.as_slice()
}

data_fn! {
    /// Nonlinear effects C(q, v) v + g(q) (nv,): `data.tau` (Pinocchio keeps it in `data.nle`).
    fn nonlinear_effects(v) -> vec_out PyArray1<f64>,
    |m, d, q| {
        dy::nonlinear_effects(m, d, q, v);
    } => |x| x.data.tau.as_slice()
}

data_fn! {
    /// Generalized gravity g(q) (nv,): `data.tau`.
    fn compute_generalized_gravity() -> vec_out PyArray1<f64>,
    |m, d, q| {
        dy::generalized_gravity(m, d, q);
    } => |x| x.data.tau.as_slice()
}

data_fn! {
    /// Joint-space inertia matrix M(q) (nv, nv), full and symmetric: `data.M`.
    fn crba() -> mat_out PyArray2<f64>,
    |m, d, q| {
        dy::crba(m, d, q);
        d.symmetrize_mass_matrix();
    } => |x| &x.data.mass_matrix
}

data_fn! {
    /// Forward dynamics (ABA): accelerations (nv,) under torques tau: `data.ddq`.
    fn aba(v, tau) -> vec_out PyArray1<f64>,
    |m, d, q| {
        // A singular mass matrix is refused naming the joint, never NaN accelerations.
        dy::try_aba(m, d, q, v, tau).map_err(|e| value_error(e.to_string()))?;
    } => |x| x.data.ddq.as_slice()
}

data_fn! {
    /// Inertial-parameter regressor Y (nv, 10 * bodies): rnea = Y @ body_parameters(model).
    /// Blocks: the floating base first, then the bodies in joint order; each block is
    /// Pinocchio's (m, mc_x, mc_y, mc_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz): `data.joint_torque_regressor`.
    fn joint_torque_regressor(v, a) -> mat_out PyArray2<f64>,
    |m, d, q| {
        dy::joint_torque_regressor(m, d, q, v, a);
    } => |x| &x.data.regressor
}

data_fn! {
    /// Static CoM regressor G (3, 4 * links): total_mass * com = G @ link_static_parameters(model),
    /// one block (m, m c_x, m c_y, m c_z) per description link (seed 004, eq 8).
    /// Pinocchio's computeStaticRegressor is this divided by the total mass, per joint.
    fn static_com_regressor() -> mat_out PyArray2<f64>,
    |m, d, q| {
        dy::static_com_regressor(m, d, q);
    } => |x| &x.data.static_regressor
}

/// Dynamic parameters of the bodies (10 * bodies,), the vector joint_torque_regressor multiplies.
#[pyfunction]
pub fn body_parameters<'py>(model: &Bound<'py, PyModel>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(model.py(), dy::body_parameters(&model.get().inner))
}

/// Per link (m, m c_x, m c_y, m c_z) (4 * links,), the vector static_com_regressor multiplies.
#[pyfunction]
pub fn link_static_parameters<'py>(model: &Bound<'py, PyModel>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(model.py(), dy::link_static_parameters(&model.get().inner))
}
