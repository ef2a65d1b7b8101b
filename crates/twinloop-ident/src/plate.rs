//! The virtual force plate: statically stable poses in seed 004's six categories
//! (section 3.1), with the centre of pressure each pose gives on the plate.
//!
//! A pose is made in three steps. (1) A posture is drawn: the category's focus
//! joints systematically below 10 % or above 90 % of their range, or all of them at
//! random; the other joints near neutral. (2) A weighted Levenberg-Marquardt solve
//! over the whole configuration stands the robot on its support foot or feet (flat,
//! on z = 0, at the category's stance width) with the CoM towards the middle of the
//! support, staying near the posture. (3) A second solve, over the base and the
//! support legs only, makes the contact exact: soles flat on the ground and, on
//! one foot, the CoM over the middle of the sole. The pose is kept if the
//! ground-projected CoM lies inside the support polygon with a margin, nothing but
//! the soles touches the ground and the joints are inside their limits; otherwise
//! it is drawn again.
//!
//! In a static pose the CoP is the ground-projected CoM (seed 004, section 3.1), so
//! the plate reads the truth model's GCOM plus Gaussian noise; the configuration
//! written gets Gaussian joint noise (the base pose is written as solved).

use crate::anatomy::{Anatomy, link_geometry_points, link_placement, polygon_margin, sole_polygon};
use crate::error::IdentError;
use crate::poses::{PoseCategory, StaticPose};
use nalgebra::{Vector2, Vector3};
use twinloop_description::Description;
use twinloop_dynamics::{Data, Model};
use twinloop_gait::ik::{Ik, IkOptions, Task};
use twinloop_random::SplitMix64;

/// What the generator is asked for.
#[derive(Debug, Clone)]
pub struct PlateOptions {
    /// Number of poses, spread evenly over `categories`.
    pub count: usize,
    pub categories: Vec<PoseCategory>,
    /// Standard deviation of the CoP noise per axis, m.
    pub cop_noise: f64,
    /// Standard deviation of the joint-angle noise in the written configuration, rad.
    pub joint_noise: f64,
    pub seed: u64,
    /// Gap between the soles' inner edges for the double-support categories, m (seed: 2 cm).
    pub gap: f64,
    /// Gap for the wide stance, m (seed: 20 cm).
    pub wide_gap: f64,
    /// Joints held at their neutral value in every pose (joint indices).
    pub hold: Vec<usize>,
    /// Foot links (left, right) when the geometry does not make them obvious.
    pub feet: Option<(String, String)>,
}

impl Default for PlateOptions {
    fn default() -> Self {
        PlateOptions {
            count: 172,
            categories: PoseCategory::ALL.to_vec(),
            cop_noise: 0.0,
            joint_noise: 0.0,
            seed: 1,
            gap: 0.02,
            wide_gap: 0.20,
            hold: Vec::new(),
            feet: None,
        }
    }
}

/// Which part of a joint's range a systematic pose puts its focus joint in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Extreme {
    /// Below 10 % of the range.
    Low,
    /// Above 90 % of the range.
    High,
}

/// How a pose was drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plan {
    /// One focus joint at an extreme, the others near neutral.
    Systematic { joint: usize, extreme: Extreme },
    /// Every focus joint uniform in its range.
    Random,
}

/// A generated pose: what the file gets (noisy), and the truth behind it.
#[derive(Debug, Clone)]
pub struct GeneratedPose {
    /// Configuration with joint noise and CoP with plate noise: what a measurement gives.
    pub pose: StaticPose,
    /// The configuration the robot really had.
    pub q_true: Vec<f64>,
    /// The truth model's ground-projected CoM.
    pub gcom_true: [f64; 2],
    pub plan: Plan,
    /// Distance of the GCOM inside the support polygon, m.
    pub support_margin: f64,
}

