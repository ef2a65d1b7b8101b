//! A sub-controller on the servo bus: the ROBOTIS CM-730 of Darwin-OP, which
//! answers at id 200 in Protocol 1.0 with a control table of its own, its 3-axis
//! gyroscope and 3-axis accelerometer among it. This module holds the board's
//! facts (addresses, scales), how a board's axes sit in the link that carries it
//! ([`BoardAxes`]), and what the host makes of its readings: SI units in the link
//! frame and a trunk tilt estimate ([`TiltFilter`]).
//!
//! Sources (no ROBOTIS e-manual page of the CM-730 control table was in the
//! material read; the DARwIn-OP framework is ROBOTIS's own host code):
//! - Addresses: the DARwIn-OP framework, `Framework/include/CM730.h` (ROBOTIS):
//!   `P_MODEL_NUMBER_L` 0, `P_VERSION` 2, `P_ID` 3, `P_BAUD_RATE` 4,
//!   `P_RETURN_DELAY_TIME` 5, `P_RETURN_LEVEL` 16, `P_DXL_POWER` 24, `P_LED_PANNEL`
//!   25, `P_LED_HEAD_L` 26, `P_LED_EYE_L` 28, `P_BUTTON` 30, `P_GYRO_Z_L` 38,
//!   `P_GYRO_Y_L` 40, `P_GYRO_X_L` 42, `P_ACCEL_X_L` 44, `P_ACCEL_Y_L` 46,
//!   `P_ACCEL_Z_L` 48, `P_VOLTAGE` 50, microphones and ADCs 51..80, `ID_CM` 200.
//!   Value ranges: the CM-730 firmware's parameter range table (`CM_DXL_COM.c`,
//!   ROBOTIS 2010): ID 0..253, baud 1..254, return delay 0..254, return level 0..2,
//!   Dynamixel power 0..1, LED panel 0..7, head and eye LEDs 0..0x7FFF.
//! - Scales: each axis is a 10-bit value centred on 512 (the framework centres the
//!   gyro on 512, `MotionManager::Initialize`). Full scale +-1600 deg/s for the
//!   gyro (1600/512 = 3.125 deg/s per count) and +-4 g for the accelerometer
//!   (4/512 g per count), as the ROBOTIS-OP ROS hardware interface converts them
//!   (`robotis_op_hardware_interface.cpp`: `(raw - 512) * 1600 / 512` deg/s and
//!   `(raw - 512) * 4 g / 512`).
//! - Model number 0x7300 (29440): not in the ROBOTIS material read; a CM-730
//!   emulation in a DARwIn-OP framework fork (HROS1-Framework `CM730.cpp`,
//!   `Reset_CM730_Emulation`: model number bytes 0x00, 0x73) and NimbRo-OP's
//!   CM730 register map (its firmware, derived from ROBOTIS's, reports 0x7301)
//!   agree on it.
//!
//! Other boards (the OP3's OpenCR, a profile's own) and the one decoder of every
//! board's inertial registers are in [`crate::board_type`].

use crate::register::{DEGREE, Item};
use crate::servo_model::ServoModel;

/// Why a board's description is refused; the mapping places it at its file, line
/// and field.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BoardError(pub String);

impl std::fmt::Display for BoardError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BoardError {}

/// The id a CM-730 answers at (`CM730::ID_CM`).
pub const CM730_ID: u8 = 200;
/// Model Number of the CM-730, 0x7300 (see the module's sources).
pub const CM730_MODEL_NUMBER: u16 = ServoModel::Cm730.model_number();
/// Standard gravity, m/s^2: the accelerometer's "g".
pub const STANDARD_GRAVITY: f64 = 9.806_65;
/// Gyroscope: 1600 deg/s over 512 counts.
pub const CM730_GYRO_RAD_S_PER_COUNT: f64 = 1600.0 / 512.0 * DEGREE;
/// Accelerometer: 4 g over 512 counts.
pub const CM730_ACCEL_M_S2_PER_COUNT: f64 = 4.0 * STANDARD_GRAVITY / 512.0;
/// Every axis is a 10-bit count centred here.
pub const CM730_CENTER: i32 = 512;
/// First address of the inertial block (Gyro Z) and its length: gyro Z, Y, X then
/// accelerometer X, Y, Z, 2 bytes each (38..49).
pub const CM730_IMU_BLOCK: (u16, u16) = (38, 12);

