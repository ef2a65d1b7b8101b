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

/// Centre of mass (3,), world frame, m: `data.com`.
#[pyfunction]
pub fn center_of_mass<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[])?;
        let com = dy::center_of_mass(&model.get().inner, &mut d.data, c.q.slice());
        d.data.com = com;
    }
    Ok(vec_out(data, |d| d.data.com.as_slice()))
}

/// CoM Jacobian (3, nv), world frame: `data.Jcom` (also sets `data.com`).
#[pyfunction]
pub fn jacobian_center_of_mass<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[])?;
        dy::jacobian_center_of_mass(&model.get().inner, &mut d.data, c.q.slice());
    }
    Ok(mat_out(data, |d| &d.data.com_jacobian))
}

/// World-frame joint Jacobians (6, nv), rows linear then angular: `data.J`.
#[pyfunction]
pub fn compute_joint_jacobians<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[])?;
        dy::compute_joint_jacobians(&model.get().inner, &mut d.data, c.q.slice());
    }
    Ok(mat_out(data, |d| &d.data.joint_jacobians))
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

/// Inverse dynamics (RNEA): tau (nv,) = M(q) a + C(q, v) v + g(q): `data.tau`.
/// q: (nq,), v and a: (nv,) (rad/s, rad/s^2; base velocity in the base frame).
#[pyfunction]
pub fn rnea<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    a: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[(v, "v"), (a, "a")])?;
        dy::rnea(
            &model.get().inner,
            &mut d.data,
            c.q.slice(),
            c.rest[0].slice(),
            c.rest[1].slice(),
        );
    }
    Ok(vec_out(data, |d| d.data.tau.as_slice()))
}

/// Nonlinear effects C(q, v) v + g(q) (nv,): `data.tau` (Pinocchio keeps it in `data.nle`).
#[pyfunction]
pub fn nonlinear_effects<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[(v, "v")])?;
        dy::nonlinear_effects(
            &model.get().inner,
            &mut d.data,
            c.q.slice(),
            c.rest[0].slice(),
        );
    }
    Ok(vec_out(data, |d| d.data.tau.as_slice()))
}

/// Generalized gravity g(q) (nv,): `data.tau`.
#[pyfunction]
pub fn compute_generalized_gravity<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[])?;
        dy::generalized_gravity(&model.get().inner, &mut d.data, c.q.slice());
    }
    Ok(vec_out(data, |d| d.data.tau.as_slice()))
}

/// Joint-space inertia matrix M(q) (nv, nv), full and symmetric: `data.M`.
#[pyfunction]
pub fn crba<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[])?;
        dy::crba(&model.get().inner, &mut d.data, c.q.slice());
        d.data.symmetrize_mass_matrix();
    }
    Ok(mat_out(data, |d| &d.data.mass_matrix))
}

/// Forward dynamics (ABA): accelerations (nv,) under torques tau: `data.ddq`.
#[pyfunction]
pub fn aba<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[(v, "v"), (tau, "tau")])?;
        // A singular mass matrix is refused naming the joint, never NaN accelerations.
        dy::try_aba(
            &model.get().inner,
            &mut d.data,
            c.q.slice(),
            c.rest[0].slice(),
            c.rest[1].slice(),
        )
        .map_err(|e| value_error(e.to_string()))?;
    }
    Ok(vec_out(data, |d| d.data.ddq.as_slice()))
}

/// Inertial-parameter regressor Y (nv, 10 * bodies): rnea = Y @ body_parameters(model).
/// Blocks: the floating base first, then the bodies in joint order; each block is
/// Pinocchio's (m, mc_x, mc_y, mc_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz): `data.joint_torque_regressor`.
#[pyfunction]
pub fn joint_torque_regressor<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    a: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[(v, "v"), (a, "a")])?;
        dy::joint_torque_regressor(
            &model.get().inner,
            &mut d.data,
            c.q.slice(),
            c.rest[0].slice(),
            c.rest[1].slice(),
        );
    }
    Ok(mat_out(data, |d| &d.data.regressor))
}

/// Static CoM regressor G (3, 4 * links): total_mass * com = G @ link_static_parameters(model),
/// one block (m, m c_x, m c_y, m c_z) per description link (seed 004, eq 8).
/// Pinocchio's computeStaticRegressor is this divided by the total mass, per joint.
#[pyfunction]
pub fn static_com_regressor<'py>(
    model: &Bound<'py, PyModel>,
    data: &Bound<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    {
        let mut d = data.borrow_mut();
        let c = check(model.get(), &d, q, &[])?;
        dy::static_com_regressor(&model.get().inner, &mut d.data, c.q.slice());
    }
    Ok(mat_out(data, |d| &d.data.static_regressor))
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
