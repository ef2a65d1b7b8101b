//! Experiments and identification, returning dicts with the fields of the CLI's JSON
//! (the same serde types, turned into Python through `json`).

use crate::arrays::{Arg, Dim, new_array};
use crate::batch::thread_count;
use crate::errors::value_error;
use crate::model::PyModel;
use crate::sim::{description_arg, description_arg_ordered};
use crate::values::{study_arg, to_py};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use twinloop_description::Description;
use twinloop_dynamics::JointOrder;
use twinloop_ident::ann_data::{self, Change, DataOptions};
use twinloop_ident::plate::{PlateOptions, generate_static_poses};
use twinloop_ident::static_ident::StaticOptions;
use twinloop_ident::tipover_study::{StudyOptions, run_study};
use twinloop_ident::{IdentError, PoseCategory, StaticPose, identify_static as ident_static};
use twinloop_random::SplitMix64;

fn ident_error(e: IdentError) -> PyErr {
    value_error(e.to_string())
}

fn study_options(
    ramp: f64,
    slow_ramp: f64,
    compliance_slope: f64,
    encoders: bool,
) -> PyResult<StudyOptions> {
    for (x, name) in [
        (ramp, "ramp"),
        (slow_ramp, "slow_ramp"),
        (compliance_slope, "compliance_slope"),
    ] {
        if !(x > 0.0 && x.is_finite()) {
            return Err(value_error(format!("{name}: must be positive, got {x}")));
        }
    }
    Ok(StudyOptions {
        ramp_deg_per_s: ramp,
        slow_ramp_deg_per_s: slow_ramp,
        dynamixel_encoders: encoders,
        compliance_units: Some((compliance_slope, 0.0)),
        ..Default::default()
    })
}

/// A change given as a dict {"link": str, "mass": kg, "xyz": [x, y, z] (m, link frame)}.
fn change_arg(c: &Bound<'_, PyAny>, k: usize) -> PyResult<Change> {
    let bad = |what: &str| value_error(format!("changes[{k}]: {what}"));
    let link: String = c
        .get_item("link")
        .and_then(|x| x.extract())
        .map_err(|_| bad("needs \"link\" (str)"))?;
    let mass: f64 = c
        .get_item("mass")
        .and_then(|x| x.extract())
        .map_err(|_| bad("needs \"mass\" (kg)"))?;
    let xyz: [f64; 3] = c
        .get_item("xyz")
        .and_then(|x| x.extract())
        .map_err(|_| bad("needs \"xyz\" (3 numbers, m)"))?;
    if !(mass.is_finite() && xyz.iter().all(|x| x.is_finite())) {
        return Err(bad("mass and xyz must be finite"));
    }
    Ok(Change { link, mass, xyz })
}

/// The simulated tip-over experiment of seeds 000 and 001 (`twinloop experiment
/// tipover --robot ... --json`): four directions, tip angles (deg), the CoM by the
/// seed's and the exact method (m) beside the model's. `add_mass`: point masses
/// added first, like `--add-mass`: each `"KG@LINK:X,Y,Z"` (the CLI's form) or
/// (kg, link, (x, y, z)), x, y, z m in the link frame; one or a list.
///
/// With `port` (and `map`, the servo mapping: builtin:km20 or a mapping TOML), the
/// experiment runs on a robot over its Dynamixel bus instead, as `twinloop experiment
/// tipover --port PORT --map MAP --json`: each direction of `directions` (default all
/// four) twice, the servos left holding the standing pose; `robot` is then the model
/// for the lean signs (default: the mapping's `urdf`). All four directions give the
/// study's fields, fewer give `robot`, `port` and each direction's angles. `record`:
/// every cycle read to that CSV; `realtime_factor`: a simulated robot served faster
/// than real time; `ankle_slope`: the ramped ankles' RX Compliance Slope; `creeps`:
/// creeping approaches per direction (the closest two averaged, one more when they
/// differ by over 0.2 deg); `dither`: sigma-delta goal counts for the joints a lean
/// turns (False: whole counts, as `--goal-counts staircase`); every servo is made
/// stiff through the servo catalogue and put back afterwards, and a servo model with
/// no known way to stiffen raises ValueError before anything moves unless
/// `soft_servos=True` (as `--soft-servos`: the servos left as they are, the result's
/// `soft_servos` true). On a serial
/// port the robot moves only with `yes=True`. A silent or faulty servo, or Ctrl-C,
/// stops the run with OSError (KeyboardInterrupt for Ctrl-C).
#[pyfunction]
#[pyo3(signature = (robot = None, ramp = 0.5, slow_ramp = 0.05, compliance_slope = 2.0, encoders = false,
    add_mass = None, *, port = None, map = None, directions = None, record = None, yes = false,
    realtime_factor = 1.0, ankle_slope = 32.0, creeps = 2, dither = true, baud = 1_000_000, timeout_ms = 10.0, retries = 2, soft_servos = false))]