/// Gyro and accelerometer, SI, along some frame's axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImuSample {
    /// Angular velocity, rad/s.
    pub gyro: [f64; 3],
    /// Specific force (acceleration minus gravity), m/s^2: +g along up at rest.
    pub accel: [f64; 3],
}

/// How a board sits in the link that carries it: for each board axis X, Y, Z,
/// the link axis it points along and the sign (a proper rotation: a signed
/// permutation with determinant +1). Written in a mapping as
/// `axes = ["x", "y", "z"]` (identity) or e.g. `["-y", "x", "z"]` (board X along
/// the link's -Y, board Y along its X).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoardAxes {
    /// Per board axis: (link axis 0..3, sign +-1).
    pub axes: [(usize, f64); 3],
}

impl Default for BoardAxes {
    fn default() -> Self {
        BoardAxes {
            axes: [(0, 1.0), (1, 1.0), (2, 1.0)],
        }
    }
}

impl BoardAxes {
    /// Parse three axis names (`x`, `-y`, `+z`, ...). `Err` says what is wrong.
    pub fn parse(names: &[String]) -> Result<BoardAxes, BoardError> {
        if names.len() != 3 {
            return Err(BoardError(format!(
                "{} axes given; name the link axis of board X, Y and Z, e.g. [\"x\", \"y\", \"z\"]",
                names.len()
            )));
        }
        let mut axes = [(0usize, 1.0f64); 3];
        for (k, n) in names.iter().enumerate() {
            let t = n.trim().to_ascii_lowercase();
            let (sign, rest) = match t.strip_prefix('-') {
                Some(r) => (-1.0, r),
                None => (1.0, t.strip_prefix('+').unwrap_or(&t)),
            };
            let axis = match rest {
                "x" => 0,
                "y" => 1,
                "z" => 2,
                _ => {
                    return Err(BoardError(format!(
                        "{n:?} is not an axis (x, y, z, -x, -y, -z)"
                    )));
                }
            };
            axes[k] = (axis, sign);
        }
        let b = BoardAxes { axes };
        let mut used = [false; 3];
        for &(a, _) in &axes {
            if used[a] {
                return Err(BoardError(format!(
                    "{names:?}: two board axes along one link axis"
                )));
            }
            used[a] = true;
        }
        if b.determinant() < 0.0 {
            return Err(BoardError(format!(
                "{names:?} is a mirror image, not a rotation (the board's axes are right-handed)"
            )));
        }
        Ok(b)
    }

    /// The rotation's determinant (+1 for a rotation, -1 for a mirror).
    fn determinant(&self) -> f64 {
        let mut m = [[0.0; 3]; 3];
        for (k, &(a, s)) in self.axes.iter().enumerate() {
            m[k][a] = s;
        }
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// A vector in the link frame expressed along the board's axes.
    pub fn link_to_board(&self, v: [f64; 3]) -> [f64; 3] {
        let [(a0, s0), (a1, s1), (a2, s2)] = self.axes;
        [s0 * v[a0], s1 * v[a1], s2 * v[a2]]
    }

    /// A vector along the board's axes expressed in the link frame.
    pub fn board_to_link(&self, v: [f64; 3]) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (k, &(a, s)) in self.axes.iter().enumerate() {
            out[a] = s * v[k];
        }
        out
    }

    /// The names [`BoardAxes::parse`] reads back.
    pub fn names(&self) -> [String; 3] {
        self.axes
            .map(|(a, s)| format!("{}{}", if s < 0.0 { "-" } else { "" }, ["x", "y", "z"][a]))
    }
}

