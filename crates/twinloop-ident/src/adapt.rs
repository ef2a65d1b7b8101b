//! Adapt the model when the hardware changes (seed 000 sections III and V.B): the
//! tip-over experiment measured the four fall angles of the changed robot; the exact
//! method ([`crate::tipover::exact_method`]) turns them into the measured CoM, the prior
//! model gives its own CoM in the same frame (relative to the midpoint of the ankle
//! pitch joints in the standing pose, x forward, y left, z up), and the difference is
//! explained by one added point mass `m_a` at `p`:
//!
//! `(M0 c0 + m_a p) / (M0 + m_a) = c_meas`, i.e. `m_a (p - c_meas) = M0 (c_meas - c0)`.
//!
//! One equation in four unknowns: with the new total mass `M` (weigh the robot),
//! `m_a = M - M0` and `p = c_meas + M0 (c_meas - c0) / m_a` (3-D). With only the host
//! link, `p` lies on the ray from `c0` through `c_meas`; it is taken where the ray
//! passes nearest the host link's CoM (its frame origin when it has no mass), and
//! `m_a = M0 |c_meas - c0| / |p - c_meas|`. With neither, only the one-parameter family
//! is known and no model is written.
//!
//! The exact method uses the feet's mass share (they stay on the ground in the fore/aft
//! lean), which changes with the added mass: the estimate is iterated with the adapted
//! model until the measured CoM moves by less than 1e-9 m (two or three iterations).

use crate::adapt_checks::{AdaptCheck, Found, plausibility};
use crate::error::IdentError;
use crate::fall_angle_fit;
use crate::tipover::{FeetMass, TipAngles, exact_method, feet_mass};
use crate::tipover_study::{StudyReport, ankle_names, hip_roll_names};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use twinloop_description::builtin::FootGeometry;
use twinloop_description::{
    Description, Geometry, Inertia, Inertial, Joint, JointKind, Link, Pose,
};
use twinloop_dynamics::{BASE, Data, Model};
use twinloop_experiments::tipover::Direction;
use twinloop_spatial::Se3;

/// What fixes the one-parameter family.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AdaptOptions {
    /// The changed robot's total mass, kg.
    pub total_mass: Option<f64>,
    /// The link the mass was added to.
    pub host: Option<String>,
    /// Merge the mass into the host's inertial instead of a fixed `added_mass` link.
    pub merge: bool,
    /// Resolution of the measured angles, deg (0.05 if unknown).
    pub angle_resolution_deg: Option<f64>,
    /// How far the protocol that measured the angles reads past a model's static
    /// tipping angles, deg per direction (forward, backward, left, right; from
    /// simulating the protocol on a model, as `twinloop demo --protocol-passes` does):
    /// the model is fitted to the measured angles minus this. `None`: zero.
    pub protocol_bias_deg: Option<[f64; 4]>,
}

/// The added mass found.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AddedMass {
    pub mass: f64,
    pub host: String,
    /// Position in the host link's frame, m.
    pub position_host: [f64; 3],
    /// Position in the standing frame (relative to the ankle pitch midpoint), m.
    pub position: [f64; 3],
    /// One-sigma uncertainty of the position, per standing axis, m:
    /// `(M0 + m_a) / m_a` times the CoM's.
    pub position_sigma: [f64; 3],
    /// One-sigma uncertainty of the mass (only with `--where`), kg.
    pub mass_sigma: Option<f64>,
    /// With the total mass and the host link both given: how far the position was
    /// moved to lie within the host's collision outline (its bounding box grown by
    /// [`OUTLINE_MARGIN`]), m; 0 if it was inside already, absent otherwise.
    #[serde(default)]
    pub moved_into_outline: Option<f64>,
}

/// The CoM's resolution: how far it can move with every measured angle within its
/// reading's resolution ([`com_resolution`]), and over a bus with the floor the
/// protocol passes fit from readings on the same counts ([`with_floor`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComResolution {
    /// Per standing axis (x, y, z), m: every share below added up.
    pub axes_m: [f64; 3],
    /// The longest displacement (every reading at a corner of its range), m.
    pub worst_m: f64,
    /// The CoM's move per angle moved by its resolution (forward, backward, left,
    /// right; the exact method linearised at the measured angles), m.
    #[serde(default)]
    pub per_angle_m: [[f64; 3]; 4],
    /// The angles' share alone (the floor held), when a floor's is in the total.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angles: Option<ResolutionShare>,
    /// The fitted floor's share, when the floor was fitted from the readings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<FloorShare>,
}

/// One share of [`ComResolution`]: per standing axis and at the worst corner, m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResolutionShare {
    pub axes_m: [f64; 3],
    pub worst_m: f64,
}

/// What the floor the protocol passes replay on was found from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FloorReading {
    /// The left and right angles' mean: the same readings as the angles, so its share
    /// moves with theirs.
    Sideways,
    /// The feet's roll at the onsets (median of four): the IMU's tilt less the tilt
    /// the ankle readings explain, a reading of its own on the same counts.
    Roll,
}

/// How the floor the protocol passes replayed on moves with the readings, and the
/// CoM with the floor ([`with_floor`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FloorPath {
    pub reading: FloorReading,
    /// The floor found: its sink under the robot's weight, m.
    pub sink_m: f64,
    /// The floor's move per degree of what its search matches, m/deg (its sign: which
    /// way): the replay's sideways mean, or the median of its feet's roll.
    pub sink_per_deg: f64,
    /// How far what the search matches moves per degree of each tip angle (forward,
    /// backward, left, right), deg/deg: the sideways floor matches the robot's
    /// sideways mean less the model's, and the model's moves with every angle through
    /// the fit (half of each sideways angle less the fit's response). Zeros for the
    /// roll, whose own reading is [`FloorReading::Roll`]'s.
    pub reading_per_angle: [f64; 4],
    /// The CoM's move per metre of floor (standing axes), m/m.
    pub com_per_sink: [f64; 3],
}

/// The floor's share of the CoM's resolution: the floor moves as far as its
/// reading's resolution lets it, and the CoM with it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FloorShare {
    #[serde(flatten)]
    pub path: FloorPath,
    /// How far the floor can move with every reading within the angles' resolution, m.
    pub resolution_m: f64,
    /// The CoM's move with the floor alone at its resolution (per axis, worst), m.
    pub share: ResolutionShare,
}

/// The LIPM and three-mass LIPM of a model.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReducedSummary {
    pub mass: f64,
    /// CoM height above the sole, m.
    pub com_height: f64,
    /// Left leg, right leg, hip (trunk, arms, head): mass, kg, and position, m, in the
    /// standing frame.
    pub three_masses: [(f64, [f64; 3]); 3],
}

