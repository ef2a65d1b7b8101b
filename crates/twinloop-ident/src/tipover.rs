//! The CoM from the ankle angles at which a standing robot tips over (seeds 000, 001).
//!
//! The experiment: from the standing pose, turn both ankles so the body leans forward
//! (then backward, left, right) over flat feet until the robot falls; the ankle angle at
//! the fall is the tip angle in that direction. Two estimators turn the four angles into
//! the CoM, both as `[x, y, z]` in metres relative to the midpoint of the two ankle
//! (pitch) axes in the standing pose, x forward, y left, z up:
//!
//! - [`seed_method`]: seed 000 eq. 8-13 exactly as printed, with its constants;
//! - [`exact_method`]: rigid-body statics. At the tipping instant the CoM is vertically
//!   above the edge of the support; a forward and a backward angle give two equations
//!   for the CoM's height and forward offset, a left and a right angle two for its
//!   height and lateral offset.
//!
//! [`tip_angles`] is the forward problem: the static tip angles of a CoM on given feet.
//!
//! Geometry (see [`twinloop_description::builtin::FootGeometry`]): leaning forward or backward, the
//! body turns about the common line of the ankle pitch axes (x = 0, z = 0 here) with
//! both feet flat, and tips over the sole's front edge at x = +F1 or back edge at
//! x = -F2.
//!
//! Leaning sideways cannot work that way. The two ankle roll axes are parallel but at
//! different places, and a rigid upper body cannot turn about both at once: with the
//! hips held, two flat feet, two legs, the pelvis and the ground form a closed chain
//! that does not move, and a robot whose ankle rolls alone are turned rocks onto its
//! sole edges instead of leaning. The sideways protocol therefore turns each hip roll
//! with its ankle roll by the same angle (what a robot's compliant hips do on their
//! own): the legs move as a parallelogram, both feet stay flat, the pelvis stays level
//! and slides sideways and down. The feet do not move, each leg link turns about its
//! ankle roll axis, everything above the hip rolls translates by the leg's length:
//! `y(theta) = y0 + S sin(theta) - C (1 - cos(theta))`, where S (the frontal lever,
//! [`frontal_lever`]) is the mass-weighted height of the leg links above their ankle
//! roll axes plus the leg length for the mass above the hips, and C the mass-weighted
//! lateral offset of the leg links from their own ankle axes (zero for mirror-image
//! legs). The robot tips over the outer edge of the leading foot, at
//! `y = +-(d + outer)` from the mid-plane, so the left and right leg angles give two
//! equations for `y0` and `S`. Sideways the experiment measures the CoM's lateral
//! offset and the lever, not a second height: the height does not enter a
//! parallelogram lean except through S.
//!
//! ```
//! use twinloop_ident::tipover::{FeetMass, FrontalLever, exact_method, tip_angles};
//! let foot = twinloop_description::builtin::foot_geometry("km20").unwrap();
//! let com = [0.004, -0.002, 0.22];
//! let lever = FrontalLever { sin: 0.17, cos: 0.0 };
//! let feet = FeetMass { fraction: 0.11, x: -0.025, z: -0.011 };
//! let angles = tip_angles(com, &feet, &lever, &foot).unwrap();
//! let back = exact_method(&angles, &feet, &foot).unwrap();
//! assert!((back.com[2] - 0.22).abs() < 1e-12);
//! ```

use crate::error::IdentError;
use twinloop_description::builtin::FootGeometry;
use twinloop_dynamics::{BASE, Data, Model, forward_kinematics};
use twinloop_reduced::error::{finite, positive};

/// Seed 000 eq. 8: the four tip angles in degrees, from raw Dynamixel positions (1024
/// steps over 300 degrees): `alpha1 = (Center - MaxFwd) 300/1024`, `beta1 = (MaxBwd -
/// Center) 300/1024`, `alpha2 = (Center - MaxLeft) 300/1024`, `beta2 = (MaxRight -
/// Center) 300/1024`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeedAngles {
    /// Max forward angle, degrees.
    pub alpha1: f64,
    /// Max backward angle, degrees.
    pub beta1: f64,
    /// Max left angle, degrees.
    pub alpha2: f64,
    /// Max right angle, degrees.
    pub beta2: f64,
}