#[allow(clippy::too_many_arguments)]
pub fn tipover<'py>(
    py: Python<'py>,
    robot: Option<&Bound<'py, PyAny>>,
    ramp: f64,
    slow_ramp: f64,
    compliance_slope: f64,
    encoders: bool,
    add_mass: Option<&Bound<'py, PyAny>>,
    port: Option<String>,
    map: Option<String>,
    directions: Option<Vec<String>>,
    record: Option<std::path::PathBuf>,
    yes: bool,
    realtime_factor: f64,
    ankle_slope: f64,
    creeps: usize,
    dither: bool,
    baud: u32,
    timeout_ms: f64,
    retries: u32,
    soft_servos: bool,
) -> PyResult<Bound<'py, PyAny>> {
    if port.is_some() || map.is_some() {
        if encoders || add_mass.is_some() {
            return Err(value_error(
                "encoders, add_mass: only for the simulator (a robot on a bus has its own)",
            ));
        }
        let plan = crate::tipover_bus::Plan {
            port,
            map,
            directions: directions.unwrap_or_default(),
            record,
            yes,
            ramp,
            slow_ramp,
            compliance_slope,
            ankle_slope,
            creeps,
            dither,
            realtime_factor,
            baud,
            timeout_ms,
            retries,
            soft_servos,
        };
        return crate::tipover_bus::run(py, robot, plan);
    }
    if directions.is_some() || record.is_some() {
        return Err(value_error(
            "directions, record: only over a bus (port= and map=)",
        ));
    }
    let Some(robot) = robot else {
        return Err(value_error(
            "robot: give a robot (the simulator) or port= and map= (a robot over its bus)",
        ));
    };
    let mut d: Description = (*description_arg(robot)?).clone();
    for (kg, link, xyz) in added_masses(add_mass)? {
        twinloop_description::builtin::add_point_mass(&mut d, &link, kg, xyz)
            .map_err(|e| value_error(format!("add_mass \"{kg}@{link}\": {e}")))?;
    }
    let opts = study_options(ramp, slow_ramp, compliance_slope, encoders)?;
    let report = py.detach(|| run_study(&d, &opts)).map_err(ident_error)?;
    to_py(py, &report)
}

/// `add_mass`: one point mass or a list of them, each `"KG@LINK:X,Y,Z"` (the CLI's
/// `--add-mass`, read by the same parser) or a tuple (kg, link, xyz).
fn added_masses(add_mass: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<(f64, String, [f64; 3])>> {
    let Some(a) = add_mass else {
        return Ok(Vec::new());
    };
    let one = |x: &Bound<'_, PyAny>| -> PyResult<(f64, String, [f64; 3])> {
        if let Ok(s) = x.extract::<String>() {
            return twinloop_description::builtin::parse_point_mass(&s)
                .map_err(|e| value_error(format!("add_mass {}", e.message)));
        }
        x.extract().map_err(|_| {
            value_error(
                "add_mass: expected \"KG@LINK:X,Y,Z\" or (kg, link, (x, y, z)), or a list of them",
            )
        })
    };
    if a.extract::<String>().is_ok() {
        return Ok(vec![one(a)?]);
    }
    let items: Vec<Bound<'_, PyAny>> = a.extract().map_err(|_| {
        value_error(
            "add_mass: expected \"KG@LINK:X,Y,Z\" or (kg, link, (x, y, z)), or a list of them",
        )
    })?;
    items.iter().map(one).collect()
}

