//! The three-mass linear inverted pendulum (3MLIPM) of seed 000 section IV.B (eq.
//! 4-7; seed 001 eq. 1): a left-leg mass, a right-leg mass and a hip mass (the rest of
//! the robot: trunk, arms, head), each a point on a massless link.
//!
//! Axes here are twinloop's: x forward, y left, z up, positions relative to the
//! support ankle. The seeds write the model with x vertical (their eq. 4 adds `g` to
//! `x''`); with their (x, y, z) renamed to our (z, y, x), eq. 4 and 5 are the x and y
//! components of the moment the ground must apply at the support ankle,
//!
//! `tau = sum_i m_i r_i x (a_i - g_vec)`, `g_vec = (0, 0, -g)`:
//!
//! - eq. 4: `tau_x = sum m_i (z'' + g) y_i - sum m_i y''_i z_i`
//! - eq. 5: `tau_y = sum m_i x''_i z_i - sum m_i (z''_i + g) x_i`
//!
//! and with constant heights and no ankle torque they become eq. 6 and 7,
//! `sum m_i y''_i z_i = sum m_i g y_i`, `sum m_i x''_i z_i = sum m_i g x_i`.
//!
//! The masses are derived from a full model by [`ThreeMasses::from_model`]: each leg is
//! the subtree below its hip joint, the hip mass is everything else.

use crate::error::{ReducedError, finite, non_negative, positive};
use crate::lipm::{GRAVITY, rk4_step};
use nalgebra::Vector3;
use twinloop_dynamics::{BASE, Data, Model, center_of_mass, forward_kinematics};

/// A point mass: kg, and a position in m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    pub mass: f64,
    pub position: [f64; 3],
}

/// The three masses of the 3MLIPM.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreeMasses {
    /// Seed 000's m1.
    pub left_leg: PointMass,
    /// m2.
    pub right_leg: PointMass,
    /// m3: trunk, arms and head.
    pub hip: PointMass,
}

impl ThreeMasses {
    /// Three masses; each mass must be > 0 and each position finite.
    pub fn new(
        left_leg: PointMass,
        right_leg: PointMass,
        hip: PointMass,
    ) -> Result<ThreeMasses, ReducedError> {
        for (name, p) in [
            ("left_leg", left_leg),
            ("right_leg", right_leg),
            ("hip", hip),
        ] {
            positive(&format!("{name}.mass"), p.mass)?;
            for (k, axis) in ["x", "y", "z"].iter().enumerate() {
                finite(&format!("{name}.position.{axis}"), p.position[k])?;
            }
        }
        Ok(ThreeMasses {
            left_leg,
            right_leg,
            hip,
        })
    }

    pub fn as_array(&self) -> [PointMass; 3] {
        [self.left_leg, self.right_leg, self.hip]
    }

    pub fn total_mass(&self) -> f64 {
        self.as_array().iter().map(|p| p.mass).sum()
    }

    /// The mass-weighted mean position (the CoM of the three points).
    pub fn com(&self) -> [f64; 3] {
        let m = self.total_mass();
        let mut c = [0.0; 3];
        for p in self.as_array() {
            for (k, ck) in c.iter_mut().enumerate() {
                *ck += p.mass * p.position[k] / m;
            }
        }
        c
    }

    /// The same masses with positions measured from `origin`.
    pub fn relative_to(&self, origin: [f64; 3]) -> ThreeMasses {
        let shift = |p: PointMass| PointMass {
            mass: p.mass,
            position: [
                p.position[0] - origin[0],
                p.position[1] - origin[1],
                p.position[2] - origin[2],
            ],
        };
        ThreeMasses {
            left_leg: shift(self.left_leg),
            right_leg: shift(self.right_leg),
            hip: shift(self.hip),
        }
    }