impl SeedAngles {
    /// Seed 000 eq. 8 from the ankle servo's raw positions (0-1023): the centre (the
    /// standing pose) and the readings at the forward, backward, left and right falls.
    pub fn from_positions(
        center: f64,
        max_forward: f64,
        max_backward: f64,
        max_left: f64,
        max_right: f64,
    ) -> Result<SeedAngles, IdentError> {
        let k = 300.0 / 1024.0;
        for (f, v) in [
            ("center", center),
            ("max_forward", max_forward),
            ("max_backward", max_backward),
            ("max_left", max_left),
            ("max_right", max_right),
        ] {
            finite(f, v)?;
        }
        Ok(SeedAngles {
            alpha1: (center - max_forward) * k,
            beta1: (max_backward - center) * k,
            alpha2: (center - max_left) * k,
            beta2: (max_right - center) * k,
        })
    }
}

/// The constants of seed 000 section V.A, in metres (the seed gives centimetres; every
/// length in eq. 10-13 scales with them, so the metre version is the same method).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeedConstants {
    /// F1: ankle to the front of the foot plate.
    pub f1: f64,
    /// F2: ankle to the back of the foot plate.
    pub f2: f64,
    /// L0: foot plate to the ankle rotation point.
    pub l0: f64,
    /// phi, "the single support ratio". It appears in none of eq. 8-13; kept so the
    /// seed's constants are complete.
    pub phi: f64,
}

/// F1 = 3.5 cm, F2 = 9.5 cm, L0 = 3.1 cm, phi = 2.2 (seed 000 section V.A).
pub const SEED_000_CONSTANTS: SeedConstants = SeedConstants {
    f1: 0.035,
    f2: 0.095,
    l0: 0.031,
    phi: 2.2,
};

impl SeedConstants {
    /// The seed's constants for a robot's feet: F1, F2, L0 from its geometry (phi kept).
    pub fn from_foot(foot: &FootGeometry) -> SeedConstants {
        SeedConstants {
            f1: foot.front,
            f2: foot.back,
            l0: foot.ankle_height,
            phi: SEED_000_CONSTANTS.phi,
        }
    }
}

/// Every quantity of seed 000 eq. 9-13 (lengths in m, angles in degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeedEstimate {
    /// Eq. 9: gamma1 = (alpha1 + beta1)/2 - alpha1.
    pub gamma1: f64,
    /// Eq. 10: L1 = tan(90 - beta1) F2.
    pub l1: f64,
    /// Eq. 11: theta1 = atan((L1 + L0) / F2).
    pub theta1: f64,
    /// Eq. 11: L3 = F2 / cos(theta1).
    pub l3: f64,
    /// Eq. 12: D1 = L3 tan(gamma1).
    pub d1: f64,
    /// Eq. 13: gamma2 = |alpha2 - beta2|.
    pub gamma2: f64,
    /// Eq. 13: W1 = -L3 tan(gamma2) if alpha2 >= beta2, else L3 tan(gamma2).
    pub w1: f64,
    /// The seed's result (x, y, z) = (L3, W1, D1) in twinloop's axes: `[D1, W1, L3]`
    /// (x forward = D1, y left = W1, z up = L3).
    pub com: [f64; 3],
}

