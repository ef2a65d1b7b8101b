//! `Description`, `Model` and `Data`: what a robot file says, the compiled dynamics
//! model, and the workspace whose results Python sees as read-only views.

use crate::arrays::{matrix_copy, read_only, read_only_vector, view_matrix, view_vector};
use crate::errors::{ModelError, description_error, value_error};
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyInt, PyList, PyTuple};
use std::path::Path;
use std::sync::Arc;
use twinloop_description::{Description, DescriptionError, lint, urdf};
use twinloop_dynamics::{BaseKind, Data, JointOrder, Model};
use twinloop_spatial::Se3;

/// The joint order Pinocchio gives the file: a URDF's (and a builtin robot's, which
/// Pinocchio reads through its URDF) by joint name, as its URDF parser numbers joints;
/// an MJCF's in file order, as its MJCF parser walks the body tree.
fn pinocchio_order(format: twinloop_description::Format) -> JointOrder {
    match format {
        twinloop_description::Format::Urdf => JointOrder::UrdfByName,
        twinloop_description::Format::Mjcf => JointOrder::File,
    }
}

/// Load `builtin:NAME` or a URDF/MJCF file, as `twinloop --robot` does, with the joint
/// order the Python package numbers the description's joints in (the order Pinocchio
/// gives the same file). A reader bug on a strange file becomes an error naming the
/// file, never a panic.
pub fn load_ordered(spec: &str) -> PyResult<(Description, JointOrder)> {
    if spec.starts_with("builtin:") {
        return twinloop_description::builtin::resolve(spec)
            .map(|d| (d, JointOrder::UrdfByName))
            .map_err(|e| ModelError::new_err(e.to_string()));
    }
    let path = Path::new(spec);
    if let Err(e) = std::fs::read(path) {
        return Err(PyOSError::new_err(format!(
            "{spec}: cannot read the file: {e}"
        )));
    }
    let loaded = std::panic::catch_unwind(|| twinloop_description::load_with_format(path));
    let result = loaded.unwrap_or_else(|_| {
        Err(
            DescriptionError::new("the reader failed unexpectedly; please report this file")
                .in_file(path),
        )
    });
    result
        .map(|(d, f)| (d, pinocchio_order(f)))
        .map_err(description_error)
}

/// The columns of `from`'s q that make `to`'s q, for two models of one description
/// in two joint orders: `to_q[k] = from_q[perm[k]]`.
pub fn q_permutation(from: &Model, to: &Model) -> Vec<usize> {
    let mut perm: Vec<usize> = (0..to.q_offset).collect();
    for (b, name) in to.joint_names.iter().enumerate() {
        let f = from
            .joint_index(name)
            .expect("one description, the same joints");
        perm.extend((0..to.joint_types[b].nq()).map(|k| from.idx_q[f] + k));
    }
    perm
}

/// What a robot file says: links with their masses, joints with their limits, and
/// what `twinloop model check` finds wrong with it.
#[pyclass(name = "Description", module = "twinloop._native", frozen)]
pub struct PyDescription {
    pub inner: Arc<Description>,
    /// The order its models number the joints in: Pinocchio's for the same file.
    pub order: JointOrder,
}

impl PyDescription {
    /// A description read from (or made from) a URDF: Pinocchio's URDF order.
    pub fn urdf(d: Description) -> PyDescription {
        PyDescription {
            inner: Arc::new(d),
            order: JointOrder::UrdfByName,
        }
    }
}

/// The lossless parts of a description for pickling: URDF text (the exact writer),
/// plus what URDF cannot say (an MJCF's gravity and joint armature, by joint name,
/// and its free joint's armature and damping), and whether its joints are numbered
/// by name (Pinocchio's URDF order).
type DescriptionState = (String, Option<[f64; 3]>, Vec<(String, f64)>, [f64; 2], bool);

fn description_state(d: &Description, order: JointOrder) -> DescriptionState {
    (
        urdf::to_string_exact(d),
        d.gravity,
        d.joints
            .iter()
            .filter(|j| j.armature != 0.0)
            .map(|j| (j.name.clone(), j.armature))
            .collect(),
        [d.base_armature, d.base_damping],
        order == JointOrder::UrdfByName,
    )
}