    /// The three masses of a full model in configuration `q` (world frame): each leg is
    /// the subtree of its hip joint (the first joint of the leg; every link that moves
    /// with it), with that subtree's mass and CoM; the hip mass is all the rest (base,
    /// trunk, arms, head). Computed from the model's links (`Model::links`: each link's
    /// own mass and CoM, placed by forward kinematics), so the three masses sum to the
    /// model's total mass and their weighted mean is the model's CoM.
    pub fn from_model(
        model: &Model,
        q: &[f64],
        left_hip_joint: &str,
        right_hip_joint: &str,
    ) -> Result<ThreeMasses, ReducedError> {
        check_configuration(model, q)?;
        let leg = |field: &str, name: &str| {
            model.joint_index(name).ok_or_else(|| {
                ReducedError::new(
                    field,
                    format!("the model \"{}\" has no joint \"{name}\"", model.name),
                )
            })
        };
        let l = leg("left_hip_joint", left_hip_joint)?;
        let r = leg("right_hip_joint", right_hip_joint)?;
        // Subtree membership by walking up the parents (the model's body numbering
        // keeps parents before children but does not make subtrees contiguous ranges).
        let inside = |root: usize, i: usize| model.ancestors(i).any(|a| a == root);
        if inside(l, r) || inside(r, l) {
            return Err(ReducedError::new(
                "right_hip_joint",
                format!(
                    "\"{left_hip_joint}\" and \"{right_hip_joint}\" must head two separate legs, \
                     but one is in the other's subtree"
                ),
            ));
        }
        let mut data = Data::new(model);
        forward_kinematics(model, &mut data, q);
        // (mass, first moment) of left leg, right leg, rest.
        let mut sums = [(0.0, Vector3::zeros()); 3];
        for link in &model.links {
            if link.body == BASE && !model.is_floating() {
                // Welded to the world: not part of the moving robot's mass.
                continue;
            }
            let body = if link.body == BASE {
                data.base_placement
            } else {
                data.o_m_i[link.body]
            };
            let c = (body * link.placement).act_point(&link.inertia.com);
            let part = if link.body != BASE && inside(l, link.body) {
                0
            } else if link.body != BASE && inside(r, link.body) {
                1
            } else {
                2
            };
            sums[part].0 += link.inertia.mass;
            sums[part].1 += c * link.inertia.mass;
        }
        let point = |field: &str, (m, h): (f64, Vector3<f64>)| {
            positive(&format!("{field}.mass"), m)?;
            let c = h / m;
            Ok::<_, ReducedError>(PointMass {
                mass: m,
                position: [c.x, c.y, c.z],
            })
        };
        ThreeMasses::new(
            point("left_leg", sums[0])?,
            point("right_leg", sums[1])?,
            point("hip", sums[2])?,
        )
    }
}

/// `q` must have the model's length, finite entries and (floating base) a unit quaternion.
pub(crate) fn check_configuration(model: &Model, q: &[f64]) -> Result<(), ReducedError> {
    if q.len() != model.nq {
        return Err(ReducedError::new(
            "q",
            format!(
                "has {} entries, the model \"{}\" needs {}",
                q.len(),
                model.name,
                model.nq
            ),
        ));
    }
    let names = model.q_names();
    for (v, n) in q.iter().zip(&names) {
        finite(&format!("q[{n}]"), *v)?;
    }
    if model.is_floating() {
        let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
        if (n - 1.0).abs() > 1e-9 {
            return Err(ReducedError::new(
                "q[base.qx..base.qw]",
                format!("the base quaternion must have norm 1, has {n}"),
            ));
        }
    }
    Ok(())
}

/// World position of the frame of each ankle joint and their midpoint: the reference
/// point of the tip-over CoM (seed 000's origin). The joint frames are the origins of
/// the joints' child bodies.
pub fn ankle_midpoint(
    model: &Model,
    q: &[f64],
    left_ankle_joint: &str,
    right_ankle_joint: &str,
) -> Result<[f64; 3], ReducedError> {
    check_configuration(model, q)?;
    let idx = |field: &str, name: &str| {
        model.joint_index(name).ok_or_else(|| {
            ReducedError::new(
                field,
                format!("the model \"{}\" has no joint \"{name}\"", model.name),
            )
        })
    };
    let l = idx("left_ankle_joint", left_ankle_joint)?;
    let r = idx("right_ankle_joint", right_ankle_joint)?;
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, q);
    let m = (data.o_m_i[l].translation + data.o_m_i[r].translation) * 0.5;
    Ok([m.x, m.y, m.z])
}

