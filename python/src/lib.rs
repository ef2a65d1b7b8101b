//! twinloop-python: the `twinloop._native` extension module behind `import twinloop`.
//!
//! Models and dynamics with Pinocchio's names (`rnea(model, data, q, v, a)`), their
//! batched forms released from the GIL, the simulator and its parallel rollouts, and
//! the experiments and identification the CLI runs, with the CLI's JSON fields.
//! Arguments are checked before any Rust code that could panic sees them: a bad
//! shape or a NaN is a `ValueError` naming the argument.

mod arrays;
mod batch;
mod compliant;
mod dynamics;
mod errors;
mod experiments;
mod link;
mod model;
mod protocol_passes;
mod sim;
mod sysid;
mod tipover_bus;
mod values;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    // `record=`/`out=` paths ending in .mcap are written as MCAP, as the CLI's are.
    twinloop_io::sink::register_recording_format("mcap", twinloop_logs::open_mcap_recording);
    // `out="run/"`: a rosbag2 folder (the same MCAP, with the metadata ROS 2 reads).
    twinloop_io::sink::register_recording_format(
        twinloop_io::sink::FOLDER,
        twinloop_logs::open_mcap_recording,
    );
    m.add("ModelError", py.get_type::<errors::ModelError>())?;
    m.add_class::<model::PyDescription>()?;
    m.add_class::<model::PyModel>()?;
    m.add_class::<model::PyData>()?;
    m.add_class::<sim::PySimulator>()?;
    m.add_class::<link::PyBus>()?;
    m.add_class::<link::PyVirtualServer>()?;
    m.add("SimulationError", py.get_type::<sim::SimulationError>())?;
    m.add_function(wrap_pyfunction!(model::load, m)?)?;
    m.add_function(wrap_pyfunction!(model::_description_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(model::_model_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::forward_kinematics, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::frames_forward_kinematics, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::center_of_mass, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::jacobian_center_of_mass, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::compute_joint_jacobians, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::frame_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::rnea, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::nonlinear_effects, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::compute_generalized_gravity, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::crba, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::aba, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::joint_torque_regressor, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::static_com_regressor, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::body_parameters, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::link_static_parameters, m)?)?;
    m.add_function(wrap_pyfunction!(batch::rnea_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::aba_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::nonlinear_effects_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::crba_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::center_of_mass_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::jacobian_center_of_mass_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::compute_joint_jacobians_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::frame_jacobian_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::joint_torque_regressor_batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch::static_com_regressor_batch, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::tipover, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::random_changes, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::tipover_changes, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::static_poses, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::identify_static, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::training_samples, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::adapt, m)?)?;
    m.add_function(wrap_pyfunction!(protocol_passes::adapt_to_protocol, m)?)?;
    m.add_function(wrap_pyfunction!(compliant::fit_compliant, m)?)?;
    m.add_function(wrap_pyfunction!(sysid::sysid_arx, m)?)?;
    m.add_function(wrap_pyfunction!(sysid::sysid_ss, m)?)?;
    Ok(())
}