/// Range of joint `i`, [-pi, pi] where unlimited.
fn range(model: &Model, i: usize) -> (f64, f64) {
    let (lo, hi) = (model.lower_limits[i], model.upper_limits[i]);
    if lo.is_finite() && hi.is_finite() && lo < hi {
        (lo, hi)
    } else {
        (-std::f64::consts::PI, std::f64::consts::PI)
    }
}

/// Neutral joint value: 0 moved into the range.
fn neutral(model: &Model, i: usize) -> f64 {
    let (lo, hi) = range(model, i);
    0.0f64.clamp(lo, hi)
}

/// The knee of a leg: the joint whose range reaches far to one side of zero and
/// hardly to the other (knees bend one way); with the sign of that side.
pub fn knee_of(model: &Model, leg: &[usize]) -> Option<(usize, f64)> {
    leg.iter()
        .filter_map(|&i| {
            let (lo, hi) = (model.lower_limits[i], model.upper_limits[i]);
            if !(lo.is_finite() && hi.is_finite()) || hi - lo < 1.0 {
                return None;
            }
            let (big, small, sign) = if hi.abs() >= lo.abs() {
                (hi.abs(), lo.abs(), 1.0)
            } else {
                (lo.abs(), hi.abs(), -1.0)
            };
            let score = big / (small + 0.1);
            (score > 3.0).then_some((i, sign, score))
        })
        .max_by(|a, b| a.2.total_cmp(&b.2))
        .map(|(i, s, _)| (i, s))
}

/// Task layout of the double-support solves (indices into `Ik::tasks`).
const D_POSTURE: usize = 7;
/// Task layout of the single-support solves.
const S_POSTURE: usize = 5;

/// Stands a model on the virtual force plate.
pub struct PlateGenerator<'a> {
    pub model: &'a Model,
    pub anatomy: Anatomy,
    data: Data,
    rng: SplitMix64,
    /// Primitive geometry points per description link (link frame), for the ground check.
    geometry: Vec<Vec<Vector3<f64>>>,
    hold: Vec<bool>,
    knees: [Option<(usize, f64)>; 2],
    /// Standing height of the base above the ground in the neutral configuration.
    stand_height: f64,
    /// Distance between the sole centres for each stance width (2 cm, 20 cm gap).
    double_weighted: Option<(Ik, f64)>,
    wide_weighted: Option<(Ik, f64)>,
    double_hard: Ik,
    single_weighted: [Ik; 2],
    single_hard: [Ik; 2],
    options: IkOptions,
}

fn foot_tasks(foot: &crate::anatomy::Foot, y: f64, weight_xy: f64) -> [Task; 3] {
    [
        Task::Axis {
            frame: foot.frame,
            axis: foot.down,
            target: Vector3::new(0.0, 0.0, -1.0),
            weight: Vector3::new(10.0, 10.0, 0.0),
        },
        Task::Point {
            frame: foot.frame,
            point: foot.sole_center,
            target: Vector3::new(0.0, y, 0.0),
            weight: Vector3::new(weight_xy, weight_xy, 10.0),
        },
        Task::Axis {
            frame: foot.frame,
            axis: foot.forward,
            target: Vector3::new(1.0, 0.0, 0.0),
            weight: Vector3::new(0.0, weight_xy, 0.0),
        },
    ]
}

/// A foot flat on the ground with its sole centre at the origin, `xy` weighting the
/// horizontal placement: the hard constraints the weighted solution is projected on.
fn hard_foot_tasks(foot: &crate::anatomy::Foot, xy: f64) -> [Task; 2] {
    [
        Task::Axis {
            frame: foot.frame,
            axis: foot.down,
            target: Vector3::new(0.0, 0.0, -1.0),
            weight: Vector3::new(1.0, 1.0, 0.0),
        },
        Task::Point {
            frame: foot.frame,
            point: foot.sole_center,
            target: Vector3::zeros(),
            weight: Vector3::new(xy, xy, 1.0),
        },
    ]
}