/// The inertial registers of a board model, in the order of [`ImuSample`]'s axes
/// (X, Y, Z).
pub fn gyro_items() -> [Item; 3] {
    [Item::GyroX, Item::GyroY, Item::GyroZ]
}

pub fn accel_items() -> [Item; 3] {
    [Item::AccelX, Item::AccelY, Item::AccelZ]
}

/// The host's trunk tilt estimate from a board's gyro and accelerometer: a
/// complementary filter on the direction of "up" seen from the link.
///
/// Why this and not the accelerometer alone: the accelerometer gives gravity's
/// direction only while the trunk does not accelerate. A robot tipping over
/// rotates about the edge of its feet, and the tangential acceleration of the
/// trunk cancels part of gravity's component along the fall, so the accelerometer
/// reads less tilt than there is exactly when tilt matters. The gyro is right
/// during the fall but drifts (bias, and the CM-730's coarse 3.125 deg/s counts
/// integrate into a slope error when the trunk turns slowly). So "up" is
/// propagated with the gyro every cycle and pulled towards the accelerometer's
/// direction with time constant `time_constant_s`: for motions faster than that
/// the gyro decides, for slower ones the accelerometer. The first reading starts
/// the estimate at the accelerometer's direction (the robot standing still).
///
/// Heading (yaw) is not observable without a magnetometer; the orientation
/// reported has yaw 0 and only its tilt means anything.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TiltFilter {
    /// Seconds over which the accelerometer corrects the gyro.
    pub time_constant_s: f64,
    /// World up in the link frame (unit), once started.
    up: Option<[f64; 3]>,
}

impl Default for TiltFilter {
    fn default() -> Self {
        TiltFilter::new(0.5)
    }
}

/// Deviation of the accelerometer's magnitude from g, as a fraction of g, beyond
/// which its direction is not used.
const ACCEL_GATE: f64 = 0.1;

/// Weight of the accelerometer's direction: 1 when it reads g, falling linearly to
/// 0 at a deviation of [`ACCEL_GATE`] g.
fn accel_trust(a: [f64; 3]) -> f64 {
    let g = STANDARD_GRAVITY;
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    (1.0 - ((n - g).abs() / g) / ACCEL_GATE).clamp(0.0, 1.0)
}