fn description_from_state(state: DescriptionState) -> PyResult<(Description, JointOrder)> {
    let (text, gravity, armature, [base_armature, base_damping], by_name) = state;
    let mut d = urdf::from_str(&text).map_err(description_error)?;
    d.gravity = gravity;
    (d.base_armature, d.base_damping) = (base_armature, base_damping);
    for (name, a) in armature {
        let joint = d
            .joints
            .iter_mut()
            .find(|j| j.name == name)
            .ok_or_else(|| {
                value_error(format!(
                    "pickled description: armature of joint \"{name}\", which it does not have"
                ))
            })?;
        joint.armature = a;
    }
    let order = match by_name {
        true => JointOrder::UrdfByName,
        false => JointOrder::File,
    };
    Ok((d, order))
}

/// Rebuild a pickled description (used by pickle).
#[pyfunction]
pub fn _description_from_state(state: DescriptionState) -> PyResult<PyDescription> {
    let (d, order) = description_from_state(state)?;
    Ok(PyDescription {
        inner: Arc::new(d),
        order,
    })
}

/// Rebuild a pickled model (used by pickle).
#[pyfunction]
pub fn _model_from_state(state: DescriptionState, floating: bool) -> PyResult<PyModel> {
    let (d, order) = description_from_state(state)?;
    PyModel::build(Arc::new(d), order, floating)
}

/// Load a robot: `"builtin:km20"`, `"builtin:lab17"`, or a URDF or MJCF file.
///
/// Raises OSError when the file cannot be read and ModelError when it is not a valid
/// description (the message names the file, line and element).
#[pyfunction]
pub fn load(path_or_builtin: &Bound<'_, PyAny>) -> PyResult<PyDescription> {
    let spec: String = if let Ok(s) = path_or_builtin.extract::<String>() {
        s
    } else {
        path_or_builtin
            .call_method0("__fspath__")
            .and_then(|p| p.extract())
            .map_err(|_| value_error("path_or_builtin: expected a str or os.PathLike"))?
    };
    let (d, order) = load_ordered(&spec)?;
    Ok(PyDescription {
        inner: Arc::new(d),
        order,
    })
}

fn se3_matrix<'py>(py: Python<'py>, x: &Se3) -> Bound<'py, PyArray2<f64>> {
    let mut m = nalgebra::DMatrix::<f64>::identity(4, 4);
    m.view_mut((0, 0), (3, 3)).copy_from(&x.rotation);
    m.view_mut((0, 3), (3, 1)).copy_from(&x.translation);
    read_only(matrix_copy(py, &m))
}

#[pymethods]
impl PyDescription {
    /// Read a description from URDF text.
    #[staticmethod]
    fn from_urdf(text: &str) -> PyResult<PyDescription> {
        Ok(PyDescription::urdf(
            urdf::from_str(text).map_err(description_error)?,
        ))
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// Sum of the link masses (kg).
    #[getter]
    fn total_mass(&self) -> f64 {
        self.inner.total_mass()
    }

    /// Links in file order: dicts with name, mass (kg), com (m, link frame) and
    /// inertia (3x3, kg m^2, about the CoM in the inertial frame), or None values
    /// for a link without `<inertial>`. The arrays are read-only copies (a changed
    /// robot is made with `with_point_mass`).
    #[getter]
    fn links<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for l in &self.inner.links {
            let d = PyDict::new(py);
            d.set_item("name", &l.name)?;
            match &l.inertial {
                Some(i) => {
                    d.set_item("mass", i.mass)?;
                    d.set_item("com", read_only_vector(py, &i.origin.xyz))?;
                    let m = i.inertia.matrix();
                    d.set_item(
                        "inertia",
                        read_only(
                            PyArray2::from_vec2(py, &m.map(|r| r.to_vec()))
                                .map_err(|e| value_error(e.to_string()))?,
                        ),
                    )?;
                }
                None => {
                    d.set_item("mass", 0.0)?;
                    d.set_item("com", py.None())?;
                    d.set_item("inertia", py.None())?;
                }
            }
            list.append(d)?;
        }
        Ok(list)
    }