/// The result of [`adapt`], serialised as the command's JSON.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AdaptReport {
    pub robot: String,
    /// The tip-over was measured with the servos left soft (`--soft-servos`): the
    /// angles include the servos' give, and so does the CoM found from them.
    #[serde(default)]
    pub soft_servos: bool,
    /// `[forward, backward, left, right]`, deg.
    pub measured_deg: [f64; 4],
    /// The measuring protocol's bias taken off the measured angles before fitting,
    /// deg (`AdaptOptions::protocol_bias_deg`; absent when none was).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub protocol_bias_deg: Option<[f64; 4]>,
    /// The feet's roll at each tip (IMU excess), deg.
    pub excess_deg: [f64; 4],
    pub prior_mass: f64,
    /// CoM of the prior model, m, standing frame.
    pub prior_com: [f64; 3],
    /// CoM from the measured angles (exact method, feet of the adapted model), m.
    pub measured_com: [f64; 3],
    /// One-sigma uncertainty of the measured CoM per axis, m, from the angle
    /// resolution by finite differences.
    pub measured_com_sigma: [f64; 3],
    pub angle_resolution_deg: f64,
    /// How far the CoM can move while every angle stays within
    /// `angle_resolution_deg` of its reading ([`com_resolution`]): what the encoders
    /// cannot tell apart (absent in reports from before it was kept).
    #[serde(default)]
    pub com_resolution: Option<ComResolution>,
    /// "total-mass", "where" or "family".
    pub mode: String,
    /// The family `m_a (p - c_meas) = M0 (c_meas - c0)`: its right side, kg m.
    pub family_moment: [f64; 3],
    pub added: Option<AddedMass>,
    /// CoM of the adapted model, m.
    pub adapted_com: Option<[f64; 3]>,
    pub iterations: usize,
    pub prior_reduced: ReducedSummary,
    pub adapted_reduced: Option<ReducedSummary>,
    /// The prior model's static fall angles (exact method's forward problem: its CoM,
    /// feet and frontal lever, feet flat), deg.
    pub prior_model_deg: [f64; 4],
    /// The adapted model's simulated fall angles (with `--check`), deg.
    pub check_deg: Option<[f64; 4]>,
    /// With the total mass known and the robot's onset postures in the tip-over file:
    /// the position refined on the fall angles (see `fall_angle_fit`).
    #[serde(default)]
    pub fall_angle_fit: Option<FallAngleFitSummary>,
    /// The lean of seed 001 the robot did (`--lean`), replayed on the prior and the
    /// adapted model: RMS torque difference per joint, before and after.
    #[serde(default)]
    pub lean: Vec<LeanJointCheck>,
    /// The robot's outline for the report's views: every link's origin in the
    /// standing frame, m.
    #[serde(default)]
    pub outline: Vec<[f64; 3]>,
    /// What is and is not well determined.
    pub notes: Vec<String>,
    /// What was held against what a real change can be before a model is written
    /// ([`crate::adapt_checks`]); empty in files written before they were made.
    #[serde(default)]
    pub checks: Vec<AdaptCheck>,
    pub files: Vec<String>,
}

impl AdaptReport {
    /// The checks that failed: a model is not written when there is one.
    pub fn failed_checks(&self) -> impl Iterator<Item = &AdaptCheck> {
        self.checks.iter().filter(|c| !c.passed)
    }
}

/// How the fit of the added mass's position to the fall angles went.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FallAngleFitSummary {
    /// Where the CoM inversion put the part (host frame, m): the fit's start.
    pub from_com_inversion: [f64; 3],
    /// The model's static angle minus the measured one at the robot's onsets
    /// (forward, backward, left, right), deg: at the start and after the fit.
    pub start_residual_deg: [f64; 4],
    pub residual_deg: [f64; 4],
    /// The common part of the left and right residuals the fit set aside, deg (see
    /// `fall_angle_fit`): how far the sideways pair disagrees with the fore-aft one.
    #[serde(default)]
    pub sideways_offset_deg: f64,
    pub iterations: usize,
}

/// One joint of the lean check: RMS of robot minus model torque, N m.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LeanJointCheck {
    pub joint: String,
    pub before_rms: f64,
    pub after_rms: f64,
    /// RMS of the robot's own torque, N m (the scale).
    pub robot_rms: f64,
}

/// Replay the lean the robot did (`robot_run`, a `twinloop experiment lean` record)
/// on `prior` and on the adapted model (seed 001 section F) and put the torque
/// differences in the report. Returns the comparison, with the replays compared.
pub fn lean_check(
    adapted: &mut Adapted,
    prior: &Description,
    robot_run: &twinloop_io::Table,
) -> Result<twinloop_experiments::LeanAdaptationCheck, IdentError> {
    let Some(after) = &adapted.robot else {
        return Err(IdentError::new(
            "the lean check needs the adapted model: give --total-mass or --where",
        ));
    };
    let options = twinloop_experiments::lean_validation::LeanSimOptions::default();
    let c =
        twinloop_experiments::lean_validation::lean_comparison(robot_run, prior, after, &options)
            .map_err(|e| IdentError::new(e.0))?;
    adapted.report.lean = c
        .before
        .joints
        .iter()
        .zip(&c.after.joints)
        .map(|(b, a)| LeanJointCheck {
            joint: b.joint.clone(),
            before_rms: b.torque_rms,
            after_rms: a.torque_rms,
            robot_rms: b.torque_rms_robot,
        })
        .collect();
    Ok(c)
}

/// The adapted description next to its report.
#[derive(Debug, Clone)]
pub struct Adapted {
    pub report: AdaptReport,
    pub robot: Option<Description>,
}

pub(crate) struct Frame {
    pub(crate) model: Model,
    pub(crate) q: Vec<f64>,
    mid: Vector3<f64>,
    data: Data,
}

pub(crate) fn standing(robot: &Description) -> Result<Frame, String> {
    let model = Model::from_description(robot).map_err(|e| e.to_string())?;
    let mut q = model.neutral_configuration();
    for i in 0..model.nbodies {
        q[model.q_offset + i] = 0f64.clamp(model.lower_limits[i], model.upper_limits[i]);
    }
    let names = ankle_names(robot)?;
    let mid = twinloop_reduced::ankle_midpoint(&model, &q, &names[0], &names[1])
        .map_err(|e| e.to_string())?;
    let mut data = Data::new(&model);
    twinloop_dynamics::frames_forward_kinematics(&model, &mut data, &q);
    Ok(Frame {
        model,
        q,
        mid: Vector3::new(mid[0], mid[1], mid[2]),
        data,
    })
}

/// A robot's CoM in the standing frame (joints at zero, feet flat), relative to the
/// ankle pitch midpoint, m: the frame of [`AdaptReport::prior_com`] and
/// [`AdaptReport::adapted_com`].
pub fn standing_com(robot: &Description) -> Result<[f64; 3], IdentError> {
    let f = standing(robot)?;
    Ok(v3(f.com(robot)?))
}

/// Where `xyz` (m, in `link`'s frame) is in the standing frame of
/// [`standing_com`], m.
pub fn standing_point(
    robot: &Description,
    link: &str,
    xyz: [f64; 3],
) -> Result<[f64; 3], IdentError> {
    let f = standing(robot)?;
    let pose = f
        .link_pose(link)
        .ok_or_else(|| IdentError::new(format!("no link \"{link}\" in \"{}\"", robot.name)))?;
    Ok(v3(pose.act_point(&Vector3::from(xyz)) - f.mid))
}

impl Frame {
    /// The box (lowest and highest corner, standing frame, m) around every link's
    /// origin and primitive collision outline: where the robot is.
    pub(crate) fn robot_box(&self, robot: &Description) -> (Vector3<f64>, Vector3<f64>) {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for link in &robot.links {
            let Some(pose) = self.link_pose(&link.name) else {
                continue;
            };
            let mut take = |local: Vector3<f64>| {
                let w = pose.act_point(&local) - self.mid;
                lo = lo.inf(&w);
                hi = hi.sup(&w);
            };
            take(Vector3::zeros());
            if let Some((a, b)) = collision_box(link) {
                for corner in 0..8 {
                    take(Vector3::from_fn(|i, _| {
                        if corner >> i & 1 == 1 { b[i] } else { a[i] }
                    }));
                }
            }
        }
        (lo, hi)
    }

