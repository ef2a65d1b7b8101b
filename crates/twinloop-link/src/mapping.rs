//! The robot profile (mapping file): which servo moves which description joint, how
//! a joint angle becomes a servo angle, the IMU boards on the bus, and which joints
//! play the roles experiments need. It is the per-robot calibration users keep
//! across tools.
//!
//! ```toml
//! [robot]
//! name = "op3"
//! description = "op3.xml"   # optional: a URDF/MJCF path, relative to this file's
//!                           # folder (never the current one), or builtin:NAME;
//!                           # `urdf = ...` is the same field's older name
//! port = "/dev/ttyUSB0"     # optional defaults for the CLI
//! baud = 1000000
//!
//! [roles]                   # optional: role = joint, each one of the [[joint]]s
//! left_ankle_pitch = "l_ank_pitch"    # also right_ankle_pitch, left/right_ankle_roll,
//! left_hip_roll = "l_hip_roll"        # left/right_hip_roll, left/right_knee
//!
//! [[joint]]
//! name = "r_sho_pitch"     # description joint name
//! id = 1                   # servo id
//! model = "XM430-W350"     # protocol follows from the model; `protocol = 1` for an X or
//!                          # MX(2.0) servo set to Protocol 1.0 (its Protocol Type register)
//! zero = 0.0               # servo angle (rad from the servo's centre) at joint angle 0
//! direction = 1            # +1: joint and servo turn the same way, -1: opposite
//! min = -1.5               # joint limits, rad (default: the servo's range)
//! max = 1.5
//! ```
//!
//! servo angle = zero + direction * joint angle. Joint order is file order.
//!
//! A sub-controller on the same bus (the trunk IMU) is a `[[board]]` of a
//! [`BoardType`]: `CM-730` (Protocol 1.0), `OpenCR` (2.0, as the OP3 runs it) or
//! `custom`, described by its own fields:
//!
//! ```toml
//! [[board]]
//! name = "trunk_imu"       # a name for messages
//! id = 200                 # the board's id (CM-730 and OpenCR: 200)
//! model = "OpenCR"         # the protocol follows from the model; `protocol = 2` checks it
//! link = "body_link"       # the description link carrying the board
//! axes = ["-x", "-y", "z"] # optional: the link axis board X, Y, Z point along
//!
//! [[board]]                # a team's own board
//! name = "imu"
//! id = 120
//! model = "custom"
//! protocol = 2             # required
//! model_number = 4660      # required: what PING answers
//! gyro = [100, 104, 108]   # required: register addresses of board X, Y, Z
//! accel = [112, 116, 120]  # required
//! size = 4                 # bytes per axis (default 2)
//! signed = true            # default true
//! gyro_deg_s_per_count = 0.01   # required
//! accel_g_per_count = 0.0001    # required
//! center = 0               # the count reading zero (default 0)
//! link = "torso"
//! ```
//!
//! Every error names the file, line, column and field.

use crate::board::BoardAxes;
use crate::board_type::{BoardType, CustomBoard};
use crate::control_table::ModelTable;
use crate::protocol::Protocol;
use crate::register::{Item, Register};
use crate::servo_model::ServoModel;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// A mapping error, located: `file:line:column: message`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MappingError {
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl fmt::Display for MappingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(
                f,
                "{}:{}:{}: {}",
                self.file, self.line, self.column, self.message
            )
        } else {
            write!(f, "{}: {}", self.file, self.message)
        }
    }
}

impl std::error::Error for MappingError {}

/// One joint's servo.
#[derive(Debug, Clone, PartialEq)]
pub struct JointMapping {
    pub name: String,
    pub id: u8,
    pub protocol: Protocol,
    pub model: ServoModel,
    /// Servo angle (rad from its centre) at joint angle 0.
    pub zero: f64,
    /// +1 or -1.
    pub direction: f64,
    /// Joint limits, rad.
    pub min: f64,
    pub max: f64,
    /// Line of the `[[joint]]` entry (0 for built-ins made in code).
    pub line: usize,
}

