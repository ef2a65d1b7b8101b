//! Black-box identification (`twinloop identify arx` / `identify ss`) on arrays,
//! returning the CLI JSON's fields.

use crate::arrays::{Arg, Dim};
use crate::errors::value_error;
use crate::values::to_py;
use pyo3::prelude::*;
use twinloop_sysid::json::{ArxJson, DataJson, SsOrdersJson, StateSpaceJson};
use twinloop_sysid::pem::{OutputWeight, PemOptions};
use twinloop_sysid::{
    ArxOrders, EvaluationOptions, IoData, SsMethod, SsOptions, identify_arx, identify_state_space,
};

/// A record from u (N, nu) and y (N, ny) arrays, channels named u0.. and y0.. unless named.
fn record(
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    which: (&'static str, &'static str),
    names: (Option<Vec<String>>, Option<Vec<String>>),
    sample_time: Option<f64>,
) -> PyResult<IoData> {
    let ua = Arg::new(u, which.0, &[Dim::Free("N"), Dim::Free("nu")])?;
    let (n, nu) = (ua.array_shape()[0], ua.array_shape()[1]);
    let ya = Arg::new(y, which.1, &[Dim::Is(n, "N (rows of u)"), Dim::Free("ny")])?;
    let ny = ya.array_shape()[1];
    if ny == 0 {
        return Err(value_error(format!(
            "{}: no output channel (shape ({n}, 0))",
            which.1
        )));
    }
    // One row per sample even when a side has no channel (nu = 0: an output-only record).
    let rows = |a: &Arg, w: usize| -> Vec<Vec<f64>> {
        (0..n)
            .map(|k| a.slice()[k * w..(k + 1) * w].to_vec())
            .collect()
    };
    let named = |given: Option<Vec<String>>,
                 prefix: &str,
                 count: usize,
                 what: &str|
     -> PyResult<Vec<String>> {
        match given {
            Some(v) if v.len() != count => Err(value_error(format!(
                "{what}: {} names for {count} channels",
                v.len()
            ))),
            Some(v) => Ok(v),
            None => Ok((0..count).map(|i| format!("{prefix}{i}")).collect()),
        }
    };
    let inputs = named(names.0, "u", nu, "input_names")?;
    let outputs = named(names.1, "y", ny, "output_names")?;
    IoData::from_samples(inputs, outputs, &rows(&ua, nu), &rows(&ya, ny), sample_time)
        .map_err(|e| value_error(format!("{}: {e}", which.0)))
}

fn eval_options(kstep: usize, lags: usize) -> EvaluationOptions {
    EvaluationOptions {
        prediction_horizon: kstep.max(1),
        max_lag: lags.max(1),
        ..EvaluationOptions::default()
    }
}

/// The estimation record, the optional validation record, and the input and output
/// means subtracted from both (when detrended).
struct Records {
    est: IoData,
    val: Option<IoData>,
    offsets: Option<(Vec<f64>, Vec<f64>)>,
}

#[allow(clippy::too_many_arguments)]
fn records(
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    u_val: Option<&Bound<'_, PyAny>>,
    y_val: Option<&Bound<'_, PyAny>>,
    input_names: Option<Vec<String>>,
    output_names: Option<Vec<String>>,
    sample_time: Option<f64>,
    detrend: bool,
) -> PyResult<Records> {
    let mut est = record(
        u,
        y,
        ("u", "y"),
        (input_names.clone(), output_names.clone()),
        sample_time,
    )?;
    let mut val = match (u_val, y_val) {
        (Some(uv), Some(yv)) => Some(record(
            uv,
            yv,
            ("u_val", "y_val"),
            (input_names, output_names),
            sample_time,
        )?),
        (None, None) => None,
        _ => return Err(value_error("u_val, y_val: give both or neither")),
    };
    // As the CLI does unless --no-detrend: the estimation record's means come off both.
    let offsets = detrend.then(|| {
        let (u0, y0) = est.means();
        est.remove_offsets(&u0, &y0);
        if let Some(v) = &mut val {
            v.remove_offsets(&u0, &y0);
        }
        (u0, y0)
    });
    Ok(Records { est, val, offsets })
}

fn data_json(r: &Records) -> DataJson {
    DataJson::new(
        "<python>".into(),
        r.val.as_ref().map(|_| "<python>".into()),
        &r.est,
        r.val.as_ref(),
        r.offsets.as_ref(),
    )
}