/// A posture task over every joint, its reference and weights set per pose.
fn posture_task(nj: usize) -> Task {
    Task::Posture {
        reference: vec![0.0; nj],
        weight: vec![0.0; nj],
    }
}

/// The weighted double-support IK for a gap between the soles' inner edges: both feet
/// flat at +-d/2, the CoM over the origin, a posture; with the sole-centre distance d.
fn double_support_ik(model: &Model, anatomy: &Anatomy, gap: f64) -> (Ik, f64) {
    let (lf, rf) = (&anatomy.left_foot, &anatomy.right_foot);
    let d = gap + 0.5 * (lf.size[1] + rf.size[1]);
    let mut tasks: Vec<Task> = Vec::new();
    tasks.extend(foot_tasks(lf, 0.5 * d, 1.0));
    tasks.extend(foot_tasks(rf, -0.5 * d, 1.0));
    tasks.push(Task::Com {
        target: Vector3::zeros(),
        weight: Vector3::new(1.0, 1.0, 0.0),
    });
    tasks.push(posture_task(model.nbodies));
    (Ik::new(model, tasks), d)
}

/// The hard double-support projection: both feet flat on the ground, over the base
/// and the legs.
fn double_support_hard_ik(model: &Model, anatomy: &Anatomy) -> Ik {
    let mut tasks: Vec<Task> = hard_foot_tasks(&anatomy.left_foot, 0.0).to_vec();
    tasks.extend(hard_foot_tasks(&anatomy.right_foot, 0.0));
    let mut ik = Ik::new(model, tasks);
    let legs: Vec<usize> = anatomy
        .left_leg
        .iter()
        .chain(&anatomy.right_leg)
        .copied()
        .collect();
    let vo = model.v_offset;
    ik.set_free(|k| k < vo || legs.contains(&(k - vo)));
    ik
}

/// The weighted single-support IK: the stance foot flat at the origin, the CoM over
/// it, the swing foot lifted, a posture.
fn single_support_ik(model: &Model, anatomy: &Anatomy, stance_left: bool) -> Ik {
    let (lf, rf) = (&anatomy.left_foot, &anatomy.right_foot);
    let (st, sw) = if stance_left { (lf, rf) } else { (rf, lf) };
    let mut tasks: Vec<Task> = foot_tasks(st, 0.0, 1.0).to_vec();
    tasks.push(Task::Com {
        target: Vector3::zeros(),
        weight: Vector3::new(3.0, 3.0, 0.0),
    });
    tasks.push(Task::Point {
        frame: sw.frame,
        point: sw.sole_center,
        target: Vector3::new(0.0, 0.0, 0.08),
        weight: Vector3::new(0.0, 0.0, 0.3),
    });
    tasks.push(posture_task(model.nbodies));
    Ik::new(model, tasks)
}

/// The hard single-support projection: the stance foot flat at the origin and the CoM
/// over it, over the base and the stance leg.
fn single_support_hard_ik(model: &Model, anatomy: &Anatomy, stance_left: bool) -> Ik {
    let st = if stance_left {
        &anatomy.left_foot
    } else {
        &anatomy.right_foot
    };
    let mut tasks: Vec<Task> = hard_foot_tasks(st, 1.0).to_vec();
    tasks.push(Task::Com {
        target: Vector3::zeros(),
        weight: Vector3::new(1.0, 1.0, 0.0),
    });
    let mut ik = Ik::new(model, tasks);
    let leg = anatomy.leg(stance_left).to_vec();
    let vo = model.v_offset;
    ik.set_free(|k| k < vo || leg.contains(&(k - vo)));
    ik
}

