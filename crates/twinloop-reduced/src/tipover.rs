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
//! Geometry (see [`twinloop_robots::FootGeometry`]): leaning forward or backward, the
//! body turns about the common line of the ankle pitch axes (x = 0, z = 0 here) with
//! both feet flat, and tips over the sole's front edge at x = +F1 or back edge at
//! x = -F2. Leaning left, the body turns about the left ankle roll axis (y = +d, at the
//! roll axis height) standing on the flat left foot (the right foot has lifted, as it
//! must: two feet turned by the same ankle roll angle cannot both lie flat), and tips
//! over its outer edge at y = d + outer; leaning right likewise about the right ankle.
//! A lean angle is the angle between the body and the foot it stands on, which is the
//! ankle joint angle measured from the standing pose.

use crate::error::{ReducedError, finite, positive};
use twinloop_robots::FootGeometry;

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
    ) -> Result<SeedAngles, ReducedError> {
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
pub fn seed_method(angles: &SeedAngles, c: &SeedConstants) -> Result<SeedEstimate, ReducedError> {
    for (f, v) in [
        ("angles.alpha1", angles.alpha1),
        ("angles.alpha2", angles.alpha2),
        ("angles.beta2", angles.beta2),
    ] {
        finite(f, v)?;
    }
    if !(angles.beta1.is_finite() && angles.beta1 > 0.0 && angles.beta1 < 90.0) {
        return Err(ReducedError::new(
            "angles.beta1",
            format!(
                "eq. 10 needs a backward tip angle in (0, 90) degrees, got {}",
                angles.beta1
            ),
        ));
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
) -> Result<(f64, f64), ReducedError> {
    finite("x", x)?;
    positive("constants.f2", c.f2)?;
    if !(z.is_finite() && z > c.f2) {
        return Err(ReducedError::new(
            "z",
            format!("the seed's L3 is at least F2 = {} m; got {z}", c.f2),
        ));
    }
    let deg = 180.0 / std::f64::consts::PI;
    let theta1 = (c.f2 / z).acos();
    let l1 = c.f2 * theta1.tan() - c.l0;
    let beta1 = 90.0 - (l1 / c.f2).atan() * deg;
    let gamma1 = (x / z).atan() * deg;
    Ok((beta1 - 2.0 * gamma1, beta1))
}

/// The four tip angles of the exact method, in radians: the lean of the body relative
/// to the foot it stands on at the moment of tipping, each a positive magnitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipAngles {
    pub forward: f64,
    pub backward: f64,
    pub left: f64,
    pub right: f64,
}

impl TipAngles {
    pub fn from_degrees(forward: f64, backward: f64, left: f64, right: f64) -> TipAngles {
        let r = std::f64::consts::PI / 180.0;
        TipAngles {
            forward: forward * r,
            backward: backward * r,
            left: left * r,
            right: right * r,
        }
    }

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

/// The CoM from the exact method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactEstimate {
    /// `[x, y, z]`, m, relative to the midpoint of the ankle pitch axes: x and z from the
    /// forward/backward pair, y from the left/right pair.
    pub com: [f64; 3],
    /// The height the left/right pair gives (a second estimate of `com[2]`).
    pub z_frontal: f64,
}

/// One tipping direction in a plane: the body turns about a pivot axis at horizontal
/// `pivot` and height `pivot_height` (relative to the reference), and tips when the
/// CoM passes above the sole edge at horizontal `edge`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tip {
    pivot: f64,
    pivot_height: f64,
    edge: f64,
}

impl Tip {
    /// +1 if the edge is on the + side of the pivot.
    fn side(&self) -> f64 {
        (self.edge - self.pivot).signum()
    }
}

/// The four tipping directions of a foot geometry: forward, backward, left, right.
fn tips(foot: &FootGeometry) -> Result<[Tip; 4], ReducedError> {
    positive("foot.front", foot.front)?;
    positive("foot.back", foot.back)?;
    positive("foot.outer", foot.outer)?;
    finite("foot.ankle_half_spacing", foot.ankle_half_spacing)?;
    finite("foot.ankle_height", foot.ankle_height)?;
    finite("foot.roll_axis_height", foot.roll_axis_height)?;
    let d = foot.ankle_half_spacing;
    let zr = foot.roll_axis_height - foot.ankle_height;
    Ok([
        Tip {
            pivot: 0.0,
            pivot_height: 0.0,
            edge: foot.front,
        },
        Tip {
            pivot: 0.0,
            pivot_height: 0.0,
            edge: -foot.back,
        },
        Tip {
            pivot: d,
            pivot_height: zr,
            edge: d + foot.outer,
        },
        Tip {
            pivot: -d,
            pivot_height: zr,
            edge: -d - foot.outer,
        },
    ])
}

