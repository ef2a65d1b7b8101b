//! `lab17`: the 17-DoF laboratory humanoid of seed 003, built from boxes.
//!
//! What seed 003 fixes (and the tests check):
//!
//! | fact | value | source |
//! |---|---|---|
//! | degrees of freedom | 17 | seed 003 section 2 |
//! | height, width, mass | 0.365 m, 0.215 m, 1.65 kg ("about 1650 g") | seed 003 section 2 |
//! | servos | LD-2015, 17 kgf cm at 7.4 V, 0-180 degrees | seed 003 section 2.1 |
//! | leg joints | ankle roll and pitch, knee pitch, hip roll and pitch | seed 003 section 7.2 |
//! | body inertias | boxes, Table 1's formulas; a servo is one box (Figure 14) | seed 003 section 3 |
//! | trims | Table 2, the servo angles of the standing pose | seed 003 section 6 |
//! | distribution board | 30 g, 53.3 x 101.5 mm | seed 003 section 2.3 |
//! | gyroscopes | two GY-521 (MPU-6050), one on each foot | seed 003 sections 2.2, 7 |
//!
//! The seed's Figure 1 (the dimension drawing) did not survive the text extraction, so
//! the layout below is ours. The 17 joints are the layout of the common 17-servo
//! humanoid kits this robot is built like: 5 per leg (the 5 the seed names), 3 per arm
//! (shoulder pitch, shoulder roll, elbow: the seed's walk moves a "shoulder pitch"), 1
//! head pan: 10 + 6 + 1 = 17.
//!
//! Joint zero is the trim pose (Table 2): the standing pose the gait moves around, so a
//! gait offset of seed 003's eq. 6 is a joint angle (times the servo's mounting
//! direction, see [`Trim`]). Axes as km20: pitch about +y, roll about +x, yaw about +z.

use crate::builtin::parts::{LinkParts, Part, PartKind, frame};
use crate::builtin::servo::{LD2015, hobby_servo_body};
use crate::builtin::{FootGeometry, JointServo};
use crate::{Description, DescriptionBuilder, DescriptionError, Inertia, Pose};

/// The robot's name, as in `builtin:lab17`.
pub const NAME: &str = "lab17";

/// Seed 003 section 2: height, width, mass.
pub const HEIGHT: f64 = 0.365;
pub const WIDTH: f64 = 0.215;
pub const MASS: f64 = 1.65;

