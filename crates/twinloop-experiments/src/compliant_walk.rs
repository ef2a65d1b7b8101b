//! The "real robot" dataset of seed 002 (section 4): COMAN walking the ZMP gait in the
//! full simulator, with series-elastic knee and ankle pitch joints (eq 1-6) and
//! position-controlled stiff joints, recording the reference and the actual CoM at 1 kHz.
//!
//! # Pipeline
//!
//! 1. **References** ([`WalkingReference`]): the ZMP/LIPM CoM reference of eq 12-13
//!    ([`ZmpReference`]) at a constant height Zc, the footprints of the plan, and swing
//!    trajectories for the free foot: forward motion by a minimum-jerk profile
//!    `s = 10u^3 - 15u^4 + 6u^5` and lift `h (1 - cos 2 pi u) / 2` over the single-support
//!    phase (u in [0, 1]); both start and end with zero velocity, so the foot leaves and
//!    lands flat and without a jerk.
//! 2. **Whole-body IK** ([`twinloop_gait::walking_ik`]) per 1 ms sample: both sole poses, the CoM
//!    at the reference and the pelvis upright give the twelve leg-joint references.
//!    Running it over the whole plan before simulating finds an unreachable step before
//!    any simulation time is spent.
//! 3. **Simulation** (`twinloop_sim`): the goals go to the joint actuators: the knee and
//!    ankle pitch joints are [`SeriesElastic`] with k_j = K_h K_s / (K_h + K_s) and the
//!    motor of eq 1 held by a stiff PD loop (the seed's assumption A1); every other joint
//!    is a [`TwoLoopServo`] whose stiffness equals K_h (the seed's k_j of a stiff joint),
//!    so the simulated robot has exactly the joint stiffness matrix K_j that eq 7 uses.
//! 4. **Recording**: at every 1 ms sample the reference (xr, zr) and the true CoM (x, z)
//!    of the simulated state, with the phase code (0 single, 1 double support).
//!
//! # Frame
//!
//! World frame, metres: origin on the ground (z = 0) midway between the two feet's
//! centres at the start; x forward (the walking direction), y to the robot's left, z up.
//! Footprints are foot centres (the middle of the sole box), where the ZMP reference
//! sits in single support.
//!
//! # Control: what the simulated robot's controller does
//!
//! - **Gravity feed-forward** on the compliant joints: each motor is pre-deflected by the
//!   static torque over k_j at the reference pose (weight on the stance foot, split by
//!   the ZMP between the feet in double support: `StaticLoad`), so the link reaches its
//!   reference in statics. Without it the stance leg leans under the body's weight
//!   (about 0.03 rad at the ankle for k_j = 290 N m/rad) and every swing foot lands
//!   about 1.5 cm ahead of its footprint (measured: the errors accumulate to 9 cm in
//!   12 s, or with the foot placement below the robot falls at 2 s). With it the dataset keeps the *dynamic*
//!   deflection (what the compact model's springs and dampers describe) and a small
//!   static sag.
//! - **Foot placement on the actual feet**: a stance sole is commanded where it touched
//!   down and a swing ends on the planned footprint, so a landing error does not carry
//!   the rest of the plan along.
//! - **Lateral balance**: the IK's CoM target moves by `kp (y_r - y) + kd (vy_r - vy)`
//!   (true CoM state; gains `balance_kp`, `balance_kd`, default 1 and 0.3 s laterally,
//!   0 sagittally). The open-loop gait's lateral sway grows from step to step until the
//!   robot falls over the stance foot's outer edge (measured: after 4 steps); the seed's
//!   compact model treats y as stiff and records only x and z, which the feedback
//!   leaves alone.
//!
//! # Stiffness choice
//!
//! The seed gives K_h about 8000 and K_s about 100 N m/rad, for the lower-body COMAN of
//! its Fig. 1. The URDF here is the full 32 kg robot: on one foot, the ankle pitch spring
//! alone holds an inverted pendulum of gravitational stiffness m g Zc (167.7 N m/rad
//! at Zc = 0.533 m), more than a 100 N m/rad spring (k_j = 98.8) can: the static
//! equilibrium is unstable ([`WalkingConfig::ankle_stability_ratio`] 0.59). The default
//! K_s = 300 (k_j = 289.2, ratio 1.72) holds it with a margin; `k_series` can be set to
//! the seed's 100 to see the robot fall (a test does).

use crate::error::{ExperimentError, err};
use nalgebra::{Matrix3, Vector3};
use twinloop_description::Description;
use twinloop_dynamics::{Data, Model, center_of_mass, jacobian_center_of_mass};
use twinloop_gait::walking_ik::{IkTargets, WholeBodyIk};
use twinloop_gait::{GaitPlan, Phase, ZmpReference};
use twinloop_reduced::{JointCompliance, SupportLeg};
use twinloop_sim::{Actuator, ContactParams, SeriesElastic, SimConfig, Simulator, TwoLoopServo};
use twinloop_spatial::Se3;

/// Sample period of the dataset (seed 002: 1 kHz), s.
pub const SAMPLE_TIME: f64 = 1e-3;
/// Samples per second; sample i is at `i / SAMPLE_RATE` (exactly rounded times).
pub const SAMPLE_RATE: f64 = 1000.0;