fn normalized(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (n > 1e-9 && n.is_finite()).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

impl TiltFilter {
    pub fn new(time_constant_s: f64) -> TiltFilter {
        TiltFilter {
            time_constant_s,
            up: None,
        }
    }

    /// Forget the estimate: the next update starts from the accelerometer.
    pub fn reset(&mut self) {
        self.up = None;
    }

    /// World up in the link frame, if started.
    pub fn up(&self) -> Option<[f64; 3]> {
        self.up
    }

    /// One reading (link frame) `dt` seconds after the previous one.
    pub fn update(&mut self, s: &ImuSample, dt: f64) {
        let measured = normalized(s.accel);
        let Some(u) = self.up else {
            self.up = measured;
            return;
        };
        let dt = if dt.is_finite() { dt.max(0.0) } else { 0.0 };
        let w = s.gyro;
        // d(up)/dt = -w x up (up is fixed in the world, the frame turns by w).
        let cross = [
            w[1] * u[2] - w[2] * u[1],
            w[2] * u[0] - w[0] * u[2],
            w[0] * u[1] - w[1] * u[0],
        ];
        let mut p = [
            u[0] - dt * cross[0],
            u[1] - dt * cross[1],
            u[2] - dt * cross[2],
        ];
        if let Some(m) = measured {
            let k = if self.time_constant_s > 0.0 {
                (dt / self.time_constant_s).min(1.0)
            } else {
                1.0
            };
            // Trust the accelerometer's direction only as far as it reads gravity's
            // magnitude: a jolt (a foot landing, contact chatter, the fall's own
            // acceleration) reads more or less than g and would tilt the estimate by
            // a whole cycle's correction at once.
            let k = k * accel_trust(s.accel);
            for i in 0..3 {
                p[i] += k * (m[i] - p[i]);
            }
        }
        if let Some(n) = normalized(p) {
            self.up = Some(n);
        }
    }

    /// Pitch and roll (rad) of the link: the rotation `Ry(pitch) Rx(roll)` that
    /// takes world up to the estimate (pitch forward-down positive about y, roll
    /// about x).
    pub fn pitch_roll(&self) -> Option<(f64, f64)> {
        let u = self.up?;
        // up in the link frame = Rx(-roll) Ry(-pitch) z = (-sin p, cos p sin r, cos p cos r)
        let pitch = (-u[0]).atan2((u[1] * u[1] + u[2] * u[2]).sqrt());
        let roll = u[1].atan2(u[2]);
        Some((pitch, roll))
    }

    /// The orientation of the link as a unit quaternion (x, y, z, w) with yaw 0:
    /// `Ry(pitch) Rx(roll)`.
    pub fn orientation(&self) -> Option<[f64; 4]> {
        let (p, r) = self.pitch_roll()?;
        let (sp, cp) = (0.5 * p).sin_cos();
        let (sr, cr) = (0.5 * r).sin_cos();
        // q = qy(p) * qx(r), with qy = (0, sp, 0, cp), qx = (sr, 0, 0, cr).
        Some([cp * sr, sp * cr, -sp * sr, cp * cr])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_parse_rotations_and_refuse_mirrors() {
        let s = |v: [&str; 3]| v.map(String::from).to_vec();
        let id = BoardAxes::parse(&s(["x", "y", "z"])).unwrap();
        assert_eq!(id, BoardAxes::default());
        let r = BoardAxes::parse(&s(["-y", "x", "z"])).unwrap();
        let v = [1.0, 2.0, 3.0];
        assert_eq!(r.link_to_board(v), [-2.0, 1.0, 3.0]);
        assert_eq!(r.board_to_link(r.link_to_board(v)), v);
        assert_eq!(r.names(), ["-y", "x", "z"].map(String::from));
        assert!(BoardAxes::parse(&s(["y", "x", "z"])).is_err());
        assert!(BoardAxes::parse(&s(["x", "x", "z"])).is_err());
        assert!(BoardAxes::parse(&s(["x", "w", "z"])).is_err());
    }

    #[test]
    fn the_filter_starts_at_the_accelerometer_and_its_orientation_has_that_tilt() {
        let mut f = TiltFilter::default();
        let (p, r) = (0.2f64, -0.1f64);
        // Specific force at rest: g times up in the link frame.
        let up = [-p.sin(), p.cos() * r.sin(), p.cos() * r.cos()];
        let s = ImuSample {
            gyro: [0.0; 3],
            accel: up.map(|u| 9.8 * u),
        };
        f.update(&s, 0.0);
        let (pe, re) = f.pitch_roll().unwrap();
        assert!((pe - p).abs() < 1e-12 && (re - r).abs() < 1e-12);
        // The quaternion's rotation has the same up axis.
        let [x, y, z, w] = f.orientation().unwrap();
        let third_row = [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ];
        for k in 0..3 {
            assert!((third_row[k] - up[k]).abs() < 1e-12, "{third_row:?} {up:?}");
        }
    }

    #[test]
    fn the_filter_follows_the_gyro_in_a_fast_turn() {
        let mut f = TiltFilter::new(0.5);
        let still = ImuSample {
            gyro: [0.0; 3],
            accel: [0.0, 0.0, 9.8],
        };
        f.update(&still, 0.0);
        // Pitching at 1 rad/s for 0.2 s while the accelerometer still says level
        // (as in a fall): the estimate follows the gyro, less a little.
        let turning = ImuSample {
            gyro: [0.0, 1.0, 0.0],
            accel: [0.0, 0.0, 9.8],
        };
        for _ in 0..40 {
            f.update(&turning, 0.005);
        }
        let (p, _) = f.pitch_roll().unwrap();
        assert!(p > 0.15 && p < 0.2, "{p}");
    }
}