/// Seed 000 eq. 9-13, exactly as printed, angles in degrees.
///
/// What the formulas compute: eq. 10 is the height above the ankle axis, at the moment
/// of a backward tip, of a CoM that stood directly above the ankle (it is then F2
/// behind the ankle, on a line tilted by beta1: `F2 / tan(beta1)`). Eq. 11 adds L0 and
/// takes the hypotenuse with F2: L3 is the distance from the sole point under the
/// ankle to that CoM position, a slanted length, which the seed reports as the CoM
/// height. Eq. 9 halves the difference of the backward and forward angles, which is
/// the tilt of the CoM from the vertical through the ankle only if the foot were
/// symmetric (F1 = F2; the seed's is not); eq. 12 and 13 turn the tilts into horizontal
/// offsets at distance L3, the lateral one with the full (not halved) difference. The
/// sign convention follows the printed formulas: a larger backward than forward angle
/// gives D1 > 0, i.e. (for a symmetric foot) a CoM ahead of the ankle, reported as +x;
/// a larger left than right angle gives W1 < 0, a CoM to the right, -y.
pub fn seed_method(angles: &SeedAngles, c: &SeedConstants) -> Result<SeedEstimate, IdentError> {
    for (f, v) in [
        ("angles.alpha1", angles.alpha1),
        ("angles.alpha2", angles.alpha2),
        ("angles.beta2", angles.beta2),
    ] {
        finite(f, v)?;
    }
    if !(angles.beta1.is_finite() && angles.beta1 > 0.0 && angles.beta1 < 90.0) {
        return Err(IdentError::new(format!(
            "eq. 10 needs a backward tip angle in (0, 90) degrees, got {}",
            angles.beta1
        ))
        .field("angles.beta1"));
    }
    positive("constants.f2", c.f2)?;
    finite("constants.l0", c.l0)?;
    let rad = std::f64::consts::PI / 180.0;
    let gamma1 = (angles.alpha1 + angles.beta1) / 2.0 - angles.alpha1;
    let l1 = ((90.0 - angles.beta1) * rad).tan() * c.f2;
    let theta1 = ((l1 + c.l0) / c.f2).atan();
    let l3 = c.f2 / theta1.cos();
    let d1 = l3 * (gamma1 * rad).tan();
    let (gamma2, w1) = if angles.alpha2 >= angles.beta2 {
        let g = angles.alpha2 - angles.beta2;
        (g, -l3 * (g * rad).tan())
    } else {
        let g = angles.beta2 - angles.alpha2;
        (g, l3 * (g * rad).tan())
    };
    Ok(SeedEstimate {
        gamma1,
        l1,
        theta1: theta1 / rad,
        l3,
        d1,
        gamma2,
        w1,
        com: [d1, w1, l3],
    })
}

/// The forward and backward angles (degrees) for which [`seed_method`] returns a CoM
/// with forward offset `x` (its D1) and height `z` (its L3): eq. 9-12 solved backwards,
/// `theta1 = acos(F2 / L3)`, `L1 = F2 tan(theta1) - L0`, `beta1 = 90 - atan(L1 / F2)`,
/// `gamma1 = atan(D1 / L3)`, `alpha1 = beta1 - 2 gamma1`. Needs `z > F2` (eq. 11 makes L3
/// at least F2).
pub fn seed_method_sagittal_angles(
    x: f64,
    z: f64,
    c: &SeedConstants,
) -> Result<(f64, f64), IdentError> {
    finite("x", x)?;
    positive("constants.f2", c.f2)?;
    if !(z.is_finite() && z > c.f2) {
        return Err(IdentError::new(format!(
            "the seed's L3 is at least F2 = {} m; got {z}",
            c.f2
        ))
        .field("z"));
    }
    let deg = 180.0 / std::f64::consts::PI;
    let theta1 = (c.f2 / z).acos();
    let l1 = c.f2 * theta1.tan() - c.l0;
    let beta1 = 90.0 - (l1 / c.f2).atan() * deg;
    let gamma1 = (x / z).atan() * deg;
    Ok((beta1 - 2.0 * gamma1, beta1))
}

/// The four tip angles of the exact method, in radians, each a positive magnitude:
/// forward and backward, the lean of the body relative to the flat feet (the ankle
/// pitch angle for a rigid robot); left and right, the legs' lean in the parallelogram
/// (the ankle roll angle).
///
/// A real robot's feet roll onto the sole edge a little before it tips (its servos
/// give under the moving load): the `*_roll` fields are that roll at each tip (rad,
/// towards the tip, zero for flat feet), which turns the whole robot about the edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipAngles {
    pub forward: f64,
    pub backward: f64,
    pub left: f64,
    pub right: f64,
    pub forward_roll: f64,
    pub backward_roll: f64,
    pub left_roll: f64,
    pub right_roll: f64,
}

impl TipAngles {
    /// From degrees, feet flat (no roll).
    pub fn from_degrees(forward: f64, backward: f64, left: f64, right: f64) -> TipAngles {
        let r = std::f64::consts::PI / 180.0;
        TipAngles {
            forward: forward * r,
            backward: backward * r,
            left: left * r,
            right: right * r,
            forward_roll: 0.0,
            backward_roll: 0.0,
            left_roll: 0.0,
            right_roll: 0.0,
        }
    }

    /// `[forward, backward, left, right]` in degrees.
    pub fn to_degrees(&self) -> [f64; 4] {
        let d = 180.0 / std::f64::consts::PI;
        [
            self.forward * d,
            self.backward * d,
            self.left * d,
            self.right * d,
        ]
    }
}