/// A MIMO ARX model (`twinloop identify arx --json`): u (N, nu), y (N, ny) samples;
/// na output lags, nb input lags, nk input delay; evaluated on (u_val, y_val) when
/// given. `detrend` (the CLI's default; False is --no-detrend) subtracts the
/// estimation record's means from both records. Returns the CLI JSON's fields (model,
/// evaluation with FIT %, timing).
#[pyfunction]
#[pyo3(signature = (u, y, na = 2, nb = 2, nk = 1, u_val = None, y_val = None, sample_time = None, input_names = None, output_names = None, kstep = 1, lags = 25, detrend = true))]
#[allow(clippy::too_many_arguments)]
pub fn sysid_arx<'py>(
    py: Python<'py>,
    u: &Bound<'py, PyAny>,
    y: &Bound<'py, PyAny>,
    na: usize,
    nb: usize,
    nk: usize,
    u_val: Option<&Bound<'py, PyAny>>,
    y_val: Option<&Bound<'py, PyAny>>,
    sample_time: Option<f64>,
    input_names: Option<Vec<String>>,
    output_names: Option<Vec<String>>,
    kstep: usize,
    lags: usize,
    detrend: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let r = records(
        u,
        y,
        u_val,
        y_val,
        input_names,
        output_names,
        sample_time,
        detrend,
    )?;
    let orders = ArxOrders { na, nb, nk };
    let t0 = std::time::Instant::now();
    let id = py
        .detach(|| identify_arx(&r.est, r.val.as_ref(), orders, &eval_options(kstep, lags)))
        .map_err(|e| value_error(e.to_string()))?;
    let elapsed = t0.elapsed().as_secs_f64();
    to_py(py, &ArxJson::new(&id, data_json(&r), orders, elapsed))
}

/// A state-space model (`twinloop identify ss --json`) of `order` states by `method`
/// ("n4sid", "pem", "arx-reduce-pem"); focus "prediction" or "simulation"; `detrend`
/// and the channel names as in `sysid_arx`.
#[pyfunction]
#[pyo3(signature = (u, y, order, method = "pem", u_val = None, y_val = None, sample_time = None, na = 10, nb = 10, nk = 1, max_iter = 100, feedthrough = false, estimate_x0 = false, focus = "prediction", kstep = 1, lags = 25, detrend = true, input_names = None, output_names = None))]
#[allow(clippy::too_many_arguments)]
pub fn sysid_ss<'py>(
    py: Python<'py>,
    u: &Bound<'py, PyAny>,
    y: &Bound<'py, PyAny>,
    order: usize,
    method: &str,
    u_val: Option<&Bound<'py, PyAny>>,
    y_val: Option<&Bound<'py, PyAny>>,
    sample_time: Option<f64>,
    na: usize,
    nb: usize,
    nk: usize,
    max_iter: usize,
    feedthrough: bool,
    estimate_x0: bool,
    focus: &str,
    kstep: usize,
    lags: usize,
    detrend: bool,
    input_names: Option<Vec<String>>,
    output_names: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyAny>> {
    let method = match method {
        "n4sid" => SsMethod::N4sid,
        "pem" => SsMethod::Pem,
        "arx-reduce-pem" => SsMethod::ArxReducePem,
        other => {
            return Err(value_error(format!(
                "method: \"{other}\" is not n4sid, pem or arx-reduce-pem"
            )));
        }
    };
    let focus: &'static str = match focus {
        "prediction" => "prediction",
        "simulation" => "simulation",
        other => {
            return Err(value_error(format!(
                "focus: \"{other}\" is not prediction or simulation"
            )));
        }
    };
    let r = records(
        u,
        y,
        u_val,
        y_val,
        input_names,
        output_names,
        sample_time,
        detrend,
    )?;
    let opts = SsOptions {
        order,
        method,
        arx_orders: ArxOrders { na, nb, nk },
        horizon: None,
        pem: PemOptions {
            max_iterations: max_iter,
            feedthrough,
            estimate_x0,
            weight: OutputWeight::Identity,
            output_error: focus == "simulation",
            ..PemOptions::default()
        },
        evaluation: eval_options(kstep, lags),
    };
    let t0 = std::time::Instant::now();
    let id = py
        .detach(|| identify_state_space(&r.est, r.val.as_ref(), &opts, &mut |_| {}))
        .map_err(|e| value_error(e.to_string()))?;
    let elapsed = t0.elapsed().as_secs_f64();
    let orders = SsOrdersJson {
        order,
        arx: (method == SsMethod::ArxReducePem).then_some(opts.arx_orders),
    };
    to_py(
        py,
        &StateSpaceJson::new(&id, data_json(&r), focus, orders, elapsed),
    )
}