/// The lean (rad) at which a CoM at horizontal `s`, height `z` tips over `tip`'s edge:
/// turning the body by theta about the pivot towards the edge moves the CoM to
/// `pivot + (s - pivot) cos(theta) + side (z - pivot_height) sin(theta)`; it tips when
/// that reaches the edge. With `A = side (s - pivot)` (offset towards the edge),
/// `B = z - pivot_height`, `C = |edge - pivot|`: `A cos + B sin = C`, i.e.
/// `theta = atan2(B, A) - acos(C / hypot(A, B))`.
fn tip_angle(s: f64, z: f64, tip: &Tip, field: &str) -> Result<f64, ReducedError> {
    let side = tip.side();
    let a = side * (s - tip.pivot);
    let b = z - tip.pivot_height;
    let c = (tip.edge - tip.pivot).abs();
    if a > c {
        return Err(ReducedError::new(
            field,
            "the CoM is already beyond this sole edge: the robot cannot stand",
        ));
    }
    if b <= 0.0 {
        return Err(ReducedError::new(
            field,
            "the CoM is not above the pivot axis: leaning never tips it this way",
        ));
    }
    let r = a.hypot(b);
    if r < c {
        return Err(ReducedError::new(
            field,
            "the CoM is too close to the pivot axis to ever pass above this sole edge",
        ));
    }
    Ok(b.atan2(a) - (c / r).acos())
}

/// The static tip angles (rad) of a rigid robot with CoM `com` (m, relative to the
/// midpoint of the ankle pitch axes, x forward, y left, z up) standing on `foot`: the
/// forward problem of [`exact_method`].
pub fn tip_angles(com: [f64; 3], foot: &FootGeometry) -> Result<TipAngles, ReducedError> {
    for (k, axis) in ["com.x", "com.y", "com.z"].iter().enumerate() {
        finite(axis, com[k])?;
    }
    let [f, b, l, r] = tips(foot)?;
    Ok(TipAngles {
        forward: tip_angle(com[0], com[2], &f, "forward")?,
        backward: tip_angle(com[0], com[2], &b, "backward")?,
        left: tip_angle(com[1], com[2], &l, "left")?,
        right: tip_angle(com[1], com[2], &r, "right")?,
    })
}

/// Solve the two tipping equations of opposite directions `p` (angle `tp`) and `n`
/// (angle `tn`) for the CoM's horizontal coordinate and height:
/// `(s - pivot) cos + side (z - pivot_height) sin = edge - pivot` for each.
fn solve_pair(
    tp: f64,
    tn: f64,
    p: &Tip,
    n: &Tip,
    fields: (&str, &str),
) -> Result<(f64, f64), ReducedError> {
    for (f, v) in [(fields.0, tp), (fields.1, tn)] {
        if !(v.is_finite() && v > 0.0 && v < std::f64::consts::FRAC_PI_2) {
            return Err(ReducedError::new(
                f,
                format!("a tip angle must be in (0, 90) degrees, got {} rad", v),
            ));
        }
    }
    // Rows: [cos, side sin] [s; z] = edge - pivot + pivot cos + side pivot_height sin.
    let row = |t: f64, tip: &Tip| {
        let (sn, cs) = t.sin_cos();
        let k = tip.side();
        (
            cs,
            k * sn,
            tip.edge - tip.pivot + tip.pivot * cs + k * tip.pivot_height * sn,
        )
    };
    let (a11, a12, b1) = row(tp, p);
    let (a21, a22, b2) = row(tn, n);
    let det = a11 * a22 - a12 * a21;
    if det.abs() < 1e-12 {
        return Err(ReducedError::new(
            fields.1,
            "the two tip angles give no height (their equations are parallel)",
        ));
    }
    Ok(((b1 * a22 - a12 * b2) / det, (a11 * b2 - a21 * b1) / det))
}

/// The exact method: the CoM from the four tip angles on `foot` (see the module
/// documentation for the geometry). x and z solve the forward/backward pair,
/// `x cos(tf) + z sin(tf) = F1`, `x cos(tb) - z sin(tb) = -F2`; y and a second height
/// solve the left/right pair about the ankle roll axes.
pub fn exact_method(
    angles: &TipAngles,
    foot: &FootGeometry,
) -> Result<ExactEstimate, ReducedError> {
    let [f, b, l, r] = tips(foot)?;
    let (x, z) = solve_pair(
        angles.forward,
        angles.backward,
        &f,
        &b,
        ("angles.forward", "angles.backward"),
    )?;
    let (y, z_frontal) = solve_pair(
        angles.left,
        angles.right,
        &l,
        &r,
        ("angles.left", "angles.right"),
    )?;
    Ok(ExactEstimate {
        com: [x, y, z],
        z_frontal,
    })
}
