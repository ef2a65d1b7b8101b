//! The plan of the tip-over over a robot's bus: one struct that the CLI (`experiment
//! tipover --port`, `adapt --port`, `demo`) and Python (`tipover(port=...)`) fill from
//! their arguments, and the protocol passes replay; [`crate::tipover_bus`] runs it.

use crate::LoopError;
use crate::port::BusPort;
use std::path::PathBuf;
use twinloop_experiments::tipover::Direction;
use twinloop_ident::tipover_bus::{ANKLE_SLOPE, ONSET_AVERAGE_S};
use twinloop_ident::tipover_study::BusProtocol;
use twinloop_link::RobotMapping;

/// How the experiment runs over the bus.
#[derive(Debug, Clone)]
pub struct BusPlan {
    /// The host's model: lean signs, the tilt reference and the static references (a
    /// spec [`crate::profile::load_description`] reads; the report names it).
    pub model_spec: String,
    /// The servo mapping: builtin:NAME or a profile TOML (its IMU `[[board]]`).
    pub map: String,
    pub port: BusPort,
    /// Every cycle read, written row by row (`twinloop_io::open_recording`: CSV, or a
    /// format the program registered for the extension, the CLI's MCAP).
    pub record: Option<PathBuf>,
    /// Do not ask before moving a robot on a serial port.
    pub yes: bool,
    pub directions: Vec<Direction>,
    /// First ramp of each direction, deg/s of robot time.
    pub ramp: f64,
    /// The second run's creep over the last half degree, deg/s.
    pub slow_ramp: f64,
    /// How stiff the servos that hold the pose are made, as an RX Compliance Slope
    /// (2: stiffest; every servo family through the catalogue).
    pub compliance_slope: i32,
    /// The same for the joints a direction ramps (see [`ANKLE_SLOPE`]).
    pub ankle_slope: i32,
    /// Leave the servos as they are (see `BusTipoverOptions::soft_servos`).
    pub soft_servos: bool,
    /// Creeping approaches per direction (see `BusTipoverOptions::creeps`).
    pub creeps: usize,
    /// Commanded tip angles known beforehand, one per direction: creeps only (see
    /// `BusTipoverOptions::first_tips`).
    pub first_tips: Option<Vec<f64>>,
    /// Dither the turned joints' goal counts (see `BusTipoverOptions::dither`).
    pub dither: bool,
    /// A creep's tip is the mean reading over this long up to its onset, s of robot
    /// time (see `BusTipoverOptions::onset_average_s`).
    pub onset_average_s: f64,
    /// Robot seconds per host second (a simulated robot served faster than real time).
    pub clock_rate: f64,
    /// Say through the run's log what is happening.
    pub verbose: bool,
}

/// Creeps per direction when the protocol is replayed on a model
/// ([`BusPlan::replaying`]).
pub const REPLAY_CREEPS: usize = 1;

impl BusPlan {
    /// The protocol `adapt --port` and `demo` run: four directions, a first ramp of
    /// 2 deg/s and creeps of 0.15 deg/s, two creeps, the stiffest servos (ankles at
    /// [`ANKLE_SLOPE`]), dithered goals, tips averaged over [`ONSET_AVERAGE_S`]; a
    /// robot in real time, asked about on a serial port, nothing recorded.
    pub fn standard(model_spec: &str, map: &str, port: BusPort) -> BusPlan {
        BusPlan {
            model_spec: model_spec.to_string(),
            map: map.to_string(),
            port,
            record: None,
            yes: false,
            directions: Direction::ALL.to_vec(),
            ramp: 2.0,
            slow_ramp: 0.15,
            compliance_slope: 2,
            ankle_slope: ANKLE_SLOPE,
            soft_servos: false,
            creeps: 2,
            first_tips: None,
            dither: true,
            onset_average_s: ONSET_AVERAGE_S,
            clock_rate: 1.0,
            verbose: true,
        }
    }

