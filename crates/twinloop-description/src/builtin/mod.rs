//! The built-in robots: the seed robots, built from primitives in code.
//!
//! - [`km20`]: the FIBO KM kid-size humanoid of seeds 000 and 001 (20 DoF, 0.53 m,
//!   3.336 kg, 18 Dynamixel RX-28 and 2 RX-64);
//! - [`lab17`]: the 17-DoF hobby-servo lab humanoid of seed 003 (0.365 m, 0.215 m wide,
//!   1.65 kg, LD-2015 servos), with the trim angles of its Table 2.
//!
//! - `op3`: ROBOTIS OP3, the MuJoCo Menagerie MJCF the repository ships
//!   (models/op3/mjcf/op3.xml), compiled into the binary ([`vendored`]);
//! - `darwin_op`: ROBOTIS Darwin-OP, models/darwin_op's URDF with sole boxes
//!   (models/darwin_op/robotis_op.feet.urdf), compiled in likewise.
//!
//! Each is a plain [`crate::Description`] (write it with
//! `crate::urdf::write_file`); what a URDF cannot hold is kept here as data
//! beside it: which servo drives each joint ([`servo_of_joint`]), the foot geometry the
//! tip-over analysis needs ([`foot_geometry`]), lab17's trims ([`lab17::TRIMS`]).
//!
//! Every dimension the seeds do not give is argued where it is chosen, and tabled in
//! docs/seed-robots.md.
//!
//! ```
//! let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
//! assert_eq!(robot.joints.len(), 20);
//! let servo = twinloop_description::builtin::servo_of_joint("km20", "l_knee").unwrap();
//! assert_eq!(servo.name, "RX-64");
//! ```

pub mod km20;
pub mod lab17;
pub mod parts;
pub mod servo;
pub mod vendored;

pub use servo::{LD2015, RX28, RX64, ServoSpec};

use crate::{Description, DescriptionError};

/// The names `builtin:NAME` accepts.
pub const BUILTIN_NAMES: [&str; 4] = [km20::NAME, lab17::NAME, vendored::OP3, vendored::DARWIN_OP];

/// A built-in robot by name (`km20`, `lab17`, `op3`, `darwin_op`), `None` for any
/// other name.
pub fn builtin(name: &str) -> Option<Description> {
    let built = match name {
        km20::NAME => km20::build(),
        lab17::NAME => lab17::build(),
        _ => vendored::read(name)?,
    };
    // The builders only combine constants; a failure is a bug here, not bad input.
    Some(built.unwrap_or_else(|e| panic!("built-in robot {name} is invalid: {e}")))
}

/// One line per built-in robot: name and what it is.
pub fn builtin_summaries() -> [(&'static str, &'static str); 4] {
    [
        (
            km20::NAME,
            "FIBO KM kid-size humanoid (seeds 000, 001): 20 DoF, 0.53 m, 3.336 kg, 18 RX-28 + 2 RX-64",
        ),
        (
            lab17::NAME,
            "17-DoF lab humanoid (seed 003): 0.365 m tall, 0.215 m wide, 1.65 kg, LD-2015 hobby servos",
        ),
        (
            vendored::OP3,
            "ROBOTIS OP3 (MuJoCo Menagerie MJCF, models/op3/mjcf): 20 XM430-W350, OpenCR IMU; profile builtin:op3",
        ),
        (
            vendored::DARWIN_OP,
            "ROBOTIS Darwin-OP (models/darwin_op URDF with sole boxes): 20 MX-28, CM-730 IMU; profile builtin:darwin_op",
        ),
    ]
}

/// A robot from a `--robot` style specification: `builtin:NAME` is a built-in robot,
/// anything else a description file read with [`crate::load`] (URDF or MJCF).
///
/// An unknown built-in name is an error that lists the known ones.
pub fn resolve(spec: &str) -> Result<Description, DescriptionError> {
    match spec.strip_prefix("builtin:") {
        Some(name) => builtin(name).ok_or_else(|| {
            DescriptionError::new(format!(
                "unknown built-in robot \"{name}\" (built-in robots: {})",
                BUILTIN_NAMES.join(", ")
            ))
        }),
        None => crate::load(spec),
    }
}