impl<'a> PlateGenerator<'a> {
    pub fn new(
        robot: &Description,
        model: &'a Model,
        seed: u64,
        hold: &[usize],
        feet: Option<(&str, &str)>,
    ) -> Result<Self, IdentError> {
        if !model.is_floating() {
            return Err(IdentError::new(
                "the force plate needs a floating-base model (the robot stands on it)",
            ));
        }
        let anatomy = Anatomy::detect(robot, model, feet)?;
        let mut data = Data::new(model);
        let geometry: Vec<Vec<Vector3<f64>>> = (0..robot.links.len())
            .map(|l| link_geometry_points(robot, l))
            .collect();
        let q0 = model.neutral_configuration();
        twinloop_dynamics::forward_kinematics(model, &mut data, &q0);
        let sole_z = |f: &crate::anatomy::Foot| {
            link_placement(model, &data, f.link)
                .act_point(&f.sole_center)
                .z
        };
        let stand_height = -sole_z(&anatomy.left_foot).min(sole_z(&anatomy.right_foot));
        let mut hold_mask = vec![false; model.nbodies];
        for &h in hold {
            hold_mask[h] = true;
        }
        let knees = [
            knee_of(model, &anatomy.left_leg),
            knee_of(model, &anatomy.right_leg),
        ];
        Ok(PlateGenerator {
            model,
            data,
            rng: SplitMix64(seed ^ 0x5EED_F0CE_u64),
            geometry,
            hold: hold_mask,
            knees,
            stand_height,
            double_weighted: Some(double_support_ik(model, &anatomy, 0.02)),
            wide_weighted: Some(double_support_ik(model, &anatomy, 0.20)),
            double_hard: double_support_hard_ik(model, &anatomy),
            single_weighted: [
                single_support_ik(model, &anatomy, true),
                single_support_ik(model, &anatomy, false),
            ],
            single_hard: [
                single_support_hard_ik(model, &anatomy, true),
                single_support_hard_ik(model, &anatomy, false),
            ],
            options: IkOptions {
                max_iterations: 200,
                ..IkOptions::default()
            },
            anatomy,
        })
    }

    /// Set the stance gaps (inner edges of the soles) for the double-support categories.
    pub fn set_gaps(&mut self, gap: f64, wide_gap: f64) {
        let (lf, rf) = (&self.anatomy.left_foot, &self.anatomy.right_foot);
        let width = 0.5 * (lf.size[1] + rf.size[1]);
        for (slot, g) in [
            (&mut self.double_weighted, gap),
            (&mut self.wide_weighted, wide_gap),
        ] {
            if let Some((ik, d)) = slot.as_mut() {
                *d = g + width;
                if let Task::Point { target, .. } = &mut ik.tasks[1] {
                    target.y = 0.5 * *d;
                }
                if let Task::Point { target, .. } = &mut ik.tasks[4] {
                    target.y = -0.5 * *d;
                }
            }
        }
    }

    /// The focus joints of a category (what its systematic poses sweep).
    pub fn focus_joints(&self, cat: PoseCategory) -> Vec<usize> {
        let a = &self.anatomy;
        let mut f: Vec<usize> = match cat {
            PoseCategory::Arm => a.right_arm.iter().chain(&a.left_arm).copied().collect(),
            PoseCategory::LeftSupport => a.right_leg.clone(),
            PoseCategory::RightSupport => a.left_leg.clone(),
            PoseCategory::Torso => a.torso.iter().chain(&a.other).copied().collect(),
            PoseCategory::Crouch | PoseCategory::Wide => a
                .torso
                .iter()
                .chain(&a.right_arm)
                .chain(&a.left_arm)
                .chain(&a.other)
                .copied()
                .collect(),
        };
        f.retain(|&j| !self.hold[j]);
        f
    }

    /// The systematic plans of a category: each focus joint low, then high.
    pub fn systematic_plans(&self, cat: PoseCategory) -> Vec<Plan> {
        if matches!(cat, PoseCategory::Crouch | PoseCategory::Wide) {
            return Vec::new();
        }
        let mut out = Vec::new();
        for j in self.focus_joints(cat) {
            for extreme in [Extreme::Low, Extreme::High] {
                out.push(Plan::Systematic { joint: j, extreme });
            }
        }
        out
    }