/// Sole to ankle roll axis, m: the roll servo stands on the 3 mm foot plate with its
/// 40 mm length vertical and its shaft 10 mm from the top: 0.003 + 0.040 - 0.010.
pub const ANKLE_ROLL_HEIGHT: f64 = 0.033;
/// Ankle roll to ankle pitch axis, m: one U bracket around a servo (30 mm).
pub const ANKLE_ROLL_TO_PITCH: f64 = 0.030;
/// Sole to ankle pitch axis (seed 000's L0 for this robot), m.
pub const ANKLE_PITCH_HEIGHT: f64 = ANKLE_ROLL_HEIGHT + ANKLE_ROLL_TO_PITCH;
/// Shin (ankle pitch to knee) and thigh (knee to hip pitch), m. With the ankle, hip and
/// trunk stack chosen here they close the 365 mm height; they are the 75 mm two-bracket
/// segments of the standard-servo kits.
pub const SHIN: f64 = 0.075;
pub const THIGH: f64 = 0.075;
/// Hip pitch to hip roll axis, m: one U bracket.
pub const HIP_PITCH_TO_ROLL: f64 = 0.030;
/// Lateral distance of each hip roll axis (and ankle) from the mid-plane, m: the two
/// hip-roll servos side by side in the 105 mm wide trunk.
pub const HIP_HALF_SPACING: f64 = 0.035;
/// Height of the trunk frame (the hip-roll axes) above the sole, m: 0.243.
pub const TRUNK_ORIGIN_HEIGHT: f64 = ANKLE_PITCH_HEIGHT + SHIN + THIGH + HIP_PITCH_TO_ROLL;
/// Trunk box, m: 105 mm wide to hold the 101.5 mm distribution board (seed 003, 2.3),
/// 60 mm deep, from 12 mm below the hip-roll axes to the head-pan joint.
pub const TRUNK_SIZE: [f64; 3] = [0.060, 0.105, 0.094];
const TRUNK_BOTTOM: f64 = -0.012;
/// Head-pan joint above the trunk frame (the trunk top), m.
pub const NECK_HEIGHT: f64 = TRUNK_BOTTOM + TRUNK_SIZE[2];
/// Shoulder pitch axes in the trunk frame, m: 20 mm below the trunk top, 57.5 mm out
/// (just outside the trunk side).
pub const SHOULDER: [f64; 3] = [0.0, 0.0575, NECK_HEIGHT - 0.020];
/// Shoulder pitch to shoulder roll axis (outwards), m.
pub const SHOULDER_TO_ROLL: f64 = 0.020;
/// Shoulder roll to elbow, m.
pub const UPPER_ARM: f64 = 0.055;
/// Forearm and hand box, m; 60 mm across so the arms' outer faces are WIDTH apart.
pub const FOREARM_SIZE: [f64; 3] = [0.030, 0.060, 0.080];
/// Foot plate, m: 130 x 60 x 3 mm with the ankle over its middle (65 mm in front, 65
/// behind). No foot size is in the seed; its walk fixes how far the sole must reach
/// behind the ankle. Seed 003 section 5: "to keep the upper stance the projected
/// location of the robot CG onto the ground surface should be kept within the
/// supporting foot base", and its sequence (section 6) lands the left foot in stage F
/// (knee and hip pitch +40 servo degrees, the shin parallel to the trunk) THIGH x
/// sin 40 deg = 48 mm ahead of the hip, toe up 10 degrees, then moves the whole weight
/// onto it in stage H before J/K straighten that leg. The CG, near the hip, is then
/// about 50 mm behind the left ankle; a toe-up sole reaches
/// `back cos 10 - ANKLE_ROLL_HEIGHT sin 10` behind it, so `back` must exceed ~56 mm.
/// With the earlier 45 mm heel the robot fell backwards in stage H/J every time
/// (docs/lab17-walking-identification.md); 65 mm leaves ~10 mm of margin.
pub const FOOT_LENGTH: f64 = 0.130;
pub const FOOT_FRONT: f64 = 0.065;
pub const FOOT_WIDTH: f64 = 0.060;
pub const FOOT_THICKNESS: f64 = 0.003;

const DEG: f64 = std::f64::consts::PI / 180.0;
const UP: [f64; 3] = [0.0, 0.0, 1.0];
const DOWN: [f64; 3] = [0.0, 0.0, -1.0];
const FORWARD: [f64; 3] = [1.0, 0.0, 0.0];
const LEFT: [f64; 3] = [0.0, 1.0, 0.0];
const RIGHT: [f64; 3] = [0.0, -1.0, 0.0];

/// Seed 003 Table 1: the inertia tensor of a rectangular parallelepiped about its
/// centre, Ix = m/12 (a^2 + b^2), Iy = m/12 (a^2 + c^2), Iz = m/12 (b^2 + c^2).
///
/// With x, y, z the body axes this makes `a` the side along z, `b` along y and `c` along
/// x (Ix involves the two sides across x). `Inertia::solid_box(m, [c, b, a])` is the
/// same tensor; the tests hold every lab17 part to this function.
pub fn table1_box_inertia(m: f64, a: f64, b: f64, c: f64) -> Inertia {
    Inertia::diagonal(
        m / 12.0 * (a * a + b * b),
        m / 12.0 * (a * a + c * c),
        m / 12.0 * (b * b + c * c),
    )
}

/// One row of seed 003's Table 2 with how it maps to the joint angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trim {
    pub joint: &'static str,
    /// Table 2: the servo angle of the standing (trim) pose, degrees on the servo's
    /// 0-180 scale. The model's joint angle 0 is this servo angle.
    pub servo_deg: f64,
    /// Joint angle = direction x (servo angle - trim). Inferred from the gait code of
    /// seed 003 (see [`TRIMS`]).
    pub direction: f64,
}