    /// Every link's origin in the standing frame, m.
    fn outline(&self) -> Vec<[f64; 3]> {
        self.model
            .links
            .iter()
            .filter_map(|l| self.link_pose(&l.name))
            .map(|p| v3(p.translation - self.mid))
            .collect()
    }

    fn link_pose(&self, link: &str) -> Option<Se3> {
        let l = self.model.links.iter().find(|l| l.name == link)?;
        let body = if l.body == BASE {
            self.data.base_placement
        } else {
            self.data.o_m_i[l.body]
        };
        Some(body * l.placement)
    }
    /// The link's CoM (its origin if massless) in the standing frame.
    fn link_point(&self, link: &str) -> Option<Vector3<f64>> {
        let l = self.model.links.iter().find(|l| l.name == link)?;
        let pose = self.link_pose(link)?;
        let local = if l.inertia.mass > 0.0 {
            l.inertia.com
        } else {
            Vector3::zeros()
        };
        Some(pose.act_point(&local) - self.mid)
    }
    pub(crate) fn com(&self, robot: &Description) -> Result<Vector3<f64>, String> {
        let n = ankle_names(robot)?;
        let c = twinloop_reduced::com_relative_to_ankles(&self.model, &self.q, &n[0], &n[1])
            .map_err(|e| e.to_string())?;
        Ok(Vector3::new(c[0], c[1], c[2]))
    }
}

fn foot_of(robot: &Description, tip: &StudyReport) -> FootGeometry {
    if let Some(f) = twinloop_description::builtin::foot_geometry(&robot.name) {
        return f;
    }
    let f = &tip.foot;
    FootGeometry {
        front: f.front,
        back: f.back,
        ankle_height: f.ankle_height,
        roll_axis_height: f.roll_axis_height,
        ankle_half_spacing: f.ankle_half_spacing,
        outer: f.outer,
        inner: f.inner,
        left_foot: String::new(),
        right_foot: String::new(),
        left_ankle_pitch: String::new(),
        right_ankle_pitch: String::new(),
        left_ankle_roll: String::new(),
        right_ankle_roll: String::new(),
        forward_lean_sign: 0.0,
        left_lean_sign: 0.0,
    }
}

fn angles_of(tip: &StudyReport) -> TipAngles {
    let r = std::f64::consts::PI / 180.0;
    TipAngles {
        forward: tip.forward.measured_deg * r,
        backward: tip.backward.measured_deg * r,
        left: tip.left.measured_deg * r,
        right: tip.right.measured_deg * r,
        forward_roll: tip.forward.excess_deg * r,
        backward_roll: tip.backward.excess_deg * r,
        left_roll: tip.left.excess_deg * r,
        right_roll: tip.right.excess_deg * r,
    }
}

