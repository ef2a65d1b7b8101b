//! The ROS 2 message types twinloop reads and writes, decoded from CDR into reused
//! buffers and encoded back, with their `ros2msg` schema texts.
//!
//! Field orders and types are the `.msg` files of ROS 2 `common_interfaces`
//! (sensor_msgs/JointState, sensor_msgs/Imu, geometry_msgs/WrenchStamped,
//! std_msgs/Float64MultiArray and its MultiArrayLayout/MultiArrayDimension,
//! tf2_msgs/TFMessage, geometry_msgs/TransformStamped, std_msgs/String) and of
//! `rcl_interfaces` (builtin_interfaces/Time). A schema's text is the message's
//! definition followed by each type it uses after a line of 80 `=` and `MSG: pkg/Type`,
//! the form rosbag2's MCAP storage and the `mcap-ros2-support` writer record.
use crate::cdr::{CdrReader, CdrWriter};
use crate::error::LogError;

/// The message types twinloop reads, by their schema names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    JointState,
    Imu,
    Wrench,
    MultiArray,
    Tf,
    String,
}

impl Kind {
    /// The type from a schema name; both `pkg/msg/Type` (ROS 2) and `pkg/Type` are taken.
    pub fn from_schema(name: &str) -> Option<Kind> {
        Some(match name.replace("/msg/", "/").as_str() {
            "sensor_msgs/JointState" => Kind::JointState,
            "sensor_msgs/Imu" => Kind::Imu,
            "geometry_msgs/WrenchStamped" => Kind::Wrench,
            "std_msgs/Float64MultiArray" => Kind::MultiArray,
            "tf2_msgs/TFMessage" => Kind::Tf,
            "std_msgs/String" => Kind::String,
            _ => return None,
        })
    }

    pub fn schema_name(self) -> &'static str {
        match self {
            Kind::JointState => "sensor_msgs/msg/JointState",
            Kind::Imu => "sensor_msgs/msg/Imu",
            Kind::Wrench => "geometry_msgs/msg/WrenchStamped",
            Kind::MultiArray => "std_msgs/msg/Float64MultiArray",
            Kind::Tf => "tf2_msgs/msg/TFMessage",
            Kind::String => "std_msgs/msg/String",
        }
    }

    /// The `ros2msg` schema text (the definition and its dependencies).
    pub fn schema_text(self) -> String {
        let (own, deps): (&str, &[(&str, &str)]) = match self {
            Kind::JointState => (
                "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
                &[HEADER, TIME],
            ),
            Kind::Imu => (
                "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n",
                &[HEADER, TIME, QUATERNION, VECTOR3],
            ),
            Kind::Wrench => (
                "std_msgs/Header header\ngeometry_msgs/Wrench wrench\n",
                &[HEADER, TIME, WRENCH, VECTOR3],
            ),
            Kind::MultiArray => (
                "std_msgs/MultiArrayLayout layout\nfloat64[] data\n",
                &[LAYOUT, DIMENSION],
            ),
            Kind::Tf => (
                "geometry_msgs/TransformStamped[] transforms\n",
                &[
                    TRANSFORM_STAMPED,
                    HEADER,
                    TIME,
                    TRANSFORM,
                    VECTOR3,
                    QUATERNION,
                ],
            ),
            Kind::String => ("string data\n", &[]),
        };
        let mut s = own.to_string();
        for (name, def) in deps {
            s.push_str(&"=".repeat(80));
            s.push_str(&format!("\nMSG: {name}\n{def}"));
        }
        s
    }
}

const HEADER: (&str, &str) = (
    "std_msgs/Header",
    "builtin_interfaces/Time stamp\nstring frame_id\n",
);
const TIME: (&str, &str) = ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n");
const QUATERNION: (&str, &str) = (
    "geometry_msgs/Quaternion",
    "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n",
);
const VECTOR3: (&str, &str) = ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n");
const WRENCH: (&str, &str) = (
    "geometry_msgs/Wrench",
    "geometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque\n",
);
const LAYOUT: (&str, &str) = (
    "std_msgs/MultiArrayLayout",
    "std_msgs/MultiArrayDimension[] dim\nuint32 data_offset\n",
);
const DIMENSION: (&str, &str) = (
    "std_msgs/MultiArrayDimension",
    "string label\nuint32 size\nuint32 stride\n",
);
const TRANSFORM_STAMPED: (&str, &str) = (
    "geometry_msgs/TransformStamped",
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
);
const TRANSFORM: (&str, &str) = (
    "geometry_msgs/Transform",
    "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
);