/// Seed 003 Table 2 ("Absolute values of servomotors") and the mounting directions.
///
/// The seed does not say which way each servo is mounted; the directions are inferred
/// from its gait stages with this model's axes (a leg steps forward by hip flexion =
/// negative hip pitch, knee flexion = positive knee, toe up = negative ankle pitch; the
/// body leans left over a foot by positive ankle roll; an arm swings forward by
/// negative shoulder pitch):
/// - stage C moves the right leg forward with ankle -10, knee -20, hip -20 (servo
///   degrees) and stage F the left leg with ankle -10, knee +40, hip +40: so hip pitch
///   is +1 on the right and -1 on the left, knee -1 on the right and +1 on the left
///   (the mirror-mounted pitch servos of the two legs), ankle pitch +1 on both sides
///   (the toe lifts in both stages, so the stepping foot lands heel first; it is
///   flattened by the weight, which pulls the body forward over it);
/// - stages B and H shift the weight onto the left foot with both ankle rolls at -7
///   (H prints `Offset_1_L = -7` twice; D, G, L and "A=0" reset both ankle rolls, so
///   the second is `Offset_1_R`). Equal offsets on both ankles can only shift the
///   weight if both servos turn the same way (both legs lean together, a
///   parallelogram); mirrored ankle-roll servos would splay the legs and shift
///   nothing (our first reading, under which lab17 never unloaded a foot). So both
///   ankle rolls are -1, and -7 leans the body left.
/// - the shoulders: B/H set the right shoulder +30 and E/M (inferred) the left -30,
///   and the seed says these pitches help shift the CG onto the supporting foot
///   ("shifted to the left leg by applying ankle roll and right shoulder pitch", B;
///   "ankle's roll and shoulder's pitch", E). Each of those weight shifts is onto the
///   foot that stepped forward (the right after C, the left after F), so the arm
///   must swing forward to help (backwards it would pull the CG off the heel of that
///   foot): +30 servo degrees on the right and -30 on the left are both forward
///   swings, so the right shoulder is -1 and the left +1.
pub const TRIMS: [Trim; 10] = [
    Trim {
        joint: "l_ank_roll",
        servo_deg: 97.0,
        direction: -1.0,
    },
    Trim {
        joint: "l_ank_pitch",
        servo_deg: 74.0,
        direction: 1.0,
    },
    Trim {
        joint: "l_knee",
        servo_deg: 6.0,
        direction: 1.0,
    },
    Trim {
        joint: "l_hip_pitch",
        servo_deg: 85.0,
        direction: -1.0,
    },
    Trim {
        joint: "l_sho_pitch",
        servo_deg: 155.0,
        direction: 1.0,
    },
    Trim {
        joint: "r_ank_roll",
        servo_deg: 79.0,
        direction: -1.0,
    },
    Trim {
        joint: "r_ank_pitch",
        servo_deg: 82.0,
        direction: 1.0,
    },
    Trim {
        joint: "r_knee",
        servo_deg: 142.0,
        direction: -1.0,
    },
    Trim {
        joint: "r_hip_pitch",
        servo_deg: 70.0,
        direction: 1.0,
    },
    Trim {
        joint: "r_sho_pitch",
        servo_deg: 87.0,
        direction: -1.0,
    },
];

/// The servo angle (degrees, 0-180) of the servos without a Table 2 row at joint zero:
/// the middle of the travel.
pub const CENTRE_DEG: f64 = 90.0;

/// The trim of a joint: its Table 2 row, or the servo centre with direction +1 for the
/// seven joints Table 2 does not list (hip and shoulder rolls, elbows, head pan).
pub fn trim(joint: &str) -> Option<Trim> {
    if let Some(t) = TRIMS.iter().find(|t| t.joint == joint) {
        return Some(*t);
    }
    SERVOS.iter().find(|s| s.joint == joint).map(|s| Trim {
        joint: s.joint,
        servo_deg: CENTRE_DEG,
        direction: 1.0,
    })
}

/// Seed 003 eq. 6 read backwards: the servo angle (degrees) that puts `joint` at
/// `angle` (rad), theta_C = theta_TRIM + direction x angle.
pub fn servo_angle_deg(joint: &str, angle: f64) -> Option<f64> {
    trim(joint).map(|t| t.servo_deg + t.direction * angle / DEG)
}