    /// Draw the posture (joint values) of a plan.
    fn draw_posture(&mut self, cat: PoseCategory, plan: Plan) -> (Vec<f64>, Vec<f64>) {
        let model = self.model;
        let nj = model.nbodies;
        let mut reference: Vec<f64> = (0..nj).map(|i| neutral(model, i)).collect();
        let mut weight = vec![0.5f64; nj];
        let focus = self.focus_joints(cat);
        let a = &self.anatomy;
        let legs: Vec<usize> = a.left_leg.iter().chain(&a.right_leg).copied().collect();
        for &i in &legs {
            weight[i] = 0.05;
        }
        // Small jitter of the upper body so that even "neutral" joints vary a little.
        for (i, r) in reference.iter_mut().enumerate() {
            if !legs.contains(&i) && !self.hold[i] {
                let (lo, hi) = range(model, i);
                let j = self.rng.uniform(-0.05, 0.05) * (hi - lo);
                *r = (*r + j).clamp(lo, hi);
            }
        }
        match plan {
            Plan::Systematic { joint, extreme } => {
                let (lo, hi) = range(model, joint);
                let w = 0.1 * (hi - lo);
                reference[joint] = match extreme {
                    Extreme::Low => self.rng.uniform(lo, lo + w),
                    Extreme::High => self.rng.uniform(hi - w, hi),
                };
                weight[joint] = 3.0;
            }
            Plan::Random => {
                for &j in &focus {
                    let (lo, hi) = range(model, j);
                    reference[j] = self.rng.uniform(lo, hi);
                    weight[j] = 1.0;
                }
            }
        }
        match cat {
            PoseCategory::LeftSupport | PoseCategory::RightSupport => {
                // The swing leg: knee bent so the foot clears the ground, unless it is the focus.
                let swing_left = cat == PoseCategory::RightSupport;
                let swing = if swing_left {
                    &a.left_leg
                } else {
                    &a.right_leg
                };
                if let Some((k, sign)) = self.knees[usize::from(!swing_left)] {
                    let is_focus = matches!(plan, Plan::Systematic { joint, .. } if joint == k);
                    if !is_focus && !matches!(plan, Plan::Random) {
                        let (lo, hi) = range(model, k);
                        let ext = if sign > 0.0 { hi } else { lo };
                        reference[k] = ext * self.rng.uniform(0.25, 0.5);
                    }
                }
                for &i in swing {
                    weight[i] = weight[i].max(0.5);
                }
            }
            PoseCategory::Crouch => {
                for (side, leg) in [&a.left_leg, &a.right_leg].into_iter().enumerate() {
                    if let Some((k, sign)) = self.knees[side] {
                        let (lo, hi) = range(model, k);
                        let ext = if sign > 0.0 { hi } else { lo };
                        reference[k] = ext * self.rng.uniform(0.15, 0.6);
                        weight[k] = 1.0;
                    }
                    let _ = leg;
                }
                // Keep the upper body calmer while crouching.
                for &j in &focus {
                    let (lo, hi) = range(model, j);
                    let n = neutral(model, j);
                    reference[j] = (n + self.rng.uniform(-0.2, 0.2) * (hi - lo)).clamp(lo, hi);
                }
            }
            _ => {}
        }
        for (i, r) in reference.iter_mut().enumerate() {
            if self.hold[i] {
                *r = neutral(model, i);
            }
        }
        (reference, weight)
    }

