//! The Dynamixel link client (`twinloop link scan` / `read`) and a virtual robot served
//! on a pseudo-terminal (`twinloop serve`), for scripts and tests without hardware.

use crate::arrays::new_array;
use crate::errors::value_error;
use crate::sim::description_arg;
use crate::values::to_py;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::Serialize;
use std::time::{Duration, Instant};
use twinloop_link::ModelTable;
use twinloop_link::transport::{self, SerialOptions, Transport};
use twinloop_link::{
    Client, ClientConfig, ControlCycle, DynamixelRobot, FoundServo, Item, Protocol, ReadMethod,
    RobotMapping, ServoModel,
};
use twinloop_robot::{Robot, RobotState};
use twinloop_virtual::{PtyServer, VirtualRobot, VirtualRobotOptions};

fn link_error(e: impl std::fmt::Display) -> PyErr {
    PyOSError::new_err(e.to_string())
}

fn protocol_arg(p: u8) -> PyResult<Protocol> {
    Protocol::parse(&p.to_string())
        .ok_or_else(|| value_error(format!("protocol: {p} is not 1 or 2")))
}

#[derive(Serialize)]
struct ServoJson {
    protocol: u8,
    id: u8,
    model: Option<&'static str>,
    model_number: u16,
    firmware: u8,
}

impl From<&FoundServo> for ServoJson {
    fn from(s: &FoundServo) -> Self {
        ServoJson {
            protocol: s.protocol.number(),
            id: s.id,
            model: s.model.map(|m| m.name()),
            model_number: s.model_number,
            firmware: s.firmware,
        }
    }
}

#[derive(Serialize)]
struct ReadJson {
    protocol: u8,
    id: u8,
    model: &'static str,
    registers: Vec<twinloop_link::Reading>,
}

/// A Dynamixel bus: a serial device, a pty path or tcp:HOST:PORT. Errors of the
/// port and of the servos are OSError with the CLI's messages.
#[pyclass(name = "Bus", module = "twinloop._native", unsendable)]
pub struct PyBus {
    /// None only while `record` has lent the client to the robot it reads.
    client: Option<Client<Box<dyn Transport>>>,
}

impl PyBus {
    fn client(&mut self) -> PyResult<&mut Client<Box<dyn Transport>>> {
        self.client
            .as_mut()
            .ok_or_else(|| link_error("the bus is in use by a recording"))
    }
}

#[pymethods]
impl PyBus {
    /// `timeout_ms`: how long to wait for a reply; `retries`: resends of an unanswered packet.
    #[new]
    #[pyo3(signature = (port, baud = 1_000_000, timeout_ms = 10.0, retries = 2))]
    fn new(port: &str, baud: u32, timeout_ms: f64, retries: u32) -> PyResult<PyBus> {
        if !(timeout_ms > 0.0 && timeout_ms.is_finite()) {
            return Err(value_error(format!(
                "timeout_ms: must be positive, got {timeout_ms}"
            )));
        }
        let t = transport::open(port, baud, &SerialOptions::default())
            .map_err(|e| PyOSError::new_err(format!("{port}: {e}")))?;
        let config = ClientConfig {
            latency: Duration::from_secs_f64(timeout_ms / 1000.0),
            retries,
            baud,
            write_replies: true,
        };
        Ok(PyBus {
            client: Some(Client::with_config(t, config)),
        })
    }