/// Everything that defines a walking run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct WalkingConfig {
    /// Step length sl, m.
    pub step_length: f64,
    /// Single-support duration Tss, s.
    pub t_single: f64,
    /// Double-support duration Tdb, s.
    pub t_double: f64,
    /// Recorded duration, s (the plan fills it: standing, steps, standing).
    pub duration: f64,
    /// Standing time at the start of the recording, s.
    pub t_start: f64,
    /// Least standing time at the end, s.
    pub t_end_min: f64,
    /// Knee bend of the initial crouch, rad: sets the CoM height Zc.
    pub knee_bend: f64,
    /// Swing-foot lift, m.
    pub swing_height: f64,
    /// Harmonic drive and series spring stiffness, N m/rad (seed 002, section 2.1).
    pub k_harmonic: f64,
    pub k_series: f64,
    /// Damping in parallel with the series spring, N m s/rad.
    pub spring_damping: f64,
    /// Gear ratio N and the motor's rotor inertia, viscous damping, torque constant,
    /// back-EMF constant and winding resistance (seed 002, eq 5-6).
    pub gear_ratio: f64,
    pub rotor_inertia: f64,
    pub rotor_damping: f64,
    pub torque_constant: f64,
    pub bemf_constant: f64,
    pub winding_resistance: f64,
    /// Stiffness of the motor position loop (seed 002 A1: stiff), N m/rad.
    pub motor_kp: f64,
    /// Speed-loop gain of the stiff joints' servos, N m s/rad; their position gain is
    /// K_h / kv so their stiffness is K_h.
    pub servo_kv: f64,
    /// Ground contact: how far the robot's weight on 8 points sinks, m (sets the
    /// normal and tangential contact stiffness, critically damped; `twinloop_sim`).
    pub contact_sink: f64,
    /// Pre-deflect the compliant joints' motors by the static torque over k_j at the
    /// reference pose (see the module documentation).
    pub gravity_feedforward: bool,
    /// Balance feedback on the CoM (true state): the IK's CoM target moves by
    /// `kp (c_r - c) + kd (v_r - v)`, sagittally (x) and laterally (y) with their own
    /// gains `[x, y]`. Zero gains: open loop on the references.
    pub balance_kp: [f64; 2],
    pub balance_kd: [f64; 2],
    /// Time constant of the first-order filter on the balance correction, s: the
    /// position servos follow a command within milliseconds, so velocity feedback
    /// straight into the position command closes a fast loop that rings.
    pub balance_filter: f64,
    /// Simulator steps per 1 ms sample.
    pub substeps: usize,
    /// Time standing still before the recording starts, s (the robot settles).
    pub settle: f64,
}

impl Default for WalkingConfig {
    fn default() -> Self {
        WalkingConfig {
            step_length: 0.03,
            t_single: 0.5,
            t_double: 0.2,
            duration: 30.0,
            t_start: 1.0,
            t_end_min: 0.5,
            knee_bend: 0.6,
            swing_height: 0.03,
            k_harmonic: 8000.0,
            k_series: 300.0,
            spring_damping: 5.0,
            gear_ratio: 100.0,
            rotor_inertia: 5e-6,
            rotor_damping: 1e-5,
            torque_constant: 0.04,
            bemf_constant: 0.04,
            winding_resistance: 2.0,
            motor_kp: 20_000.0,
            servo_kv: 100.0,
            contact_sink: 5e-4,
            gravity_feedforward: true,
            balance_kp: [0.0, 1.0],
            balance_kd: [0.0, 0.3],
            balance_filter: 0.02,
            substeps: 1,
            settle: 5.0,
        }
    }
}

impl WalkingConfig {
    /// Checks every field; the error names the field at fault.
    pub fn validate(&self) -> Result<(), ExperimentError> {
        let positive = [
            ("step length", self.step_length),
            ("single-support duration Tss", self.t_single),
            ("double-support duration Tdb", self.t_double),
            ("duration", self.duration),
            ("knee bend", self.knee_bend),
            ("swing height", self.swing_height),
            ("harmonic-drive stiffness K_h", self.k_harmonic),
            ("series stiffness K_s", self.k_series),
            ("gear ratio N", self.gear_ratio),
            ("rotor inertia J_m", self.rotor_inertia),
            ("winding resistance R_m", self.winding_resistance),
            ("motor position gain", self.motor_kp),
            ("servo speed gain kv", self.servo_kv),
            ("contact sink", self.contact_sink),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return err(format!("{name} must be positive and finite, got {v}"));
            }
        }
        let non_negative = [
            ("start time", self.t_start),
            ("end time", self.t_end_min),
            ("spring damping", self.spring_damping),
            ("rotor damping D_m", self.rotor_damping),
            ("torque constant", self.torque_constant),
            ("back-EMF constant", self.bemf_constant),
            ("settling time", self.settle),
            ("balance filter time constant", self.balance_filter),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return err(format!("{name} must be non-negative and finite, got {v}"));
            }
        }
        for (name, g) in [
            ("balance_kp", self.balance_kp),
            ("balance_kd", self.balance_kd),
        ] {
            if g.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
                return err(format!(
                    "{name} gains must be non-negative and finite, got {g:?}"
                ));
            }
        }
        if self.substeps == 0 || self.substeps > 100 {
            return err(format!("substeps must be 1..=100, got {}", self.substeps));
        }
        if self.duration > 3600.0 {
            return err(format!("duration {} s is over an hour", self.duration));
        }
        Ok(())
    }

    /// Joint stiffness of a compliant joint, k_j = K_h K_s / (K_h + K_s) (seed 002).
    pub fn compliant_stiffness(&self) -> f64 {
        SeriesElastic::series_stiffness(self.k_harmonic, self.k_series)
    }

    /// The joint compliance of eq 7 that this robot has.
    pub fn joint_compliance(&self) -> JointCompliance {
        JointCompliance {
            k_harmonic: self.k_harmonic,
            k_series: self.k_series,
            d_stiff: self.servo_kv,
            d_compliant: self.spring_damping.max(1e-9),
            ..JointCompliance::default()
        }
    }

    /// k_j / (m g Zc): below 1 a single ankle pitch spring cannot hold the robot upright
    /// on one foot (the inverted pendulum on a torsion spring is statically unstable).
    pub fn ankle_stability_ratio(&self, mass: f64, gravity: f64, com_height: f64) -> f64 {
        self.compliant_stiffness() / (mass * gravity * com_height)
    }

    /// The footstep plan filling `duration`: as many steps as fit after the start
    /// standing and before at least `t_end_min` of standing at the end.
    pub fn plan(&self, step_width: f64, com_height: f64) -> Result<GaitPlan, ExperimentError> {
        self.validate()?;
        let cycle = self.t_single + self.t_double;
        let room = self.duration - self.t_start - self.t_double - self.t_end_min;
        let steps = (room / cycle + 1e-9).floor();
        if steps < 1.0 {
            return err(format!(
                "duration {} s leaves no room for a step (start {} s + Tdb {} s + one step {} s + end {} s)",
                self.duration, self.t_start, self.t_double, cycle, self.t_end_min
            ));
        }
        let steps = steps as usize;
        let t_end = self.duration - self.t_start - self.t_double - steps as f64 * cycle;
        let plan = GaitPlan {
            step_length: self.step_length,
            t_single: self.t_single,
            t_double: self.t_double,
            step_width,
            steps,
            com_height,
            gravity: twinloop_description::GRAVITY,
            t_start: self.t_start,
            t_end,
            ..GaitPlan::default()
        };
        plan.validate()?;
        Ok(plan)
    }
}