    /// Try once to make a statically stable pose of `cat` following `plan`. The
    /// error says why the draw was rejected.
    pub fn try_pose(
        &mut self,
        cat: PoseCategory,
        plan: Plan,
    ) -> Result<(Vec<f64>, f64), IdentError> {
        let model = self.model;
        let (reference, weight) = self.draw_posture(cat, plan);
        let mut q = model.neutral_configuration();
        q[2] = self.stand_height;
        q[model.q_offset..].copy_from_slice(&reference);
        let vo = model.v_offset;
        let hold = self.hold.clone();
        let free = |k: usize| k < vo || !hold[k - vo];
        let opts = self.options.clone();
        let double = cat.double_support();
        let stance_left = cat != PoseCategory::RightSupport;
        if double {
            let slot = if cat == PoseCategory::Wide {
                &mut self.wide_weighted
            } else {
                &mut self.double_weighted
            };
            let (ik, _) = slot.as_mut().expect("built in new");
            if let Task::Posture {
                reference: r,
                weight: w,
            } = &mut ik.tasks[D_POSTURE]
            {
                r.copy_from_slice(&reference);
                w.copy_from_slice(&weight);
            }
            ik.set_free(free);
            ik.solve(model, &mut self.data, &mut q, &opts);
            self.double_hard.set_free(|k| {
                let legs = self.anatomy.left_leg.iter().chain(&self.anatomy.right_leg);
                k < vo || (!hold[k - vo] && legs.clone().any(|&b| b == k - vo))
            });
            let rep = self.double_hard.solve(model, &mut self.data, &mut q, &opts);
            if rep.max_residual > 1e-9 {
                return Err(IdentError::new(format!(
                    "the feet cannot both be flat on the ground (residual {:.2e})",
                    rep.max_residual
                )));
            }
        } else {
            let s = usize::from(!stance_left);
            let ik = &mut self.single_weighted[s];
            if let Task::Posture {
                reference: r,
                weight: w,
            } = &mut ik.tasks[S_POSTURE]
            {
                r.copy_from_slice(&reference);
                w.copy_from_slice(&weight);
            }
            ik.set_free(free);
            ik.solve(model, &mut self.data, &mut q, &opts);
            // Exact: the stance sole where it is now, flat, and the CoM over its centre.
            let foot = self.anatomy.foot(stance_left).clone();
            twinloop_dynamics::forward_kinematics(model, &mut self.data, &q);
            let x = link_placement(model, &self.data, foot.link);
            let c = x.act_point(&foot.sole_center);
            let hard = &mut self.single_hard[s];
            if let Task::Point { target, .. } = &mut hard.tasks[1] {
                *target = Vector3::new(c.x, c.y, 0.0);
            }
            if let Task::Com { target, .. } = &mut hard.tasks[2] {
                *target = Vector3::new(c.x, c.y, 0.0);
            }
            // Every joint but a systematic focus joint may help balance.
            let pinned = match plan {
                Plan::Systematic { joint, .. } => Some(joint),
                Plan::Random => None,
            };
            hard.set_free(|k| k < vo || (!hold[k - vo] && pinned != Some(k - vo)));
            let rep = hard.solve(model, &mut self.data, &mut q, &opts);
            if rep.max_residual > 1e-9 {
                // The CoM cannot reach the middle of the sole (a narrow foot, a weak
                // hip): make the contact exact alone and let the support check decide.
                if let Task::Com { weight, .. } = &mut hard.tasks[2] {
                    *weight = Vector3::zeros();
                }
                let rep = hard.solve(model, &mut self.data, &mut q, &opts);
                if let Task::Com { weight, .. } = &mut hard.tasks[2] {
                    *weight = Vector3::new(1.0, 1.0, 0.0);
                }
                if rep.max_residual > 1e-9 {
                    return Err(IdentError::new(format!(
                        "the stance foot cannot be flat on the ground (residual {:.2e})",
                        rep.max_residual
                    )));
                }
            }
        }
        self.check(&q, cat).map(|m| (q, m))
    }