    /// Ping ids `lo..=hi` (default: all) with `protocol` (1, 2, or None for both):
    /// `twinloop link scan --json`'s list (protocol, id, model, model_number, firmware).
    #[pyo3(signature = (protocol = None, ids = None))]
    fn scan<'py>(
        &mut self,
        py: Python<'py>,
        protocol: Option<u8>,
        ids: Option<(u8, u8)>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let protocols = match protocol {
            Some(p) => vec![protocol_arg(p)?],
            None => vec![Protocol::V1, Protocol::V2],
        };
        let mut found = Vec::new();
        for p in protocols {
            let (lo, hi) = ids.unwrap_or((0, p.max_id()));
            if lo > hi || hi > p.max_id() {
                return Err(value_error(format!(
                    "ids: ({lo}, {hi}) is not a range within 0..={}",
                    p.max_id()
                )));
            }
            found.extend(self.client()?.scan(p, lo..=hi).map_err(link_error)?);
        }
        let v: Vec<ServoJson> = found.iter().map(ServoJson::from).collect();
        to_py(py, &v)
    }

    /// Read a servo's control table (`twinloop link read --json`): every register, or
    /// the named ones, raw and in SI units.
    #[pyo3(signature = (id, protocol, registers = None))]
    fn read<'py>(
        &mut self,
        py: Python<'py>,
        id: u8,
        protocol: u8,
        registers: Option<Vec<String>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = protocol_arg(protocol)?;
        let found = self.client()?.ping(p, id).map_err(link_error)?;
        let Some(model) = found.model else {
            return Err(link_error(format!(
                "servo id {id}: model number {} has no control table in twinloop (known: {})",
                found.model_number,
                ServoModel::known_names()
            )));
        };
        let table = model.table();
        let selected: Vec<_> = match &registers {
            None => table.registers.iter().collect(),
            Some(names) => names
                .iter()
                .map(|n| {
                    table.by_name(n).ok_or_else(|| {
                        value_error(format!("registers: {model} has no register {n:?}"))
                    })
                })
                .collect::<PyResult<_>>()?,
        };
        let mut memory = vec![0u8; table.len()];
        self.client()?
            .read(p, id, 0, &mut memory)
            .map_err(link_error)?;
        let rows = selected.iter().map(|r| r.reading(&memory)).collect();
        to_py(
            py,
            &ReadJson {
                protocol,
                id,
                model: model.name(),
                registers: rows,
            },
        )
    }

    /// Record every joint in a loop (`twinloop link record`): one row per read of
    /// `t` (s since start), `q:<joint>` (rad), `v:<joint>` (rad/s), `tau:<joint>`
    /// (N m, an estimate from Present Load or Present Current), joints in mapping
    /// order, for `duration` s at `rate` reads per second (0: as fast as the bus
    /// allows). The robot is `map` (a mapping TOML or builtin:km20 / builtin:op3) or
    /// `protocol` and `ids` (joints `id<N>`, models by PING). With `out`, every row
    /// is also written to that CSV as it is read (the CLI's file). Ctrl-C ends the
    /// recording early and returns what was read (`interrupted` True).
    ///
    /// Returns a dict: `columns` (list of str), `data` (rows, 1 + 3 joints) float64
    /// with NaN where a servo did not answer, `rows`, `seconds`, `failures` (failed
    /// reads per joint name), `interrupted`. A link failure raises OSError naming how
    /// many rows were read (and kept in `out`).
    #[pyo3(signature = (duration, map = None, protocol = None, ids = None, rate = 100.0,
        method = "auto", out = None, verified_reads = false))]
    #[allow(clippy::too_many_arguments)]
    fn record<'py>(
        &mut self,
        py: Python<'py>,
        duration: f64,
        map: Option<&str>,
        protocol: Option<u8>,
        ids: Option<Vec<u8>>,
        rate: f64,
        method: &str,
        out: Option<std::path::PathBuf>,
        verified_reads: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let method = record_options(duration, rate, method)?;
        let mapping = self.record_mapping(map, protocol, ids, method)?;
        let names = mapping.joint_names();
        let ids_text = mapping
            .joints
            .iter()
            .map(|j| format!("{} (protocol {}.0)", j.id, j.protocol.number()))
            .collect::<Vec<_>>()
            .join(", ");
        let mut columns = vec!["t".to_string()];
        for prefix in ["q", "v", "tau"] {
            columns.extend(names.iter().map(|n| format!("{prefix}:{n}")));
        }
        // A CSV, or an MCAP of ROS 2 messages when `out` ends in .mcap (registered
        // at import, as the CLI registers it).
        let mut writer = match &out {
            Some(path) => Some(
                twinloop_io::sink::open_recording(path, &columns)
                    .map_err(|e| PyOSError::new_err(e.to_string()))?,
            ),
            None => None,
        };
        let client = self.client.take().expect("checked by self.client()");
        let mut robot = match DynamixelRobot::new(client, mapping, method) {
            Ok(r) => r,
            // ControlCycle::new accepted these servos above: the robot cannot refuse them.
            Err(e) => return Err(link_error(e)),
        };
        robot.cycle_mut().verify_v1 = verified_reads;
        let rec = record_rows(py, &mut robot, writer.as_mut(), duration, rate);
        self.client = Some(robot.client);
        // Nothing measured: the file is given up, an older recording of the name stays.
        let finished = match writer {
            Some(w) if rec.silent && rec.error.is_none() => {
                w.discard();
                Ok(None)
            }
            w => w.map(|w| w.finish()).transpose(),
        };
        let rows = rec.data.len() / (1 + 3 * names.len());
        if let Some(e) = rec.error {
            return Err(link_error(format!(
                "recording stopped: {e}; the {rows} rows read before are {}",
                if out.is_some() { "in the file" } else { "lost" }
            )));
        }
        finished.map_err(|e| PyOSError::new_err(e.to_string()))?;
        if rec.silent {
            // A file of NaN must not look like a recording: none was written.
            return Err(link_error(format!(
                "no servo of the mapping answered in the first {FIRST_CYCLES} cycles (ids {}); \
                 check the mapping, the port and the baud rate (Bus.scan lists what answers)",
                ids_text
            )));
        }
        recording_dict(py, &columns, &names, rec)
    }
}