/// Minimum-jerk blend 0 -> 1 with zero velocity and acceleration at both ends.
fn min_jerk(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
}

/// The references of a plan: CoM (from the ZMP, eq 12-13) and both feet.
#[derive(Debug, Clone)]
pub struct WalkingReference {
    pub zmp: ZmpReference,
    /// Sole frame origin relative to the foot centre, in the foot frame (x, y), m.
    pub sole_offset: [f64; 2],
    pub swing_height: f64,
}

/// Feet and CoM references at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkingSample {
    pub t: f64,
    pub phase: Phase,
    /// CoM reference (x, y, Zc) and velocity (x, y).
    pub com: [f64; 3],
    pub com_vel: [f64; 2],
    /// Sole frame origin targets (left, right), world.
    pub soles: [[f64; 3]; 2],
    /// Whether each foot (left, right) is meant to be on the ground.
    pub stance: [bool; 2],
    /// For a swinging foot: the planned landing sole position (x, y) and the forward
    /// blend 0 -> 1 of the swing (`soles` = start + (landing - start) * blend).
    pub landing: [[f64; 2]; 2],
    pub blend: [f64; 2],
}

impl WalkingReference {
    /// Foot centre after `c` completed swings: left feet land on odd swings, right
    /// on even ones (the plan of [`ZmpReference`]: footprint j at x = j sl).
    fn footprint(&self, left: bool, completed: usize) -> [f64; 2] {
        let p = self.zmp.plan();
        let half = 0.5 * p.step_width;
        let j = if left {
            if completed == 0 {
                return [0.0, half];
            }
            if completed % 2 == 1 {
                completed
            } else {
                completed - 1
            }
        } else {
            if completed < 2 {
                return [0.0, -half];
            }
            if completed.is_multiple_of(2) {
                completed
            } else {
                completed - 1
            }
        };
        [j as f64 * p.step_length, if left { half } else { -half }]
    }

    /// The references at time t.
    pub fn at(&self, t: f64) -> WalkingSample {
        let p = self.zmp.plan();
        let z = self.zmp.at(t);
        let cycle = p.t_single + p.t_double;
        let walk0 = p.t_start + p.t_double;
        // swing j (1-based) runs on [walk0 + (j-1) cycle, walk0 + (j-1) cycle + Tss]
        let (completed, swing) = if t < walk0 {
            (0, None)
        } else {
            let k = ((t - walk0) / cycle).floor() as usize; // swings started before: k + 1
            let j = k + 1;
            if j > p.steps {
                (p.steps, None)
            } else {
                let u = (t - walk0 - k as f64 * cycle) / p.t_single;
                if u < 1.0 {
                    (j - 1, Some((j, u)))
                } else {
                    (j, None)
                }
            }
        };
        let mut soles = [[0.0; 3]; 2];
        let mut stance = [true; 2];
        let mut landing = [[0.0; 2]; 2];
        let mut blend = [0.0; 2];
        for (s, left) in [true, false].into_iter().enumerate() {
            let mut c = self.footprint(left, completed);
            let mut lift = 0.0;
            if let Some((j, u)) = swing
                && (j % 2 == 1) == left
            {
                let to = self.footprint(left, j);
                let b = min_jerk(u);
                c = [c[0] + (to[0] - c[0]) * b, c[1] + (to[1] - c[1]) * b];
                landing[s] = [to[0] + self.sole_offset[0], to[1] + self.sole_offset[1]];
                blend[s] = b;
                lift = self.swing_height * 0.5 * (1.0 - (std::f64::consts::TAU * u).cos());
                stance[s] = false;
            }
            soles[s] = [c[0] + self.sole_offset[0], c[1] + self.sole_offset[1], lift];
        }
        WalkingSample {
            t,
            phase: z.phase,
            com: z.com,
            com_vel: z.vel,
            soles,
            stance,
            landing,
            blend,
        }
    }
}

/// One recorded sample: `t, xr, zr, x, z, phase` (seed 002's data).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DatasetRow {
    pub t: f64,
    pub xr: f64,
    pub zr: f64,
    pub x: f64,
    pub z: f64,
    /// 0 single support, 1 double support.
    pub phase: u8,
}

/// What the run measured.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct WalkingSummary {
    pub samples: usize,
    pub steps: usize,
    /// CoM height Zc of the reference, m.
    pub com_height: f64,
    pub step_width: f64,
    /// Compliant joint stiffness k_j and the ankle stability ratio k_j / (m g Zc).
    pub k_compliant: f64,
    pub ankle_stability_ratio: f64,
    pub mass: f64,
    /// RMS and maximum of x - xr and z - zr, m; mean of z - zr (the sag), m.
    pub rms_x: f64,
    pub rms_z: f64,
    pub max_abs_x: f64,
    pub max_abs_z: f64,
    pub mean_z: f64,
    /// RMS of the CoM's lateral error y - yr, m.
    pub rms_y: f64,
    /// Largest spring deflection |theta - q| of a compliant joint, rad, and which.
    pub max_deflection: f64,
    pub max_deflection_joint: String,
    /// Largest horizontal motion of a stance sole since it touched down, m.
    pub max_foot_slip: f64,
    /// Largest horizontal distance of a landed sole from its planned footprint, m.
    pub max_landing_error: f64,
    /// Largest pelvis tilt from upright, rad.
    pub max_trunk_tilt: f64,
    /// Smallest signed distance of the CoM's ground projection from the edge of the
    /// support polygon (the convex hull of the soles of the feet meant to be down, at
    /// their actual placement), m: positive inside.
    pub min_com_support_margin: f64,
    /// The same for the reference CoM over the planned soles (the gait's own margin).
    pub min_reference_support_margin: f64,
    /// Smallest CoM height over the run, m.
    pub min_com_height: f64,
    /// Largest IK task error and IK iterations in total (planning pass), and the largest
    /// task error of the online IK (feet on their touchdown places, balance feedback).
    pub ik_max_error: f64,
    pub online_ik_max_error: f64,
    pub ik_iterations: usize,
}

