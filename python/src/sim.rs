//! `Simulator`: the time-stepping simulator with state as arrays, sensors as a dict,
//! and `rollout`: many independent rollouts on all cores with the GIL released (the
//! shape of `mujoco.rollout`).

use crate::arrays::{Arg, Dim, new_array, read_only_vector};
use crate::batch::thread_count;
use crate::errors::value_error;
use crate::model::{PyDescription, load_ordered};
use numpy::{PyArray1, PyArrayDyn};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Arc;
use twinloop_description::Description;
use twinloop_dynamics::{BaseKind, JointOrder, Model};
use twinloop_robot::RobotState;
use twinloop_sim::{Actuator, DynamixelServo, SimConfig, Simulator};

pyo3::create_exception!(
    twinloop,
    SimulationError,
    pyo3::exceptions::PyRuntimeError,
    "The simulation diverged (the state became non-finite)."
);

/// How to build a simulator: everything `Simulator(robot, config)` accepts.
#[derive(Clone, Debug)]
pub struct Settings {
    pub dt: f64,
    /// "auto", "rx28", "rx64", "xm430", "passive" or "torque".
    pub servo: String,
    pub ground: bool,
    /// Start standing on the ground at the neutral pose (clamped into the limits).
    pub stand: bool,
    /// The joint order of q, v and the goals: the description's (Pinocchio's).
    pub order: JointOrder,
}

impl Settings {
    pub fn from_dict(config: Option<&Bound<'_, PyDict>>) -> PyResult<Settings> {
        let mut s = Settings {
            dt: 1e-3,
            servo: "auto".into(),
            ground: true,
            stand: true,
            order: JointOrder::File,
        };
        let Some(c) = config else { return Ok(s) };
        for (k, v) in c.iter() {
            let key: String = k.extract()?;
            let bad = |what: &str| value_error(format!("config[\"{key}\"]: {what}"));
            match key.as_str() {
                "dt" => {
                    s.dt = v.extract().map_err(|_| bad("expected a number (s)"))?;
                    if !(s.dt > 0.0 && s.dt.is_finite()) {
                        return Err(bad(&format!(
                            "the time step must be positive, not {}",
                            s.dt
                        )));
                    }
                }
                "servo" => {
                    s.servo = v.extract().map_err(|_| bad("expected a str"))?;
                    if !["auto", "rx28", "rx64", "xm430", "passive", "torque"]
                        .contains(&s.servo.as_str())
                    {
                        return Err(bad("expected auto, rx28, rx64, xm430, passive or torque"));
                    }
                }
                "ground" => s.ground = v.extract().map_err(|_| bad("expected a bool"))?,
                "stand" => s.stand = v.extract().map_err(|_| bad("expected a bool"))?,
                _ => return Err(bad("unknown key (dt, servo, ground, stand)")),
            }
        }
        Ok(s)
    }
}

fn actuator(servo: &str, robot: &str, model: &twinloop_dynamics::Model, i: usize) -> Actuator {
    let s: DynamixelServo = match servo {
        "passive" => return Actuator::Passive,
        "torque" => return Actuator::Torque,
        "rx28" => DynamixelServo::rx28(),
        "rx64" => DynamixelServo::rx64(),
        "xm430" => twinloop_sim::servo_from_limits(f64::NAN, f64::NAN, 0.0),
        _ => twinloop_sim::servo_for_joint(robot, model, i),
    };
    Actuator::Dynamixel(s)
}

/// Build a simulator as `twinloop simulate` does: floating base, each joint on its
/// servo, standing on the ground at the neutral pose.
pub fn build(robot: &Description, s: &Settings) -> Result<Simulator, String> {
    let cfg = SimConfig {
        dt: s.dt,
        ground: s.ground,
        ..Default::default()
    };
    let model = Model::from_description_ordered(robot, BaseKind::Floating, s.order)
        .map_err(|e| e.to_string())?;
    let mut sim = Simulator::from_model(robot, model, cfg).map_err(|e| e.to_string())?;
    for i in 0..sim.model.nbodies {
        sim.actuators[i] = actuator(&s.servo, &robot.name, &sim.model, i);
    }
    if s.stand {
        // The simulator's own standing: its pose, and its refusal of a robot with
        // nothing to stand on (as `Simulator::standing_on_servos`, whose servos are
        // Dynamixels only; here a joint may be passive or torque-driven).
        if s.ground {
            sim.check_can_stand().map_err(|e| e.to_string())?;
        }
        let pose = twinloop_sim::standing_pose(&sim.model);
        sim.place_on_ground(&pose).map_err(|e| e.to_string())?;
    }
    Ok(sim)
}