/// Seed 003 eq. 6: the joint angle (rad) of a servo angle, from the offset
/// Delta theta = theta_C - theta_TRIM.
pub fn joint_angle(joint: &str, servo_deg: f64) -> Option<f64> {
    trim(joint).map(|t| t.direction * (servo_deg - t.servo_deg) * DEG)
}

/// Which servo drives each joint: all seventeen are LD-2015.
pub const SERVOS: [JointServo; 17] = [
    JointServo::new("l_hip_roll", &LD2015),
    JointServo::new("l_hip_pitch", &LD2015),
    JointServo::new("l_knee", &LD2015),
    JointServo::new("l_ank_pitch", &LD2015),
    JointServo::new("l_ank_roll", &LD2015),
    JointServo::new("r_hip_roll", &LD2015),
    JointServo::new("r_hip_pitch", &LD2015),
    JointServo::new("r_knee", &LD2015),
    JointServo::new("r_ank_pitch", &LD2015),
    JointServo::new("r_ank_roll", &LD2015),
    JointServo::new("l_sho_pitch", &LD2015),
    JointServo::new("l_sho_roll", &LD2015),
    JointServo::new("l_elbow", &LD2015),
    JointServo::new("r_sho_pitch", &LD2015),
    JointServo::new("r_sho_roll", &LD2015),
    JointServo::new("r_elbow", &LD2015),
    JointServo::new("head_pan", &LD2015),
];

/// Joint limits (rad): the servo's 0-180 degree travel seen from the trim, i.e. the
/// joint angles of servo angles 0 and 180. The brackets may stop a joint earlier; the
/// seed does not say where.
pub fn limits(joint: &str) -> Option<(f64, f64)> {
    let a = joint_angle(joint, 0.0)?;
    let b = joint_angle(joint, 180.0)?;
    Some((a.min(b), a.max(b)))
}

/// The foot and ankle geometry the tip-over analysis uses.
pub fn foot_geometry() -> FootGeometry {
    FootGeometry {
        front: FOOT_FRONT,
        back: FOOT_LENGTH - FOOT_FRONT,
        ankle_height: ANKLE_PITCH_HEIGHT,
        roll_axis_height: ANKLE_ROLL_HEIGHT,
        ankle_half_spacing: HIP_HALF_SPACING,
        outer: 0.5 * FOOT_WIDTH,
        inner: 0.5 * FOOT_WIDTH,
        left_foot: "l_foot".into(),
        right_foot: "r_foot".into(),
        left_ankle_pitch: "l_ank_pitch".into(),
        right_ankle_pitch: "r_ank_pitch".into(),
        left_ankle_roll: "l_ank_roll".into(),
        right_ankle_roll: "r_ank_roll".into(),
        forward_lean_sign: -1.0,
        left_lean_sign: 1.0,
    }
}

/// Structure masses, kg: plausible weights of the aluminium brackets of a
/// standard-servo kit (a U bracket 10-15 g). The trunk's frame, battery and wiring
/// take what is left of the 1.65 kg.
mod budget {
    pub const HIP_BRACKET: f64 = 0.015;
    pub const THIGH_BRACKETS: f64 = 0.025;
    pub const SHIN_BRACKETS: f64 = 0.025;
    pub const ANKLE_CROSS: f64 = 0.012;
    pub const FOOT_PLATE: f64 = 0.030;
    /// GY-521 board with its header (seed 003: one gyroscope per foot).
    pub const GYRO: f64 = 0.004;
    pub const SHOULDER_BRACKET: f64 = 0.010;
    pub const UPPER_ARM_BRACKET: f64 = 0.010;
    pub const FOREARM: f64 = 0.020;
    pub const HEAD: f64 = 0.030;
    /// Arduino Mega 2560 board.
    pub const ARDUINO: f64 = 0.037;
    /// The distribution board (seed 003 section 2.3: 30 g).
    pub const DISTRIBUTION_BOARD: f64 = 0.030;
}