/// The outcome of a run: the rows and the summary.
#[derive(Debug, Clone)]
pub struct WalkingDataset {
    pub rows: Vec<DatasetRow>,
    pub summary: WalkingSummary,
}

/// Bound on the pelvis tilt beyond which the robot counts as fallen, rad.
pub const FALL_TILT: f64 = 0.5;

/// COMAN set up to walk: the simulator, the references and the joint references.
pub struct ComanWalker {
    pub config: WalkingConfig,
    pub sim: Simulator,
    pub reference: WalkingReference,
    /// Joint position references (all joints, model order) per 1 ms sample.
    pub joint_references: Vec<Vec<f64>>,
    /// Indices of the compliant joints (model order).
    pub compliant: Vec<usize>,
    /// The bottom contact points of each sole (left, right), sole frame: the corners of
    /// the support polygon.
    pub sole_points: [Vec<Vector3<f64>>; 2],
    /// Gravity feed-forward of the compliant joints' motors per sample (sample-major,
    /// compliant joints in model order), rad; empty without feed-forward.
    pub feedforward: Vec<f64>,
    legs: [SupportLeg; 2],
    ik: WholeBodyIk,
    /// The IK's full configuration at t = 0 (the online IK's warm start).
    q_first: Vec<f64>,
    ik_max_error: f64,
    ik_iterations: usize,
}

fn sim_err(e: twinloop_sim::SimError) -> ExperimentError {
    ExperimentError(e.to_string())
}

impl ComanWalker {
    /// Builds the robot, the plan and every joint reference (the IK pass). Errors name a
    /// bad field, a missing COMAN joint or frame, or the time at which a step is out of
    /// the legs' reach.
    pub fn new(
        robot: &Description,
        config: &WalkingConfig,
    ) -> Result<ComanWalker, ExperimentError> {
        config.validate()?;
        let compliance = config.joint_compliance();
        let mass: f64 = robot
            .links
            .iter()
            .filter_map(|l| l.inertial.as_ref().map(|i| i.mass))
            .sum();
        let sim_config = SimConfig {
            dt: SAMPLE_TIME / config.substeps as f64,
            contact: Some(ContactParams::for_robot(mass, 8, config.contact_sink)),
            ..SimConfig::default()
        };
        let mut sim = Simulator::new(robot, sim_config).map_err(sim_err)?;
        let model = sim.model.clone();
        let legs = [SupportLeg::coman(true), SupportLeg::coman(false)];
        let mut ik = WholeBodyIk::new(
            &model,
            [&legs[0].joints, &legs[1].joints],
            [&legs[0].foot_frame, &legs[1].foot_frame],
        )?;
        let mut data = Data::new(&model);
        // Initial crouch: the stance geometry and Zc come from it.
        let mut q = twinloop_reduced::coman_crouch(&model, config.knee_bend)?;
        twinloop_dynamics::frames_forward_kinematics(&model, &mut data, &q);
        let soles = ik.sole_frames();
        let ps: Vec<Se3> = soles
            .iter()
            .map(|&f| WholeBodyIk::frame_placement(&model, &data, f))
            .collect();
        let step_width = (ps[0].translation.y - ps[1].translation.y).abs();
        let com0 = center_of_mass(&model, &mut data, &q);
        let ground = ps[0].translation.z.min(ps[1].translation.z);
        let com_height = com0.z - ground;
        // Foot centre: the middle of the lowest contact points of the foot's body, in
        // the sole frame.
        let (sole_offset, left_sole_points) = foot_centre_offset(&sim, &model, &data, soles[0])?;
        let (_, right_sole_points) = foot_centre_offset(&sim, &model, &data, soles[1])?;
        let sole_points = [left_sole_points, right_sole_points];
        let plan = config.plan(step_width, com_height)?;
        let zmp = ZmpReference::new(&plan)?;
        let reference = WalkingReference {
            zmp,
            sole_offset: [-sole_offset[0], -sole_offset[1]],
            swing_height: config.swing_height,
        };
        let compliant_joints = compliant_joint_indices(&model, &compliance);
        let pass = JointReferencePass::run(
            &model,
            &mut data,
            &mut ik,
            &reference,
            config,
            &compliant_joints,
            &mut q,
        )?;
        let (actuators, compliant) = joint_actuators(robot, &model, config)?;
        sim.actuators = actuators;
        // On the ground where the plan has the feet: the IK's first pose has the soles at
        // z = 0, where the bottoms of the foot boxes are.
        let qo = model.q_offset;
        sim.place_on_ground(&pass.joint_references[0])
            .map_err(sim_err)?;
        sim.q[..qo].copy_from_slice(&pass.q_first[..qo]);
        Ok(ComanWalker {
            config: config.clone(),
            sim,
            reference,
            joint_references: pass.joint_references,
            compliant,
            sole_points,
            feedforward: pass.feedforward,
            legs,
            ik,
            q_first: pass.q_first,
            ik_max_error: pass.ik_max_error,
            ik_iterations: pass.ik_iterations,
        })
    }