/// Reset to (q, v) at time 0: contacts released, actuator states at the joints.
fn reset(sim: &mut Simulator, q: &[f64], v: &[f64]) -> Result<(), String> {
    let o = sim.model.q_offset;
    sim.set_joint_positions(&q[o..])
        .map_err(|e| e.to_string())?;
    sim.q[..o].copy_from_slice(&q[..o]);
    sim.v.copy_from_slice(v);
    sim.time = 0.0;
    Ok(())
}

/// A robot description from a Description or a path / builtin name.
pub fn description_arg(robot: &Bound<'_, PyAny>) -> PyResult<Arc<Description>> {
    description_arg_ordered(robot).map(|(d, _)| d)
}

/// As [`description_arg`], with the joint order its models use (Pinocchio's).
pub fn description_arg_ordered(
    robot: &Bound<'_, PyAny>,
) -> PyResult<(Arc<Description>, JointOrder)> {
    if let Ok(d) = robot.cast::<PyDescription>() {
        return Ok((d.get().inner.clone(), d.get().order));
    }
    let spec: String = robot
        .extract()
        .or_else(|_| robot.call_method0("__fspath__").and_then(|p| p.extract()))
        .map_err(|_| value_error("robot: expected a Description, a path or \"builtin:NAME\""))?;
    let (d, order) = load_ordered(&spec)?;
    Ok((Arc::new(d), order))
}

/// The simulator: a floating-base robot on the ground, its joints on servos.
#[pyclass(name = "Simulator", module = "twinloop._native")]
pub struct PySimulator {
    pub description: Arc<Description>,
    pub settings: Settings,
    pub sim: Simulator,
}

#[pymethods]
impl PySimulator {
    /// `robot`: a Description, a URDF/MJCF path or "builtin:NAME". `config`: a dict
    /// with dt (s, default 1e-3), servo ("auto" (the robot's own or one from its
    /// limits), "rx28", "rx64", "xm430", "passive", "torque"), ground (bool) and
    /// stand (bool: start standing on the ground at the neutral pose).
    #[new]
    #[pyo3(signature = (robot, config = None))]
    fn new(robot: &Bound<'_, PyAny>, config: Option<&Bound<'_, PyDict>>) -> PyResult<PySimulator> {
        let (description, order) = description_arg_ordered(robot)?;
        let settings = Settings {
            order,
            ..Settings::from_dict(config)?
        };
        let sim = build(&description, &settings).map_err(value_error)?;
        Ok(PySimulator {
            description,
            settings,
            sim,
        })
    }