impl JointMapping {
    fn goal_register(&self) -> &'static Register {
        self.model
            .table()
            .item(Item::GoalPosition)
            .expect("every table has a goal position")
    }

    /// Servo angle for a joint angle.
    pub fn servo_angle(&self, joint: f64) -> f64 {
        self.zero + self.direction * joint
    }

    /// Joint angle for a servo angle.
    pub fn joint_angle(&self, servo: f64) -> f64 {
        self.direction * (servo - self.zero)
    }

    /// Raw Goal Position for a joint angle, clamped to the joint limits first.
    pub fn goal_raw(&self, joint: f64) -> i32 {
        self.goal_register()
            .from_si(self.servo_angle(self.clamped(joint)))
    }

    /// [`JointMapping::goal_raw`] dithered: the part of a count rounding drops is
    /// carried in `residual` to the next goal ([`Register::from_si_carrying`]).
    pub fn goal_raw_carrying(&self, joint: f64, residual: &mut f64) -> i32 {
        self.goal_register()
            .from_si_carrying(self.servo_angle(self.clamped(joint)), residual)
    }

    fn clamped(&self, joint: f64) -> f64 {
        if joint.is_nan() {
            0.0
        } else {
            joint.clamp(self.min, self.max)
        }
    }

    /// Joint angle of a raw Present Position.
    pub fn position(&self, raw: i32) -> f64 {
        let r = self
            .model
            .table()
            .item(Item::PresentPosition)
            .expect("every table has a present position");
        self.joint_angle(r.to_si(raw))
    }

    /// The servo angles the servo's position limit registers allow (its range).
    pub fn servo_range(model: ServoModel) -> (f64, f64) {
        let t = model.table();
        let r = t
            .item(Item::MaxPositionLimit)
            .expect("every table has limits");
        (r.to_si(r.min), r.to_si(r.max))
    }
}

/// A sub-controller board on the bus (the CM-730, the OpenCR, a custom one) and
/// where it sits.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardMapping {
    pub name: String,
    pub id: u8,
    pub protocol: Protocol,
    /// What it answers as and where its IMU registers are.
    pub kind: &'static BoardType,
    /// The description link the board is fixed to.
    pub link: String,
    /// The link axis each board axis points along.
    pub axes: BoardAxes,
    /// Line of the `[[board]]` entry (0 for built-ins made in code).
    pub line: usize,
}