fn v3(v: Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// The top joint of each leg (below the joint both legs share): the leg roots the
/// three-mass LIPM splits at.
pub(crate) fn leg_roots(model: &Model, robot: &Description) -> Result<[String; 2], String> {
    let n = ankle_names(robot)?;
    let idx = |s: &str| model.joint_index(s).ok_or(format!("no joint \"{s}\""));
    let (l, r) = (idx(&n[0])?, idx(&n[1])?);
    let ra: Vec<usize> = model.ancestors(r).collect();
    let la: Vec<usize> = model.ancestors(l).collect();
    let top = |a: &[usize], other: &[usize]| {
        a.iter()
            .copied()
            .rfind(|i| !other.contains(i))
            .map(|i| model.joint_names[i].clone())
    };
    match (top(&la, &ra), top(&ra, &la)) {
        (Some(a), Some(b)) => Ok([a, b]),
        _ => Err("cannot find the legs' root joints".into()),
    }
}

pub(crate) fn reduced(
    frame: &Frame,
    robot: &Description,
    foot: &FootGeometry,
) -> Result<ReducedSummary, String> {
    let com = frame.com(robot)?;
    let roots = leg_roots(&frame.model, robot)?;
    let three =
        twinloop_reduced::ThreeMasses::from_model(&frame.model, &frame.q, &roots[0], &roots[1])
            .map_err(|e| e.to_string())?
            .relative_to(v3(frame.mid));
    let pm = |p: twinloop_reduced::PointMass| (p.mass, p.position);
    Ok(ReducedSummary {
        mass: frame.model.total_mass,
        com_height: com.z + foot.ankle_height,
        three_masses: [pm(three.left_leg), pm(three.right_leg), pm(three.hip)],
    })
}

/// The prior with the added mass: a fixed `added_mass` link (point mass, a 1 cm sphere's
/// inertia) on the host, or merged into the host's inertial.
pub fn with_added_mass(
    prior: &Description,
    host: &str,
    mass: f64,
    xyz: [f64; 3],
    merge: bool,
) -> Result<Description, String> {
    let mut d = prior.clone();
    // A part taken off comes off its host's own inertial: no link has negative mass.
    if merge || mass < 0.0 {
        twinloop_description::builtin::add_point_mass(&mut d, host, mass, xyz)
            .map_err(|e| e.to_string())?;
        return Ok(d);
    }
    if d.link(host).is_none() {
        return Err(format!("no link \"{host}\" in \"{}\"", prior.name));
    }
    let mut name = "added_mass".to_string();
    let mut k = 1;
    while d.link(&name).is_some() {
        k += 1;
        name = format!("added_mass_{k}");
    }
    let i = 0.4 * mass * 0.01 * 0.01;
    let mut link = Link::new(name.clone());
    link.inertial = Some(Inertial {
        origin: Pose::IDENTITY,
        mass,
        inertia: Inertia::from_matrix([[i, 0.0, 0.0], [0.0, i, 0.0], [0.0, 0.0, i]]),
    });
    d.links.push(link);
    let mut j = Joint::new(format!("{name}_joint"), JointKind::Fixed, host, name);
    j.origin = Pose::from_xyz(xyz);
    d.joints.push(j);
    Ok(d)
}

fn measured_com(
    angles: &TipAngles,
    frame: &Frame,
    robot: &Description,
    foot: &FootGeometry,
) -> Result<(Vector3<f64>, FeetMass), String> {
    let n = ankle_names(robot)?;
    let feet = feet_mass(&frame.model, &frame.q, [&n[0], &n[1]]).map_err(|e| e.to_string())?;
    let e = exact_method(angles, &feet, foot).map_err(|e| e.to_string())?;
    Ok((Vector3::new(e.com[0], e.com[1], e.com[2]), feet))
}

/// Adapt `prior` to the tip-over measurement `tip` (see the module documentation), in
/// four stages: measure (the angles less the protocol's bias, the prior's CoM), place
/// (the CoM inversion, then the fall-angle fit), report (uncertainty and notes), and
/// check ([`crate::adapt_checks`]).
pub fn adapt(
    prior: &Description,
    tip: &StudyReport,
    opts: &AdaptOptions,
) -> Result<Adapted, IdentError> {
    let m = measure(prior, tip, opts)?;
    let mut placed = place_by_com(prior, &m, opts)?;
    refine_by_fall_angles(prior, tip, &m, opts, &mut placed)?;
    let mut report = report_of(prior, tip, &m, opts, &placed)?;
    let robot = match placed.adapted {
        None => {
            report.notes.push(
                "only m_a (p - c_meas) = M0 (c_meas - c0) is known: give the total mass or the link the mass is on to place it".into(),
            );
            None
        }
        Some((d, mut added)) => {
            let k = ((m.m0 + added.mass) / added.mass).abs();
            added.position_sigma = v3(m_sigma(&report) * k);
            if m.mode == "where" {
                let dn = (placed.cm - m.c0).norm();
                let sigma = m_sigma(&report);
                added.mass_sigma = Some(added.mass.abs() * sigma.norm() / dn.max(1e-12));
                report.notes.push(
                    "with only the host link given, the mass and the distance along the ray trade off: the mass is as uncertain as |c_meas - c0|".into(),
                );
            }
            if let Some(host) = &opts.host
                && has_no_collision_outline(prior, host)
            {
                report.notes.push(format!(
                    "{host} has no primitive collision shape: the part was kept within {:.0} mm of its skeleton (its origin, CoM and child joints), not within its outline",
                    SKELETON_MARGIN * 1e3
                ));
            }
            let af = standing(&d)?;
            report.adapted_com = Some(v3(af.com(&d)?));
            report.adapted_reduced = Some(reduced(&af, &d, &m.foot)?);
            report.added = Some(added);
            Some(d)
        }
    };
    let (lo, hi) = m.pf.robot_box(prior);
    report.checks = plausibility(&Found {
        part: report.added.as_ref().map(|a| (a.mass, a.position)),
        prior_mass: report.prior_mass,
        robot_box: (v3(lo), v3(hi)),
        measured_deg: report.measured_deg,
        protocol_bias_deg: report.protocol_bias_deg,
        prior_model_deg: report.prior_model_deg,
        fit_residual_deg: report.fall_angle_fit.as_ref().map(|f| f.residual_deg),
        angle_resolution_deg: report.angle_resolution_deg,
        over_bus: tip.protocol.is_some(),
    });
    Ok(Adapted { report, robot })
}

fn m_sigma(report: &AdaptReport) -> Vector3<f64> {
    Vector3::from(report.measured_com_sigma)
}

/// Stage 1: what was measured, in the prior's standing frame.
struct Measured {
    foot: FootGeometry,
    /// The fall angles less the protocol's bias.
    angles: TipAngles,
    pf: Frame,
    m0: f64,
    c0: Vector3<f64>,
    res: f64,
    /// "total-mass", "where" or "family".
    mode: &'static str,
}

fn measure(
    prior: &Description,
    tip: &StudyReport,
    opts: &AdaptOptions,
) -> Result<Measured, IdentError> {
    let foot = foot_of(prior, tip);
    let bias = opts.protocol_bias_deg.unwrap_or([0.0; 4]);
    let mut angles = angles_of(tip);
    let r = std::f64::consts::PI / 180.0;
    angles.forward -= bias[0] * r;
    angles.backward -= bias[1] * r;
    angles.left -= bias[2] * r;
    angles.right -= bias[3] * r;
    let pf = standing(prior)?;
    let m0 = pf.model.total_mass;
    let c0 = pf.com(prior)?;
    if let Some(h) = &opts.host
        && prior.link(h).is_none()
    {
        return Err(
            IdentError::new(format!("no link \"{h}\" in \"{}\"", prior.name)).option("host"),
        );
    }
    if let Some(m) = opts.total_mass
        && !(m.is_finite() && m > 0.0 && (m - m0).abs() >= MIN_CHANGE_KG)
    {
        return Err(IdentError::new(format!(
            "{m} kg is within {MIN_CHANGE_KG} kg of the prior's {m0:.4} kg: no part was added or \
             taken off that the scale can tell (more: added; less: taken off)"
        ))
        .option("total_mass"));
    }
    let mode = match (opts.total_mass, &opts.host) {
        (Some(_), _) => "total-mass",
        (None, Some(_)) => "where",
        (None, None) => "family",
    };
    Ok(Measured {
        foot,
        angles,
        pf,
        m0,
        c0,
        res: opts.angle_resolution_deg.unwrap_or(0.05),
        mode,
    })
}

/// Stage 2's result: the measured CoM and the part placed (if the options fix it).
struct Placed {
    cm: Vector3<f64>,
    iterations: usize,
    /// The standing frame of the model with the part merged: its feet.
    frame_for_feet: Frame,
    adapted: Option<(Description, AddedMass)>,
    fit: Option<FallAngleFitSummary>,
}

/// Stage 2a: the CoM inversion, iterated with the adapted model's feet.
fn place_by_com(
    prior: &Description,
    m: &Measured,
    opts: &AdaptOptions,
) -> Result<Placed, IdentError> {
    let mut out = Placed {
        cm: Vector3::zeros(),
        iterations: 0,
        frame_for_feet: standing(prior)?,
        adapted: None,
        fit: None,
    };
    for it in 1..=20 {
        out.iterations = it;
        let (c, _) = measured_com(&m.angles, &out.frame_for_feet, prior, &m.foot)?;
        let settled = (c - out.cm).norm() < 1e-9;
        out.cm = c;
        if m.mode == "family" || settled {
            break;
        }
        let (ma, p, host) = part_on_its_ray(prior, m, opts, out.cm)?;
        let pf = &m.pf;
        let pose = pf.link_pose(&host).ok_or(format!("no link \"{host}\""))?;
        let mut local = pose.inverse().act_point(&(p + pf.mid));
        let mut p = p;
        let mut moved_into_outline = None;
        // Both the mass and the link known: the part is somewhere on that link, so
        // the point goes to the nearest point of the link's outline grown by
        // `OUTLINE_MARGIN` (projecting onto a convex set that holds the truth never
        // moves the point away from the truth, and the adapted CoM, which moves
        // with the point times m_a / M, comes nearer the truth's too).
        if opts.total_mass.is_some()
            && opts.host.is_some()
            && let Some((lo, hi)) = part_box(prior, &host)
        {
            let inside = local.sup(&lo).inf(&hi);
            moved_into_outline = Some((inside - local).norm());
            local = inside;
            p = pose.act_point(&local) - pf.mid;
        }
        let placed = place(prior, host, ma, local, p, moved_into_outline, opts.merge)?;
        out.frame_for_feet = placed.0;
        out.adapted = Some(placed.1);
    }
    Ok(out)
}

/// The part's mass, its point (standing frame) and its link, from the measured CoM
/// `cm`: with the total mass, `p = c_meas + M0 (c_meas - c0) / m_a`; with the link
/// only, where the ray from `c0` through `c_meas` passes nearest the link.
fn part_on_its_ray(
    prior: &Description,
    m: &Measured,
    opts: &AdaptOptions,
    cm: Vector3<f64>,
) -> Result<(f64, Vector3<f64>, String), IdentError> {
    let (m0, c0) = (m.m0, m.c0);
    let d = cm - c0;
    if let Some(total) = opts.total_mass {
        let ma = total - m0;
        let p = cm + d * (m0 / ma);
        let host = match &opts.host {
            Some(h) => h.clone(),
            None => nearest_link(&m.pf, prior, p, removable_from(ma))?,
        };
        return Ok((ma, p, host));
    }
    let host = opts.host.clone().unwrap_or_default();
    let h =
        m.pf.link_point(&host)
            .ok_or(format!("no link \"{host}\""))?;
    let u = d / d.norm();
    let t = (h - c0).dot(&u);
    if t <= d.norm() * 1.001 {
        return Err(IdentError::new(format!(
            "{host}: the CoM moved away from that link (the ray from the prior CoM through the measured one passes it {:.1} mm before the measured CoM); give the total mass",
            (d.norm() - t) * 1e3
        ))
        .option("host"));
    }
    Ok((m0 * d.norm() / (t - d.norm()), c0 + u * t, host))
}

/// Stage 2b: with the mass known, place it by the fall angles themselves
/// (fall_angle_fit.rs: every link's part alike, feet and ankle crosses included), from
/// the CoM inversion's point, when the tip-over kept the robot's onset postures.
fn refine_by_fall_angles(
    prior: &Description,
    tip: &StudyReport,
    m: &Measured,
    opts: &AdaptOptions,
    placed: &mut Placed,
) -> Result<(), IdentError> {
    let Some((_, added)) = &placed.adapted else {
        return Ok(());
    };
    if m.mode != "total-mass"
        || Direction::ALL
            .iter()
            .any(|&d| tip.direction(d).onset_positions.is_empty())
    {
        return Ok(());
    }
    let host = added.host.clone();
    // The named link's outline; a link found as the nearest is a guess, so the fit
    // stays within `FIT_REACH` of the inversion's point instead (what the angles
    // cannot pin down is not sent decimetres away by noise).
    let start = Vector3::from(added.position_host);
    let reach = Vector3::repeat(FIT_REACH);
    let named = opts.host.is_some();
    let bounds = match part_box(prior, &host).filter(|_| named) {
        Some(b) => b,
        None => (start - reach, start + reach),
    };
    let bounds = if named {
        still_part_bounds(prior, &m.pf, &host, bounds)
    } else {
        bounds
    };
    let with_part = |p: Vector3<f64>| {
        with_added_mass(prior, &host, added.mass, v3(p), true).map_err(IdentError::new)
    };
    let fit = fall_angle_fit::fit_position(
        &with_part,
        tip,
        start,
        bounds,
        opts.protocol_bias_deg.unwrap_or([0.0; 4]),
        match opts.protocol_bias_deg {
            Some(_) => fall_angle_fit::PROTOCOL_OFFSET_WEIGHT,
            None => fall_angle_fit::OFFSET_WEIGHT,
        },
    )?;
    let local = Vector3::from(fit.position_host);
    let pose = m.pf.link_pose(&host).ok_or(format!("no link \"{host}\""))?;
    let p = pose.act_point(&local) - m.pf.mid;
    let (ma, moved) = (added.mass, added.moved_into_outline);
    placed.fit = Some(FallAngleFitSummary {
        from_com_inversion: added.position_host,
        start_residual_deg: fit.start_residual_deg,
        residual_deg: fit.residual_deg,
        sideways_offset_deg: fit.sideways_offset_deg,
        iterations: fit.iterations,
    });
    let (frame, part) = place(prior, host, ma, local, p, moved, opts.merge)?;
    placed.frame_for_feet = frame;
    placed.adapted = Some(part);
    Ok(())
}

/// The bounds of the fall-angle fit for a part on a foot (`bounds`: the host's
/// frame, its outline): its height pinned at the middle of the foot's outline. The
/// foot stays on the ground in every lean, so the robot's angles do not see the
/// part's height ([`crate::tipover_study::feet_links`]); the static model does, by a
/// few hundredths of a degree over the foot's height, and the fit pushed its residual
/// into it: the CoM inversion's point, clamped into the outline, or the fit, put the
/// part on a face of the box grown by [`OUTLINE_MARGIN`] (10 mm above an OP3's sole
/// plate, the CoM 1.4 mm high; 10 mm under a Darwin-OP's sole, 1.0 mm low). The
/// middle is the nearest to every height the foot allows. Other links, or a foot not
/// standing on an axis of its frame: `bounds`.
fn still_part_bounds(
    prior: &Description,
    frame: &Frame,
    host: &str,
    bounds: (Vector3<f64>, Vector3<f64>),
) -> (Vector3<f64>, Vector3<f64>) {
    let on_a_foot = crate::tipover_study::feet_links(prior)
        .is_ok_and(|[l, r]| l.iter().chain(&r).any(|f| f == host));
    let Some(pose) = frame.link_pose(host).filter(|_| on_a_foot) else {
        return bounds;
    };
    // The vertical, in the foot's frame.
    let inv = pose.inverse();
    let up = inv.act_point(&Vector3::z()) - inv.act_point(&Vector3::zeros());
    let k = up.iamax();
    let (mut lo, mut hi) = bounds;
    if up[k].abs() > 0.99 {
        let mid = 0.5 * (lo[k] + hi[k]);
        (lo[k], hi[k]) = (mid, mid);
    }
    (lo, hi)
}

/// How far the measured CoM moves per angle moved by the resolution, through the
/// exact method (forward, backward, left, right; central differences), m.
fn com_per_angle(
    prior: &Description,
    m: &Measured,
    placed: &Placed,
) -> Result<[Vector3<f64>; 4], IdentError> {
    let (_, feet) = measured_com(&m.angles, &placed.frame_for_feet, prior, &m.foot)?;
    let r = m.res.to_radians();
    let mut out = [Vector3::zeros(); 4];
    for (k, dc) in out.iter_mut().enumerate() {
        let mut a = m.angles;
        let mut b = m.angles;
        let (pa, pb) = match k {
            0 => (&mut a.forward, &mut b.forward),
            1 => (&mut a.backward, &mut b.backward),
            2 => (&mut a.left, &mut b.left),
            _ => (&mut a.right, &mut b.right),
        };
        *pa += r;
        *pb -= r;
        let ea = exact_method(&a, &feet, &m.foot).map_err(|e| e.to_string())?;
        let eb = exact_method(&b, &feet, &m.foot).map_err(|e| e.to_string())?;
        *dc = (Vector3::from(ea.com) - Vector3::from(eb.com)) * 0.5;
    }
    Ok(out)
}

/// The measured CoM's one-sigma uncertainty per axis: each angle moved by the
/// resolution, independently.
fn com_sigma(per_angle: &[Vector3<f64>; 4]) -> Vector3<f64> {
    per_angle
        .iter()
        .fold(Vector3::zeros(), |v: Vector3<f64>, dc| {
            v + dc.component_mul(dc)
        })
        .map(f64::sqrt)
}

/// How far the CoM can move while each of the four angles stays within its
/// resolution (a reading's quantisation: half an ankle count, and the protocol's
/// step), on the exact method's map linearised at the measured angles: per axis the
/// sum of the four angles' shares (the worst corner of the angles' box, axis by
/// axis), and the longest of the sixteen corners' displacements, m.
pub fn com_resolution(per_angle: &[Vector3<f64>; 4]) -> ComResolution {
    let share = corners(per_angle);
    ComResolution {
        axes_m: share.axes_m,
        worst_m: share.worst_m,
        per_angle_m: per_angle.map(v3),
        angles: None,
        floor: None,
    }
}

/// The box of independent readings each moving the CoM by `+-moves[k]`: per axis the
/// sum of their sizes, and the longest of the corners' displacements, m.
fn corners(moves: &[Vector3<f64>]) -> ResolutionShare {
    let axes = moves
        .iter()
        .fold(Vector3::zeros(), |v: Vector3<f64>, dc| v + dc.abs());
    let worst = (0..1_u32 << moves.len())
        .map(|signs| {
            (0..moves.len())
                .map(|k| moves[k] * if signs >> k & 1 == 1 { 1.0 } else { -1.0 })
                .sum::<Vector3<f64>>()
                .norm()
        })
        .fold(0.0_f64, f64::max);
    ResolutionShare {
        axes_m: v3(axes),
        worst_m: worst,
    }
}

/// `angles` (the angles' [`com_resolution`] at resolution `res` deg) with the floor's
/// share added ([`FloorPath`]): each reading, known to `res` (the same counts), moves
/// the floor, and the floor the CoM. Found from the sideways mean, the floor moves
/// with the tip angles themselves (`reading_per_angle`): each angle's side of the box
/// is its direct move plus its move through the floor. Found from the feet's roll, the
/// roll is a fifth reading with a side of its own.
pub fn with_floor(angles: &ComResolution, res: f64, path: FloorPath) -> ComResolution {
    let per_angle = angles.per_angle_m.map(Vector3::from);
    let com_per_sink = Vector3::from(path.com_per_sink);
    let through: [f64; 4] = match path.reading {
        FloorReading::Sideways => path.reading_per_angle.map(|c| c * res * path.sink_per_deg),
        FloorReading::Roll => [0.0; 4],
    };
    let own = match path.reading {
        FloorReading::Sideways => 0.0,
        FloorReading::Roll => res * path.sink_per_deg,
    };
    let mut sides: Vec<Vector3<f64>> = (0..4)
        .map(|k| per_angle[k] + com_per_sink * through[k])
        .collect();
    let mut floor_sides: Vec<Vector3<f64>> = through.iter().map(|t| com_per_sink * *t).collect();
    if own != 0.0 {
        sides.push(com_per_sink * own);
        floor_sides.push(com_per_sink * own);
    }
    let total = corners(&sides);
    ComResolution {
        axes_m: total.axes_m,
        worst_m: total.worst_m,
        per_angle_m: angles.per_angle_m,
        angles: Some(corners(&per_angle)),
        floor: Some(FloorShare {
            path,
            resolution_m: through.iter().map(|t| t.abs()).sum::<f64>() + own.abs(),
            share: corners(&floor_sides),
        }),
    }
}

/// What is and is not well determined, in words.
fn notes_of(
    res: f64,
    sigma: Vector3<f64>,
    bound: &ComResolution,
    fit: Option<&FallAngleFitSummary>,
) -> Vec<String> {
    let b = bound.axes_m.map(|v| v * 1e3);
    let mut notes = vec![
        "x and z come from the forward/backward pair alone, y from the left/right pair".into(),
        format!(
            "CoM sigma from a {res} deg angle resolution: x {:.2} mm, y {:.2} mm, z {:.2} mm",
            sigma.x * 1e3,
            sigma.y * 1e3,
            sigma.z * 1e3
        ),
        format!(
            "the CoM's resolution: with every angle anywhere within {res:.3} deg of its \
             reading the CoM moves up to x {:.2} mm, y {:.2} mm, z {:.2} mm, {:.2} mm at \
             worst; the angles cannot tell apart CoMs closer than that",
            b[0],
            b[1],
            b[2],
            bound.worst_m * 1e3
        ),
    ];
    let imax = if sigma.x >= sigma.y && sigma.x >= sigma.z {
        "x"
    } else if sigma.y >= sigma.z {
        "y"
    } else {
        "z"
    };
    notes.push(format!("the poorest determined direction is {imax}"));
    notes.push(
        "the tip-over sees only the CoM: several parts added at once are found as the one equivalent part (their total mass at their common CoM)".into(),
    );
    if let Some(f) = fit {
        notes.extend(fit_notes(f));
    }
    notes
}

fn fit_notes(f: &FallAngleFitSummary) -> Vec<String> {
    let mut notes = Vec::new();
    let (k, worst) = f
        .residual_deg
        .iter()
        .enumerate()
        .fold(
            (0, 0.0_f64),
            |b, (k, v)| {
                if v.abs() > b.1.abs() { (k, *v) } else { b }
            },
        );
    let dirs = ["forward", "backward", "left", "right"];
    notes.push(format!(
        "the part's position was fitted to the four fall angles at the robot's onsets: the adapted model's static angles are within {:.2} deg of the measured ones (largest {}), {:.2} deg before the fit",
        worst.abs(),
        dirs[k],
        f.start_residual_deg.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
    ));
    if f.sideways_offset_deg.abs() > 0.05 {
        notes.push(format!(
            "the left and right angles share an error of {:+.2} deg against the fore-aft pair (both measured {} than one CoM explains): set aside, as the exact method's free frontal lever does; x and z come from the fore-aft angles",
            f.sideways_offset_deg,
            if f.sideways_offset_deg > 0.0 { "earlier" } else { "later" }
        ));
    }
    if worst.abs() > 0.3 {
        notes.push(format!(
            "the four angles do not fit one part on this link to 0.3 deg: the change may be elsewhere or in several places, or the {} angle was measured poorly",
            dirs[k]
        ));
    }
    notes
}

/// Stage 3: the report of what was measured and placed (the part itself is added by
/// the caller, with its uncertainty).
fn report_of(
    prior: &Description,
    tip: &StudyReport,
    m: &Measured,
    opts: &AdaptOptions,
    placed: &Placed,
) -> Result<AdaptReport, IdentError> {
    let per_angle = com_per_angle(prior, m, placed)?;
    let sigma = com_sigma(&per_angle);
    let resolution = com_resolution(&per_angle);
    let dirs = Direction::ALL.map(|d| tip.direction(d));
    Ok(AdaptReport {
        robot: prior.name.clone(),
        soft_servos: tip.protocol.as_ref().is_some_and(|p| p.soft_servos),
        measured_deg: dirs.map(|d| d.measured_deg),
        excess_deg: dirs.map(|d| d.excess_deg),
        prior_mass: m.m0,
        prior_com: v3(m.c0),
        measured_com: v3(placed.cm),
        measured_com_sigma: v3(sigma),
        angle_resolution_deg: m.res,
        mode: m.mode.into(),
        family_moment: v3((placed.cm - m.c0) * m.m0),
        added: None,
        adapted_com: None,
        iterations: placed.iterations,
        prior_reduced: reduced(&m.pf, prior, &m.foot)?,
        adapted_reduced: None,
        prior_model_deg: prior_model_angles(&m.pf, prior, m.c0, &m.foot)?,
        check_deg: None,
        fall_angle_fit: placed.fit.clone(),
        protocol_bias_deg: opts.protocol_bias_deg,
        lean: Vec::new(),
        outline: m.pf.outline(),
        notes: notes_of(m.res, sigma, &resolution, placed.fit.as_ref()),
        com_resolution: Some(resolution),
        checks: Vec::new(),
        files: vec![],
    })
}

/// The prior with `mass` at `local` on `host` (merged with `merge`), the standing
/// frame of the merged model (the feet the exact method then uses) and the part as
/// the report gives it (`p`: standing frame).
fn place(
    prior: &Description,
    host: String,
    mass: f64,
    local: Vector3<f64>,
    p: Vector3<f64>,
    moved_into_outline: Option<f64>,
    merge: bool,
) -> Result<(Frame, (Description, AddedMass)), String> {
    let frame = standing(&with_added_mass(prior, &host, mass, v3(local), true)?)?;
    let out = with_added_mass(prior, &host, mass, v3(local), merge)?;
    let added = AddedMass {
        mass,
        host,
        position_host: v3(local),
        position: v3(p),
        position_sigma: [0.0; 3],
        mass_sigma: None,
        moved_into_outline,
    };
    Ok((frame, (out, added)))
}

/// The ray of positions that explain the measured CoM with an unknown mass, in the
/// view's coordinates (`i`: 0 side, 1 front; the other is z): `p(m) = c_meas +
/// (M0 / m) (c_meas - c0)` for m from 2 kg down to 0.05 kg. Empty when the mass was
/// known (then nothing trades off) or the CoM did not move.
fn ambiguity_line(r: &AdaptReport, i: usize) -> (Vec<f64>, Vec<f64>) {
    if r.mode == "total-mass" {
        return (vec![], vec![]);
    }
    let (c, c0) = (Vector3::from(r.measured_com), Vector3::from(r.prior_com));
    if (c - c0).norm() < 1e-9 {
        return (vec![], vec![]);
    }
    [2.0, 1.0, 0.5, 0.3, 0.2, 0.1, 0.05]
        .iter()
        .map(|m| {
            let p = c + (c - c0) * (r.prior_mass / m);
            (p[i], p.z)
        })
        .unzip()
}

/// The smallest change of the total mass `adapt` takes as a part added or taken off,
/// kg: a kitchen scale's resolution (1 g) times ten.
pub const MIN_CHANGE_KG: f64 = 0.01;

/// How far the fall-angle fit may move the part from the CoM inversion's point when
/// the link is not named, m, per axis.
pub const FIT_REACH: f64 = 0.03;

/// How far outside its host's collision outline an added part's CoM may lie, m: a
/// battery or camera is bolted onto the link's surface, its centre about half its
/// thickness outside.
pub const OUTLINE_MARGIN: f64 = 0.01;

/// How far a part may lie from the skeleton of a link that has no primitive
/// collision shape (its origin, its CoM and its child joints), m: about a limb's
/// half-thickness (km20's and OP3's limbs are 4-7 cm across).
pub const SKELETON_MARGIN: f64 = 0.03;

/// Where a part bolted onto the link `name` of `robot` can be (link frame: lowest
/// and highest corner): the box of [`collision_box`]; for a link without a
/// primitive collision shape (meshes only, or none), the box around its origin, its
/// CoM and its child joints' origins grown by [`SKELETON_MARGIN`] (issue 30 item 10:
/// `--where` on such a link did not constrain the part at all). `None` for no link.
fn part_box(robot: &Description, name: &str) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let link = robot.link(name)?;
    collision_box(link).or_else(|| Some(skeleton_box(robot, link)))
}