    /// Advance `n` steps of dt. Raises SimulationError if the state diverges.
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, py: Python<'_>, n: usize) -> PyResult<()> {
        let sim = &mut self.sim;
        py.detach(|| {
            for _ in 0..n {
                sim.step()?;
            }
            Ok::<(), twinloop_sim::SimError>(())
        })
        .map_err(|e| SimulationError::new_err(e.to_string()))
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time
    }
    /// Time step, s.
    #[getter]
    fn dt(&self) -> f64 {
        self.sim.dt()
    }
    #[getter]
    fn nq(&self) -> usize {
        self.sim.model.nq
    }
    #[getter]
    fn nv(&self) -> usize {
        self.sim.model.nv
    }
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.sim.model.joint_names.clone()
    }
    /// Configuration (nq,): [x, y, z (m), qx, qy, qz, qw, joints (rad)]. A read-only
    /// copy (writing raises ValueError); change it with set_state.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only_vector(py, &self.sim.q)
    }
    /// Velocity (nv,): [linear (m/s), angular (rad/s, base frame), joints (rad/s)]. A
    /// read-only copy; change it with set_state.
    #[getter]
    fn v<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only_vector(py, &self.sim.v)
    }
    /// The state as one array (nq + nv,): q then v.
    fn get_state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let mut s = self.sim.q.clone();
        s.extend_from_slice(&self.sim.v);
        PyArray1::from_vec(py, s)
    }
    /// Set q (nq,) and v (nv,), time kept; contacts released.
    fn set_state(&mut self, q: &Bound<'_, PyAny>, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let m = &self.sim.model;
        let q = Arg::new(q, "q", &[Dim::Is(m.nq, "nq")])?;
        let v = Arg::new(v, "v", &[Dim::Is(m.nv, "nv")])?;
        let t = self.sim.time;
        reset(&mut self.sim, q.slice(), v.slice()).map_err(value_error)?;
        self.sim.time = t;
        Ok(())
    }
    /// Joint goals (joints,) (rad for servos, N m for torque actuators). A read-only
    /// copy: assign the whole array (`sim.goals = g`) to change them.
    #[getter]
    fn goals<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only_vector(py, &self.sim.goals)
    }
    #[setter]
    fn set_goals(&mut self, goals: &Bound<'_, PyAny>) -> PyResult<()> {
        let g = Arg::new(goals, "goals", &[Dim::Is(self.sim.goals.len(), "joints")])?;
        self.sim.goals.copy_from_slice(g.slice());
        Ok(())
    }
    /// Torque (joints,) each actuator applied in the last step (N m); read-only.
    #[getter]
    fn applied<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only_vector(py, &self.sim.applied)
    }
    /// Centre of mass (3,), world, m.
    fn center_of_mass<'py>(&mut self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.sim.center_of_mass().as_slice())
    }

    /// What the robot's sensors read now, as the `Robot` seam gives it: time (s),
    /// positions (rad), velocities (rad/s), efforts (N m), imu_gyro (rad/s),
    /// imu_accel (m/s^2), imu_orientation (x, y, z, w), foot_force (N, one per foot),
    /// foot_cop ((feet, 2), m, NaN without contact), foot_names.
    fn sensors<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut st = RobotState::default();
        self.sim.read_sensors(&mut st);
        let d = PyDict::new(py);
        d.set_item("time", st.time)?;
        d.set_item("positions", PyArray1::from_vec(py, st.positions))?;
        let opt = |x: Option<Vec<f64>>| x.map(|v| PyArray1::from_vec(py, v));
        d.set_item("velocities", opt(st.velocities))?;
        d.set_item("efforts", opt(st.efforts))?;
        if let Some(imu) = st.imu {
            d.set_item("imu_gyro", PyArray1::from_slice(py, &imu.gyro))?;
            d.set_item("imu_accel", PyArray1::from_slice(py, &imu.accel))?;
            d.set_item(
                "imu_orientation",
                imu.orientation.map(|o| PyArray1::from_slice(py, &o)),
            )?;
        }
        let forces: Vec<f64> = st.feet.iter().map(|f| f.force).collect();
        let cops: Vec<f64> = st
            .feet
            .iter()
            .flat_map(|f| f.cop.unwrap_or([f64::NAN; 2]))
            .collect();
        d.set_item(
            "foot_names",
            st.feet.iter().map(|f| f.name.clone()).collect::<Vec<_>>(),
        )?;
        d.set_item("foot_force", PyArray1::from_vec(py, forces))?;
        d.set_item("foot_cop", new_array(py, cops, &[st.feet.len(), 2])?)?;
        Ok(d)
    }

    /// Run independent rollouts from this simulator's settings, on `threads` threads
    /// (default: every core) with the GIL released, like `mujoco.rollout`.
    ///
    /// q0: (nq,) or (N, nq) initial configurations; v0: (nv,) or (N, nv), default
    /// zero; goals: (N, T, joints) joint goals for each of T steps. Returns the
    /// states after each step, (N, T, nq + nv): q then v. This simulator is not
    /// changed.
    #[pyo3(signature = (q0, goals, v0 = None, threads = None))]
    fn rollout<'py>(
        &self,
        py: Python<'py>,
        q0: &Bound<'py, PyAny>,
        goals: &Bound<'py, PyAny>,
        v0: Option<&Bound<'py, PyAny>>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let m = &self.sim.model;
        let nj = m.nbodies;
        let g = Arg::new(
            goals,
            "goals",
            &[Dim::Free("N"), Dim::Free("T"), Dim::Is(nj, "joints")],
        )?;
        let shape = g.array_shape();
        let (n, t) = (shape[0], shape[1]);
        let q = per_rollout(q0, "q0", n, (m.nq, "nq"))?;
        let zeros = vec![0.0; m.nv];
        let v = match v0 {
            Some(v0) => Some(per_rollout(v0, "v0", n, (m.nv, "nv"))?),
            None => None,
        };
        let threads = thread_count(threads)?;
        let job = Rollouts {
            description: &self.description,
            settings: &self.settings,
            q: (q.0.slice(), q.1),
            v: v.as_ref()
                .map_or((&zeros[..], false), |v| (v.0.slice(), v.1)),
            goals: g.slice(),
            n,
            t,
        };
        let states = py
            .detach(|| job.run(threads))
            .map_err(SimulationError::new_err)?;
        new_array(py, states, &[n, t, m.nq + m.nv])
    }

    fn __repr__(&self) -> String {
        format!(
            "<twinloop.Simulator {:?}: t = {} s, dt = {} s, {} joints>",
            self.description.name,
            self.sim.time,
            self.sim.dt(),
            self.sim.model.nbodies
        )
    }
}