/// The model's CoM relative to the midpoint of the two ankle joints (world axes): the
/// "true" CoM in the reference of the tip-over estimators, for a robot standing in `q`
/// facing world +x.
pub fn com_relative_to_ankles(
    model: &Model,
    q: &[f64],
    left_ankle_joint: &str,
    right_ankle_joint: &str,
) -> Result<[f64; 3], ReducedError> {
    let mid = ankle_midpoint(model, q, left_ankle_joint, right_ankle_joint)?;
    let mut data = Data::new(model);
    let c = center_of_mass(model, &mut data, q);
    Ok([c.x - mid[0], c.y - mid[1], c.z - mid[2]])
}

/// Seed 000 eq. 4 and 5 (seed 001 eq. 1): the moment `[tau_x, tau_y]` the ground
/// applies at the support ankle for point masses at `positions` (relative to the ankle)
/// moving with `accelerations`: `tau_x = sum m (z'' + g) y - sum m y'' z` (eq. 4, the
/// frontal-plane moment, seed's `tau_z`), `tau_y = sum m x'' z - sum m (z'' + g) x`
/// (eq. 5, the sagittal-plane moment, seed's `tau_y`).
pub fn ankle_torque(masses: &[PointMass], accelerations: &[[f64; 3]], gravity: f64) -> [f64; 2] {
    let mut tau = [0.0; 2];
    for (p, a) in masses.iter().zip(accelerations) {
        let [x, y, z] = p.position;
        tau[0] += p.mass * ((a[2] + gravity) * y - a[1] * z);
        tau[1] += p.mass * (a[0] * z - (a[2] + gravity) * x);
    }
    tau
}

/// The plane a 3MLIPM simulation runs in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    /// x (forward), eq. 5 and 7.
    Sagittal,
    /// y (left), eq. 4 and 6.
    Frontal,
}

impl Plane {
    fn axis(self) -> usize {
        match self {
            Plane::Sagittal => 0,
            Plane::Frontal => 1,
        }
    }
}

/// How a leg mass moves during a 3MLIPM simulation.
pub enum LegMotion<'a> {
    /// A support leg: a straight leg from the support ankle to the hip carries its mass
    /// at a fixed fraction `k = z_leg / z_hip` of its length, so with constant heights
    /// its horizontal coordinate follows the hip's, `u = k u_hip + c` (`c` keeps the
    /// initial offset). With both legs like this the model is a standing robot leaning
    /// on its ankles.
    SupportLine,
    /// A swing leg on a given trajectory: `f(t) = (u, u'')`, its horizontal coordinate
    /// in the simulated plane and that coordinate's acceleration.
    Prescribed(&'a dyn Fn(f64) -> (f64, f64)),
}

/// One sample of a 3MLIPM simulation (coordinates in the simulated plane, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreeMassSample {
    pub t: f64,
    pub hip: f64,
    pub hip_velocity: f64,
    pub hip_acceleration: f64,
    pub left_leg: f64,
    pub right_leg: f64,
    /// The ankle moment of eq. 5 (sagittal) or eq. 4 (frontal) computed back from the
    /// simulated positions and accelerations: equal to the input torque, which checks
    /// that what was integrated is the seed's equation.
    pub ankle_torque: f64,
    /// The CoM coordinate of the three masses.
    pub com: f64,
}

/// A three-mass LIPM: masses with positions relative to the support ankle (heights
/// stay constant, as the seed assumes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreeMassLipm {
    pub masses: ThreeMasses,
    pub gravity: f64,
}