/// Random hardware changes of a robot: `n` dicts {link, mass (kg), xyz (m)}, a point
/// mass inside a link's collision outline, drawn from `seed`.
#[pyfunction]
#[pyo3(signature = (robot, n, seed = 1, mass_range = (0.05, 0.5)))]
pub fn random_changes<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyAny>,
    n: usize,
    seed: u64,
    mass_range: (f64, f64),
) -> PyResult<Bound<'py, PyAny>> {
    let d = description_arg(robot)?;
    let links = ann_data::outlined_links(&d);
    if links.is_empty() {
        return Err(value_error(format!(
            "robot: \"{}\" has no link with a collision outline",
            d.name
        )));
    }
    if !(mass_range.0 > 0.0 && mass_range.1 >= mass_range.0 && mass_range.1.is_finite()) {
        return Err(value_error(format!(
            "mass_range: needs 0 < low <= high, got {:?}",
            mass_range
        )));
    }
    let mut rng = SplitMix64(seed);
    let changes: Vec<Change> = (0..n)
        .map(|_| ann_data::random_change(&d, &links, mass_range, &mut rng))
        .collect();
    to_py(py, &changes)
}

/// The tip-over of each change: the static route's four fall angles (deg: forward,
/// backward, left, right) and CoM (m, standing frame), and with `simulate=True` the
/// full simulated study's measured angles too. Runs on `threads` threads (default
/// every core) with the GIL released; returns one dict per change, in order.
#[pyfunction]
#[pyo3(signature = (robot, changes, simulate = false, ramp = 0.5, slow_ramp = 0.05, threads = None))]
pub fn tipover_changes<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyAny>,
    changes: &Bound<'py, PyList>,
    simulate: bool,
    ramp: f64,
    slow_ramp: f64,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyList>> {
    let d = description_arg(robot)?;
    let changes: Vec<Change> = changes
        .iter()
        .enumerate()
        .map(|(k, c)| change_arg(&c, k))
        .collect::<PyResult<_>>()?;
    let opts = study_options(ramp, slow_ramp, 2.0, false)?;
    let threads = thread_count(threads)?;
    let foot = ann_data::training_foot(&d).map_err(ident_error)?;
    let rows = py
        .detach(|| {
            parallel(changes.len(), threads, |i| -> Result<_, IdentError> {
                let changed = ann_data::changed(&d, &changes[i])?;
                let s = ann_data::static_tip(&changed, &foot)?;
                let sim = if simulate {
                    let r = run_study(&changed, &opts)?;
                    Some([
                        r.forward.measured_deg,
                        r.backward.measured_deg,
                        r.left.measured_deg,
                        r.right.measured_deg,
                    ])
                } else {
                    None
                };
                Ok((s.angles.to_degrees(), s.com, s.total_mass, sim))
            })
        })
        .map_err(|(i, e)| value_error(format!("changes[{i}]: {e}")))?;
    let out = PyList::empty(py);
    for (c, (deg, com, mass, sim)) in changes.iter().zip(rows) {
        let row = PyDict::new(py);
        row.set_item("change", to_py(py, c)?)?;
        row.set_item("static_deg", deg.to_vec())?;
        row.set_item("com", com.to_vec())?;
        row.set_item("total_mass", mass)?;
        row.set_item("simulated_deg", sim.map(|s| s.to_vec()))?;
        out.append(row)?;
    }
    Ok(out)
}

/// `f(i)` for i in 0..n on `threads` threads, results in order; the first error
/// with its index.
fn parallel<T: Send, E: std::fmt::Display>(
    n: usize,
    threads: usize,
    f: impl Fn(usize) -> Result<T, E> + Sync,
) -> Result<Vec<T>, (usize, String)> {
    let threads = threads.min(n).max(1);
    let per = n.div_ceil(threads).max(1);
    let parts: Vec<Option<Vec<Result<T, String>>>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let f = &f;
                s.spawn(move || {
                    (t * per..((t + 1) * per).min(n))
                        .map(|i| f(i).map_err(|e| e.to_string()))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().ok()).collect()
    });
    let mut out = Vec::with_capacity(n);
    for part in parts {
        let part = part.ok_or((
            out.len(),
            "a worker thread stopped unexpectedly".to_string(),
        ))?;
        for r in part {
            let i = out.len();
            out.push(r.map_err(|e| (i, e))?);
        }
    }
    Ok(out)
}