/// An argument given once for all rollouts, (width,), or per rollout, (N, width);
/// returned with whether it is per rollout.
fn per_rollout<'py>(
    x: &Bound<'py, PyAny>,
    name: &'static str,
    n: usize,
    width: (usize, &'static str),
) -> PyResult<(Arg<'py>, bool)> {
    let ndim: usize = x.getattr("ndim").and_then(|d| d.extract()).unwrap_or(1);
    if ndim == 1 {
        Ok((Arg::new(x, name, &[Dim::Is(width.0, width.1)])?, false))
    } else {
        Ok((
            Arg::new(
                x,
                name,
                &[
                    Dim::Is(n, "N (rollouts in goals)"),
                    Dim::Is(width.0, width.1),
                ],
            )?,
            true,
        ))
    }
}

/// The rollouts of one call, split over threads; each thread builds its own simulator.
struct Rollouts<'a> {
    description: &'a Description,
    settings: &'a Settings,
    q: (&'a [f64], bool),
    v: (&'a [f64], bool),
    goals: &'a [f64],
    n: usize,
    t: usize,
}

impl Rollouts<'_> {
    fn row(x: (&[f64], bool), i: usize, w: usize) -> &[f64] {
        if x.1 { &x.0[i * w..(i + 1) * w] } else { x.0 }
    }

    fn run(&self, threads: usize) -> Result<Vec<f64>, String> {
        let probe = build(self.description, self.settings)?;
        let (nq, nv, nj) = (probe.model.nq, probe.model.nv, probe.model.nbodies);
        let width = self.t * (nq + nv);
        let mut out = vec![0.0; self.n * width];
        if self.n == 0 || width == 0 {
            return Ok(out);
        }
        let per = self.n.div_ceil(threads.min(self.n));
        let results: Vec<Result<(), String>> = std::thread::scope(|s| {
            let handles: Vec<_> = out
                .chunks_mut(per * width)
                .enumerate()
                .map(|(c, chunk)| {
                    s.spawn(move || -> Result<(), String> {
                        let mut sim = build(self.description, self.settings)?;
                        for (k, states) in chunk.chunks_mut(width).enumerate() {
                            let i = c * per + k;
                            reset(&mut sim, Self::row(self.q, i, nq), Self::row(self.v, i, nv))?;
                            for (step, st) in states.chunks_mut(nq + nv).enumerate() {
                                let g0 = (i * self.t + step) * nj;
                                sim.goals.copy_from_slice(&self.goals[g0..g0 + nj]);
                                sim.step().map_err(|e| format!("rollout {i}: {e}"))?;
                                st[..nq].copy_from_slice(&sim.q);
                                st[nq..].copy_from_slice(&sim.v);
                            }
                        }
                        Ok(())
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| {
                    h.join()
                        .unwrap_or_else(|_| Err("a rollout thread failed".into()))
                })
                .collect()
        });
        results.into_iter().collect::<Result<(), String>>()?;
        Ok(out)
    }
}
