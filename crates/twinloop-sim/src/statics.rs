//! Static tipping analysis from the model alone: with both feet flat on the ground,
//! at which ankle angle does the centre of mass reach the edge of the support polygon?
//! This is the reference the tip-over experiment is checked against.

use crate::contact::ContactPoint;
use nalgebra::Vector3;
use twinloop_dynamics::{BASE, Data, Model, center_of_mass, frames_forward_kinematics};
use twinloop_spatial::Se3;

/// Feet flat on the ground: the geometry a static analysis needs.
pub struct FlatFeet<'a> {
    pub model: &'a Model,
    /// Description links of the two feet (left, right); every contact point on the same
    /// rigid body as a foot link counts as that foot's.
    pub feet: [usize; 2],
    /// Contact points of the robot (only those on the feet are used).
    pub points: &'a [ContactPoint],
    /// World placements of the two feet when standing.
    pub foot_world: [Se3; 2],
    /// Which foot is held flat at its place (0 or 1): the one the robot leans onto.
    pub held: usize,
    /// How far the whole robot already leans about its support edge beyond what the
    /// joint angles explain, rad, towards the direction [`FlatFeet::margin`] is asked
    /// about: the feet rolled onto their edges, as the IMU sees it. Zero for feet flat.
    /// Servo deflection does this in the sideways lean, where the two legs and the
    /// ground form a closed chain: a few hundredths of a degree put a foot's pressure on
    /// its edge and, once the far foot unloads, the robot rests on one sole edge tilted
    /// by tenths of a degree, which moves the CoM over the edge by millimetres.
    pub tilt: f64,
}

impl FlatFeet<'_> {
    fn link_in_world(model: &Model, data: &Data, link: usize) -> Se3 {
        let info = &model.links[link];
        (if info.body == BASE {
            data.base_placement
        } else {
            data.o_m_i[info.body]
        }) * info.placement
    }

    /// CoM and support points in the world for joint positions `joints`, the held foot
    /// at its standing placement.
    pub fn com_and_support(
        &self,
        data: &mut Data,
        joints: &[f64],
    ) -> (Vector3<f64>, Vec<Vector3<f64>>) {
        let m = self.model;
        let mut q = m.neutral_configuration();
        q[m.q_offset..].copy_from_slice(joints);
        frames_forward_kinematics(m, data, &q);
        // Move the base so the held foot sits at its standing placement.
        let foot = Self::link_in_world(m, data, self.feet[self.held]);
        let correction = self.foot_world[self.held] * foot.inverse();
        let base = correction * data.base_placement;
        let quat = twinloop_spatial::matrix_to_quaternion_xyzw(&base.rotation);
        q[0..3].copy_from_slice(base.translation.as_slice());
        q[3..7].copy_from_slice(&quat);
        let com = center_of_mass(m, data, &q);
        frames_forward_kinematics(m, data, &q);
        // The soles: on each foot, the points lowest in the foot's own frame (the bottom
        // corners of its boxes), wherever the foot is; projected to the ground they are
        // the support polygon. (Selecting by world height instead would lose a foot that
        // is tilted by a fraction of a degree by unequal servo deflection.) "Lowest" is
        // along the foot frame's axis nearest to world down: a URDF's foot frame need
        // not have z up (Darwin-OP's points x down).
        let mut support = Vec::new();
        for &foot in &self.feet {
            let info = &m.links[foot];
            let on_foot: Vec<&ContactPoint> =
                self.points.iter().filter(|p| p.body == info.body).collect();
            let up = Self::link_in_world(m, data, foot).rotation.transpose() * Vector3::z();
            let axis = (0..3)
                .max_by(|&a, &b| up[a].abs().total_cmp(&up[b].abs()))
                .unwrap_or(2);
            let sign = up[axis].signum();
            let local_z =
                |p: &ContactPoint| sign * info.placement.act_inv_point(&p.local)[axis] - p.radius;
            let zmin = on_foot
                .iter()
                .map(|p| local_z(p))
                .fold(f64::INFINITY, f64::min);
            for p in on_foot {
                if local_z(p) < zmin + 1e-6 {
                    let x = if p.body == BASE {
                        data.base_placement
                    } else {
                        data.o_m_i[p.body]
                    }
                    .act_point(&p.local);
                    support.push(x - Vector3::new(0.0, 0.0, p.radius));
                }
            }
        }
        (com, support)
    }

    /// Pitch and roll (rad) of a link's up axis with the held foot flat at its place:
    /// what an IMU on that link would read if the foot had not moved. Pitch is positive
    /// leaning forward (+x), roll positive leaning left (+y).
    pub fn link_tilt(&self, data: &mut Data, joints: &[f64], link: usize) -> [f64; 2] {
        let _ = self.com_and_support(data, joints);
        let x = Self::link_in_world(self.model, data, link);
        let r = x.rotation;
        [r[(0, 2)].atan2(r[(2, 2)]), r[(1, 2)].atan2(r[(2, 2)])]
    }

    /// How far the CoM is inside the support polygon's edge along `dir` (a horizontal
    /// unit vector): `edge - com` projected on `dir`; zero at the tipping point.
    pub fn margin(&self, data: &mut Data, joints: &[f64], dir: Vector3<f64>) -> f64 {
        let (com, support) = self.com_and_support(data, joints);
        let edge = support
            .iter()
            .copied()
            .max_by(|a, b| a.dot(&dir).total_cmp(&b.dot(&dir)))
            .unwrap_or(com);
        // Turn the CoM about the edge line by `tilt` (towards `dir`): its offset beyond
        // the edge becomes `u cos + h sin` (u along `dir`, h the height above the edge).
        let u = (com - edge).dot(&dir);
        let h = com.z - edge.z;
        let (s, c) = self.tilt.sin_cos();
        -(u * c + h * s)
    }

    /// The lean (rad) at which the margin along `dir` reaches zero, each joint of
    /// `turned` (index, sign) moved by `sign * theta` from `joints` (the ankles alone for
    /// a rigid lean, ankles and hips for the parallelogram sideways lean); bisection over
    /// [lo, hi] (the margin must be positive at `lo` and negative at `hi`; otherwise
    /// the error says which end is wrong).
    pub fn tipping_angle(
        &self,
        data: &mut Data,
        joints: &[f64],
        turned: &[(usize, f64)],
        dir: Vector3<f64>,
        lo: f64,
        hi: f64,
    ) -> Result<f64, NoTippingAngle> {
        let mut q = joints.to_vec();
        let mut at = |theta: f64, q: &mut Vec<f64>| {
            for &(j, sign) in turned {
                q[j] = joints[j] + sign * theta;
            }
            self.margin(data, q, dir)
        };
        let (mut lo, mut hi) = (lo, hi);
        if at(lo, &mut q) <= 0.0 {
            return Err(NoTippingAngle::PastEdge { lean: lo });
        }
        if at(hi, &mut q) > 0.0 {
            return Err(NoTippingAngle::StillInside { lean: hi });
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if at(mid, &mut q) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(0.5 * (lo + hi))
    }
}