fn leg_links(s: f64) -> Vec<LinkParts> {
    use budget::*;
    let p = if s > 0.0 { "l" } else { "r" };
    let outward = if s > 0.0 { LEFT } else { RIGHT };
    let servo = |name: &str, mount: Pose| hobby_servo_body(&LD2015, &format!("{p}_{name}"), mount);
    // Hip-roll child: U bracket down to the hip-pitch servo (shaft along y, case
    // lying backwards from it).
    let hip = LinkParts::new(&format!("{p}_hip"))
        .with(Part::boxed(
            &format!("{p}_hip_bracket"),
            PartKind::Structure,
            HIP_BRACKET,
            [0.025, 0.045, 0.003],
            [0.0, 0.0, -0.010],
        ))
        .with_all(servo(
            "hip_pitch_servo",
            frame([0.0, 0.0, -HIP_PITCH_TO_ROLL], FORWARD, outward),
        ))
        .collision_box([0.040, 0.041, 0.030], [-0.010, 0.0, -0.020]);
    // Thigh: brackets and the knee servo, its case standing up from the knee shaft.
    let thigh = LinkParts::new(&format!("{p}_thigh"))
        .with(Part::boxed(
            &format!("{p}_thigh_brackets"),
            PartKind::Structure,
            THIGH_BRACKETS,
            [0.025, 0.048, 0.040],
            [0.0, 0.0, -0.030],
        ))
        .with_all(servo(
            "knee_servo",
            frame([0.0, 0.0, -THIGH], DOWN, outward),
        ))
        .collision_box([0.025, 0.048, THIGH], [0.0, 0.0, -0.5 * THIGH]);
    let shin = LinkParts::new(&format!("{p}_shin"))
        .with(Part::boxed(
            &format!("{p}_shin_brackets"),
            PartKind::Structure,
            SHIN_BRACKETS,
            [0.025, 0.048, 0.040],
            [0.0, 0.0, -0.030],
        ))
        .with_all(servo(
            "ankle_pitch_servo",
            frame([0.0, 0.0, -SHIN], DOWN, outward),
        ))
        .collision_box([0.025, 0.048, SHIN], [0.0, 0.0, -0.5 * SHIN]);
    // Ankle pitch child: the cross bracket down to the roll servo's shaft.
    let ankle = LinkParts::new(&format!("{p}_ankle"))
        .with(Part::boxed(
            &format!("{p}_ankle_cross"),
            PartKind::Structure,
            ANKLE_CROSS,
            [0.025, 0.045, 0.003],
            [0.0, 0.0, -0.010],
        ))
        .collision_box([0.025, 0.045, 0.003], [0.0, 0.0, -0.010]);
    // Foot: the roll servo standing on the plate (shaft along x, 10 mm below the case
    // top), the plate and the gyroscope board.
    let sole_z = -ANKLE_ROLL_HEIGHT + 0.5 * FOOT_THICKNESS;
    let sole_x = FOOT_FRONT - 0.5 * FOOT_LENGTH;
    let foot = LinkParts::new(&format!("{p}_foot"))
        .with_all(servo(
            "ankle_roll_servo",
            frame([0.0, 0.0, 0.0], UP, FORWARD),
        ))
        .with(Part::boxed(
            &format!("{p}_sole_plate"),
            PartKind::Foot,
            FOOT_PLATE,
            [FOOT_LENGTH, FOOT_WIDTH, FOOT_THICKNESS],
            [sole_x, 0.0, sole_z],
        ))
        .with(Part::boxed(
            &format!("{p}_gyroscope"),
            PartKind::Electronics,
            GYRO,
            [0.020, 0.016, 0.004],
            [0.035, 0.0, sole_z + 0.5 * FOOT_THICKNESS + 0.002],
        ))
        .collision_box(
            [FOOT_LENGTH, FOOT_WIDTH, FOOT_THICKNESS],
            [sole_x, 0.0, sole_z],
        );
    vec![hip, thigh, shin, ankle, foot]
}

