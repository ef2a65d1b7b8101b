//! Servo data: what the makers publish, and the primitive bodies the seed papers build
//! a servo from.
//!
//! Every number carries its source in [`ServoSpec::source`]. Speeds are stored in
//! rad/s and torques in N m (SI inside, as everywhere in twinloop); the datasheet
//! units are converted here, once.

use crate::builtin::parts::{Part, PartKind};
use crate::{Geometry, Pose};
// The catalogue's datasheets (stall torque, voltage, speed); mass and size are here.
use twinloop_servos::ServoModel::{Rx28, Rx64};

/// One servo model as its datasheet gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoSpec {
    /// Maker's model name, e.g. `RX-28`.
    pub name: &'static str,
    /// Stall torque, N m (the URDF `effort` limit of the joints it drives).
    pub stall_torque: f64,
    /// Supply voltage the stall torque and no-load speed are given at, V.
    pub rated_voltage: f64,
    /// No-load output speed, rad/s (the URDF `velocity` limit).
    pub no_load_speed: f64,
    /// Mass of the servo, kg.
    pub mass: f64,
    /// Case size as the maker lists it, m: for Dynamixel `W x H x D` (D along the
    /// output axis), for hobby servos `length x width x height` (height along the
    /// output shaft).
    pub size: [f64; 3],
    /// Full travel of position control, rad (Dynamixel RX: 300 degrees).
    pub travel: f64,
    /// Position feedback steps over [`ServoSpec::travel`] (Dynamixel RX: 1024);
    /// `None` for a hobby servo without feedback to the controller.
    pub position_steps: Option<u32>,
    /// Where the numbers come from.
    pub source: &'static str,
}

/// rpm to rad/s.
pub const fn rpm(v: f64) -> f64 {
    v * std::f64::consts::PI / 30.0
}

/// kgf cm (the hobby-servo torque unit, printed as "kg/cm" in seed 003) to N m.
pub const fn kgf_cm(v: f64) -> f64 {
    v * 9.80665 / 100.0
}

/// ROBOTIS Dynamixel RX-28 (18 of them in km20).
pub const RX28: ServoSpec = ServoSpec {
    name: Rx28.name(),
    stall_torque: Rx28.spec().stall_torque,
    rated_voltage: Rx28.spec().voltage,
    no_load_speed: Rx28.spec().no_load_speed,
    mass: 0.072,
    size: [0.0356, 0.0506, 0.0355],
    travel: 300.0 * std::f64::consts::PI / 180.0,
    position_steps: Some(1024),
    source: "ROBOTIS e-manual, RX-28 specifications: 72 g, 35.6 x 50.6 x 35.5 mm (W x H x D), \
             stall torque 3.7 N m at 18.5 V, no-load speed 85 rpm at 18.5 V, 0-300 degrees, 0.29 degree resolution",
};

/// ROBOTIS Dynamixel RX-64 (2 of them in km20, at the knees).
pub const RX64: ServoSpec = ServoSpec {
    name: Rx64.name(),
    stall_torque: Rx64.spec().stall_torque,
    rated_voltage: Rx64.spec().voltage,
    no_load_speed: Rx64.spec().no_load_speed,
    mass: 0.125,
    size: [0.0402, 0.0611, 0.041],
    travel: 300.0 * std::f64::consts::PI / 180.0,
    position_steps: Some(1024),
    source: "ROBOTIS e-manual, RX-64 specifications: 125 g, 40.2 x 61.1 x 41 mm (W x H x D), \
             stall torque 5.3 N m at 18.5 V, no-load speed 64 rpm at 18.5 V, 0-300 degrees",
};

/// The LD-2015 hobby servo of lab17 (seed 003).
///
/// Only the torque, travel and the no-load current are in seed 003 ("Stall torque:
/// 15 kg/cm at 6 V; 17 kg/cm at 7.4 V", "0.5~2.5 ms high level pulse, 0~180 degree").
/// We take the 7.4 V figure because the robot's distribution board is rated "up to
/// 7.4 V" (seed 003, section 2.3), i.e. a 2-cell Li-Po. No maker datasheet for the
/// LD-2015 was available to us, so mass, size and speed are ASSUMED values of the
/// standard-size metal-gear digital servo class it belongs to (the seed's Figure 14
/// draws it as a plain parallelepiped): case 40 x 20 x 40.5 mm, 60 g, 0.16 s per 60
/// degrees at 7.4 V. Replace them when the real servo is weighed and timed.
pub const LD2015: ServoSpec = ServoSpec {
    name: "LD-2015",
    stall_torque: kgf_cm(17.0),
    rated_voltage: 7.4,
    no_load_speed: (60.0 / 0.16) * std::f64::consts::PI / 180.0,
    mass: 0.060,
    size: [0.040, 0.020, 0.0405],
    travel: std::f64::consts::PI,
    position_steps: None,
    source: "seed 003 section 2.1: stall torque 17 kgf cm at 7.4 V (15 at 6 V), 0-180 degrees; \
             ASSUMED (no datasheet available): 60 g, 40 x 20 x 40.5 mm, 0.16 s/60 degrees at 7.4 V",
};