impl PyBus {
    /// The robot `record` reads: `map`, or `protocol` and `ids` (models by PING); its
    /// servos checked against `method` before the client is lent to the robot, so a
    /// refusal keeps the bus.
    fn record_mapping(
        &mut self,
        map: Option<&str>,
        protocol: Option<u8>,
        ids: Option<Vec<u8>>,
        method: ReadMethod,
    ) -> PyResult<RobotMapping> {
        let mapping = match (map, protocol, ids) {
            (Some(m), None, None) => {
                RobotMapping::resolve(m).map_err(|e| value_error(format!("map: {e}")))?
            }
            (None, Some(p), Some(ids)) if !ids.is_empty() => {
                let p = protocol_arg(p)?;
                RobotMapping::from_ids(self.client()?, p, &ids).map_err(link_error)?
            }
            _ => {
                return Err(value_error(
                    "give map=MAPPING, or protocol= and ids= (a non-empty list)",
                ));
            }
        };
        let servos = mapping.cycle_servos();
        ControlCycle::new(&servos, method)
            .map_err(|e| value_error(format!("method: {}: {e}", mapping.source)))?;
        Ok(mapping)
    }
}

/// `record`'s duration, rate and read method, checked.
fn record_options(duration: f64, rate: f64, method: &str) -> PyResult<ReadMethod> {
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(value_error(format!(
            "duration: must be positive, got {duration}"
        )));
    }
    if !(rate >= 0.0 && rate.is_finite()) {
        return Err(value_error(format!(
            "rate: must be zero or positive, got {rate}"
        )));
    }
    ReadMethod::parse(method).ok_or_else(|| {
        value_error(format!(
            "method: {method:?} is not auto, read, bulk, sync or fast"
        ))
    })
}

/// `record`'s answer: columns, the rows as an array, counts and failures per joint.
fn recording_dict<'py>(
    py: Python<'py>,
    columns: &[String],
    names: &[String],
    rec: Recording,
) -> PyResult<Bound<'py, PyDict>> {
    let n = names.len();
    let rows = rec.data.len() / (1 + 3 * n);
    let d = PyDict::new(py);
    d.set_item("columns", columns)?;
    d.set_item("data", new_array(py, rec.data, &[rows, 1 + 3 * n])?)?;
    d.set_item("rows", rows)?;
    d.set_item("seconds", rec.seconds)?;
    let failures = PyDict::new(py);
    for (name, f) in names.iter().zip(&rec.failures) {
        failures.set_item(name, f)?;
    }
    d.set_item("failures", failures)?;
    d.set_item("interrupted", rec.interrupted)?;
    Ok(d)
}

/// After this many cycles, a recording in which no servo has answered stops.
const FIRST_CYCLES: usize = 3;

/// What the recording loop read.
struct Recording {
    /// Rows of 1 + 3 joints values, row-major.
    data: Vec<f64>,
    seconds: f64,
    failures: Vec<usize>,
    interrupted: bool,
    /// No servo answered in the first cycles.
    silent: bool,
    /// Why the recording stopped early: the link or the file failed.
    error: Option<String>,
}