fn arm_links(s: f64) -> Vec<LinkParts> {
    use budget::*;
    let p = if s > 0.0 { "l" } else { "r" };
    let servo = |name: &str, mount: Pose| hobby_servo_body(&LD2015, &format!("{p}_{name}"), mount);
    let shoulder = LinkParts::new(&format!("{p}_shoulder"))
        .with(Part::boxed(
            &format!("{p}_shoulder_bracket"),
            PartKind::Structure,
            SHOULDER_BRACKET,
            [0.025, 0.003, 0.040],
            [0.0, s * 0.003, 0.0],
        ))
        .with_all(servo(
            "shoulder_roll_servo",
            frame([0.0, s * SHOULDER_TO_ROLL, 0.0], UP, FORWARD),
        ))
        .collision_box([0.041, 0.020, 0.040], [0.0, s * SHOULDER_TO_ROLL, -0.010]);
    let upper = LinkParts::new(&format!("{p}_upper_arm"))
        .with(Part::boxed(
            &format!("{p}_upper_arm_bracket"),
            PartKind::Structure,
            UPPER_ARM_BRACKET,
            [0.025, 0.045, 0.003],
            [0.0, 0.0, -0.015],
        ))
        .with_all(servo(
            "elbow_servo",
            frame([0.0, 0.0, -UPPER_ARM], DOWN, LEFT),
        ))
        .collision_box([0.025, 0.041, UPPER_ARM], [0.0, 0.0, -0.5 * UPPER_ARM]);
    let center = [0.0, 0.0, -0.5 * FOREARM_SIZE[2]];
    let forearm = LinkParts::new(&format!("{p}_forearm"))
        .with(Part::boxed(
            &format!("{p}_forearm_and_hand"),
            PartKind::Structure,
            FOREARM,
            FOREARM_SIZE,
            center,
        ))
        .collision_box(FOREARM_SIZE, center);
    vec![shoulder, upper, forearm]
}

fn trunk_link(rest: f64) -> LinkParts {
    use budget::*;
    let servo = |name: &str, mount: Pose| hobby_servo_body(&LD2015, name, mount);
    let mut t = LinkParts::new("trunk");
    for (p, s) in [("l", 1.0), ("r", -1.0)] {
        // Hip-roll servos: shaft forward at the hip-roll axis, case standing up.
        t = t.with_all(servo(
            &format!("{p}_hip_roll_servo"),
            frame([0.0, s * HIP_HALF_SPACING, 0.0], DOWN, FORWARD),
        ));
        // Shoulder-pitch servos: shaft out at the shoulder, case hanging down inside.
        t = t.with_all(servo(
            &format!("{p}_shoulder_pitch_servo"),
            frame(
                [0.0, s * (SHOULDER[1] - 0.5 * LD2015.size[2]), SHOULDER[2]],
                UP,
                if s > 0.0 { LEFT } else { RIGHT },
            ),
        ));
    }
    t = t.with_all(servo(
        "head_pan_servo",
        frame([0.0, 0.0, NECK_HEIGHT - 0.5 * LD2015.size[2]], FORWARD, UP),
    ));
    t = t
        .with(Part::boxed(
            "arduino_mega",
            PartKind::Electronics,
            ARDUINO,
            [0.012, 0.1016, 0.0533],
            [0.022, 0.0, 0.040],
        ))
        .with(Part::boxed(
            "distribution_board",
            PartKind::Electronics,
            DISTRIBUTION_BOARD,
            [0.006, 0.1015, 0.0533],
            [-0.022, 0.0, 0.040],
        ));
    // Frame, battery and wiring: an open box of four walls and a bottom plate carrying
    // the rest of the mass, spread by area.
    let frame_mass = rest - t.mass();
    let [fx, fy, fz] = TRUNK_SIZE;
    let zc = TRUNK_BOTTOM + 0.5 * fz;
    let walls = [
        ("trunk_left", [fx, 0.003, fz], [0.0, 0.5 * fy, zc]),
        ("trunk_right", [fx, 0.003, fz], [0.0, -0.5 * fy, zc]),
        ("trunk_front", [0.003, fy, fz], [0.5 * fx, 0.0, zc]),
        ("trunk_back", [0.003, fy, fz], [-0.5 * fx, 0.0, zc]),
        (
            "trunk_bottom",
            [fx, fy, 0.003],
            [0.0, 0.0, TRUNK_BOTTOM + 0.0015],
        ),
    ];
    let area = |s: [f64; 3]| {
        let mut v = s;
        v.sort_by(f64::total_cmp);
        v[1] * v[2]
    };
    let total_area: f64 = walls.iter().map(|w| area(w.1)).sum();
    for (name, size, xyz) in walls {
        t = t.with(Part::boxed(
            name,
            PartKind::Structure,
            frame_mass * area(size) / total_area,
            size,
            xyz,
        ));
    }
    t.collision_box(TRUNK_SIZE, [0.0, 0.0, zc])
}