/// Poses from the virtual force plate (`twinloop experiment static-poses`, seed 004
/// section 3.1): q (P, nq) with joint noise (rad), the measured CoP (P, 2) (m) with
/// plate noise, and each pose's category.
#[pyfunction]
#[pyo3(signature = (robot, count = 172, cop_noise = 0.0, joint_noise = 0.0, seed = 1))]
pub fn static_poses<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyAny>,
    count: usize,
    cop_noise: f64,
    joint_noise: f64,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    for (x, name) in [(cop_noise, "cop_noise"), (joint_noise, "joint_noise")] {
        if !(x >= 0.0 && x.is_finite()) {
            return Err(value_error(format!("{name}: must be >= 0, got {x}")));
        }
    }
    let (d, order) = description_arg_ordered(robot)?;
    // The poses are drawn joint by joint in the CLI's (file) order, so that one seed
    // gives the CLI's poses, then put in the package's order.
    let model = PyModel::build(d.clone(), JointOrder::File, true)?;
    let ours = PyModel::build(d.clone(), order, true)?;
    let perm = crate::model::q_permutation(&model.inner, &ours.inner);
    let options = PlateOptions {
        count,
        cop_noise,
        joint_noise,
        seed,
        ..Default::default()
    };
    let generated = py
        .detach(|| generate_static_poses(&d, &model.inner, &options, |_| {}))
        .map_err(ident_error)?;
    let nq = model.inner.nq;
    let poses: Vec<&StaticPose> = generated.poses.iter().map(|g| &g.pose).collect();
    let q: Vec<f64> = poses
        .iter()
        .flat_map(|p| perm.iter().map(|&k| p.q[k]))
        .collect();
    let cop: Vec<f64> = poses.iter().flat_map(|p| p.cop).collect();
    let out = PyDict::new(py);
    out.set_item("q", new_array(py, q, &[poses.len(), nq])?)?;
    out.set_item("cop", new_array(py, cop, &[poses.len(), 2])?)?;
    out.set_item(
        "category",
        poses
            .iter()
            .map(|p| p.category.map(|c| c.name()))
            .collect::<Vec<_>>(),
    )?;
    Ok(out)
}

/// Static identification of link masses and CoMs (`twinloop identify static`, seed
/// 004 eq 8-9) from P poses: q (P, nq), the measured CoP cop (P, 2) (m), the robot's
/// weighed total_mass (kg). Returns the CLI JSON's fields (schema, cop_sigma,
/// com_margin, result).
#[pyfunction]
#[pyo3(signature = (robot, q, cop, total_mass, links = None, cop_sigma = 1e-3, com_margin = 0.03, category = None))]
#[allow(clippy::too_many_arguments)]
pub fn identify_static<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    cop: &Bound<'py, PyAny>,
    total_mass: f64,
    links: Option<Vec<String>>,
    cop_sigma: f64,
    com_margin: f64,
    category: Option<Vec<Option<String>>>,
) -> PyResult<Bound<'py, PyAny>> {
    let (d, order) = description_arg_ordered(robot)?;
    // q comes in the package's joint order; the fit runs in the CLI's (file) order, so
    // that the same poses give the command's numbers (a rank decision included).
    let model = PyModel::build(d.clone(), JointOrder::File, true)?.inner;
    let ours = PyModel::build(d.clone(), order, true)?.inner;
    let perm = crate::model::q_permutation(&ours, &model);
    let qa = Arg::new(q, "q", &[Dim::Free("P"), Dim::Is(model.nq, "nq")])?;
    let n = qa.rows();
    let ca = Arg::new(cop, "cop", &[Dim::Is(n, "P (rows of q)"), Dim::Is(2, "")])?;
    if !(total_mass > 0.0 && total_mass.is_finite()) {
        return Err(value_error(format!(
            "total_mass: must be positive, got {total_mass}"
        )));
    }
    if let Some(c) = &category
        && c.len() != n
    {
        return Err(value_error(format!(
            "category: {} entries for {n} poses",
            c.len()
        )));
    }
    let poses: Vec<StaticPose> = (0..n)
        .map(|i| -> PyResult<StaticPose> {
            let cat = match category.as_ref().and_then(|c| c[i].as_deref()) {
                None => None,
                Some(s) => Some(PoseCategory::from_name(s).ok_or_else(|| {
                    value_error(format!("category[{i}]: unknown category \"{s}\""))
                })?),
            };
            let row = &qa.slice()[i * model.nq..(i + 1) * model.nq];
            Ok(StaticPose {
                q: perm.iter().map(|&k| row[k]).collect(),
                cop: [ca.slice()[2 * i], ca.slice()[2 * i + 1]],
                category: cat,
            })
        })
        .collect::<PyResult<_>>()?;
    let options = StaticOptions {
        links,
        cop_sigma,
        com_margin,
        ..StaticOptions::default()
    };
    let result = py
        .detach(|| ident_static(&d, &model, &poses, total_mass, &options))
        .map_err(ident_error)?;
    let json = serde_json::json!({
        "schema": "twinloop-static-identification/1",
        "cop_sigma": cop_sigma,
        "com_margin": com_margin,
        "result": &result,
    });
    to_py(py, &json)
}