    /// Settle, then walk and record every 1 ms. `progress(i, n)` is called every 100
    /// samples. Errors if the simulation diverges.
    pub fn run(
        &mut self,
        mut progress: impl FnMut(usize, usize),
    ) -> Result<WalkingDataset, ExperimentError> {
        let n = self.joint_references.len();
        // Settle first, under the same controller holding the first sample's references,
        // so the recording starts at rest (the fit starts its model from the first row).
        let settle = (self.config.settle / SAMPLE_TIME).round() as usize;
        self.sim.goals.copy_from_slice(&self.joint_references[0]);
        let model = self.sim.model.clone();
        let mut data = Data::new(&model);
        let soles = [
            model.frame_index(&self.legs[0].foot_frame).unwrap_or(0),
            model.frame_index(&self.legs[1].foot_frame).unwrap_or(0),
        ];
        let mut rows = Vec::with_capacity(n);
        let mut s = Stats {
            min_z: f64::INFINITY,
            min_support: f64::INFINITY,
            min_support_ref: f64::INFINITY,
            ..Stats::default()
        };
        let mut q_cmd = self.q_first.clone();
        // Online, the IK is part of the controller: best effort near a stretched knee.
        self.ik.best_effort = true;
        self.ik.damping = 1e-4;
        self.ik.max_iterations = 10;
        let mut online_ik_error: f64 = 0.0;
        let mut correction = [0.0; 2];
        let mut anchors = FootAnchors::default();
        let mut polygon = [[0.0f64; 2]; MAX_SUPPORT_POINTS];
        let mut ik_data = Data::new(&model);
        for step in 0..settle + n {
            let recording = step >= settle;
            let i = step.saturating_sub(settle);
            let r = self.reference.at(i as f64 / SAMPLE_RATE);
            // Record the state at the sample time, then command and step.
            let (com, vel) = com_state(&model, &mut data, &self.sim.q, &self.sim.v);
            twinloop_dynamics::frames_forward_kinematics(&model, &mut data, &self.sim.q);
            if recording {
                rows.push(DatasetRow {
                    t: r.t,
                    xr: r.com[0],
                    zr: r.com[2],
                    x: com.x,
                    z: com.z,
                    phase: r.phase.code(),
                });
                s.add(com, &r);
            }
            anchors.update(&model, &data, soles, &r, recording.then_some(&mut s));
            let rb = data.base_placement.rotation;
            let tilt = rb[(2, 2)].clamp(-1.0, 1.0).acos();
            if recording {
                s.max_tilt = s.max_tilt.max(tilt);
                self.record_support_margins(&model, &data, soles, &r, com, &mut polygon, &mut s);
                self.record_deflection(&mut s);
            }
            if tilt > FALL_TILT || com.z < 0.5 * r.com[2] {
                return err(format!(
                    "the robot fell at t = {:.3} s (pelvis tilt {:.2} rad, CoM height {:.3} m)",
                    r.t, tilt, com.z
                ));
            }
            let mut targets = targets_of(&r);
            anchors.place(&r, &mut targets);
            self.balance(&r, com, vel, &mut correction, &mut targets);
            let rep = self
                .ik
                .solve(&model, &mut ik_data, &mut q_cmd, &targets)
                .map_err(|e| ExperimentError(format!("at t = {:.3} s: {e}", r.t)))?;
            online_ik_error = online_ik_error.max(rep.error);
            self.command(&q_cmd, i);
            for _ in 0..self.config.substeps {
                self.sim.step().map_err(sim_err)?;
            }
            if recording && i % 100 == 0 {
                progress(i, n);
            }
        }
        progress(n, n);
        let summary = self.summary(&model, &s, n, online_ik_error);
        Ok(WalkingDataset { rows, summary })
    }

    /// Support polygons of the feet meant to be down, into the statistics: the CoM over
    /// the soles where they are, and the reference CoM over the planned soles.
    #[allow(clippy::too_many_arguments)]
    fn record_support_margins(
        &self,
        model: &Model,
        data: &Data,
        soles: [usize; 2],
        r: &WalkingSample,
        com: Vector3<f64>,
        polygon: &mut [[f64; 2]; MAX_SUPPORT_POINTS],
        s: &mut Stats,
    ) {
        let mut n_pts = 0;
        for (f, &frame) in soles.iter().enumerate() {
            if r.stance[f] {
                let m = WholeBodyIk::frame_placement(model, data, frame);
                for p in &self.sole_points[f] {
                    if n_pts < MAX_SUPPORT_POINTS {
                        let w = m.act_point(p);
                        polygon[n_pts] = [w.x, w.y];
                        n_pts += 1;
                    }
                }
            }
        }
        if let Some(m) = support_margin(&mut polygon[..n_pts], [com.x, com.y]) {
            s.min_support = s.min_support.min(m);
        }
        // The same for the reference CoM over the planned soles: the LIPM gait itself
        // puts its CoM at the stance foot's inner edge when single support begins.
        let mut n_pts = 0;
        for f in 0..2 {
            if r.stance[f] {
                for p in &self.sole_points[f] {
                    if n_pts < MAX_SUPPORT_POINTS {
                        polygon[n_pts] = [r.soles[f][0] + p.x, r.soles[f][1] + p.y];
                        n_pts += 1;
                    }
                }
            }
        }
        if let Some(m) = support_margin(&mut polygon[..n_pts], [r.com[0], r.com[1]]) {
            s.min_support_ref = s.min_support_ref.min(m);
        }
    }

    /// The largest spring deflection of a compliant joint so far, into the statistics.
    fn record_deflection(&self, s: &mut Stats) {
        let qo = self.sim.model.q_offset;
        for &k in &self.compliant {
            if let Actuator::SeriesElastic(a) = &self.sim.actuators[k] {
                let d = (a.theta - self.sim.q[qo + k]).abs();
                if d > s.max_deflection {
                    s.max_deflection = d;
                    s.max_deflection_joint = k;
                }
            }
        }
    }

    /// Balance feedback on the CoM target, gains [x, y], low-pass filtered (see
    /// [`WalkingConfig::balance_kp`]).
    fn balance(
        &self,
        r: &WalkingSample,
        com: Vector3<f64>,
        vel: Vector3<f64>,
        correction: &mut [f64; 2],
        targets: &mut IkTargets,
    ) {
        let alpha = SAMPLE_TIME / (SAMPLE_TIME + self.config.balance_filter);
        for axis in 0..2 {
            let u = self.config.balance_kp[axis] * (r.com[axis] - com[axis])
                + self.config.balance_kd[axis] * (r.com_vel[axis] - vel[axis]);
            correction[axis] += alpha * (u - correction[axis]);
            targets.com[axis] += correction[axis];
        }
    }

    /// The joint goals of sample `i`: the IK's joints plus the compliant joints' gravity
    /// feed-forward.
    fn command(&mut self, q_cmd: &[f64], i: usize) {
        let qo = self.sim.model.q_offset;
        self.sim.goals.copy_from_slice(&q_cmd[qo..]);
        if !self.feedforward.is_empty() {
            let nc = self.compliant.len();
            for (c, &k) in self.compliant.iter().enumerate() {
                self.sim.goals[k] += self.feedforward[i * nc + c];
            }
        }
    }