/// A `std_msgs/Header`'s stamp in ns since the epoch, and its frame.
fn header<'a>(r: &mut CdrReader<'a>) -> Result<(i64, &'a str), LogError> {
    let sec = r.i32()? as i64;
    let nanosec = r.u32()? as i64;
    Ok((sec * 1_000_000_000 + nanosec, r.string()?))
}

fn write_header(w: &mut CdrWriter, stamp_ns: i64, frame: &str) {
    w.i32(stamp_ns.div_euclid(1_000_000_000) as i32);
    w.u32(stamp_ns.rem_euclid(1_000_000_000) as u32);
    w.string(frame);
}

/// A `sensor_msgs/JointState`, decoded into buffers kept from message to message.
#[derive(Debug, Default, Clone)]
pub struct JointState {
    pub stamp_ns: i64,
    pub names: Vec<String>,
    /// Whether the last decode changed `names` (a new set or order of joints).
    pub names_changed: bool,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

impl JointState {
    /// Decode `data`; names equal to the previous message's are not rewritten, so a
    /// stream of messages allocates nothing after the first.
    pub fn decode(&mut self, data: &[u8]) -> Result<(), LogError> {
        let mut r = CdrReader::new(data)?;
        self.stamp_ns = header(&mut r)?.0;
        let n = r.count(5)?;
        self.names_changed = n != self.names.len();
        self.names.truncate(n);
        for i in 0..n {
            let bytes = r.string_bytes()?;
            if self.names.get(i).is_some_and(|old| old.as_bytes() == bytes) {
                continue;
            }
            let s = std::str::from_utf8(bytes)
                .map_err(|_| LogError::new("a joint name is not UTF-8"))?;
            match self.names.get_mut(i) {
                Some(old) => {
                    old.clear();
                    old.push_str(s);
                    self.names_changed = true;
                }
                None => self.names.push(s.to_string()),
            }
        }
        r.f64_seq(&mut self.position)?;
        r.f64_seq(&mut self.velocity)?;
        r.f64_seq(&mut self.effort)?;
        for (what, len) in [
            ("position", self.position.len()),
            ("velocity", self.velocity.len()),
            ("effort", self.effort.len()),
        ] {
            if len != 0 && len != n {
                return Err(LogError::new(format!(
                    "{n} joint names but {len} {what} values (it must be as many or none)"
                )));
            }
        }
        Ok(())
    }

    pub fn encode(&self, w: &mut CdrWriter, frame: &str) {
        write_header(w, self.stamp_ns, frame);
        w.u32(self.names.len() as u32);
        for n in &self.names {
            w.string(n);
        }
        w.f64_seq(&self.position);
        w.f64_seq(&self.velocity);
        w.f64_seq(&self.effort);
    }
}

/// A `sensor_msgs/Imu` (covariances are read past and written as unknown).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Imu {
    pub stamp_ns: i64,
    pub frame: String,
    /// x, y, z, w.
    pub orientation: [f64; 4],
    pub angular_velocity: [f64; 3],
    pub linear_acceleration: [f64; 3],
}

impl Imu {
    pub fn decode(&mut self, data: &[u8]) -> Result<(), LogError> {
        let mut r = CdrReader::new(data)?;
        let (stamp, frame) = header(&mut r)?;
        self.stamp_ns = stamp;
        if self.frame != frame {
            self.frame = frame.to_string();
        }
        self.orientation = r.f64s::<4>()?;
        r.f64s::<9>()?;
        self.angular_velocity = r.f64s::<3>()?;
        r.f64s::<9>()?;
        self.linear_acceleration = r.f64s::<3>()?;
        r.f64s::<9>()?;
        Ok(())
    }