/// Read the robot and keep a row, at `rate`, until `duration` ran out, Ctrl-C, or
/// the link failed (as `twinloop link record`'s loop).
fn record_rows(
    py: Python<'_>,
    robot: &mut DynamixelRobot<Box<dyn Transport>>,
    mut writer: Option<&mut Box<dyn twinloop_io::RowSink>>,
    duration: f64,
    rate: f64,
) -> Recording {
    let n = robot.outcomes().count();
    let mut state = RobotState::default();
    let mut row = vec![0.0; 1 + 3 * n];
    let mut rec = Recording {
        data: Vec::new(),
        seconds: 0.0,
        failures: vec![0; n],
        interrupted: false,
        silent: false,
        error: None,
    };
    let start = Instant::now();
    let dt = if rate > 0.0 { 1.0 / rate } else { 0.0 };
    while start.elapsed().as_secs_f64() < duration {
        if py.check_signals().is_err() {
            rec.interrupted = true;
            break;
        }
        if let Err(e) = robot.read(&mut state)
            && e.joint.is_none()
        {
            rec.error = Some(e.to_string());
            break;
        }
        for (k, (_, o)) in robot.outcomes().enumerate() {
            if o.is_err() {
                rec.failures[k] += 1;
            }
        }
        row[0] = state.time;
        row[1..1 + n].copy_from_slice(&state.positions);
        row[1 + n..1 + 2 * n].copy_from_slice(state.velocities.as_deref().unwrap_or(&[]));
        row[1 + 2 * n..].copy_from_slice(state.efforts.as_deref().unwrap_or(&[]));
        if let Some(w) = writer.as_deref_mut()
            && let Err(e) = w.write_row(&row)
        {
            rec.error = Some(e.to_string());
            break;
        }
        rec.data.extend_from_slice(&row);
        let rows = rec.data.len() / row.len();
        if rows == FIRST_CYCLES && rec.failures.iter().all(|&f| f == rows) {
            rec.silent = true;
            break;
        }
        if dt > 0.0 {
            let _ = robot.advance(dt);
        }
    }
    rec.seconds = start.elapsed().as_secs_f64();
    rec
}

/// A simulated robot behind the servo side of the protocol on a new pty, as
/// `twinloop serve` runs it; `path` is the port to open a Bus on. Stops on close().
#[pyclass(name = "VirtualRobotServer", module = "twinloop._native", unsendable)]
pub struct PyVirtualServer {
    server: Option<PtyServer>,
    path: String,
}

#[pymethods]
impl PyVirtualServer {
    /// `robot`: a Description, path or builtin name; `mapping`: the servo mapping
    /// (builtin:km20 or a mapping TOML); as `twinloop serve`'s options:
    /// `realtime_factor` (simulated seconds per wall-clock second), `catch_falls` (an
    /// operator stands a falling robot up, as between tip-over runs), `ground_sink`
    /// (m, the floor's stiffness; default 1 mm).
    #[new]
    #[pyo3(signature = (robot = None, mapping = "builtin:km20", realtime_factor = 1.0,
        catch_falls = false, ground_sink = None))]
    fn new(
        robot: Option<&Bound<'_, PyAny>>,
        mapping: &str,
        realtime_factor: f64,
        catch_falls: bool,
        ground_sink: Option<f64>,
    ) -> PyResult<PyVirtualServer> {
        if !(realtime_factor > 0.0 && realtime_factor.is_finite()) {
            return Err(value_error(format!(
                "realtime_factor: must be positive, got {realtime_factor}"
            )));
        }
        if let Some(s) = ground_sink
            && !(s > 0.0 && s.is_finite())
        {
            return Err(value_error(format!(
                "ground_sink: must be positive, got {s}"
            )));
        }
        let options = VirtualRobotOptions {
            realtime_factor,
            catch_falls,
            ground_sink,
            ..Default::default()
        };
        let map =
            RobotMapping::resolve(mapping).map_err(|e| value_error(format!("mapping: {e}")))?;
        let d = match robot {
            Some(r) => description_arg(r)?,
            None => std::sync::Arc::new(
                twinloop_description::builtin::builtin("km20")
                    .ok_or_else(|| value_error("robot: no built-in km20"))?,
            ),
        };
        let vr = VirtualRobot::new(&d, &map, &options).map_err(|e| value_error(e.to_string()))?;
        let devices = map.joints.len() + map.boards.len();
        let server = PtyServer::start(vr, Some(1_000_000), |bus| {
            for k in 0..devices {
                // Return Delay Time 0 is within every table's range.
                let _ = bus.host_write(k, Item::ReturnDelayTime, 0);
            }
        })
        .map_err(|e| {
            PyOSError::new_err(format!("cannot serve the robot on a pseudo-terminal: {e}"))
        })?;
        let path = server.path().to_string();
        Ok(PyVirtualServer {
            server: Some(server),
            path,
        })
    }
    #[getter]
    fn path(&self) -> &str {
        &self.path
    }
    fn close(&mut self) -> PyResult<()> {
        match self.server.take() {
            Some(s) => s.stop().map_err(|e| PyOSError::new_err(e.to_string())),
            None => Ok(()),
        }
    }
    fn __enter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }
    fn __exit__(
        &mut self,
        _a: Option<&Bound<'_, PyAny>>,
        _b: Option<&Bound<'_, PyAny>>,
        _c: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        self.close()
    }
}