    fn summary(&self, model: &Model, s: &Stats, n: usize, online_ik_error: f64) -> WalkingSummary {
        let plan = self.reference.zmp.plan();
        let nf = n.max(1) as f64;
        WalkingSummary {
            samples: n,
            steps: plan.steps,
            com_height: plan.com_height,
            step_width: plan.step_width,
            k_compliant: self.config.compliant_stiffness(),
            ankle_stability_ratio: self.config.ankle_stability_ratio(
                model.total_mass,
                twinloop_description::GRAVITY,
                plan.com_height,
            ),
            mass: model.total_mass,
            rms_x: (s.sx2 / nf).sqrt(),
            rms_z: (s.sz2 / nf).sqrt(),
            max_abs_x: s.max_x,
            max_abs_z: s.max_z,
            mean_z: s.sz / nf,
            rms_y: (s.sy2 / nf).sqrt(),
            max_deflection: s.max_deflection,
            max_deflection_joint: model.joint_names[s.max_deflection_joint].clone(),
            max_foot_slip: s.max_slip,
            max_landing_error: s.max_landing,
            max_trunk_tilt: s.max_tilt,
            min_com_support_margin: s.min_support,
            min_reference_support_margin: s.min_support_ref,
            min_com_height: s.min_z,
            ik_max_error: self.ik_max_error,
            online_ik_max_error: online_ik_error,
            ik_iterations: self.ik_iterations,
        }
    }
}

/// The CoM's position and velocity (`Jcom v`) at the simulated state.
fn com_state(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) -> (Vector3<f64>, Vector3<f64>) {
    let jc = jacobian_center_of_mass(model, data, q);
    let mut vel = Vector3::zeros();
    for (k, v) in v.iter().enumerate() {
        vel += Vector3::new(jc[(0, k)], jc[(1, k)], jc[(2, k)]) * *v;
    }
    (data.com, vel)
}

/// Where each foot is held: the sole's place when it touched down (slip is measured
/// from there) and where it lifted off (a swing starts there).
#[derive(Default)]
struct FootAnchors {
    down: [Option<[f64; 2]>; 2],
    lift_off: [Option<[f64; 2]>; 2],
}

impl FootAnchors {
    /// Anchors a stance sole where it is when it touches down, releases a swinging
    /// one; with `stats` (recording), the landing error against the plan and the slip
    /// since touchdown.
    fn update(
        &mut self,
        model: &Model,
        data: &Data,
        soles: [usize; 2],
        r: &WalkingSample,
        mut stats: Option<&mut Stats>,
    ) {
        for (f, &frame) in soles.iter().enumerate() {
            if r.stance[f] {
                let p = WholeBodyIk::frame_placement(model, data, frame).translation;
                match (self.down[f], stats.as_deref_mut()) {
                    (None, stats) => {
                        self.down[f] = Some([p.x, p.y]);
                        if let Some(s) = stats {
                            let e = (p.x - r.soles[f][0]).hypot(p.y - r.soles[f][1]);
                            s.max_landing = s.max_landing.max(e);
                        }
                    }
                    (Some(a), Some(s)) => {
                        s.max_slip = s.max_slip.max((p.x - a[0]).hypot(p.y - a[1]));
                    }
                    (Some(_), None) => {}
                }
            } else {
                if self.down[f].is_some() {
                    self.lift_off[f] = self.down[f];
                }
                self.down[f] = None;
            }
        }
    }

    /// Foot placement on the actual feet: stance soles stay where they touched down, a
    /// swing starts where the foot lifted off and ends on the planned footprint.
    /// Without this, each landing error (the compliant stance leg leans under the
    /// body's inertia) would carry the whole plan along.
    fn place(&self, r: &WalkingSample, targets: &mut IkTargets) {
        for f in 0..2 {
            let start = if r.stance[f] {
                self.down[f]
            } else {
                self.lift_off[f]
            };
            if let Some(a) = start {
                let b = if r.stance[f] { 0.0 } else { r.blend[f] };
                let end = if r.stance[f] { a } else { r.landing[f] };
                targets.soles[f].translation.x = a[0] + (end[0] - a[0]) * b;
                targets.soles[f].translation.y = a[1] + (end[1] - a[1]) * b;
            }
        }
    }
}

/// The joints (model order) whose names end in one of the compliance's compliant
/// joint names.
fn compliant_joint_indices(model: &Model, compliance: &JointCompliance) -> Vec<usize> {
    model
        .joint_names
        .iter()
        .enumerate()
        .filter(|(_, name)| {
            compliance
                .compliant
                .iter()
                .any(|c| name.ends_with(c.as_str()))
        })
        .map(|(k, _)| k)
        .collect()
}

/// The planning pass: the whole-body IK over every 1 ms sample of the plan before any
/// simulation, which finds an unreachable step first.
struct JointReferencePass {
    /// Joint position references (all joints, model order) per sample, the compliant
    /// joints' gravity feed-forward included.
    joint_references: Vec<Vec<f64>>,
    /// The feed-forward alone (sample-major, compliant joints in model order).
    feedforward: Vec<f64>,
    /// The IK's full configuration at t = 0.
    q_first: Vec<f64>,
    ik_max_error: f64,
    ik_iterations: usize,
}