/// ANN training samples `start..stop` of `twinloop adapt train`'s set (the same
/// draws whatever the split, so ranges can run on different machines): per sample the
/// change, its body part, the true and noisy static fall angles (deg), the CoM (m),
/// total_mass (kg), feet (mass fraction, x, z), and the three-mass LIPM's masses (kg)
/// and positions (m): what `twinloop adapt train --ray` trains on.
#[pyfunction]
#[pyo3(signature = (robot, start, stop, seed = 1, mass_range = (0.05, 0.5), noise_deg = 0.0, threads = None))]
#[allow(clippy::too_many_arguments)]
pub fn training_samples<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyAny>,
    start: usize,
    stop: usize,
    seed: u64,
    mass_range: (f64, f64),
    noise_deg: f64,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    if stop < start {
        return Err(value_error(format!("stop: {stop} is before start {start}")));
    }
    let d = description_arg(robot)?;
    let opts = DataOptions {
        samples: stop,
        seed,
        mass_range,
        noise_deg,
        threads: thread_count(threads)?,
    };
    let (_, samples) = py
        .detach(|| ann_data::generate_range(&d, &opts, start..stop, &|_| {}))
        .map_err(ident_error)?;
    to_py(py, &samples)
}

/// Adapt the model to a tip-over experiment (`twinloop adapt --tipover FILE --json`,
/// seed 000 sections III and V.B): `tipover` is `tipover()`'s dict (or a JSON file's
/// contents). `total_mass` (kg) or `host` (the link the mass went on) fixes the added
/// mass; `check=True` reruns the tip-over on the adapted model. Returns (the report's
/// fields, the adapted Description or None when the family is not fixed).
#[pyfunction]
#[pyo3(signature = (prior, tipover, total_mass = None, host = None, merge = false, resolution = None, check = false))]
#[allow(clippy::too_many_arguments)]
pub fn adapt<'py>(
    py: Python<'py>,
    prior: &Bound<'py, PyAny>,
    tipover: &Bound<'py, PyAny>,
    total_mass: Option<f64>,
    host: Option<String>,
    merge: bool,
    resolution: Option<f64>,
    check: bool,
) -> PyResult<(Bound<'py, PyAny>, Option<crate::model::PyDescription>)> {
    let d = description_arg(prior)?;
    let tip = study_arg(py, tipover)?;
    if let Some(r) = resolution
        && !(r > 0.0 && r.is_finite())
    {
        return Err(value_error(format!(
            "resolution: must be positive, got {r}"
        )));
    }
    // The CLI's rule: over a bus, the mapping's ankle servo's half count.
    let resolution = twinloop_loop::bus_plan::tipover_resolution_deg(resolution, &tip)
        .map_err(crate::tipover_bus::loop_error)?;
    let opts = twinloop_ident::adapt::AdaptOptions {
        total_mass,
        host,
        merge,
        angle_resolution_deg: Some(resolution),
        protocol_bias_deg: None,
    };
    let adapted = py
        .detach(|| {
            let mut a = twinloop_ident::adapt::adapt(&d, &tip, &opts)?;
            if check {
                twinloop_ident::adapt::check(&mut a, &StudyOptions::default())?;
            }
            Ok::<_, IdentError>(a)
        })
        .map_err(ident_error)?;
    let robot = adapted.robot.map(crate::model::PyDescription::urdf);
    Ok((to_py(py, &adapted.report)?, robot))
}