impl ThreeMassLipm {
    /// Every mass must be above the ankle (z > 0).
    pub fn new(masses: ThreeMasses) -> Result<ThreeMassLipm, ReducedError> {
        let m = ThreeMasses::new(masses.left_leg, masses.right_leg, masses.hip)?;
        for (name, p) in [
            ("left_leg", m.left_leg),
            ("right_leg", m.right_leg),
            ("hip", m.hip),
        ] {
            positive(&format!("{name}.position.z"), p.position[2])?;
        }
        Ok(ThreeMassLipm {
            masses: m,
            gravity: GRAVITY,
        })
    }

    /// The equivalent single pendulum length when both legs are support lines:
    /// `sum m z^2 / sum m z` (>= the CoM height `sum m z / sum m`, so the three masses
    /// fall more slowly than a LIPM of the same CoM).
    pub fn effective_length(&self) -> f64 {
        let ps = self.masses.as_array();
        let a: f64 = ps.iter().map(|p| p.mass * p.position[2].powi(2)).sum();
        let b: f64 = ps.iter().map(|p| p.mass * p.position[2]).sum();
        a / b
    }

    /// Integrate eq. 7 (sagittal, with the ankle torque of eq. 5) or eq. 6 (frontal,
    /// eq. 4) for the hip coordinate, classical Runge-Kutta 4 at step `dt`, for
    /// `duration` s. The hip starts at its position in [`ThreeMassLipm::masses`] with
    /// `hip_velocity`; the legs `(left, right)` move per their [`LegMotion`]; `torque(t)` is the ankle
    /// moment (`tau_y` of eq. 5 or `tau_x` of eq. 4; 0 gives eq. 7 / 6 exactly).
    ///
    /// The hip equation: with support-line legs `u_i = k_i u + c_i` and prescribed legs
    /// `u_j(t)`, eq. 5 at constant heights reads
    /// `(m_h z_h + sum k_i m_i z_i) u'' = g (m_h u + sum m_i (k_i u + c_i) + sum m_j u_j)
    ///  - sum m_j z_j u_j'' + tau` (frontal: `- tau`).
    pub fn simulate(
        &self,
        plane: Plane,
        (left, right): (LegMotion<'_>, LegMotion<'_>),
        hip_velocity: f64,
        torque: impl Fn(f64) -> f64,
        dt: f64,
        duration: f64,
    ) -> Result<Vec<ThreeMassSample>, ReducedError> {
        finite("hip_velocity", hip_velocity)?;
        positive("dt", dt)?;
        non_negative("duration", duration)?;
        let eq = HipEquation::new(self, plane, [&left, &right], torque);
        let n = ((duration / dt) - 1e-9).ceil().max(0.0) as usize;
        let mut out = Vec::with_capacity(n + 1);
        let (mut t, mut u, mut v) = (0.0, eq.u0, hip_velocity);
        out.push(eq.sample(t, u, v));
        for k in 1..=n {
            let next = if k == n { duration } else { k as f64 * dt };
            let h = next - t;
            let eq = &eq;
            let accel = |t: f64| move |u: f64| eq.accel(t, u);
            (u, v) = rk4_step(u, v, h, [&accel(t), &accel(t + 0.5 * h), &accel(next)]);
            t = next;
            if !(u.is_finite() && v.is_finite()) {
                return Err(ReducedError::new(
                    "torque",
                    format!("the state stopped being finite at t = {t} s (non-finite input?)"),
                ));
            }
            out.push(eq.sample(t, u, v));
        }
        Ok(out)
    }
}

/// The hip equation of [`ThreeMassLipm::simulate`] in one plane (seed 000 eq. 4-7 at
/// constant heights): `a u'' = g (b u + c + sum m_j u_j) - sum m_j z_j u_j'' + sign tau`,
/// with `a = m_h z_h + sum k_i m_i z_i`, `b = m_h + sum k_i m_i`, `c = sum m_i c_i` over
/// the support-line legs `i` and the prescribed legs `j`.
struct HipEquation<'a, 'l, T> {
    lipm: &'a ThreeMassLipm,
    plane: Plane,
    /// Index of the plane's horizontal coordinate.
    ax: usize,
    legs: [(&'a LegMotion<'l>, PointMass); 2],
    /// Hip height and initial horizontal coordinate.
    zh: f64,
    u0: f64,
    a_coef: f64,
    b_coef: f64,
    c_const: f64,
    /// +1 sagittal (eq. 5), -1 frontal (eq. 4).
    sign: f64,
    torque: T,
}