    /// Covariances: orientation's first element -1 when `orientation` is unknown
    /// (the message's own convention), zeros ("unknown") otherwise.
    pub fn encode(&self, w: &mut CdrWriter, orientation_known: bool) {
        write_header(w, self.stamp_ns, &self.frame);
        let mut unknown = [0.0; 9];
        for x in self.orientation {
            w.f64(x);
        }
        if !orientation_known {
            unknown[0] = -1.0;
        }
        unknown.iter().for_each(|&x| w.f64(x));
        self.angular_velocity.iter().for_each(|&x| w.f64(x));
        [0.0; 9].iter().for_each(|&x| w.f64(x));
        self.linear_acceleration.iter().for_each(|&x| w.f64(x));
        [0.0; 9].iter().for_each(|&x| w.f64(x));
    }
}

/// A `geometry_msgs/WrenchStamped`: force then torque.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Wrench {
    pub stamp_ns: i64,
    pub frame: String,
    pub force: [f64; 3],
    pub torque: [f64; 3],
}

impl Wrench {
    pub fn decode(&mut self, data: &[u8]) -> Result<(), LogError> {
        let mut r = CdrReader::new(data)?;
        let (stamp, frame) = header(&mut r)?;
        self.stamp_ns = stamp;
        if self.frame != frame {
            self.frame = frame.to_string();
        }
        self.force = r.f64s::<3>()?;
        self.torque = r.f64s::<3>()?;
        Ok(())
    }

    pub fn encode(&self, w: &mut CdrWriter) {
        write_header(w, self.stamp_ns, &self.frame);
        self.force
            .iter()
            .chain(&self.torque)
            .for_each(|&x| w.f64(x));
    }
}

/// A `std_msgs/Float64MultiArray`'s data into `out`, and the label of its first
/// dimension (twinloop writes its column names there, comma-separated). It has no
/// header, so its time is the log time.
pub fn decode_multi_array<'a>(data: &'a [u8], out: &mut Vec<f64>) -> Result<&'a str, LogError> {
    let mut r = CdrReader::new(data)?;
    let dims = r.count(12)?;
    let mut first = "";
    for i in 0..dims {
        let label = r.string()?;
        if i == 0 {
            first = label;
        }
        r.u32()?;
        r.u32()?;
    }
    r.u32()?;
    r.f64_seq(out)?;
    Ok(first)
}

/// A one-dimensional array labelled `label`.
pub fn encode_multi_array(w: &mut CdrWriter, label: &str, data: &[f64]) {
    w.u32(1);
    w.string(label);
    w.u32(data.len() as u32);
    w.u32(data.len() as u32);
    w.u32(0);
    w.f64_seq(data);
}

/// One `geometry_msgs/TransformStamped`.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Transform {
    pub stamp_ns: i64,
    pub parent: String,
    pub child: String,
    pub translation: [f64; 3],
    /// x, y, z, w.
    pub rotation: [f64; 4],
}

/// A `tf2_msgs/TFMessage` into `out` (its elements reused).
pub fn decode_tf(data: &[u8], out: &mut Vec<Transform>) -> Result<(), LogError> {
    let mut r = CdrReader::new(data)?;
    let n = r.count(4 * 8 + 7 * 8)?;
    out.resize_with(n, Transform::default);
    for t in out.iter_mut() {
        let (stamp, parent) = header(&mut r)?;
        t.stamp_ns = stamp;
        if t.parent != parent {
            t.parent = parent.to_string();
        }
        let child = r.string()?;
        if t.child != child {
            t.child = child.to_string();
        }
        t.translation = r.f64s::<3>()?;
        t.rotation = r.f64s::<4>()?;
    }
    Ok(())
}

pub fn encode_tf(w: &mut CdrWriter, transforms: &[Transform]) {
    w.u32(transforms.len() as u32);
    for t in transforms {
        write_header(w, t.stamp_ns, &t.parent);
        w.string(&t.child);
        t.translation
            .iter()
            .chain(&t.rotation)
            .for_each(|&x| w.f64(x));
    }
}

/// A `std_msgs/String`.
pub fn decode_string(data: &[u8]) -> Result<String, LogError> {
    Ok(CdrReader::new(data)?.string()?.to_string())
}

pub fn encode_string(w: &mut CdrWriter, s: &str) {
    w.string(s);
}