/// Whether [`part_box`] of `name` falls back on the link's skeleton.
pub fn has_no_collision_outline(robot: &Description, name: &str) -> bool {
    robot.link(name).is_some_and(|l| collision_box(l).is_none())
}

/// The box around `link`'s origin, CoM and child joints, grown by [`SKELETON_MARGIN`].
fn skeleton_box(robot: &Description, link: &Link) -> (Vector3<f64>, Vector3<f64>) {
    let mut lo = Vector3::zeros();
    let mut hi = Vector3::zeros();
    let points = link
        .inertial
        .iter()
        .map(|i| Vector3::from(i.origin.xyz))
        .chain(
            robot
                .joints
                .iter()
                .filter(|j| j.parent == link.name)
                .map(|j| Vector3::from(j.origin.xyz)),
        );
    for p in points {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    let margin = Vector3::repeat(SKELETON_MARGIN);
    (lo - margin, hi + margin)
}

/// The box (link frame: lowest and highest corner) around `link`'s primitive
/// collision shapes, grown by [`OUTLINE_MARGIN`]; `None` without one.
fn collision_box(link: &Link) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for shape in &link.collisions {
        let half = match shape.geometry {
            Geometry::Box { size } => Vector3::from(size) * 0.5,
            Geometry::Sphere { radius } => Vector3::repeat(radius),
            Geometry::Cylinder { radius, length } => Vector3::new(radius, radius, 0.5 * length),
            Geometry::Capsule { radius, length } => {
                Vector3::new(radius, radius, 0.5 * length + radius)
            }
            Geometry::Mesh { .. } => continue,
        };
        let (r, o) = (shape.origin.rotation(), shape.origin.xyz);
        for corner in 0..8 {
            let c = Vector3::from_fn(|i, _| {
                if corner >> i & 1 == 1 {
                    half[i]
                } else {
                    -half[i]
                }
            });
            let w = Vector3::from_fn(|i, _| o[i] + (0..3).map(|j| r[i][j] * c[j]).sum::<f64>());
            lo = lo.inf(&w);
            hi = hi.sup(&w);
        }
    }
    let margin = Vector3::repeat(OUTLINE_MARGIN);
    lo.x.is_finite().then_some((lo - margin, hi + margin))
}