    /// Accept a solved pose: joints in range, GCOM inside the support polygon with a
    /// margin, nothing but the support soles on or below the ground. Returns the margin.
    fn check(&mut self, q: &[f64], cat: PoseCategory) -> Result<f64, IdentError> {
        let model = self.model;
        for i in 0..model.nbodies {
            let x = q[model.q_offset + i];
            if x < model.lower_limits[i] - 1e-9 || x > model.upper_limits[i] + 1e-9 {
                return Err(IdentError::new(format!(
                    "joint {} out of its limits",
                    model.joint_names[i]
                )));
            }
        }
        let com = twinloop_dynamics::center_of_mass(model, &mut self.data, q);
        let a = &self.anatomy;
        let supports: Vec<&crate::anatomy::Foot> = match cat {
            PoseCategory::LeftSupport => vec![&a.left_foot],
            PoseCategory::RightSupport => vec![&a.right_foot],
            _ => vec![&a.left_foot, &a.right_foot],
        };
        let soles: Vec<Vec<Vector2<f64>>> = supports
            .iter()
            .map(|f| sole_polygon(f, &link_placement(model, &self.data, f.link)))
            .collect();
        if cat.double_support() {
            // The feet must not overlap or cross.
            for (s, o) in [(0, 1), (1, 0)] {
                if soles[s]
                    .iter()
                    .any(|p| polygon_margin(&soles[o], p) > -1e-4)
                {
                    return Err(IdentError::new("the feet overlap"));
                }
            }
            let yl = link_placement(model, &self.data, a.left_foot.link)
                .translation
                .y;
            let yr = link_placement(model, &self.data, a.right_foot.link)
                .translation
                .y;
            if yl <= yr {
                return Err(IdentError::new("the feet cross"));
            }
        }
        let poly = crate::anatomy::support_polygon(&soles);
        let g = Vector2::new(com.x, com.y);
        let margin = polygon_margin(&poly, &g);
        let half_width = supports
            .iter()
            .map(|f| 0.5 * f.size[1])
            .fold(f64::INFINITY, f64::min);
        let need = (0.25 * half_width).min(0.005);
        if margin < need {
            return Err(IdentError::new(format!(
                "the GCOM is {:.1} mm inside the support polygon (needs {:.1} mm)",
                margin * 1e3,
                need * 1e3
            )));
        }
        // Ground clearance of everything but the support soles.
        let support_bodies: Vec<usize> = supports.iter().map(|f| f.body).collect();
        for (l, pts) in self.geometry.iter().enumerate() {
            if pts.is_empty() || support_bodies.contains(&model.links[l].body) {
                continue;
            }
            let x = link_placement(model, &self.data, l);
            let low = pts
                .iter()
                .map(|p| x.act_point(p).z)
                .fold(f64::INFINITY, f64::min);
            if low < 0.01 {
                return Err(IdentError::new(format!(
                    "link {} reaches {:.1} mm above the ground (needs 10 mm)",
                    model.links[l].name,
                    low * 1e3
                )));
            }
        }
        Ok(margin)
    }

    /// A stable pose of `cat`: the plan first, redrawn up to `attempts` times, then
    /// random plans. The error gives the last reason for rejection.
    pub fn pose(
        &mut self,
        cat: PoseCategory,
        plan: Plan,
        attempts: usize,
    ) -> Result<(Vec<f64>, Plan, f64), IdentError> {
        let mut last = String::new();
        for k in 0..attempts * 4 {
            let p = if k < attempts { plan } else { Plan::Random };
            match self.try_pose(cat, p) {
                Ok((q, m)) => return Ok((q, p, m)),
                Err(e) => last = e.message,
            }
        }
        Err(IdentError::new(format!(
            "could not make a statically stable \"{}\" pose in {} attempts; last rejection: {last}",
            cat.name(),
            attempts * 4
        ))
        .option("categories"))
    }

    pub fn rng(&mut self) -> &mut SplitMix64 {
        &mut self.rng
    }
}