/// The part of the robot that stays on the ground in the forward and backward lean:
/// everything below the ankle pitch joints (both feet, with whatever of the ankle turns
/// with them). Its share of the total mass and its CoM (m, relative to the midpoint of
/// the ankle pitch axes, x forward, z up). The body above the ankles turns, the feet do
/// not, so the robot's CoM does not turn rigidly about the ankle axis: on km20 (feet
/// 11 % of the mass) taking it as rigid puts the CoM 1.6 mm too high. The feet are part
/// of the robot's fixed geometry, like their outline: weigh them once.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FeetMass {
    pub fraction: f64,
    pub x: f64,
    pub z: f64,
}

impl FeetMass {
    /// Massless feet: the whole robot turns about the ankle axis.
    pub const NONE: FeetMass = FeetMass {
        fraction: 0.0,
        x: 0.0,
        z: 0.0,
    };
}

/// The feet of a model in configuration `q`: the links below (and including the child
/// of) the two ankle pitch joints, placed by forward kinematics, relative to the
/// midpoint of the two ankle pitch joints.
pub fn feet_mass(model: &Model, q: &[f64], ankle_pitch: [&str; 2]) -> Result<FeetMass, IdentError> {
    if q.len() != model.nq {
        return Err(
            IdentError::new(format!("has {} entries, the model {}", q.len(), model.nq)).field("q"),
        );
    }
    let joint = |name: &str| {
        model.joint_index(name).ok_or_else(|| {
            IdentError::new(format!(
                "the model \"{}\" has no joint \"{name}\"",
                model.name
            ))
            .field("ankle_pitch")
        })
    };
    let ankles = [joint(ankle_pitch[0])?, joint(ankle_pitch[1])?];
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, q);
    let mid = (data.o_m_i[ankles[0]].translation + data.o_m_i[ankles[1]].translation) * 0.5;
    let (mut total, mut mass, mut first) = (0.0, 0.0, nalgebra::Vector3::zeros());
    for link in &model.links {
        if link.body == BASE && !model.is_floating() {
            continue;
        }
        total += link.inertia.mass;
        let below = link.body != BASE
            && model
                .ancestors(link.body)
                .any(|a| a == ankles[0] || a == ankles[1]);
        if below {
            let p = (data.o_m_i[link.body] * link.placement).act_point(&link.inertia.com);
            mass += link.inertia.mass;
            first += (p - mid) * link.inertia.mass;
        }
    }
    positive("model.total_mass", total)?;
    if mass <= 0.0 {
        return Ok(FeetMass::NONE);
    }
    Ok(FeetMass {
        fraction: mass / total,
        x: first.x / mass,
        z: first.z / mass,
    })
}

/// How the CoM moves in the parallelogram sideways lean (see the module
/// documentation): `y(theta) = y0 + sin * sin(theta) - cos * (1 - cos(theta))`, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontalLever {
    /// S: mass-weighted height of the leg links above their ankle roll axes, the mass
    /// above the hip rolls counted at the leg length, over the total mass.
    pub sin: f64,
    /// C: mass-weighted lateral offset of the leg links from their ankle roll axes
    /// (towards +y), over the total mass; zero for mirror-image legs.
    pub cos: f64,
}