/// The least mass a link must have to be where a part of `ma` kg was (negative: taken
/// off): nothing for an added part; for a removed one, enough that the link keeps
/// [`twinloop_description::builtin::MIN_REMAINING_FRACTION`] of its own.
fn removable_from(ma: f64) -> f64 {
    if ma >= 0.0 {
        0.0
    } else {
        -ma / (1.0 - twinloop_description::builtin::MIN_REMAINING_FRACTION)
    }
}

/// The link whose CoM (origin if massless) is nearest `p` (standing frame), among the
/// links of at least `min_mass` kg.
fn nearest_link(
    frame: &Frame,
    robot: &Description,
    p: Vector3<f64>,
    min_mass: f64,
) -> Result<String, String> {
    robot
        .links
        .iter()
        .filter(|l| min_mass <= 0.0 || l.inertial.as_ref().is_some_and(|i| i.mass >= min_mass))
        .filter_map(|l| {
            frame
                .link_point(&l.name)
                .map(|x| (l.name.clone(), (x - p).norm()))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|x| x.0)
        .ok_or_else(|| {
            format!("no link of the model weighs {min_mass:.3} kg: a part that heavy was not taken off one")
        })
}

/// A model's static fall angles, deg, `[forward, backward, left, right]`: the exact
/// method's forward problem ([`crate::tipover::tip_angles`] of its CoM, feet and
/// frontal lever, standing with its feet flat) on the feet `tip` measured with (a
/// built-in robot's own): [`AdaptReport::prior_model_deg`] for the prior, and what
/// `adapt --mcap` writes as each model's prediction of the measured angles.
pub fn static_fall_angles(robot: &Description, tip: &StudyReport) -> Result<[f64; 4], IdentError> {
    let f = standing(robot)?;
    let c = f.com(robot)?;
    Ok(prior_model_angles(&f, robot, c, &foot_of(robot, tip))?)
}

/// The prior's static fall angles, deg: [`crate::tipover::tip_angles`] of its CoM, feet
/// and frontal lever.
fn prior_model_angles(
    frame: &Frame,
    robot: &Description,
    c0: Vector3<f64>,
    foot: &FootGeometry,
) -> Result<[f64; 4], String> {
    let n = ankle_names(robot)?;
    let h = hip_roll_names(robot)?;
    let feet = feet_mass(&frame.model, &frame.q, [&n[0], &n[1]]).map_err(|e| e.to_string())?;
    let lever =
        crate::tipover::frontal_lever(&frame.model, &frame.q, [&h[0], &h[1]], [&n[2], &n[3]])
            .map_err(|e| e.to_string())?;
    let t = crate::tipover::tip_angles(v3(c0), &feet, &lever, foot).map_err(|e| e.to_string())?;
    Ok(t.to_degrees())
}

/// `--check`: the simulated tip-over study on the adapted model; its four fall angles
/// go into the report beside the measured ones.
pub fn check(
    adapted: &mut Adapted,
    opts: &crate::tipover_study::StudyOptions,
) -> Result<(), IdentError> {
    let robot = adapted.robot.as_ref().ok_or_else(|| {
        IdentError::new("checking needs an adapted model: give the total mass or the host link")
            .option("check")
    })?;
    let s = crate::tipover_study::run_study(robot, opts)?;
    adapted.report.check_deg = Some([
        s.forward.measured_deg,
        s.backward.measured_deg,
        s.left.measured_deg,
        s.right.measured_deg,
    ]);
    Ok(())
}

/// What every output of a tip-over measured with soft servos says.
pub const SOFT_SERVOS_NOTE: &str = "servos soft: the tip-over ran with the servos as they were \
     (--soft-servos), not stiffened; the angles include the servos' give";

/// The HTML report: fall angles robot vs model, the CoMs, side (x-z) and front (y-z)
/// views with the prior CoM, the measured CoM and the added mass.
pub fn html_report(r: &AdaptReport) -> twinloop_report::Report {
    let mut rep =
        twinloop_report::Report::new(format!("Adapting {} to the tip-over angles", r.robot));
    rep.paragraph(
        "Seed 000 sections III and V.B: the exact method turns the measured fall angles into \
         the CoM; one added point mass explains its move from the prior model's CoM. Frame: \
         the midpoint of the ankle pitch joints in the standing pose, x forward, y left, z up.",
    );
    if r.soft_servos {
        rep.paragraph(SOFT_SERVOS_NOTE);
    }
    fall_angles_table(&mut rep, r);
    lean_table(&mut rep, r);
    com_table(&mut rep, r);
    for (title, i, label) in [
        ("Side view (x-z)", 0, "x, m"),
        ("Front view (y-z)", 1, "y, m"),
    ] {
        rep.plot(&view_plot(r, title, i, label));
    }
    rep.heading("What is determined");
    for n in &r.notes {
        rep.paragraph(n.clone());
    }
    checks_table(&mut rep, r);
    rep
}

/// The report's fall angles: the robot's, the prior's and the adapted model's.
fn fall_angles_table(rep: &mut twinloop_report::Report, r: &AdaptReport) {
    rep.heading("Fall angles, deg");
    let dirs = ["forward", "backward", "left", "right"];
    let mut header = vec![
        "direction".into(),
        "robot (measured)".into(),
        "prior model".into(),
    ];
    if r.fall_angle_fit.is_some() {
        header.push("adapted model (static, at the robot's onsets)".into());
    }
    if r.check_deg.is_some() {
        header.push("adapted model (simulated)".into());
    }
    let rows = (0..4)
        .map(|k| {
            let mut row = vec![
                dirs[k].to_string(),
                format!("{:.3}", r.measured_deg[k]),
                format!("{:.3}", r.prior_model_deg[k]),
            ];
            if let Some(f) = &r.fall_angle_fit {
                // The residual is against the angles fitted: the measured ones less
                // the protocol's bias, when one was taken off.
                let bias = r.protocol_bias_deg.map_or(0.0, |b| b[k]);
                row.push(format!(
                    "{:.3}",
                    r.measured_deg[k] - bias + f.residual_deg[k]
                ));
            }
            if let Some(c) = r.check_deg {
                row.push(format!("{:.3}", c[k]));
            }
            row
        })
        .collect();
    rep.table(header, rows);
}

/// The report's lean (seed 001), when one was given: torque RMS per joint.
fn lean_table(rep: &mut twinloop_report::Report, r: &AdaptReport) {
    if !r.lean.is_empty() {
        rep.heading("The lean (seed 001): robot minus model torque, RMS, N m");
        let rows = r
            .lean
            .iter()
            .map(|l| {
                vec![
                    l.joint.clone(),
                    format!("{:.4}", l.before_rms),
                    format!("{:.4}", l.after_rms),
                    format!("{:.4}", l.robot_rms),
                ]
            })
            .collect();
        rep.table(
            vec![
                "joint".into(),
                "prior model".into(),
                "adapted model".into(),
                "robot's torque (scale)".into(),
            ],
            rows,
        );
    }
}

/// The report's CoMs and the added part, mm.
fn com_table(rep: &mut twinloop_report::Report, r: &AdaptReport) {
    use twinloop_report::number;
    rep.heading("CoM, mm");
    let mm = |v: [f64; 3]| {
        v.iter()
            .map(|x| format!("{:.2}", x * 1e3))
            .collect::<Vec<_>>()
    };
    let mut rows = vec![
        [vec!["prior".to_string()], mm(r.prior_com)].concat(),
        [vec!["measured".to_string()], mm(r.measured_com)].concat(),
        [
            vec!["measured, 1 sigma".to_string()],
            mm(r.measured_com_sigma),
        ]
        .concat(),
    ];
    if let Some(c) = r.adapted_com {
        rows.push([vec!["adapted model".to_string()], mm(c)].concat());
    }
    if let Some(a) = &r.added {
        rows.push(
            [
                vec![format!("added {} kg on {}", number(a.mass), a.host)],
                mm(a.position),
            ]
            .concat(),
        );
        rows.push(
            [
                vec!["added mass, 1 sigma".to_string()],
                mm(a.position_sigma),
            ]
            .concat(),
        );
    }
    rep.table(vec!["".into(), "x".into(), "y".into(), "z".into()], rows);
}

/// The report's checks, when any were made.
fn checks_table(rep: &mut twinloop_report::Report, r: &AdaptReport) {
    if !r.checks.is_empty() {
        rep.heading("Checks before the model is written");
        if r.failed_checks().next().is_some() {
            rep.paragraph(
                "FAILED: the adapted model was not written. Over a bus there is no truth to \
                 compare with; what was found is not what a real change can be.",
            );
        }
        let rows = r
            .checks
            .iter()
            .map(|c| {
                let verdict = if c.passed { "passed" } else { "FAILED" };
                vec![c.name.clone(), verdict.into(), c.detail.clone()]
            })
            .collect();
        rep.table(vec!["check".into(), "result".into(), "detail".into()], rows);
    }
}

/// One view of the robot (axis `i` against z, to scale) with the CoMs, the added part
/// and what the angles cannot tell apart.
fn view_plot(r: &AdaptReport, title: &str, i: usize, label: &str) -> twinloop_report::Plot {
    use twinloop_report::{Plot, SeriesStyle};
    let (ox, oz): (Vec<f64>, Vec<f64>) = r.outline.iter().map(|o| (o[i], o[2])).unzip();
    // To scale: a robot stretched sideways misleads about where a part can be.
    let mut p = Plot::new(title, label, "z, m")
        .equal_aspect()
        .height(480.0)
        .series("robot (link origins)", &ox, &oz, SeriesStyle::Points)
        .series(
            "prior CoM",
            &[r.prior_com[i]],
            &[r.prior_com[2]],
            SeriesStyle::Points,
        )
        .series(
            "measured CoM",
            &[r.measured_com[i]],
            &[r.measured_com[2]],
            SeriesStyle::Points,
        );
    if let Some(a) = &r.added {
        p = p.series(
            "added mass",
            &[a.position[i]],
            &[a.position[2]],
            SeriesStyle::Points,
        );
    }
    // What the angles cannot tell apart, drawn rather than guessed: without the
    // mass, every point of the ray from the measured CoM away from the prior's
    // explains them (a lighter part further out); with it, the 1-sigma box.
    let (line_x, line_z) = ambiguity_line(r, i);
    if !line_x.is_empty() {
        p = p.series(
            "equally good (mass unknown: 0.05-2 kg along the ray)",
            &line_x,
            &line_z,
            SeriesStyle::DashedLine,
        );
    }
    if let (Some(a), "total-mass") = (&r.added, r.mode.as_str()) {
        let (c, s) = (a.position, a.position_sigma);
        let bx = [
            c[i] - s[i],
            c[i] + s[i],
            c[i] + s[i],
            c[i] - s[i],
            c[i] - s[i],
        ];
        let bz = [
            c[2] - s[2],
            c[2] - s[2],
            c[2] + s[2],
            c[2] + s[2],
            c[2] - s[2],
        ];
        p = p.series("added mass, 1 sigma", &bx, &bz, SeriesStyle::Line);
    }
    p
}