    /// The plan that runs `protocol` again (one creep per direction, [`REPLAY_CREEPS`]), creeping from `first_tips` (commanded,
    /// deg, one per direction in `Direction::ALL`'s order), with `model_spec` as the
    /// host's model; no port, no record (for [`crate::tipover_bus::tipover_in_lockstep`]).
    pub fn replaying(protocol: &BusProtocol, model_spec: &str, first_tips: Vec<f64>) -> BusPlan {
        BusPlan {
            model_spec: model_spec.to_string(),
            map: protocol.map.clone(),
            port: BusPort::quick(None, 10.0, 0),
            record: None,
            yes: true,
            directions: Direction::ALL.to_vec(),
            ramp: protocol.ramp_deg_per_s,
            slow_ramp: protocol.slow_ramp_deg_per_s,
            compliance_slope: protocol.compliance_slope,
            ankle_slope: protocol.ankle_slope,
            soft_servos: protocol.soft_servos,
            // One creep: the replay is a simulation in lockstep, the same every time,
            // and its second creep read within 0.04 deg of the first (one ankle count's
            // half on MX and X) on served OP3, Darwin-OP and km20 measurements, at half
            // the replay's time (docs/adaptation.md, "Adapting in a minute").
            creeps: REPLAY_CREEPS,
            first_tips: Some(first_tips),
            dither: protocol.dither,
            onset_average_s: protocol.onset_average_s,
            clock_rate: 1.0,
            verbose: false,
        }
    }

    /// How the run was measured, as the report keeps it (`StudyReport::protocol`; the
    /// protocol passes replay it), at the run's median host cycle `cycle_s`.
    pub fn protocol(&self, cycle_s: f64) -> BusProtocol {
        BusProtocol {
            map: self.map.clone(),
            ramp_deg_per_s: self.ramp,
            slow_ramp_deg_per_s: self.slow_ramp,
            compliance_slope: self.compliance_slope,
            ankle_slope: self.ankle_slope,
            creeps: self.creeps,
            dither: self.dither,
            onset_average_s: self.onset_average_s,
            cycle_s,
            soft_servos: self.soft_servos,
        }
    }
}

/// Half a count of the left ankle pitch's servo, deg (the tip is read on both ankles,
/// averaged; every built-in's ankles are one model): RX 0.29 deg a count (EM-RX28
/// Goal Position: 300 deg / 1024), MX and X 0.088 deg (EM-MX28, EM-XM430: 360 deg /
/// 4096).
pub fn ankle_half_count_deg(mapping: &RobotMapping) -> Result<f64, LoopError> {
    let ankle = mapping
        .role("left_ankle_pitch")
        .and_then(|joint| mapping.joints.iter().find(|j| j.name == joint))
        .ok_or_else(|| {
            LoopError::new(format!(
                "{}: no [[joint]] for roles.left_ankle_pitch",
                mapping.source
            ))
        })?;
    Ok(0.5 * ankle.model.resolution().to_degrees())
}

/// The measured fall angles' resolution over the bus, deg: the reading's
/// quantisation (half an ankle count) and how far the protocol's creep moves the lean
/// in one host cycle (the onset is known to a cycle; 0.004 deg at the served
/// protocol's 0.05 deg/s and 80 ms of robot time).
pub fn angle_resolution_deg(
    mapping: &RobotMapping,
    protocol: &BusProtocol,
) -> Result<f64, LoopError> {
    Ok(ankle_half_count_deg(mapping)? + protocol.slow_ramp_deg_per_s * protocol.cycle_s)
}

/// [`angle_resolution_deg`] for a tip-over measured by `protocol`, its mapping read
/// from `protocol.map`.
pub fn protocol_resolution_deg(protocol: &BusProtocol) -> Result<f64, LoopError> {
    let mapping = RobotMapping::resolve(&protocol.map).map_err(|e| {
        LoopError::new(format!(
            "the tip-over's protocol.map {:?}: {e} (give --resolution DEG)",
            protocol.map
        ))
    })?;
    angle_resolution_deg(&mapping, protocol)
}

/// The measured angles' resolution `adapt` holds a tip-over to, deg: the one given;
/// else, for a tip-over measured over a bus, its mapping's
/// ([`protocol_resolution_deg`]); else 0.05 (a simulated study's readings). One rule
/// for the CLI and Python, so both adapt a measurement alike.
pub fn tipover_resolution_deg(
    given: Option<f64>,
    tip: &twinloop_ident::tipover_study::StudyReport,
) -> Result<f64, LoopError> {
    match (given, &tip.protocol) {
        (Some(r), _) => Ok(r),
        (None, Some(p)) => protocol_resolution_deg(p),
        (None, None) => Ok(0.05),
    }
}