/// The frontal lever of a model in configuration `q` (straight legs, the hip and ankle
/// roll axes parallel): each link's mass and CoM placed by forward kinematics; the
/// links below an ankle roll joint (the feet) stay, the links between a hip roll and
/// its ankle roll turn about the ankle roll axis, all the rest translates with the
/// pelvis by the leg length (hip roll axis above ankle roll axis).
pub fn frontal_lever(
    model: &Model,
    q: &[f64],
    hip_roll: [&str; 2],
    ankle_roll: [&str; 2],
) -> Result<FrontalLever, IdentError> {
    if q.len() != model.nq {
        return Err(
            IdentError::new(format!("has {} entries, the model {}", q.len(), model.nq)).field("q"),
        );
    }
    let joint = |field: &str, name: &str| {
        model.joint_index(name).ok_or_else(|| {
            IdentError::new(format!(
                "the model \"{}\" has no joint \"{name}\"",
                model.name
            ))
            .field(field)
        })
    };
    let hips = [
        joint("hip_roll", hip_roll[0])?,
        joint("hip_roll", hip_roll[1])?,
    ];
    let ankles = [
        joint("ankle_roll", ankle_roll[0])?,
        joint("ankle_roll", ankle_roll[1])?,
    ];
    let inside = |root: usize, i: usize| i != BASE && model.ancestors(i).any(|a| a == root);
    for k in 0..2 {
        if !inside(hips[k], ankles[k]) {
            return Err(IdentError::new(format!(
                "\"{}\" is not below \"{}\" in the model",
                ankle_roll[k], hip_roll[k]
            ))
            .field("ankle_roll"));
        }
    }
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, q);
    let origin = |j: usize| data.o_m_i[j].translation;
    let legs = [
        origin(hips[0]).z - origin(ankles[0]).z,
        origin(hips[1]).z - origin(ankles[1]).z,
    ];
    if (legs[0] - legs[1]).abs() > 1e-3 {
        return Err(IdentError::new(format!(
            "the legs are {:.4} and {:.4} m long: unequal legs cannot lean as a parallelogram",
            legs[0], legs[1]
        ))
        .field("hip_roll"));
    }
    let leg = 0.5 * (legs[0] + legs[1]);
    let (mut mass, mut s, mut c) = (0.0, 0.0, 0.0);
    for link in &model.links {
        if link.body == BASE && !model.is_floating() {
            continue;
        }
        let body = if link.body == BASE {
            data.base_placement
        } else {
            data.o_m_i[link.body]
        };
        let p = (body * link.placement).act_point(&link.inertia.com);
        let m = link.inertia.mass;
        mass += m;
        let side = (0..2).find(|&k| inside(hips[k], link.body));
        match side {
            Some(k) if inside(ankles[k], link.body) => {}
            Some(k) => {
                let a = origin(ankles[k]);
                s += m * (p.z - a.z);
                c += m * (p.y - a.y);
            }
            None => s += m * leg,
        }
    }
    positive("model.total_mass", mass)?;
    Ok(FrontalLever {
        sin: s / mass,
        cos: c / mass,
    })
}

/// The CoM from the exact method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactEstimate {
    /// `[x, y, z]`, m, relative to the midpoint of the ankle pitch axes: x and z from the
    /// forward/backward pair, y from the left/right pair.
    pub com: [f64; 3],
    /// The frontal lever S the left/right pair gives (see [`FrontalLever`]).
    pub frontal_lever: f64,
}

fn check_foot(foot: &FootGeometry) -> Result<(), IdentError> {
    positive("foot.front", foot.front)?;
    positive("foot.back", foot.back)?;
    positive("foot.outer", foot.outer)?;
    finite("foot.ankle_half_spacing", foot.ankle_half_spacing)?;
    finite("foot.ankle_height", foot.ankle_height)?;
    Ok(())
}

/// The lean (rad) at which a CoM at forward offset `s` and height `z` above the ankle
/// pitch axis tips over the sole edge at `edge` (+F1 or -F2): turning the body by theta
/// about the axis towards the edge moves the CoM to `s cos(theta) + side z sin(theta)`;
/// with `A = side s`, `C = |edge|`: `A cos + z sin = C`,
/// `theta = atan2(z, A) - acos(C / hypot(A, z))`.
fn sagittal_tip(s: f64, z: f64, edge: f64, field: &str) -> Result<f64, IdentError> {
    let a = edge.signum() * s;
    let c = edge.abs();
    if a > c {
        return Err(IdentError::new(
            "the CoM is already beyond this sole edge: the robot cannot stand",
        )
        .field(field));
    }
    if z <= 0.0 {
        return Err(IdentError::new(
            "the CoM is not above the pivot axis: leaning never tips it this way",
        )
        .field(field));
    }
    let r = a.hypot(z);
    if r < c {
        return Err(IdentError::new(
            "the CoM is too close to the pivot axis to ever pass above this sole edge",
        )
        .field(field));
    }
    Ok(z.atan2(a) - (c / r).acos())
}

fn check_feet(feet: &FeetMass) -> Result<(), IdentError> {
    if !(feet.fraction.is_finite() && (0.0..1.0).contains(&feet.fraction)) {
        return Err(
            IdentError::new(format!("must be in [0, 1), got {}", feet.fraction))
                .field("feet.fraction"),
        );
    }
    finite("feet.x", feet.x)?;
    finite("feet.z", feet.z)?;
    Ok(())
}

