//! `adapt_to_protocol`: the adaptation made again less the bias of the protocol a
//! tip-over over a bus was measured by (`twinloop adapt --protocol-passes N`): the
//! keywords mapped onto `twinloop_loop::protocol_bias`, which runs the passes.

use crate::errors::value_error;
use crate::sim::description_arg_ordered;
use crate::tipover_bus::loop_error;
use crate::values::{study_arg, to_py};
use pyo3::prelude::*;
use twinloop_ident::adapt::AdaptOptions;
use twinloop_loop::LoopError;
use twinloop_loop::adapt_to_protocol as passes_on;
use twinloop_loop::protocol_bias::{REPLAY_GROUND_SINK, Replay, replay_options};

/// Adapt `prior` to `tipover` (a tip-over measured over a bus: its `protocol`) in
/// `passes` passes, as `twinloop adapt --tipover FILE --protocol-passes N --json`:
/// each pass simulates the same protocol on the adapted model, in lockstep with a
/// host at the robot run's cycle (on a floor sinking `ground_sink` m; None: the
/// floor on which the adapted model tips sideways as the robot did, found by up to
/// six replays, as the CLI without `--ground-sink`), and adapts again
/// to the measured angles less what it read past the model's static angles; the last
/// pass is kept. Returns (the report's fields, the adapted Description or None, the
/// passes as `demo --json`'s `calibration` or None when none ran).
#[pyfunction]
#[pyo3(signature = (prior, tipover, passes = 3, total_mass = None, host = None, merge = false, resolution = None, ground_sink = None))]
#[allow(clippy::too_many_arguments)]
pub fn adapt_to_protocol<'py>(
    py: Python<'py>,
    prior: &Bound<'py, PyAny>,
    tipover: &Bound<'py, PyAny>,
    passes: usize,
    total_mass: Option<f64>,
    host: Option<String>,
    merge: bool,
    resolution: Option<f64>,
    ground_sink: Option<f64>,
) -> PyResult<(
    Bound<'py, PyAny>,
    Option<crate::model::PyDescription>,
    Bound<'py, PyAny>,
)> {
    let (d, order) = description_arg_ordered(prior)?;
    let model_spec = prior.extract::<String>().unwrap_or_else(|_| d.name.clone());
    let tip = study_arg(py, tipover)?;
    let given = [(resolution, "resolution"), (ground_sink, "ground_sink")];
    for (x, name) in given.iter().filter_map(|(x, n)| x.map(|x| (x, *n))) {
        if !(x > 0.0 && x.is_finite()) {
            return Err(value_error(format!("{name}: must be positive, got {x}")));
        }
    }
    if passes > 5 {
        return Err(value_error(format!("passes: at most 5, got {passes}")));
    }
    // The CLI's rule: over a bus, the mapping's ankle servo's half count.
    let resolution =
        twinloop_loop::bus_plan::tipover_resolution_deg(resolution, &tip).map_err(loop_error)?;
    let opts = AdaptOptions {
        total_mass,
        host,
        merge,
        angle_resolution_deg: Some(resolution),
        protocol_bias_deg: None,
    };
    let options = replay_options(ground_sink.unwrap_or(REPLAY_GROUND_SINK));
    let replay = Replay {
        model_spec: &model_spec,
        host: &d,
        passes,
        options: &options,
        fit_floor: ground_sink.is_none(),
        other_places: true,
    };
    let (adapted, calibration) = py
        .detach(|| {
            passes_on(&d, &tip, &opts, &replay, &mut |_| {}, &|e| {
                LoopError::from(e)
            })
        })
        .map_err(loop_error)?;
    let robot = adapted.robot.map(|r| crate::model::PyDescription {
        inner: std::sync::Arc::new(r),
        order,
    });
    Ok((to_py(py, &adapted.report)?, robot, to_py(py, &calibration)?))
}