fn head_link() -> LinkParts {
    let h = HEIGHT - TRUNK_ORIGIN_HEIGHT - NECK_HEIGHT;
    let size = [0.040, 0.040, h];
    let center = [0.0, 0.0, 0.5 * h];
    LinkParts::new("head")
        .with(Part::boxed(
            "head_shell",
            PartKind::Structure,
            budget::HEAD,
            size,
            center,
        ))
        .collision_box(size, center)
}

fn joint(
    b: DescriptionBuilder,
    name: &str,
    parent: &str,
    child: &str,
    axis: [f64; 3],
    xyz: [f64; 3],
) -> DescriptionBuilder {
    let (lo, hi) = limits(name).expect("every lab17 joint has a servo");
    b.revolute(name, parent, child, axis)
        .origin(Pose::from_xyz(xyz))
        .limits(lo, hi, LD2015.stall_torque, LD2015.no_load_speed)
        .done()
}

/// Build lab17. The zero configuration is the trim (standing) pose; with the trunk
/// frame [`TRUNK_ORIGIN_HEIGHT`] above the ground the soles rest on it.
pub fn build() -> Result<Description, DescriptionError> {
    const X: [f64; 3] = [1.0, 0.0, 0.0];
    const Y: [f64; 3] = [0.0, 1.0, 0.0];
    const Z: [f64; 3] = [0.0, 0.0, 1.0];
    let legs = [leg_links(1.0), leg_links(-1.0)];
    let arms = [arm_links(1.0), arm_links(-1.0)];
    let head = head_link();
    let limbs: f64 = legs
        .iter()
        .chain(arms.iter())
        .flatten()
        .map(|l| l.mass())
        .sum();
    let trunk = trunk_link(MASS - limbs - head.mass());
    let mut b = DescriptionBuilder::new(NAME).add_link(trunk.to_link());
    for ((p, s), links) in [("l", 1.0), ("r", -1.0)].into_iter().zip(&legs) {
        for l in links {
            b = b.add_link(l.to_link());
        }
        let n = |j: &str| format!("{p}_{j}");
        let chain = [
            (
                "hip_roll",
                "trunk".to_string(),
                X,
                [0.0, s * HIP_HALF_SPACING, 0.0],
            ),
            ("hip_pitch", n("hip"), Y, [0.0, 0.0, -HIP_PITCH_TO_ROLL]),
            ("knee", n("thigh"), Y, [0.0, 0.0, -THIGH]),
            ("ank_pitch", n("shin"), Y, [0.0, 0.0, -SHIN]),
            ("ank_roll", n("ankle"), X, [0.0, 0.0, -ANKLE_ROLL_TO_PITCH]),
        ];
        for ((kind, parent, axis, xyz), child) in chain.into_iter().zip(links) {
            b = joint(b, &n(kind), &parent, &child.name, axis, xyz);
        }
    }
    for ((p, s), links) in [("l", 1.0), ("r", -1.0)].into_iter().zip(&arms) {
        for l in links {
            b = b.add_link(l.to_link());
        }
        let n = |j: &str| format!("{p}_{j}");
        let chain = [
            (
                "sho_pitch",
                "trunk".to_string(),
                Y,
                [SHOULDER[0], s * SHOULDER[1], SHOULDER[2]],
            ),
            (
                "sho_roll",
                n("shoulder"),
                X,
                [0.0, s * SHOULDER_TO_ROLL, 0.0],
            ),
            ("elbow", n("upper_arm"), Y, [0.0, 0.0, -UPPER_ARM]),
        ];
        for ((kind, parent, axis, xyz), child) in chain.into_iter().zip(links) {
            b = joint(b, &n(kind), &parent, &child.name, axis, xyz);
        }
    }
    b = b.add_link(head.to_link());
    b = joint(b, "head_pan", "trunk", "head", Z, [0.0, 0.0, NECK_HEIGHT]);
    b.build()
}