/// The static forward and backward tip angles (rad) of a robot with its CoM at forward
/// offset `x` and height `z` above the ankle pitch axes, whose `feet` stay on the
/// ground while the rest turns rigidly about the axes: the turning part (CoM
/// `(c - mu p) / (1 - mu)`) tips when `(1 - mu) c_turning . e = edge - mu p_x`.
pub fn sagittal_tip_angles(
    x: f64,
    z: f64,
    feet: &FeetMass,
    foot: &FootGeometry,
) -> Result<(f64, f64), IdentError> {
    finite("com.x", x)?;
    finite("com.z", z)?;
    check_foot(foot)?;
    check_feet(feet)?;
    let k = 1.0 - feet.fraction;
    let (tx, tz) = (
        (x - feet.fraction * feet.x) / k,
        (z - feet.fraction * feet.z) / k,
    );
    let edge = |e: f64| (e - feet.fraction * feet.x) / k;
    Ok((
        sagittal_tip(tx, tz, edge(foot.front), "forward")?,
        sagittal_tip(tx, tz, edge(-foot.back), "backward")?,
    ))
}

/// The static left and right leg angles (rad) at which the parallelogram lean tips a
/// robot whose CoM is `y` to the left of the mid-plane: `y(theta)` reaches the outer
/// edge `E = d + outer`. Left: `S sin + C cos = E - y + C`; right (theta turned the
/// other way): `S sin - C cos = E + y - C`; with `R = hypot(S, C)`, `phi = atan2(C, S)`:
/// `theta = asin((E - y + C) / R) - phi` and `asin((E + y - C) / R) + phi`.
pub fn frontal_tip_angles(
    y: f64,
    lever: &FrontalLever,
    foot: &FootGeometry,
) -> Result<(f64, f64), IdentError> {
    finite("com.y", y)?;
    positive("lever.sin", lever.sin)?;
    finite("lever.cos", lever.cos)?;
    check_foot(foot)?;
    let e = foot.ankle_half_spacing + foot.outer;
    let r = lever.sin.hypot(lever.cos);
    let phi = lever.cos.atan2(lever.sin);
    let angle = |u: f64, field: &str| {
        if u < 0.0 {
            return Err(IdentError::new(
                "the CoM is already beyond this sole edge: the robot cannot stand",
            )
            .field(field));
        }
        if u > r {
            return Err(IdentError::new(
                "the lever is too short for the CoM ever to reach this sole edge",
            )
            .field(field));
        }
        Ok((u / r).asin())
    };
    Ok((
        angle(e - y + lever.cos, "left")? - phi,
        angle(e + y - lever.cos, "right")? + phi,
    ))
}

/// The static tip angles (rad) of a robot with CoM `com` (m, relative to the midpoint of
/// the ankle pitch axes, x forward, y left, z up), feet `feet` and frontal lever
/// `lever`, standing on `foot`, feet flat: the forward problem of [`exact_method`].
pub fn tip_angles(
    com: [f64; 3],
    feet: &FeetMass,
    lever: &FrontalLever,
    foot: &FootGeometry,
) -> Result<TipAngles, IdentError> {
    let (forward, backward) = sagittal_tip_angles(com[0], com[2], feet, foot)?;
    let (left, right) = frontal_tip_angles(com[1], lever, foot)?;
    Ok(TipAngles {
        forward,
        backward,
        left,
        right,
        forward_roll: 0.0,
        backward_roll: 0.0,
        left_roll: 0.0,
        right_roll: 0.0,
    })
}

fn solve2(a: [[f64; 2]; 2], b: [f64; 2], field: &str) -> Result<(f64, f64), IdentError> {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    if det.abs() < 1e-12 {
        return Err(IdentError::new(
            "the two tip angles give no solution (their equations are parallel)",
        )
        .field(field));
    }
    Ok((
        (b[0] * a[1][1] - a[0][1] * b[1]) / det,
        (a[0][0] * b[1] - a[1][0] * b[0]) / det,
    ))
}

