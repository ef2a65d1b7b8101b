//! What every experiment on a robot over its bus shares in the CLI: the confirmation
//! asked on a serial port, the mapping and port resolved, the raw record's file. The
//! guarded robot itself (Ctrl-C and faults stop the run; servos left holding) is
//! `twinloop_experiments::guarded`.

use crate::bus_args::PortArgs;
pub(super) use crate::bus_args::confirm;
use crate::error::CliError;
use std::path::Path;
use twinloop_experiments::guarded::record_columns;
pub(super) use twinloop_experiments::guarded::{Guarded, hold_standing, is_serial};
use twinloop_io::RowSink;
use twinloop_link::RobotMapping;

/// The raw record of `--record` (columns [`record_columns`]), flushed row by row: a
/// CSV, or an MCAP when the path ends in .mcap (main registers the format) with
/// `robot` on `/robot_description`, as `link record` writes.
pub(super) fn record_writer(
    path: &Path,
    names: &[String],
    robot: &twinloop_description::Description,
) -> Result<Box<dyn RowSink>, CliError> {
    let mut w = twinloop_io::open_recording(path, &record_columns(names))?;
    w.describe(&twinloop_description::urdf::to_string(robot))?;
    Ok(w)
}

/// The robot on the bus: its mapping (`--map`), the port (`--port`, else the
/// mapping's) and the description that gives the experiment its joints and signs
/// (`--robot`, else the mapping's `urdf`).
pub(super) fn resolve(
    map: Option<&str>,
    bus: &PortArgs,
    robot: Option<&str>,
    what: &str,
) -> Result<(RobotMapping, String, String), CliError> {
    let Some(map) = map else {
        return Err(CliError::new(
            "--port needs --map MAP (builtin:km20 or a mapping TOML)",
        ));
    };
    let mapping = RobotMapping::resolve(map)?;
    let port = bus
        .port
        .clone()
        .or_else(|| mapping.port.clone())
        .ok_or_else(|| CliError::new("--map needs --port PORT (or the mapping's port)"))?;
    // Without --robot, the profile itself: its description with its joint roles.
    let model_spec = match robot {
        Some(r) => r.to_string(),
        None if mapping.urdf.is_some() => map.to_string(),
        None => {
            return Err(CliError::new(format!(
                "{}: no `description` in [robot]; give --robot ROBOT for {what}",
                mapping.source
            )));
        }
    };
    Ok((mapping, port, model_spec))
}