/// Which servo model drives a joint of a built-in robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointServo {
    pub joint: &'static str,
    pub servo: &'static ServoSpec,
}

impl JointServo {
    pub const fn new(joint: &'static str, servo: &'static ServoSpec) -> Self {
        JointServo { joint, servo }
    }
}

/// The joint-to-servo table of a built-in robot (by robot name, so a description read
/// back from an exported URDF, which keeps the name, finds it too).
pub fn servo_table(robot_name: &str) -> Option<&'static [JointServo]> {
    match robot_name {
        km20::NAME => Some(&km20::SERVOS),
        lab17::NAME => Some(&lab17::SERVOS),
        _ => None,
    }
}

/// The servo that drives `joint` of the built-in robot `robot_name`; `None` for other
/// robots or joints.
pub fn servo_of_joint(robot_name: &str, joint: &str) -> Option<&'static ServoSpec> {
    servo_table(robot_name)?
        .iter()
        .find(|s| s.joint == joint)
        .map(|s| s.servo)
}

/// Foot and ankle geometry, as the tip-over analysis needs it (all lengths in m,
/// measured in the standing pose, feet flat).
///
/// Sagittal plane: the ankle pitch axes of both feet are one line (the robot leans
/// about it); the sole reaches `front` ahead of it and `back` behind it (seed 000's F1
/// and F2), and the axis is `ankle_height` above the sole (L0). Frontal plane: each
/// ankle roll axis is `ankle_half_spacing` from the mid-plane, `roll_axis_height` above
/// the sole; each sole reaches `outer` beyond it (away from the mid-plane) and `inner`
/// towards the mid-plane.
#[derive(Debug, Clone, PartialEq)]
pub struct FootGeometry {
    /// F1: ankle pitch axis to the front edge of the sole.
    pub front: f64,
    /// F2: ankle pitch axis to the back edge of the sole.
    pub back: f64,
    /// L0: ankle pitch axis above the sole.
    pub ankle_height: f64,
    /// Ankle roll axis above the sole.
    pub roll_axis_height: f64,
    /// Lateral distance of each ankle roll axis from the mid-plane between the feet.
    pub ankle_half_spacing: f64,
    /// Ankle roll axis to the outer sole edge.
    pub outer: f64,
    /// Ankle roll axis to the inner sole edge.
    pub inner: f64,
    pub left_foot: String,
    pub right_foot: String,
    pub left_ankle_pitch: String,
    pub right_ankle_pitch: String,
    pub left_ankle_roll: String,
    pub right_ankle_roll: String,
    /// Sign of the ankle pitch joint angle that leans the body forward over a flat foot
    /// (km20: -1, its pitch axes point left).
    pub forward_lean_sign: f64,
    /// Sign of the ankle roll joint angle that leans the body to the left (km20: +1).
    pub left_lean_sign: f64,
}

/// Foot geometry of a built-in robot, by name.
pub fn foot_geometry(robot_name: &str) -> Option<FootGeometry> {
    match robot_name {
        km20::NAME => Some(km20::foot_geometry()),
        lab17::NAME => Some(lab17::foot_geometry()),
        _ => None,
    }
}

/// The least share of its own mass a link keeps when a part is taken off it
/// ([`add_point_mass`] with a negative mass): a part heavier than that was not on it.
pub const MIN_REMAINING_FRACTION: f64 = 0.1;

/// A point mass as the CLI's `--add-mass` and the Python package's `add_mass` write
/// it: `KG@LINK:X,Y,Z` (kg; X,Y,Z in metres in the link frame; a negative mass is a
/// part taken off), as its three parts. The link name may hold ':' (the position
/// follows the last one). Errors quote the text and say which part is wrong.
pub fn parse_point_mass(s: &str) -> Result<(f64, String, [f64; 3]), DescriptionError> {
    let bad = |why: &str| DescriptionError::new(format!("\"{s}\": {why} (expected KG@LINK:X,Y,Z)"));
    let (kg, rest) = s.split_once('@').ok_or_else(|| bad("no '@'"))?;
    let (link, xyz) = rest
        .rsplit_once(':')
        .ok_or_else(|| bad("no ':' before the position"))?;
    let kg: f64 = kg
        .trim()
        .parse()
        .map_err(|_| bad("the mass is not a number"))?;
    let v: Vec<f64> = xyz
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad("the position is not three numbers"))?;
    if v.len() != 3 {
        return Err(bad("the position needs three numbers"));
    }
    Ok((kg, link.to_string(), [v[0], v[1], v[2]]))
}