impl<'a, 'l, T: Fn(f64) -> f64> HipEquation<'a, 'l, T> {
    fn new(
        lipm: &'a ThreeMassLipm,
        plane: Plane,
        [left, right]: [&'a LegMotion<'l>; 2],
        torque: T,
    ) -> Self {
        let ax = plane.axis();
        let hip = lipm.masses.hip;
        let mut eq = HipEquation {
            lipm,
            plane,
            ax,
            legs: [(left, lipm.masses.left_leg), (right, lipm.masses.right_leg)],
            zh: hip.position[2],
            u0: hip.position[ax],
            a_coef: hip.mass * hip.position[2],
            b_coef: hip.mass,
            c_const: 0.0,
            sign: match plane {
                Plane::Sagittal => 1.0,
                Plane::Frontal => -1.0,
            },
            torque,
        };
        for (motion, p) in eq.legs {
            if let LegMotion::SupportLine = motion {
                let (k, c) = eq.line(p);
                eq.a_coef += k * p.mass * p.position[2];
                eq.b_coef += k * p.mass;
                eq.c_const += p.mass * c;
            }
        }
        eq
    }

    /// Support-line coefficients `(k, c)` of a leg: `u_leg = k u + c`.
    fn line(&self, p: PointMass) -> (f64, f64) {
        let k = p.position[2] / self.zh;
        (k, p.position[self.ax] - k * self.u0)
    }

    /// The hip's acceleration at time `t` and coordinate `u`.
    fn accel(&self, t: f64, u: f64) -> f64 {
        let g = self.lipm.gravity;
        let mut rhs = g * (self.b_coef * u + self.c_const) + self.sign * (self.torque)(t);
        for (motion, p) in self.legs {
            if let LegMotion::Prescribed(f) = motion {
                let (uj, ujdd) = f(t);
                rhs += g * p.mass * uj - p.mass * p.position[2] * ujdd;
            }
        }
        rhs / self.a_coef
    }

    /// A leg's coordinate and acceleration at time `t` for hip `(u, u'')`.
    fn leg_state(&self, leg: usize, t: f64, u: f64, udd: f64) -> (f64, f64) {
        let (motion, p) = self.legs[leg];
        match motion {
            LegMotion::SupportLine => {
                let (k, c) = self.line(p);
                (k * u + c, k * udd)
            }
            LegMotion::Prescribed(f) => f(t),
        }
    }

    /// The sample at `(t, u, v)`, with the ankle torque back through eq. 4/5 and the
    /// CoM of the simulated state.
    fn sample(&self, t: f64, u: f64, v: f64) -> ThreeMassSample {
        let (ax, g) = (self.ax, self.lipm.gravity);
        let udd = self.accel(t, u);
        let (ul, ul_dd) = self.leg_state(0, t, u, udd);
        let (ur, ur_dd) = self.leg_state(1, t, u, udd);
        let mut ps = self.lipm.masses.as_array();
        ps[0].position[ax] = ul;
        ps[1].position[ax] = ur;
        ps[2].position[ax] = u;
        let mut acc = [[0.0; 3]; 3];
        acc[0][ax] = ul_dd;
        acc[1][ax] = ur_dd;
        acc[2][ax] = udd;
        let tau = ankle_torque(&ps, &acc, g);
        let m: f64 = ps.iter().map(|p| p.mass).sum();
        ThreeMassSample {
            t,
            hip: u,
            hip_velocity: v,
            hip_acceleration: udd,
            left_leg: ul,
            right_leg: ur,
            ankle_torque: match self.plane {
                Plane::Sagittal => tau[1],
                Plane::Frontal => tau[0],
            },
            com: ps.iter().map(|p| p.mass * p.position[ax]).sum::<f64>() / m,
        }
    }
}