/// Why a posture has no static tipping angle in the range searched.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NoTippingAngle {
    /// The CoM is already beyond the support's edge at the range's start (rad).
    PastEdge { lean: f64 },
    /// The CoM is still over the support at the range's end (rad).
    StillInside { lean: f64 },
}

impl std::fmt::Display for NoTippingAngle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NoTippingAngle::PastEdge { lean } => write!(
                f,
                "no static tipping angle: the CoM is already beyond the support's edge at a lean of {:.1} deg",
                lean.to_degrees()
            ),
            NoTippingAngle::StillInside { lean } => write!(
                f,
                "no static tipping angle: the CoM is still over the support at a lean of {:.1} deg",
                lean.to_degrees()
            ),
        }
    }
}

impl std::error::Error for NoTippingAngle {}

/// For each of two ankle joints, the sign of its angle that leans the robot towards
/// `lean` (a horizontal world direction, e.g. +x forward, +y left) with the feet flat.
///
/// The foot is the ankle joint's child, so with the foot held, turning the joint by
/// `+d` about its world axis `a` turns the leg above it by `-d` about `a`. Leaning
/// towards `lean` is a rotation about `z x lean`; the sign follows from `a . (z x lean)`.
/// Left and right ankles often have mirrored axes, so the signs differ.
pub fn lean_signs(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    ankles: [usize; 2],
    lean: Vector3<f64>,
) -> [f64; 2] {
    twinloop_dynamics::forward_kinematics(model, data, q);
    let about = Vector3::z().cross(&lean);
    let mut out = [0.0; 2];
    for k in 0..2 {
        let a = data.o_m_i[ankles[k]].rotation * model.axes[ankles[k]];
        out[k] = if a.dot(&about) > 0.0 { -1.0 } else { 1.0 };
    }
    out
}

/// For each of two hip joints (parents of the legs), the sign of its angle that leans its
/// leg towards `lean` with the pelvis held: turning the joint by `+d` about its world
/// axis `a` turns the leg below it by `+d` about `a` (the opposite of an ankle, whose
/// child is the held foot). With [`lean_signs`] for the ankles this moves the legs as a
/// parallelogram: ankles and hips turned by the same angle keep the feet and the pelvis
/// level.
pub fn hip_lean_signs(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    hips: [usize; 2],
    lean: Vector3<f64>,
) -> [f64; 2] {
    let s = lean_signs(model, data, q, hips, lean);
    [-s[0], -s[1]]
}