    /// Joints in file order: dicts with name, type (URDF's word), parent, child,
    /// axis, and limits lower/upper (rad or m), effort (N m or N), velocity
    /// (rad/s or m/s), each None when the file has none.
    #[getter]
    fn joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for j in &self.inner.joints {
            let d = PyDict::new(py);
            d.set_item("name", &j.name)?;
            d.set_item("type", j.kind.urdf_name())?;
            d.set_item("parent", &j.parent)?;
            d.set_item("child", &j.child)?;
            d.set_item("axis", j.axis.map(|a| a.to_vec()))?;
            let lim = j.limit.unwrap_or_default();
            d.set_item("lower", lim.lower)?;
            d.set_item("upper", lim.upper)?;
            d.set_item("effort", lim.effort)?;
            d.set_item("velocity", lim.velocity)?;
            d.set_item("armature", j.armature)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The floating base's armature (kg and kg m^2): an MJCF free joint's `armature`,
    /// which MuJoCo adds to the six base diagonal entries of the mass matrix (and
    /// twinloop's dynamics with it); 0 for a URDF, which cannot say it.
    #[getter]
    fn base_armature(&self) -> f64 {
        self.inner.base_armature
    }

    /// What `twinloop model check --json` reports: a dict with the counts and the
    /// list of findings (severity, code, subject, name, message).
    fn lint<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let report = lint::lint(&self.inner);
        let text = serde_json::to_string(&report).map_err(|e| value_error(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// The findings of `lint()` alone.
    #[getter]
    fn findings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.lint(py)?.get_item("findings")
    }

    /// A copy with a point mass (kg) added to a link at xyz (m, link frame), its
    /// inertial merged (what `--add-mass KG@LINK:X,Y,Z` does).
    fn with_point_mass(&self, link: &str, mass: f64, xyz: [f64; 3]) -> PyResult<PyDescription> {
        if !(mass.is_finite() && xyz.iter().all(|x| x.is_finite())) {
            return Err(value_error("mass, xyz: must be finite"));
        }
        let mut d = (*self.inner).clone();
        twinloop_description::builtin::add_point_mass(&mut d, link, mass, xyz)
            .map_err(|e| value_error(format!("link: {e}")))?;
        Ok(PyDescription {
            inner: Arc::new(d),
            order: self.order,
        })
    }

    /// The description as URDF text, as `twinloop model export` writes it (a file
    /// Pinocchio and urdfdom load: ball joints as three revolute joints).
    fn to_urdf(&self) -> String {
        urdf::to_string(&self.inner)
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let f = py
            .import("twinloop._native")?
            .getattr("_description_from_state")?;
        let state = description_state(&self.inner, self.order).into_pyobject(py)?;
        PyTuple::new(py, [f, PyTuple::new(py, [state])?.into_any()])
    }

    fn __repr__(&self) -> String {
        format!(
            "<twinloop.Description {:?}: {} links, {} joints, {:.3} kg>",
            self.inner.name,
            self.inner.links.len(),
            self.inner.joints.len(),
            self.inner.total_mass()
        )
    }
}

/// The compiled dynamics model (Pinocchio's `Model`): constant after construction.
#[pyclass(name = "Model", module = "twinloop._native", frozen)]
pub struct PyModel {
    pub inner: Arc<Model>,
    pub description: Arc<Description>,
    pub order: JointOrder,
    pub floating: bool,
}

impl PyModel {
    pub fn build(
        description: Arc<Description>,
        order: JointOrder,
        floating: bool,
    ) -> PyResult<PyModel> {
        let base = if floating {
            BaseKind::Floating
        } else {
            BaseKind::Fixed
        };
        let model = Model::from_description_ordered(&description, base, order)
            .map_err(description_error)?;
        Ok(PyModel {
            inner: Arc::new(model),
            description,
            order,
            floating,
        })
    }

    /// Index of a frame given by name or index.
    pub fn frame_id(&self, frame: &Bound<'_, PyAny>) -> PyResult<usize> {
        let m = &self.inner;
        if frame.is_instance_of::<PyInt>() {
            // Negative or huge ints too: Pinocchio's indices are never negative.
            return match frame.extract::<usize>() {
                Ok(k) if k < m.frames.len() => Ok(k),
                _ => Err(value_error(format!(
                    "frame: index {frame} out of range (the model has {} frames)",
                    m.frames.len()
                ))),
            };
        }
        let name: String = frame
            .extract()
            .map_err(|_| value_error("frame: expected a frame name (str) or index (int)"))?;
        m.frame_index(&name).ok_or_else(|| {
            value_error(format!(
                "frame: no frame named \"{name}\" in robot \"{}\"",
                m.name
            ))
        })
    }
}

#[pymethods]
impl PyModel {
    /// Compile a description. `floating=True` gives the robot a free-flyer base
    /// (Pinocchio's JointModelFreeFlyer: q = [x, y, z, qx, qy, qz, qw, joints...],
    /// v = [linear, angular (base frame), joint velocities...]); False welds its root
    /// link to the world. Raises ModelError for a description the dynamics cannot take.
    #[staticmethod]
    #[pyo3(signature = (description, floating = true))]
    fn from_description(
        description: &Bound<'_, PyDescription>,
        floating: bool,
    ) -> PyResult<PyModel> {
        let d = description.get();
        PyModel::build(d.inner.clone(), d.order, floating)
    }

    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    /// Length of q (7 + joints for a floating base).
    #[getter]
    fn nq(&self) -> usize {
        self.inner.nq
    }
    /// Length of v (6 + joints for a floating base).
    #[getter]
    fn nv(&self) -> usize {
        self.inner.nv
    }
    /// Moving joints in twinloop's order (depth first, children in file order); joint
    /// i has q index `nq - njoints + i`.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.inner.joint_names.clone()
    }
    /// Frame names (one per description link, then extra frames), for `frame_jacobian`.
    #[getter]
    fn frame_names(&self) -> Vec<String> {
        self.inner.frames.iter().map(|f| f.name.clone()).collect()
    }
    /// Link names in description order (the blocks of `static_com_regressor`).
    #[getter]
    fn link_names(&self) -> Vec<String> {
        self.inner.links.iter().map(|l| l.name.clone()).collect()
    }
    #[getter]
    fn floating(&self) -> bool {
        self.floating
    }
    /// Total mass (kg).
    #[getter]
    fn total_mass(&self) -> f64 {
        self.inner.total_mass
    }
    /// Gravity (3,) in the world frame (m/s^2); read-only (the model is constant).
    #[getter]
    fn gravity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only_vector(py, self.inner.gravity.as_slice())
    }
    /// Lower joint position limits (joints,) (rad or m), one per joint; read-only.
    #[getter]
    fn lower_position_limit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only_vector(py, &self.inner.lower_limits)
    }
    /// Upper joint position limits (joints,) (rad or m), one per joint; read-only.
    #[getter]
    fn upper_position_limit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only_vector(py, &self.inner.upper_limits)
    }
    /// The description this model was compiled from.
    #[getter]
    fn description(&self) -> PyDescription {
        PyDescription {
            inner: self.description.clone(),
            order: self.order,
        }
    }
    /// Index of a joint by name (None if absent).
    fn joint_index(&self, name: &str) -> Option<usize> {
        self.inner.joint_index(name)
    }
    /// Index of a frame by name (Pinocchio's getFrameId); raises ValueError if absent.
    fn frame_index(&self, name: &Bound<'_, PyAny>) -> PyResult<usize> {
        self.frame_id(name)
    }
    /// The neutral configuration: base at the origin, identity orientation, joints 0.
    fn neutral<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let mut q = vec![0.0; self.inner.nq];
        if self.inner.is_floating() {
            q[6] = 1.0;
        }
        PyArray1::from_vec(py, q)
    }
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let f = py
            .import("twinloop._native")?
            .getattr("_model_from_state")?;
        let state = description_state(&self.description, self.order)
            .into_pyobject(py)?
            .into_any();
        let floating = self.floating.into_pyobject(py)?.to_owned().into_any();
        PyTuple::new(py, [f, PyTuple::new(py, [state, floating])?.into_any()])
    }
    fn __repr__(&self) -> String {
        format!(
            "<twinloop.Model {:?}: nq = {}, nv = {}, {} base, {:.3} kg>",
            self.inner.name,
            self.inner.nq,
            self.inner.nv,
            if self.floating { "floating" } else { "fixed" },
            self.inner.total_mass
        )
    }
}