/// The exact method: the CoM from the four tip angles on `foot`, the robot's feet being
/// `feet` (see the module documentation for the geometry).
///
/// Forward and backward the body above the ankles turns by the tip angle about the
/// ankle pitch axes while the feet (mass share mu, CoM p) stay; with the feet rolled
/// onto the edge by e the whole robot then turns about the edge `(X, -L0)`
/// (`X = F1` or `-F2`, s = +1 forward, -1 backward, `phi = s t`, `psi = s e`):
/// `(1 - mu) (cx cos(phi + psi) + cz sin(phi + psi)) = X cos(psi) - L0 sin(psi)
/// - mu (px cos(psi) + pz sin(psi))`, two linear equations for the turning part's CoM
/// `(cx, cz)`; the CoM is `mu p + (1 - mu) c`. With flat, massless feet this is
/// `x cos(tf) + z sin(tf) = F1`, `x cos(tb) - z sin(tb) = -F2`.
///
/// Sideways, y and the lever S solve, for the left tip with leg angle `tl` and foot roll
/// `el` (the whole robot turned about the outer edge by `el`, the CoM then above it):
/// `(y + S sin(tl) - E) cos(el) + (h - S (1 - cos(tl))) sin(el) = 0`, and the mirror
/// image for the right, where `E = d + outer` and `h = z + L0` is the CoM's height
/// above the sole in the standing pose (the parallelogram lowers it by
/// `S (1 - cos)`; the lateral offset C of the leg links is taken as zero, i.e. mirror
/// legs). With flat feet this is `y + S sin(tl) = E`, `y - S sin(tr) = -E`.
pub fn exact_method(
    angles: &TipAngles,
    feet: &FeetMass,
    foot: &FootGeometry,
) -> Result<ExactEstimate, IdentError> {
    check_foot(foot)?;
    check_feet(feet)?;
    for (f, v) in [
        ("angles.forward", angles.forward),
        ("angles.backward", angles.backward),
        ("angles.left", angles.left),
        ("angles.right", angles.right),
    ] {
        if !(v.is_finite() && v > 0.0 && v < std::f64::consts::FRAC_PI_2) {
            return Err(IdentError::new(format!(
                "a tip angle must be in (0, 90) degrees, got {}",
                degrees_text(v)
            ))
            .field(f));
        }
    }
    for (f, v) in [
        ("angles.forward_roll", angles.forward_roll),
        ("angles.backward_roll", angles.backward_roll),
        ("angles.left_roll", angles.left_roll),
        ("angles.right_roll", angles.right_roll),
    ] {
        if !(v.is_finite() && v.abs() < 0.2) {
            return Err(IdentError::new(format!(
                "a foot roll must be small (under 0.2 rad), got {v} rad"
            ))
            .field(f));
        }
    }
    let mu = feet.fraction;
    let sagittal_row = |t: f64, roll: f64, side: f64, edge: f64| {
        let (phi, psi) = (side * t, side * roll);
        let (sp, cp) = (phi + psi).sin_cos();
        let (ss, cs) = psi.sin_cos();
        (
            [(1.0 - mu) * cp, (1.0 - mu) * sp],
            edge * cs - foot.ankle_height * ss - mu * (feet.x * cs + feet.z * ss),
        )
    };
    let (f, bf) = sagittal_row(angles.forward, angles.forward_roll, 1.0, foot.front);
    let (b, bb) = sagittal_row(angles.backward, angles.backward_roll, -1.0, -foot.back);
    let (cx, cz) = solve2([f, b], [bf, bb], "angles.backward")?;
    let (x, z) = (mu * feet.x + (1.0 - mu) * cx, mu * feet.z + (1.0 - mu) * cz);
    let e = foot.ankle_half_spacing + foot.outer;
    let h = z + foot.ankle_height;
    // Rows [y coefficient, S coefficient] = rhs; the right tip is the left one mirrored
    // (y -> -y).
    let row = |t: f64, roll: f64, side: f64| {
        let (st, ct) = t.sin_cos();
        let (sr, cr) = roll.sin_cos();
        ([side * cr, st * cr - (1.0 - ct) * sr], e * cr - h * sr)
    };
    let (l, bl) = row(angles.left, angles.left_roll, 1.0);
    let (r, br) = row(angles.right, angles.right_roll, -1.0);
    let (y, s) = solve2([l, r], [bl, br], "angles.right")?;
    Ok(ExactEstimate {
        com: [x, y, z],
        frontal_lever: s,
    })
}

/// An angle in radians as degrees with sensible digits for a message (a value of
/// 1e300 rad is not worth 300 digits).
fn degrees_text(rad: f64) -> String {
    let deg = rad.to_degrees();
    if !deg.is_finite() {
        format!("{rad} rad")
    } else if deg.abs() < 1e6 {
        format!("{deg:.2} deg")
    } else {
        format!("{deg:.3e} deg")
    }
}