impl JointReferencePass {
    /// Solves the IK at every sample from `q` (the crouch; left at the last sample),
    /// each warm-started from the previous one.
    fn run(
        model: &Model,
        data: &mut Data,
        ik: &mut WholeBodyIk,
        reference: &WalkingReference,
        config: &WalkingConfig,
        compliant_joints: &[usize],
        q: &mut [f64],
    ) -> Result<JointReferencePass, ExperimentError> {
        let n = (config.duration / SAMPLE_TIME).round() as usize;
        let mut pass = JointReferencePass {
            joint_references: Vec::with_capacity(n),
            feedforward: Vec::new(),
            q_first: q.to_vec(),
            ik_max_error: 0.0,
            ik_iterations: 0,
        };
        let qo = model.q_offset;
        let mut statics = StaticLoad::new(model, ik.sole_frames())?;
        let k_compliant = config.compliant_stiffness();
        for i in 0..n {
            let t = i as f64 / SAMPLE_RATE;
            let r = reference.at(t);
            let targets = targets_of(&r);
            let rep = ik.solve(model, data, q, &targets).map_err(|e| {
                ExperimentError(format!(
                    "at t = {t:.3} s (sl {} m, Tss {} s): {e}",
                    config.step_length, config.t_single
                ))
            })?;
            pass.ik_max_error = pass.ik_max_error.max(rep.error);
            pass.ik_iterations += rep.iterations;
            check_reachable(model, q, t)?;
            if i == 0 {
                pass.q_first.copy_from_slice(q);
            }
            let mut refs = q[qo..].to_vec();
            if config.gravity_feedforward {
                let share = left_load_share(&r, reference);
                let tau = statics.joint_torques(model, data, q, share)?;
                for &k in compliant_joints {
                    refs[k] += tau[k] / k_compliant;
                    pass.feedforward.push(tau[k] / k_compliant);
                }
            }
            pass.joint_references.push(refs);
        }
        Ok(pass)
    }
}

/// Errors if a joint of the IK's solution at `t` is beyond its limits: the step is out
/// of reach.
fn check_reachable(model: &Model, q: &[f64], t: f64) -> Result<(), ExperimentError> {
    for (k, name) in model.joint_names.iter().enumerate() {
        let v = q[model.q_offset + k];
        let (lo, hi) = (model.lower_limits[k], model.upper_limits[k]);
        if v < lo - 1e-9 || v > hi + 1e-9 {
            return err(format!(
                "at t = {t:.3} s the step is out of reach: joint {name} would need \
                 {v:.3} rad, beyond its limits [{lo:.3}, {hi:.3}]"
            ));
        }
    }
    Ok(())
}

#[derive(Default)]
struct Stats {
    sx2: f64,
    sz2: f64,
    sy2: f64,
    sz: f64,
    max_x: f64,
    max_z: f64,
    max_deflection: f64,
    max_deflection_joint: usize,
    max_slip: f64,
    max_landing: f64,
    max_tilt: f64,
    min_z: f64,
    min_support: f64,
    min_support_ref: f64,
}

impl Stats {
    fn add(&mut self, com: Vector3<f64>, r: &WalkingSample) {
        let (ex, ey, ez) = (com.x - r.com[0], com.y - r.com[1], com.z - r.com[2]);
        self.sx2 += ex * ex;
        self.sy2 += ey * ey;
        self.sz2 += ez * ez;
        self.sz += ez;
        self.max_x = self.max_x.max(ex.abs());
        self.max_z = self.max_z.max(ez.abs());
        self.min_z = self.min_z.min(com.z);
    }
}

fn targets_of(r: &WalkingSample) -> IkTargets {
    let sole = |p: [f64; 3]| Se3::new(Matrix3::identity(), Vector3::new(p[0], p[1], p[2]));
    IkTargets {
        soles: [sole(r.soles[0]), sole(r.soles[1])],
        com: Vector3::new(r.com[0], r.com[1], r.com[2]),
        pelvis: Matrix3::identity(),
    }
}

/// The joint actuators of the walking COMAN (model joint order) and the indices of the
/// compliant joints: knee and ankle pitch are [`SeriesElastic`] (seed 002, eq 1-6:
/// k_j = K_h K_s / (K_h + K_s), reflected motor inertia and damping of eq 5-6, motor
/// position loop stiff and critically damped), every other joint a [`TwoLoopServo`] of
/// stiffness K_h (the seed's k_j of a stiff joint). Torque limits: the URDF efforts.
pub fn joint_actuators(
    robot: &Description,
    model: &Model,
    config: &WalkingConfig,
) -> Result<(Vec<Actuator>, Vec<usize>), ExperimentError> {
    config.validate()?;
    let compliance = config.joint_compliance();
    let (i_m, d_m) = SeriesElastic::reflected(
        config.gear_ratio,
        config.rotor_inertia,
        config.rotor_damping,
        config.torque_constant,
        config.bemf_constant,
        config.winding_resistance,
    );
    let mut actuators = Vec::with_capacity(model.nbodies);
    let mut compliant = Vec::new();
    for (k, name) in model.joint_names.iter().enumerate() {
        let (kj, _) = compliance.joint(name)?;
        let effort = robot
            .joint(name)
            .and_then(|j| j.limit.as_ref().and_then(|l| l.effort))
            .filter(|e| e.is_finite() && *e > 0.0)
            .unwrap_or(50.0);
        let is_compliant = compliance
            .compliant
            .iter()
            .any(|c| name.ends_with(c.as_str()));
        actuators.push(if is_compliant {
            compliant.push(k);
            // Motor loop critically damped on the reflected rotor inertia (eq 5).
            let kd = (2.0 * (config.motor_kp * i_m).sqrt() - d_m).max(0.0);
            Actuator::SeriesElastic(SeriesElastic {
                stiffness: kj,
                spring_damping: config.spring_damping,
                motor_inertia: i_m,
                motor_damping: d_m,
                kp: config.motor_kp,
                kd,
                max_torque: effort,
                theta: 0.0,
                theta_dot: 0.0,
            })
        } else {
            Actuator::TwoLoop(TwoLoopServo {
                kp_position: kj / config.servo_kv,
                kv: config.servo_kv,
                max_speed: 20.0,
                max_torque: effort,
            })
        });
    }
    Ok((actuators, compliant))
}

/// Most contact points a support polygon is built from (the feet have 16).
const MAX_SUPPORT_POINTS: usize = 64;