/// Add a point mass of `mass` kg at `xyz` (m, link frame) to `link`: its inertial
/// becomes the rigid sum of what it had and the point (parallel-axis theorem), written
/// in the link's axes. A negative `mass` takes a part off (a battery removed, seed
/// 000's scenario b): the point is subtracted the same way, and the link must keep a
/// mass of its own ([`MIN_REMAINING_FRACTION`] of what it had). When the subtraction
/// leaves a rotational inertia no body has (a negative principal moment or the
/// triangle inequality broken: the part's own inertia was never in the link's), the
/// link keeps its own rotational inertia scaled by the mass it keeps, about its new
/// CoM. Errors name the link or the bad number.
pub fn add_point_mass(
    robot: &mut Description,
    link: &str,
    mass: f64,
    xyz: [f64; 3],
) -> Result<(), DescriptionError> {
    use twinloop_spatial::{Inertia as Rigid, Matrix3, Vector3};
    if !(mass.is_finite() && mass != 0.0) {
        return Err(DescriptionError::new(format!(
            "added mass: must be a finite number of kg, not 0 (negative: a part taken off), got {mass}"
        )));
    }
    if xyz.iter().any(|v| !v.is_finite()) {
        return Err(DescriptionError::new(format!(
            "added mass position: must be finite, got {xyz:?}"
        )));
    }
    let known: Vec<String> = robot.links.iter().map(|l| l.name.clone()).collect();
    let l = robot.link_mut(link).ok_or_else(|| {
        DescriptionError::new(format!(
            "added mass: no link \"{link}\" (links: {})",
            known.join(", ")
        ))
    })?;
    let own = match &l.inertial {
        None => Rigid::ZERO,
        Some(i) => {
            let r = i.origin.rotation();
            let rot = Matrix3::from_fn(|a, b| r[a][b]);
            let m = i.inertia.matrix();
            Rigid::new(
                i.mass,
                Vector3::new(i.origin.xyz[0], i.origin.xyz[1], i.origin.xyz[2]),
                rot * Matrix3::from_fn(|a, b| m[a][b]) * rot.transpose(),
            )
        }
    };
    let point = Rigid::new(mass, Vector3::new(xyz[0], xyz[1], xyz[2]), Matrix3::zeros());
    let mut sum = own + point;
    if mass < 0.0 {
        if sum.mass < MIN_REMAINING_FRACTION * own.mass {
            return Err(DescriptionError::new(format!(
                "removed mass: {} kg taken off link \"{link}\" of {} kg would leave it {} kg \
                 (it must keep at least {:.0} % of its own mass); the part sits on a heavier link",
                -mass,
                own.mass,
                sum.mass,
                MIN_REMAINING_FRACTION * 100.0
            )));
        }
        let trial = crate::Inertia::from_matrix(std::array::from_fn(|a| {
            std::array::from_fn(|b| sum.inertia[(a, b)])
        }));
        let [l1, l2, l3] = crate::lint::principal_moments(&trial);
        if l1 < 0.0 || l1 + l2 < l3 {
            sum.inertia = own.inertia * (sum.mass / own.mass);
        }
    }
    let i = sum.inertia;
    l.inertial = Some(crate::Inertial {
        origin: crate::Pose::from_xyz([sum.com.x, sum.com.y, sum.com.z]),
        mass: sum.mass,
        inertia: crate::Inertia::from_matrix([
            [i[(0, 0)], i[(0, 1)], i[(0, 2)]],
            [i[(1, 0)], i[(1, 1)], i[(1, 2)]],
            [i[(2, 0)], i[(2, 1)], i[(2, 2)]],
        ]),
    });
    Ok(())
}