/// A robot's mapping: joints in order, then boards.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotMapping {
    pub name: String,
    /// The robot's description (`[robot] description`, or `urdf`): a path, relative
    /// to the profile file's folder once loaded, or `builtin:NAME`.
    pub urdf: Option<PathBuf>,
    /// `[roles]`: (role, joint) in [`RobotMapping::ROLES`] order, the roles named.
    pub roles: Vec<(String, String)>,
    pub port: Option<String>,
    pub baud: Option<u32>,
    pub joints: Vec<JointMapping>,
    /// Sub-controllers (the trunk IMU's board), in file order.
    pub boards: Vec<BoardMapping>,
    /// Where it came from (file path or `builtin:NAME`), for messages.
    pub source: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    robot: Option<Spanned<RawRobot>>,
    roles: Option<BTreeMap<String, Spanned<String>>>,
    #[serde(default)]
    joint: Vec<Spanned<RawJoint>>,
    #[serde(default)]
    board: Vec<Spanned<RawBoard>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBoard {
    name: Spanned<String>,
    id: Spanned<i64>,
    model: Spanned<String>,
    protocol: Option<Spanned<RawProtocol>>,
    link: Spanned<String>,
    axes: Option<Spanned<Vec<String>>>,
    // A `model = "custom"` board's own description.
    model_number: Option<Spanned<i64>>,
    gyro: Option<Spanned<Vec<i64>>>,
    accel: Option<Spanned<Vec<i64>>>,
    size: Option<Spanned<i64>>,
    signed: Option<bool>,
    gyro_deg_s_per_count: Option<Spanned<f64>>,
    accel_g_per_count: Option<Spanned<f64>>,
    center: Option<Spanned<i64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRobot {
    name: Option<String>,
    description: Option<Spanned<String>>,
    urdf: Option<Spanned<String>>,
    port: Option<String>,
    baud: Option<Spanned<i64>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawProtocol {
    Int(i64),
    Float(f64),
    Text(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawJoint {
    name: Spanned<String>,
    id: Spanned<i64>,
    model: Spanned<String>,
    protocol: Option<Spanned<RawProtocol>>,
    zero: Option<Spanned<f64>>,
    direction: Option<Spanned<i64>>,
    min: Option<Spanned<f64>>,
    max: Option<Spanned<f64>>,
}

/// An error about field `field` of joint `name`, at the start of `span`.
type JointError<'a> = dyn Fn(std::ops::Range<usize>, &str, String) -> MappingError + 'a;

/// One `[[joint]]` entry (starting on line `line`), checked against itself and the
/// joints before it (`earlier`): names and (id, protocol) pairs are unique.
/// A joint's servo model: one we know, and a servo rather than a board.
fn joint_servo_model(j: &RawJoint, at: &JointError) -> Result<ServoModel, MappingError> {
    let model = ServoModel::parse(j.model.get_ref()).ok_or_else(|| {
        at(
            j.model.span(),
            "model",
            format!(
                "unknown model {:?}; known: {}",
                j.model.get_ref(),
                ServoModel::known_names()
            ),
        )
    })?;
    if model.is_board() {
        return Err(at(
            j.model.span(),
            "model",
            format!("{model} is a sub-controller, not a servo: declare it as a [[board]]"),
        ));
    }
    Ok(model)
}

/// A joint's zero offset, a servo angle the servo can take (one it cannot, 10 rad
/// on a 300-degree RX, would put every joint angle off by the difference).
fn joint_zero(
    j: &RawJoint,
    model: ServoModel,
    id: u8,
    at: &JointError,
) -> Result<f64, MappingError> {
    let Some(z) = j.zero.as_ref() else {
        return Ok(0.0);
    };
    let zero = *z.get_ref();
    if !zero.is_finite() {
        return Err(at(z.span(), "zero", "not a finite number".into()));
    }
    // The joint's zero is a servo angle: one the servo cannot take (10 rad on a
    // 300-degree RX) would put every joint angle off by the difference.
    let (smin, smax) = JointMapping::servo_range(model);
    if zero < smin - 1e-9 || zero > smax + 1e-9 {
        return Err(at(
            z.span(),
            "zero",
            format!(
                "{zero} rad ({:.1} deg) is outside servo id {id}'s range ({model}): {smin:.4}..{smax:.4} rad",
                zero.to_degrees()
            ),
        ));
    }
    Ok(zero)
}

/// A joint named once, its servo driving no other joint.
fn check_unique(
    j: &RawJoint,
    name: &str,
    id: u8,
    protocol: Protocol,
    earlier: &[JointMapping],
    at: &JointError,
) -> Result<(), MappingError> {
    if let Some(other) = earlier.iter().find(|o| o.name == name) {
        return Err(at(
            j.name.span(),
            "name",
            format!("joint listed twice (first on line {})", other.line),
        ));
    }
    if let Some(other) = earlier
        .iter()
        .find(|o| o.id == id && o.protocol == protocol)
    {
        return Err(at(
            j.id.span(),
            "id",
            format!(
                "servo id {id} ({protocol}) already drives joint {:?} (line {})",
                other.name, other.line
            ),
        ));
    }
    Ok(())
}

fn parse_joint(
    j: RawJoint,
    line: usize,
    earlier: &[JointMapping],
    err_at: &dyn Fn(usize, String) -> MappingError,
) -> Result<JointMapping, MappingError> {
    let name = j.name.get_ref().trim().to_string();
    let at = |s: std::ops::Range<usize>, field: &str, msg: String| {
        err_at(s.start, format!("joint {name:?}: {field}: {msg}"))
    };
    if name.is_empty() {
        return Err(at(j.name.span(), "name", "empty".into()));
    }
    let model = joint_servo_model(&j, &at)?;
    let protocol = explicit_protocol(j.protocol.as_ref(), model, &at)?;
    let id = *j.id.get_ref();
    // The protocol's ids, within what the model's ID register holds (an X servo on
    // 1.0 still stops at 252, EM-XM ID(7)).
    let max_id = model
        .table()
        .item(Item::Id)
        .map_or(protocol.max_id() as i64, |r| r.max as i64)
        .min(protocol.max_id() as i64);
    if id < 0 || id > max_id {
        return Err(at(
            j.id.span(),
            "id",
            format!("servo id {id} outside 0..={max_id} ({model} on {protocol})"),
        ));
    }
    let id = id as u8;
    let direction = match &j.direction {
        None => 1.0,
        Some(d) => match *d.get_ref() {
            1 => 1.0,
            -1 => -1.0,
            v => return Err(at(d.span(), "direction", format!("{v} is not 1 or -1"))),
        },
    };
    let zero = joint_zero(&j, model, id, &at)?;
    let (lo, hi) = joint_limits(&j, model, id, zero, direction, &at)?;
    check_unique(&j, &name, id, protocol, earlier, &at)?;
    Ok(JointMapping {
        name,
        id,
        protocol,
        model,
        zero,
        direction,
        min: lo,
        max: hi,
        line,
    })
}

/// A joint's or board's protocol: the model's, or an explicit `protocol` (1 or 2)
/// the model speaks: its own, or either for a model with a Protocol Type register
/// ([`ServoModel::speaks`]: X series and MX(2.0) can be set to Protocol 1.0).
fn explicit_protocol(
    protocol: Option<&Spanned<RawProtocol>>,
    model: ServoModel,
    at: &JointError,
) -> Result<Protocol, MappingError> {
    Ok(match protocol {
        None => model.protocol(),
        Some(p) => {
            let parsed = parse_protocol(p, at)?;
            if !model.speaks(parsed) {
                return Err(at(
                    p.span(),
                    "protocol",
                    format!(
                        "{model} runs {} only (it has no Protocol Type register); for the other firmware name the model so (e.g. MX-28(2.0))",
                        model.protocol()
                    ),
                ));
            }
            parsed
        }
    })
}

/// A `protocol` field: 1 or 2 (or "1.0", "2.0").
fn parse_protocol(p: &Spanned<RawProtocol>, at: &JointError) -> Result<Protocol, MappingError> {
    let parsed = match p.get_ref() {
        RawProtocol::Int(1) => Some(Protocol::V1),
        RawProtocol::Int(2) => Some(Protocol::V2),
        RawProtocol::Float(v) if *v == 1.0 => Some(Protocol::V1),
        RawProtocol::Float(v) if *v == 2.0 => Some(Protocol::V2),
        RawProtocol::Text(t) => Protocol::parse(t),
        _ => None,
    };
    parsed.ok_or_else(|| at(p.span(), "protocol", "must be 1 or 2".into()))
}

/// The joint's limits: `min` and `max` where given (within what the servo reaches
/// through `zero` and `direction`), else the servo's reach; never empty.
fn joint_limits(
    j: &RawJoint,
    model: ServoModel,
    id: u8,
    zero: f64,
    direction: f64,
    at: &JointError,
) -> Result<(f64, f64), MappingError> {
    let (smin, smax) = JointMapping::servo_range(model);
    // The joint angles the servo can reach.
    let (a, b) = (direction * (smin - zero), direction * (smax - zero));
    let (reach_min, reach_max) = (a.min(b), a.max(b));
    let min = j.min.as_ref().map(|v| (*v.get_ref(), v.span()));
    let max = j.max.as_ref().map(|v| (*v.get_ref(), v.span()));
    let lo = min.clone().map(|v| v.0).unwrap_or(reach_min);
    let hi = max.clone().map(|v| v.0).unwrap_or(reach_max);
    if let Some((v, span)) = &min
        && (!v.is_finite() || *v < reach_min - 1e-9)
    {
        return Err(at(
            span.clone(),
            "min",
            format!(
                "{v} rad is outside what servo id {id} ({model}) reaches: {reach_min:.4}..{reach_max:.4} rad"
            ),
        ));
    }
    if let Some((v, span)) = &max
        && (!v.is_finite() || *v > reach_max + 1e-9)
    {
        return Err(at(
            span.clone(),
            "max",
            format!(
                "{v} rad is outside what servo id {id} ({model}) reaches: {reach_min:.4}..{reach_max:.4} rad"
            ),
        ));
    }
    if lo >= hi {
        let span = max.map(|m| m.1).unwrap_or(j.name.span());
        return Err(at(span, "max", format!("limits {lo} .. {hi} are empty")));
    }
    Ok((lo, hi))
}

/// One `[[board]]` entry (on line `line`), checked against the joints and the
/// boards before it: names and (id, protocol) pairs are unique on the bus.
fn parse_board(
    b: RawBoard,
    line: usize,
    joints: &[JointMapping],
    earlier: &[BoardMapping],
    err_at: &dyn Fn(usize, String) -> MappingError,
) -> Result<BoardMapping, MappingError> {
    let name = b.name.get_ref().trim().to_string();
    let at = |s: std::ops::Range<usize>, field: &str, msg: String| {
        err_at(s.start, format!("board {name:?}: {field}: {msg}"))
    };
    if name.is_empty() {
        return Err(at(b.name.span(), "name", "empty".into()));
    }
    let kind = board_kind(&b, &name, &at)?;
    let protocol = kind.protocol;
    if let Some(p) = &b.protocol
        && parse_protocol(p, &at)? != protocol
    {
        return Err(at(
            p.span(),
            "protocol",
            format!("{} runs {protocol}", kind.name),
        ));
    }
    let id = *b.id.get_ref();
    if id < 0 || id > protocol.max_id() as i64 {
        return Err(at(
            b.id.span(),
            "id",
            format!("id {id} outside 0..={} ({protocol})", protocol.max_id()),
        ));
    }
    let id = id as u8;
    let link = b.link.get_ref().trim().to_string();
    if link.is_empty() {
        return Err(at(b.link.span(), "link", "empty".into()));
    }
    let axes = match &b.axes {
        None => BoardAxes::default(),
        Some(a) => BoardAxes::parse(a.get_ref()).map_err(|m| at(a.span(), "axes", m.0))?,
    };
    if let Some(other) = earlier.iter().find(|o| o.name == name) {
        return Err(at(
            b.name.span(),
            "name",
            format!("board listed twice (first on line {})", other.line),
        ));
    }
    if let Some(j) = joints.iter().find(|j| j.id == id && j.protocol == protocol) {
        return Err(at(
            b.id.span(),
            "id",
            format!(
                "id {id} ({protocol}) is the servo of joint {:?} (line {})",
                j.name, j.line
            ),
        ));
    }
    if let Some(o) = earlier
        .iter()
        .find(|o| o.id == id && o.protocol == protocol)
    {
        return Err(at(
            b.id.span(),
            "id",
            format!(
                "id {id} ({protocol}) is board {:?} (line {})",
                o.name, o.line
            ),
        ));
    }
    Ok(BoardMapping {
        name,
        id,
        protocol,
        kind,
        link,
        axes,
        line,
    })
}

/// A board's type: a built-in one by `model`, or `model = "custom"` described by
/// the entry's own fields (which a built-in board refuses).
fn board_kind(
    b: &RawBoard,
    name: &str,
    at: &JointError,
) -> Result<&'static BoardType, MappingError> {
    let model = b.model.get_ref().trim();
    if !model.eq_ignore_ascii_case("custom") {
        let own = [
            ("model_number", b.model_number.as_ref().map(|v| v.span())),
            ("gyro", b.gyro.as_ref().map(|v| v.span())),
            ("accel", b.accel.as_ref().map(|v| v.span())),
            ("size", b.size.as_ref().map(|v| v.span())),
            (
                "gyro_deg_s_per_count",
                b.gyro_deg_s_per_count.as_ref().map(|v| v.span()),
            ),
            (
                "accel_g_per_count",
                b.accel_g_per_count.as_ref().map(|v| v.span()),
            ),
            ("center", b.center.as_ref().map(|v| v.span())),
        ];
        if let Some((field, Some(span))) = own.into_iter().find(|(_, s)| s.is_some()) {
            return Err(at(
                span,
                field,
                format!("only a model = \"custom\" board takes this ({model} has its own table)"),
            ));
        }
        return BoardType::builtin(model).ok_or_else(|| {
            at(
                b.model.span(),
                "model",
                format!(
                    "unknown board {model:?}; known: {}, or \"custom\" with its registers",
                    BoardType::BUILTIN.join(", ")
                ),
            )
        });
    }
    let missing = |field: &str| at(b.model.span(), field, "a custom board needs it".into());
    let protocol = match &b.protocol {
        Some(p) => parse_protocol(p, at)?,
        None => return Err(missing("protocol")),
    };
    let model_number = b
        .model_number
        .as_ref()
        .ok_or_else(|| missing("model_number"))?;
    let model_number = u16::try_from(*model_number.get_ref()).map_err(|_| {
        at(
            model_number.span(),
            "model_number",
            "must be 0..=65535".into(),
        )
    })?;
    let addresses =
        |field: &str, v: &Option<Spanned<Vec<i64>>>| -> Result<[u16; 3], MappingError> {
            let v = v.as_ref().ok_or_else(|| missing(field))?;
            let a: Vec<u16> = v
                .get_ref()
                .iter()
                .filter_map(|&x| u16::try_from(x).ok())
                .collect();
            <[u16; 3]>::try_from(a).map_err(|_| {
                at(
                    v.span(),
                    field,
                    "three register addresses (board X, Y, Z), each 0..=65535".into(),
                )
            })
        };
    let scale = |field: &str, v: &Option<Spanned<f64>>| -> Result<f64, MappingError> {
        Ok(*v.as_ref().ok_or_else(|| missing(field))?.get_ref())
    };
    let size = b.size.as_ref().map(|v| *v.get_ref()).unwrap_or(2);
    let center = b.center.as_ref().map(|v| *v.get_ref()).unwrap_or(0);
    let custom = CustomBoard {
        name: name.to_string(),
        protocol,
        model_number,
        gyro: addresses("gyro", &b.gyro)?,
        accel: addresses("accel", &b.accel)?,
        size: u8::try_from(size).unwrap_or(0),
        signed: b.signed.unwrap_or(true),
        gyro_deg_s_per_count: scale("gyro_deg_s_per_count", &b.gyro_deg_s_per_count)?,
        accel_g_per_count: scale("accel_g_per_count", &b.accel_g_per_count)?,
        center: i32::try_from(center).unwrap_or(i32::MAX),
    };
    BoardType::custom(&custom).map_err(|m| at(b.model.span(), "model", m.0))
}

/// The `[roles]` table: each key one of [`RobotMapping::ROLES`], each value one of
/// the profile's `[[joint]]` names. Kept in [`RobotMapping::ROLES`] order.
fn read_roles(
    roles: BTreeMap<String, Spanned<String>>,
    joints: &[JointMapping],
    err_at: &dyn Fn(usize, String) -> MappingError,
) -> Result<Vec<(String, String)>, MappingError> {
    let mut out = Vec::with_capacity(roles.len());
    for (role, joint) in &roles {
        if !RobotMapping::ROLES.contains(&role.as_str()) {
            return Err(err_at(
                joint.span().start,
                format!(
                    "roles.{role}: not a role; roles: {}",
                    RobotMapping::ROLES.join(", ")
                ),
            ));
        }
        let name = joint.get_ref().trim();
        if name.is_empty() {
            return Err(err_at(joint.span().start, format!("roles.{role}: empty")));
        }
        if !joints.is_empty() && !joints.iter().any(|j| j.name == name) {
            return Err(err_at(
                joint.span().start,
                format!("roles.{role}: {name:?} is no [[joint]] of this profile"),
            ));
        }
    }
    for role in RobotMapping::ROLES {
        if let Some(j) = roles.get(role) {
            out.push((role.to_string(), j.get_ref().trim().to_string()));
        }
    }
    Ok(out)
}

/// The fields of a custom board's entry, as [`board_kind`] reads them.
fn custom_board_toml(b: &BoardType) -> String {
    use crate::board::{accel_items, gyro_items};
    use crate::register::{Encoding, Unit};
    let addr = |items: [crate::register::Item; 3]| {
        items.map(|i| b.register(i).map(|r| r.address).unwrap_or(0))
    };
    let Some(g) = b.register(crate::register::Item::GyroX) else {
        return String::new();
    };
    let a = b.register(crate::register::Item::AccelX).unwrap_or(g);
    let (gyro_scale, center) = match g.unit {
        Unit::Gyro {
            rad_s_per_unit,
            center,
        } => (rad_s_per_unit / crate::register::DEGREE, center),
        _ => (0.0, 0),
    };
    let accel_scale = match a.unit {
        Unit::Accel { m_s2_per_unit, .. } => m_s2_per_unit / crate::board::STANDARD_GRAVITY,
        _ => 0.0,
    };
    format!(
        "model_number = {}\ngyro = {:?}\naccel = {:?}\nsize = {}\nsigned = {}\ngyro_deg_s_per_count = {:?}\naccel_g_per_count = {:?}\ncenter = {}\n",
        b.model_number,
        addr(gyro_items()),
        addr(accel_items()),
        g.size,
        g.encoding == Encoding::Signed,
        gyro_scale,
        accel_scale,
        center
    )
}

/// 1-based line and column of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map(|i| i + 1).unwrap_or(0) + 1;
    (line, col)
}

const BUILTIN_KM20: &str = include_str!("mappings/km20.toml");
const BUILTIN_OP3: &str = include_str!("mappings/op3.toml");
const BUILTIN_DARWIN_OP: &str = include_str!("mappings/darwin_op.toml");

impl RobotMapping {
    /// The mapped servos as the control cycle reads them: each id, model and the
    /// protocol the mapping gives it.
    pub fn cycle_servos(&self) -> Vec<crate::control_cycle::CycleServo> {
        self.joints
            .iter()
            .map(|j| crate::control_cycle::CycleServo {
                id: j.id,
                model: j.model,
                protocol: j.protocol,
            })
            .collect()
    }

    /// Names after `builtin:`.
    pub const BUILTINS: [&'static str; 3] = ["km20", "op3", "darwin_op"];

    /// The roles a `[roles]` table may name (the same names as
    /// `twinloop_description::JointRoles::NAMES`, which a CLI test holds equal).
    pub const ROLES: [&'static str; 8] = [
        "left_ankle_pitch",
        "right_ankle_pitch",
        "left_ankle_roll",
        "right_ankle_roll",
        "left_hip_roll",
        "right_hip_roll",
        "left_knee",
        "right_knee",
    ];

    /// A mapping from `builtin:NAME` or a TOML file path.
    pub fn resolve(spec: &str) -> Result<RobotMapping, MappingError> {
        match spec.strip_prefix("builtin:") {
            Some(name) => RobotMapping::builtin(name).ok_or_else(|| MappingError {
                file: spec.to_string(),
                line: 0,
                column: 0,
                message: format!(
                    "no built-in robot {name:?}; built-in: {}",
                    RobotMapping::BUILTINS.join(", ")
                ),
            }),
            None => RobotMapping::load(spec),
        }
    }

    /// A built-in profile: `km20` (the FIBO KM kid-size robot of the seed papers: 20
    /// joints, RX-64 knees and RX-28 elsewhere on Protocol 1.0, a CM-730), `op3`
    /// (ROBOTIS OP3: 20 XM430-W350 on Protocol 2.0, the OpenCR) or `darwin_op`
    /// (ROBOTIS Darwin-OP: 20 MX-28 on Protocol 1.0, the CM-730). Each names its
    /// description as `builtin:NAME` (built into twinloop-description).
    pub fn builtin(name: &str) -> Option<RobotMapping> {
        let text = match name {
            "km20" => BUILTIN_KM20,
            "op3" => BUILTIN_OP3,
            "darwin_op" => BUILTIN_DARWIN_OP,
            _ => return None,
        };
        Some(RobotMapping::parse(text, &format!("builtin:{name}")).expect("built-ins are valid"))
    }

    /// A profile file. A relative description path in it is relative to the file's
    /// folder (not the current one), so a profile works from anywhere.
    pub fn load(path: impl AsRef<Path>) -> Result<RobotMapping, MappingError> {
        let path = path.as_ref();
        let text = twinloop_io::input::read_to_string(path).map_err(|e| MappingError {
            file: path.display().to_string(),
            line: 0,
            column: 0,
            message: format!("cannot read: {e}"),
        })?;
        let mut m = RobotMapping::parse(&text, &path.display().to_string())?;
        if let Some(d) = &m.urdf
            && d.is_relative()
            && !d.to_string_lossy().starts_with("builtin:")
        {
            let folder = path.parent().unwrap_or(Path::new(""));
            m.urdf = Some(folder.join(d));
        }
        Ok(m)
    }

    /// Parse mapping text; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<RobotMapping, MappingError> {
        let err_at = |offset: usize, message: String| {
            let (line, column) = line_col(text, offset);
            MappingError {
                file: source.to_string(),
                line,
                column,
                message,
            }
        };
        let raw: RawFile = toml::from_str(text).map_err(|e| {
            let offset = e.span().map(|s| s.start).unwrap_or(0);
            let message = e.message().trim().to_string();
            err_at(offset, message)
        })?;
        let mut mapping = RobotMapping {
            name: String::new(),
            urdf: None,
            roles: Vec::new(),
            port: None,
            baud: None,
            joints: Vec::with_capacity(raw.joint.len()),
            boards: Vec::with_capacity(raw.board.len()),
            source: source.to_string(),
        };
        if let Some(robot) = raw.robot {
            mapping.read_robot(robot.into_inner(), &err_at)?;
        }
        let roles = raw.roles.unwrap_or_default();
        if raw.joint.is_empty() {
            return Err(err_at(0, "no [[joint]] entries".into()));
        }
        for entry in raw.joint {
            let line = line_col(text, entry.span().start).0;
            let joint = parse_joint(entry.into_inner(), line, &mapping.joints, &err_at)?;
            mapping.joints.push(joint);
        }
        for entry in raw.board {
            let line = line_col(text, entry.span().start).0;
            let board = parse_board(
                entry.into_inner(),
                line,
                &mapping.joints,
                &mapping.boards,
                &err_at,
            )?;
            mapping.boards.push(board);
        }
        mapping.roles = read_roles(roles, &mapping.joints, &err_at)?;
        Ok(mapping)
    }

    /// The `[robot]` table: name, URDF, port and a bit rate that is one.
    fn read_robot(
        &mut self,
        robot: RawRobot,
        err_at: &dyn Fn(usize, String) -> MappingError,
    ) -> Result<(), MappingError> {
        self.name = robot.name.unwrap_or_default();
        if let (Some(d), Some(u)) = (&robot.description, &robot.urdf) {
            return Err(err_at(
                u.span().start,
                format!(
                    "robot.urdf: the description is already given (robot.description = {:?}); keep one",
                    d.get_ref()
                ),
            ));
        }
        if let Some(d) = robot.description.or(robot.urdf) {
            if d.get_ref().trim().is_empty() {
                return Err(err_at(d.span().start, "robot.description: empty".into()));
            }
            self.urdf = Some(PathBuf::from(d.into_inner()));
        }
        self.port = robot.port;
        if let Some(b) = robot.baud {
            let v = *b.get_ref();
            let range = crate::servo_model::BAUD_RANGE;
            if !u32::try_from(v).is_ok_and(|v| range.contains(&v)) {
                return Err(err_at(
                    b.span().start,
                    format!(
                        "robot.baud: {v} is not a Dynamixel bit rate ({} to {})",
                        range.start(),
                        range.end()
                    ),
                ));
            }
            self.baud = Some(v as u32);
        }
        Ok(())
    }

    /// Everything on the bus, in bus order: the joints' servos, then the boards
    /// (what a virtual bus serves for this mapping).
    ///
    /// Boards whose type has a table of its own (the OpenCR, a custom board) are not
    /// servo catalogue models: they come from [`RobotMapping::bus_boards`], and a bus
    /// with all of them is `VirtualBus::with_boards(&m.bus(), &m.bus_boards(), ..)`.
    /// Set up a served bus as this mapping and the line describe it: each joint's
    /// servo talks the protocol the mapping names (devices in [`RobotMapping::bus`]
    /// order), every Baud Rate register holds the line's code. A device the mapping
    /// cannot have (a bus not made from it) is left as it is.
    pub fn configure<B: crate::servo::VirtualServoBackend>(
        &self,
        bus: &mut crate::servo::VirtualBus<B>,
        line_baud: u32,
    ) {
        let protocols = self.joints.iter().map(|j| j.protocol);
        let protocols = protocols.chain(self.boards.iter().map(|b| b.protocol));
        for (k, protocol) in protocols.enumerate().take(bus.servos.len()) {
            // A mapping only names protocols its models speak (checked on load).
            let _ = bus.set_protocol(k, protocol);
        }
        bus.set_line_baud(line_baud);
    }

    pub fn bus(&self) -> Vec<crate::servo::BusServo> {
        let joints = self.joints.iter().map(|j| (j.id, j.model));
        let boards = self
            .boards
            .iter()
            .filter_map(|b| b.kind.catalogue.map(|m| (b.id, m)));
        joints
            .chain(boards)
            .map(|(id, model)| crate::servo::BusServo { id, model })
            .collect()
    }

    /// The boards [`RobotMapping::bus`] leaves out: those with a table of their own.
    pub fn bus_boards(&self) -> Vec<crate::servo::BusBoard> {
        self.boards
            .iter()
            .filter(|b| b.kind.catalogue.is_none())
            .map(|b| crate::servo::BusBoard {
                id: b.id,
                board: b.kind,
            })
            .collect()
    }

    /// The joint playing `role` (one of [`RobotMapping::ROLES`]), if `[roles]` names it.
    pub fn role(&self, role: &str) -> Option<&str> {
        self.roles
            .iter()
            .find(|(r, _)| r == role)
            .map(|(_, j)| j.as_str())
    }

    /// A mapping for servos given by protocol and ids (`link record --ids`): joints
    /// named `id<N>`, models found by PING, zero 0, direction 1, the servo's range.
    pub fn from_ids<T: crate::transport::Transport>(
        c: &mut crate::Client<T>,
        protocol: Protocol,
        ids: &[u8],
    ) -> Result<RobotMapping, MappingError> {
        let error = |message: String| MappingError {
            file: "--ids".into(),
            line: 0,
            column: 0,
            message,
        };
        let mut joints = Vec::new();
        for &id in ids {
            let s = c.ping(protocol, id).map_err(|e| error(e.to_string()))?;
            let model = s.model.ok_or_else(|| {
                error(format!(
                    "servo id {id}: model number {} has no control table in twinloop",
                    s.model_number
                ))
            })?;
            let (min, max) = JointMapping::servo_range(model);
            joints.push(JointMapping {
                name: format!("id{id}"),
                id,
                protocol,
                model,
                zero: 0.0,
                direction: 1.0,
                min,
                max,
                line: 0,
            });
        }
        Ok(RobotMapping {
            name: "servos".into(),
            urdf: None,
            roles: Vec::new(),
            port: None,
            baud: None,
            joints,
            boards: Vec::new(),
            source: "--ids".into(),
        })
    }

    pub fn joint_names(&self) -> Vec<String> {
        self.joints.iter().map(|j| j.name.clone()).collect()
    }

    /// The mapping as TOML that [`RobotMapping::parse`] reads back.
    pub fn to_toml(&self) -> String {
        let mut s = String::from("[robot]\n");
        s += &format!("name = {:?}\n", self.name);
        if let Some(u) = &self.urdf {
            s += &format!("description = {:?}\n", u.display().to_string());
        }
        if let Some(p) = &self.port {
            s += &format!("port = {p:?}\n");
        }
        if let Some(b) = self.baud {
            s += &format!("baud = {b}\n");
        }
        if !self.roles.is_empty() {
            s += "\n[roles]\n";
            for (role, joint) in &self.roles {
                s += &format!("{role} = {joint:?}\n");
            }
        }
        for j in &self.joints {
            s += &format!(
                "\n[[joint]]\nname = {:?}\nid = {}\nmodel = {:?}\nprotocol = {}\nzero = {:?}\ndirection = {}\nmin = {:?}\nmax = {:?}\n",
                j.name,
                j.id,
                j.model.name(),
                j.protocol.number(),
                j.zero,
                j.direction as i32,
                j.min,
                j.max
            );
        }
        for b in &self.boards {
            let custom = b.kind.catalogue.is_none() && BoardType::builtin(&b.kind.name).is_none();
            s += &format!(
                "\n[[board]]\nname = {:?}\nid = {}\nmodel = {:?}\nprotocol = {}\nlink = {:?}\naxes = {:?}\n",
                b.name,
                b.id,
                if custom {
                    "custom"
                } else {
                    b.kind.name.as_str()
                },
                b.protocol.number(),
                b.link,
                b.axes.names()
            );
            if custom {
                s += &custom_board_toml(b.kind);
            }
        }
        s
    }
}