/// The workspace of one model (Pinocchio's `Data`). Results are read-only numpy views
/// into it: no copy, up to date after every call, writing to them raises.
#[pyclass(name = "Data", module = "twinloop._native")]
pub struct PyData {
    pub model: Arc<Model>,
    pub data: Data,
}

impl PyData {
    /// The Rust data of `data` for `model`, or a ValueError if it was made for another.
    pub fn check_model(&self, model: &PyModel) -> PyResult<()> {
        if Arc::ptr_eq(&self.model, &model.inner) {
            Ok(())
        } else {
            Err(value_error(
                "data: made for another model (create it with Data(model))",
            ))
        }
    }
}

fn vec_view<'py>(
    slf: &Bound<'py, PyData>,
    f: impl Fn(&Data) -> &[f64],
) -> Bound<'py, PyArray1<f64>> {
    let this = slf.borrow();
    // SAFETY: the buffer lives in the Data object, allocated once in Data::new.
    unsafe { view_vector(slf.as_any(), f(&this.data)) }
}

fn mat_view<'py>(
    slf: &Bound<'py, PyData>,
    f: impl Fn(&Data) -> &nalgebra::DMatrix<f64>,
) -> Bound<'py, PyArray2<f64>> {
    let this = slf.borrow();
    // SAFETY: as in vec_view.
    unsafe { view_matrix(slf.as_any(), f(&this.data)) }
}

