//! The Dynamixel link client (`twinloop link scan` / `read`) and a virtual robot served
//! on a pseudo-terminal (`twinloop serve`), for scripts and tests without hardware.

use crate::errors::value_error;
use crate::experiments::to_py;
use crate::sim::description_arg;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use serde::Serialize;
use std::time::Duration;
use twinloop_link::transport::{self, SerialOptions, Transport};
use twinloop_link::{
    Access, Client, ClientConfig, FoundServo, Item, Protocol, RobotMapping, ServoModel,
};
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
struct RegisterJson {
    address: u16,
    name: &'static str,
    size: u8,
    access: &'static str,
    raw: i32,
    value: f64,
}

#[derive(Serialize)]
struct ReadJson {
    protocol: u8,
    id: u8,
    model: &'static str,
    registers: Vec<RegisterJson>,
}

/// A Dynamixel bus: a serial device, a pty path or tcp:HOST:PORT. Errors of the
/// port and of the servos are OSError with the CLI's messages.
#[pyclass(name = "Bus", module = "twinloop._native", unsendable)]
pub struct PyBus {
    client: Client<Box<dyn Transport>>,
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
            client: Client::with_config(t, config),
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
            found.extend(self.client.scan(p, lo..=hi).map_err(link_error)?);
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
        let found = self.client.ping(p, id).map_err(link_error)?;
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
        self.client
            .read(p, id, 0, &mut memory)
            .map_err(link_error)?;
        let rows = selected
            .iter()
            .map(|r| {
                let raw = r.decode(&memory[r.address as usize..r.end() as usize]);
                RegisterJson {
                    address: r.address,
                    name: r.name,
                    size: r.size,
                    access: if r.access == Access::Read { "R" } else { "RW" },
                    raw,
                    value: r.to_si(raw),
                }
            })
            .collect();
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
    /// (builtin:km20 or a mapping TOML).
    #[new]
    #[pyo3(signature = (robot = None, mapping = "builtin:km20"))]
    fn new(robot: Option<&Bound<'_, PyAny>>, mapping: &str) -> PyResult<PyVirtualServer> {
        let map =
            RobotMapping::resolve(mapping).map_err(|e| value_error(format!("mapping: {e}")))?;
        let d = match robot {
            Some(r) => description_arg(r)?,
            None => std::sync::Arc::new(
                twinloop_description::builtin::builtin("km20")
                    .ok_or_else(|| value_error("robot: no built-in km20"))?,
            ),
        };
        let vr =
            VirtualRobot::new(&d, &map, &VirtualRobotOptions::default()).map_err(value_error)?;
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