/// Every servo model the built-in robots use.
pub const ALL_SERVOS: [&ServoSpec; 3] = [&RX28, &RX64, &LD2015];

/// Density of the aluminium horns, kg/m^3.
const ALUMINIUM: f64 = 2700.0;
/// Horn thickness of the Dynamixel RX horns, m (a few millimetres; it only moves
/// grams around).
const HORN_THICKNESS: f64 = 0.0025;
/// Front and back cover thickness, m.
const COVER_THICKNESS: f64 = 0.005;
/// How much smaller the covers are than the middle case at each edge (their rounded rim), m.
const COVER_INSET: f64 = 0.001;

/// The horn radius of a Dynamixel RX servo, m: the horn spans a little more than half
/// the case width (RX-28 horn about 22 mm across, RX-64 about 25 mm).
fn horn_radius(spec: &ServoSpec) -> f64 {
    0.31 * spec.size[0]
}

/// A Dynamixel servo body as seed 000 builds it: three boxes and two cylinders.
///
/// The boxes are the case's three shells (middle case, front cover, back cover; the
/// covers a little smaller at the rim, so the three are of different sizes, as seed
/// 001's Figure 4 shows); the cylinders are the aluminium output horn on the front
/// face and the idler horn on the back face. The horns get the mass of aluminium
/// discs; the rest of the datasheet mass is spread over the three boxes by volume, so
/// the five parts weigh exactly [`ServoSpec::mass`].
///
/// Servo frame: origin on the output axis at the middle of the case's depth, z along
/// the output axis (front face at +z), the case's long side `H` along -x: the axis
/// sits in the middle of the `W x W` square at the +x end of the case, as on the RX
/// series. `mount` places this frame in the link.
pub fn dynamixel_body(spec: &ServoSpec, prefix: &str, mount: Pose) -> Vec<Part> {
    let [w, h, d] = spec.size;
    let r = horn_radius(spec);
    let horn_mass = ALUMINIUM * std::f64::consts::PI * r * r * HORN_THICKNESS;
    let case_depth = d - 2.0 * HORN_THICKNESS;
    let middle_depth = case_depth - 2.0 * COVER_THICKNESS;
    let x_center = 0.5 * (w - h);
    let middle = [h, w, middle_depth];
    let cover = [
        h - 2.0 * COVER_INSET,
        w - 2.0 * COVER_INSET,
        COVER_THICKNESS,
    ];
    let vol = |s: [f64; 3]| s[0] * s[1] * s[2];
    let box_mass = spec.mass - 2.0 * horn_mass;
    let total_volume = vol(middle) + 2.0 * vol(cover);
    let cover_z = 0.5 * case_depth - 0.5 * COVER_THICKNESS;
    let horn_z = 0.5 * case_depth + 0.5 * HORN_THICKNESS;
    let local = [
        (
            "case",
            box_mass * vol(middle) / total_volume,
            Pose::from_xyz([x_center, 0.0, 0.0]),
            Geometry::Box { size: middle },
        ),
        (
            "front_cover",
            box_mass * vol(cover) / total_volume,
            Pose::from_xyz([x_center, 0.0, cover_z]),
            Geometry::Box { size: cover },
        ),
        (
            "back_cover",
            box_mass * vol(cover) / total_volume,
            Pose::from_xyz([x_center, 0.0, -cover_z]),
            Geometry::Box { size: cover },
        ),
        (
            "horn",
            horn_mass,
            Pose::from_xyz([0.0, 0.0, horn_z]),
            Geometry::Cylinder {
                radius: r,
                length: HORN_THICKNESS,
            },
        ),
        (
            "idler_horn",
            horn_mass,
            Pose::from_xyz([0.0, 0.0, -horn_z]),
            Geometry::Cylinder {
                radius: r,
                length: HORN_THICKNESS,
            },
        ),
    ];
    local
        .into_iter()
        .map(|(name, mass, pose, geometry)| Part {
            name: format!("{prefix}_{name}"),
            mass,
            origin: crate::builtin::parts::compose(&mount, &pose),
            geometry,
            kind: PartKind::Servo,
        })
        .collect()
}

/// A hobby servo as seed 003 models it (its Figure 14: "the servomotor ... considered as
/// the equivalent of a parallelepiped"): one box of the case size and the servo's mass.
///
/// Servo frame: origin on the output shaft at the middle of the case height, z along
/// the shaft, the case's length along x with the shaft 10 mm from the +x end (the
/// standard-size layout), width along y.
pub fn hobby_servo_body(spec: &ServoSpec, prefix: &str, mount: Pose) -> Vec<Part> {
    let [l, w, h] = spec.size;
    let shaft_from_end = 0.010;
    let pose = Pose::from_xyz([shaft_from_end - 0.5 * l, 0.0, 0.0]);
    vec![Part {
        name: format!("{prefix}_case"),
        mass: spec.mass,
        origin: crate::builtin::parts::compose(&mount, &pose),
        geometry: Geometry::Box { size: [l, w, h] },
        kind: PartKind::Servo,
    }]
}