#[pymethods]
impl PyData {
    #[new]
    fn new(model: &Bound<'_, PyModel>) -> PyData {
        let m = model.get().inner.clone();
        PyData {
            data: Data::new(&m),
            model: m,
        }
    }

    /// Joint torques (nv,) from rnea, nonlinear_effects, compute_generalized_gravity (N m or N; the base wrench in the base frame).
    #[getter]
    fn tau<'py>(slf: &Bound<'py, Self>) -> Bound<'py, PyArray1<f64>> {
        vec_view(slf, |d| d.tau.as_slice())
    }

    /// Accelerations (nv,) from aba (rad/s^2 or m/s^2; base: linear then angular, base frame).
    #[getter]
    fn ddq<'py>(slf: &Bound<'py, Self>) -> Bound<'py, PyArray1<f64>> {
        vec_view(slf, |d| d.ddq.as_slice())
    }

    /// Centre of mass (3,), world frame (m), from center_of_mass and jacobian_center_of_mass.
    #[getter]
    fn com<'py>(slf: &Bound<'py, Self>) -> Bound<'py, PyArray1<f64>> {
        vec_view(slf, |d| d.com.as_slice())
    }

    /// Joint-space inertia matrix (nv, nv) from crba, full and symmetric (kg m^2, kg, kg m).
    #[getter]
    #[allow(non_snake_case)]
    fn M<'py>(slf: &Bound<'py, Self>) -> Bound<'py, PyArray2<f64>> {
        mat_view(slf, |d| &d.mass_matrix)
    }

    /// World-frame joint Jacobians (6, nv) from compute_joint_jacobians; rows linear then angular.
    #[getter]
    #[allow(non_snake_case)]
    fn J<'py>(slf: &Bound<'py, Self>) -> Bound<'py, PyArray2<f64>> {
        mat_view(slf, |d| &d.joint_jacobians)
    }

    /// CoM Jacobian (3, nv), world frame, from jacobian_center_of_mass.
    #[getter]
    #[allow(non_snake_case)]
    fn Jcom<'py>(slf: &Bound<'py, Self>) -> Bound<'py, PyArray2<f64>> {
        mat_view(slf, |d| &d.com_jacobian)
    }

    /// Inertial-parameter regressor (nv, 10 * bodies) from joint_torque_regressor.
    #[getter]
    fn joint_torque_regressor<'py>(slf: &Bound<'py, Self>) -> Bound<'py, PyArray2<f64>> {
        mat_view(slf, |d| &d.regressor)
    }

    /// Static CoM regressor (3, 4 * links) from static_com_regressor (not divided by the mass).
    #[getter]
    fn static_regressor<'py>(slf: &Bound<'py, Self>) -> Bound<'py, PyArray2<f64>> {
        mat_view(slf, |d| &d.static_regressor)
    }

    /// World placements of the bodies (list of (4, 4) homogeneous matrices, m), after
    /// forward_kinematics; body i is the child of joint i. Read-only copies: writing
    /// to one raises ValueError (it would not move the body).
    #[getter]
    #[allow(non_snake_case)]
    fn oMi<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyArray2<f64>>> {
        self.data.o_m_i.iter().map(|x| se3_matrix(py, x)).collect()
    }

    /// World placements of the frames (list of (4, 4), m), after
    /// frames_forward_kinematics. Read-only copies, as `oMi`.
    #[getter]
    #[allow(non_snake_case)]
    fn oMf<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyArray2<f64>>> {
        self.data.o_m_f.iter().map(|x| se3_matrix(py, x)).collect()
    }
}