/// The plans for `count` poses spread over `categories`: per category, the systematic
/// sweep first (interleaved low/high), leaving at least a third (and up to 10) of
/// that category's poses random, as the seed did.
pub fn plan_poses(
    generator: &PlateGenerator,
    count: usize,
    categories: &[PoseCategory],
) -> Vec<(PoseCategory, Plan)> {
    let nc = categories.len().max(1);
    let mut out = Vec::with_capacity(count);
    for (c, &cat) in categories.iter().enumerate() {
        let n = count / nc + usize::from(c < count % nc);
        let random_min = (n / 3).max(n.min(10)).min(n);
        let sys = generator.systematic_plans(cat);
        let take = sys.len().min(n - random_min);
        out.extend(sys.into_iter().take(take).map(|p| (cat, p)));
        out.extend(std::iter::repeat_n((cat, Plan::Random), n - take));
    }
    out
}

/// What the generator made, and the categories it had to leave out.
#[derive(Debug, Clone)]
pub struct Generated {
    pub poses: Vec<GeneratedPose>,
    /// Categories the robot cannot stand in (with the last reason), their share
    /// given to the others.
    pub skipped: Vec<(PoseCategory, String)>,
}

/// Generate `options.count` poses on the virtual force plate with the truth model
/// (seed 004, section 3.1: six categories, joints below 10 % and above 90 % of their
/// range plus random poses, each statically stable);
/// `progress` is called after each pose. A category in which the robot cannot stand
/// (H1's 3 cm wide sole bar cannot carry its CoM on one foot) is skipped and its
/// share given to the others; if no category works, that is an error.
pub fn generate_static_poses(
    robot: &Description,
    model: &Model,
    options: &PlateOptions,
    mut progress: impl FnMut(usize),
) -> Result<Generated, IdentError> {
    if options.count == 0 {
        return Err(IdentError::new("at least one pose is needed").option("count"));
    }
    if options.categories.is_empty() {
        return Err(IdentError::new("no category chosen").option("categories"));
    }
    let feet = options.feet.as_ref().map(|(l, r)| (l.as_str(), r.as_str()));
    let mut generator = PlateGenerator::new(robot, model, options.seed, &options.hold, feet)?;
    generator.set_gaps(options.gap, options.wide_gap);
    let mut usable = Vec::new();
    let mut skipped = Vec::new();
    for &cat in &options.categories {
        if cat == PoseCategory::Arm && generator.anatomy.left_arm.is_empty() {
            skipped.push((cat, "the robot has no arms".to_string()));
            continue;
        }
        match generator.pose(cat, Plan::Random, 10) {
            Ok(_) => usable.push(cat),
            Err(e) => skipped.push((cat, e.message)),
        }
    }
    if usable.is_empty() {
        return Err(IdentError::new(format!(
            "the robot cannot stand in any of the chosen categories: {}",
            skipped
                .iter()
                .map(|(c, e)| format!("{}: {e}", c.name()))
                .collect::<Vec<_>>()
                .join("; ")
        ))
        .option("categories"));
    }
    let plans = plan_poses(&generator, options.count, &usable);
    let mut data = Data::new(model);
    let mut out = Vec::with_capacity(plans.len());
    for (k, (cat, plan)) in plans.into_iter().enumerate() {
        let (q_true, plan, margin) = generator.pose(cat, plan, 25)?;
        let com = twinloop_dynamics::center_of_mass(model, &mut data, &q_true);
        let rng = generator.rng();
        let mut q = q_true.clone();
        for x in &mut q[model.q_offset..] {
            *x += options.joint_noise * rng.normal();
        }
        let cop = [
            com.x + options.cop_noise * rng.normal(),
            com.y + options.cop_noise * rng.normal(),
        ];
        out.push(GeneratedPose {
            pose: StaticPose {
                q,
                cop,
                category: Some(cat),
            },
            q_true,
            gcom_true: [com.x, com.y],
            plan,
            support_margin: margin,
        });
        progress(k + 1);
    }
    Ok(Generated {
        poses: out,
        skipped,
    })
}