/// Signed distance (m) of `p` from the edge of the convex hull of `pts` (ground
/// projections, reordered in place), positive inside; None for fewer than 3 points or a
/// degenerate hull. Andrew's monotone chain on a stack buffer: no allocation per sample.
fn support_margin(pts: &mut [[f64; 2]], p: [f64; 2]) -> Option<f64> {
    if pts.len() < 3 || pts.len() > MAX_SUPPORT_POINTS {
        return None;
    }
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull = [[0.0f64; 2]; 2 * MAX_SUPPORT_POINTS];
    let mut k = 0;
    for &q in pts.iter() {
        while k >= 2 && cross(hull[k - 2], hull[k - 1], q) <= 0.0 {
            k -= 1;
        }
        hull[k] = q;
        k += 1;
    }
    let lower = k + 1;
    for &q in pts.iter().rev().skip(1) {
        while k >= lower && cross(hull[k - 2], hull[k - 1], q) <= 0.0 {
            k -= 1;
        }
        hull[k] = q;
        k += 1;
    }
    let m = k - 1; // the last point repeats the first
    if m < 3 {
        return None;
    }
    let mut margin = f64::INFINITY;
    for i in 0..m {
        let (a, b) = (hull[i], hull[(i + 1) % m]);
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        let len = ex.hypot(ey);
        if len > 0.0 {
            // counter-clockwise: inside is to the left of each edge
            margin = margin.min((ex * (p[1] - a[1]) - ey * (p[0] - a[0])) / len);
        }
    }
    Some(margin)
}

/// Share of the weight on the left foot: 1 or 0 in single support; in double support
/// the ZMP reference's position along the segment from the right to the left foot centre.
fn left_load_share(r: &WalkingSample, reference: &WalkingReference) -> f64 {
    match r.phase {
        Phase::Single(twinloop_gait::Foot::Right) => 0.0,
        Phase::Single(twinloop_gait::Foot::Left) => 1.0,
        _ => {
            let z = reference.zmp.at(r.t).zmp;
            let c = |s: [f64; 3]| {
                [
                    s[0] - reference.sole_offset[0],
                    s[1] - reference.sole_offset[1],
                ]
            };
            let (l, rr) = (c(r.soles[0]), c(r.soles[1]));
            let d = [l[0] - rr[0], l[1] - rr[1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            if len2 < 1e-12 {
                return 0.5;
            }
            (((z[0] - rr[0]) * d[0] + (z[1] - rr[1]) * d[1]) / len2).clamp(0.0, 1.0)
        }
    }
}

/// Static joint torques with the weight on the feet: with the sole wrench F of one foot
/// balancing gravity on the floating base, `J_b^T F = g_b`, the joints carry
/// `tau = g_j - J_j^T F`; with both feet the torques blend linearly by the load share
/// (statics is linear in the wrench split, so the blend is balanced too).
struct StaticLoad {
    soles: [usize; 2],
    jf: nalgebra::DMatrix<f64>,
    g: Vec<f64>,
    tau: Vec<f64>,
}

impl StaticLoad {
    fn new(model: &Model, soles: [usize; 2]) -> Result<StaticLoad, ExperimentError> {
        Ok(StaticLoad {
            soles,
            jf: nalgebra::DMatrix::zeros(6, model.nv),
            g: vec![0.0; model.nv],
            tau: vec![0.0; model.nbodies],
        })
    }

    /// Joint torques (model joint order) at q with `left_share` of the weight on the left.
    fn joint_torques(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        left_share: f64,
    ) -> Result<&[f64], ExperimentError> {
        let g = &mut self.g;
        g.copy_from_slice(twinloop_dynamics::generalized_gravity(model, data, q).as_slice());
        twinloop_dynamics::compute_joint_jacobians(model, data, q);
        self.tau.iter_mut().for_each(|t| *t = 0.0);
        let off = model.v_offset;
        for (s, share) in [(0, left_share), (1, 1.0 - left_share)] {
            if share <= 0.0 {
                continue;
            }
            twinloop_dynamics::frame_jacobian(
                model,
                data,
                self.soles[s],
                twinloop_dynamics::ReferenceFrame::LocalWorldAligned,
                &mut self.jf,
            );
            let jb = nalgebra::Matrix6::from_fn(|r, c| self.jf[(r, c)]);
            let gb = nalgebra::Vector6::from_fn(|r, _| g[r]);
            let Some(f) = jb.transpose().lu().solve(&gb) else {
                return err("the foot Jacobian's base block is singular");
            };
            for k in 0..model.nbodies {
                let mut jtf = 0.0;
                for r in 0..6 {
                    jtf += self.jf[(r, off + k)] * f[r];
                }
                self.tau[k] += share * (g[off + k] - jtf);
            }
        }
        Ok(&self.tau)
    }
}

/// Foot centre relative to the sole frame (x, y in the sole frame): the middle of the
/// bottom contact points of the sole's body; and those points (sole frame).
fn foot_centre_offset(
    sim: &Simulator,
    model: &Model,
    data: &Data,
    sole: usize,
) -> Result<([f64; 2], Vec<Vector3<f64>>), ExperimentError> {
    let body = model.frames[sole].body;
    let m_sole = WholeBodyIk::frame_placement(model, data, sole);
    let m_body = data.o_m_i[body];
    let local: Vec<Vector3<f64>> = sim
        .contact_points()
        .iter()
        .filter(|p| p.body == body)
        .map(|p| m_sole.act_inv_point(&m_body.act_point(&p.local)) - Vector3::z() * p.radius)
        .collect();
    if local.is_empty() {
        return err("the foot has no collision primitives (contact points) to stand on");
    }
    let zmin = local.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let bottom: Vec<&Vector3<f64>> = local.iter().filter(|p| p.z < zmin + 1e-6).collect();
    let (mut x, mut y) = (0.0, 0.0);
    for p in &bottom {
        x += p.x;
        y += p.y;
    }
    let k = bottom.len() as f64;
    Ok(([x / k, y / k], bottom.into_iter().copied().collect()))
}

/// Writes the dataset as CSV with columns `t, xr, zr, x, z, phase` (phase an integer:
/// 0 single, 1 double support; numbers in shortest round-trip form).
pub fn write_csv(path: &std::path::Path, rows: &[DatasetRow]) -> Result<(), ExperimentError> {
    use std::fmt::Write as _;
    let mut text = String::from("t,xr,zr,x,z,phase\n");
    for r in rows {
        let _ = writeln!(
            text,
            "{:?},{:?},{:?},{:?},{:?},{}",
            r.t, r.xr, r.zr, r.x, r.z, r.phase
        );
    }
    // Beside the file, renamed when complete: a failure keeps the old file.
    twinloop_io::output::write_atomic(path, text).map_err(|e| ExperimentError(e.to_string()))
}
