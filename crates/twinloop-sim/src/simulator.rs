//! The simulator: state, configuration and the time step.

use crate::actuator::{Actuator, Drive};
use crate::contact::{ContactParams, ContactPoint, ContactState, contact_points};
use crate::ltdl;
use crate::sensors::{self, SensedState, SensorState};
use ltdl::TreeMatrix;
use nalgebra::{DMatrix, Vector3};
use std::fmt;
use twinloop_description::{Description, DescriptionError};
use twinloop_dynamics::configuration::integrate;
use twinloop_dynamics::{
    BASE, Data, JointType, Model, crba, crba_and_bias_from_kinematics, kinematics_pass,
};
use twinloop_robot::RobotState;
use twinloop_spatial::Se3;

/// Simulation settings. `Default` gives a 1 ms step, gravity 9.81, a ground plane,
/// contact parameters scaled to the robot's mass and stiff joint-limit springs.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Time step, s.
    pub dt: f64,
    /// Gravity acceleration (world), m/s^2.
    pub gravity: Vector3<f64>,
    /// Whether there is a ground plane at z = 0.
    pub ground: bool,
    /// Contact parameters; `None`: derived from the robot's mass (1 mm sink on 8 points).
    pub contact: Option<ContactParams>,
    /// Joint-limit spring and damper beyond a limit, N m/rad and N m s/rad; `None`:
    /// scaled to the robot (its weight times 1 m per radian).
    pub joint_limit_stiffness: Option<f64>,
    pub joint_limit_damping: Option<f64>,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            dt: 1e-3,
            gravity: Vector3::new(0.0, 0.0, -twinloop_description::GRAVITY),
            ground: true,
            contact: None,
            joint_limit_stiffness: None,
            joint_limit_damping: None,
        }
    }
}

/// Why a simulation could not go on.
#[derive(Debug, Clone, PartialEq)]
pub enum SimError {
    /// The description cannot be compiled.
    Model(DescriptionError),
    /// The state became non-finite or the step matrix lost positive definiteness.
    Diverged { time: f64, message: String },
    /// A name or size given by the caller does not fit the robot.
    Input(String),
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::Model(e) => write!(f, "{e}"),
            SimError::Diverged { time, message } => {
                write!(f, "the simulation diverged at t = {time} s: {message}")
            }
            SimError::Input(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for SimError {}

impl From<DescriptionError> for SimError {
    fn from(e: DescriptionError) -> Self {
        SimError::Model(e)
    }
}

/// Per-body sums of its contact points for one step.
#[derive(Debug, Clone, Default)]
struct ContactBody {
    active: bool,
    /// World twist of the body (spatial velocity at the world origin).
    twist: nalgebra::Vector6<f64>,
    /// Sum of A_p^T W_p A_p over its points.
    matrix: nalgebra::Matrix6<f64>,
    /// Sum of the points' step forces as a wrench about the world origin.
    wrench: nalgebra::Vector6<f64>,
}

/// World twist of a body from the world-frame joint Jacobians: the sum of
/// `J_dof v_dof` over its chain.
#[inline]
fn body_twist(jacobians: &DMatrix<f64>, chain: &[usize], v: &[f64]) -> nalgebra::Vector6<f64> {
    let mut tw = nalgebra::Vector6::zeros();
    for &dof in chain {
        let col = jacobians.column(dof);
        tw += nalgebra::Vector6::from_column_slice(col.as_slice()) * v[dof];
    }
    tw
}

/// Force on a point at `x`, `pen` below the ground and moving at `vp`: a normal
/// spring-damper, and a tangential spring to the anchor clipped to the friction cone
/// (the anchor then follows the point: sliding). Updates the anchor and the sliding
/// flag of `state` (whose `force` is still the last step's). Returns the force and the
/// tangential stiffness and damping the implicit step keeps, or `None` when the normal
/// force would pull.
///
/// A sliding point's force is explicit (Coulomb's, on the cone), except in a step in
/// which it turns against the last step's sliding force: the point has passed through
/// rest, and an explicit force would throw it back past rest again. That step keeps a
/// damping `s (d + k dt)`, the clipped force's own gain on the point's velocity (`s =
/// limit / |trial|`; the trial force gains `d + k dt` per unit of velocity over a
/// step), so the point settles towards rest within the step and sticks. Without it a
/// lightly loaded point whose friction impulse `mu f_n dt` exceeded the momentum it
/// had to stop reversed every step (period-2 chatter that grew with the load): on km20
/// leaning backward at 5 deg/s with a 0.14 kg part on an arm, the toes' chatter pumped
/// a hip yaw until the explicit bias forces blew the state up. Only at a reversal, so
/// steady and decelerating sliding keep the exact Coulomb force.
#[inline]
fn point_force(
    cp: &ContactParams,
    dt: f64,
    state: &mut ContactState,
    x: &Vector3<f64>,
    vp: &Vector3<f64>,
    pen: f64,
) -> Option<(Vector3<f64>, f64, f64)> {
    let fn_ = cp.stiffness * pen - cp.damping * vp.z;
    if fn_ <= 0.0 {
        return None;
    }
    if !state.active {
        state.anchor = [x.x, x.y];
        state.active = true;
    }
    let mut ft = [
        -cp.tangential_stiffness * (x.x - state.anchor[0]) - cp.tangential_damping * vp.x,
        -cp.tangential_stiffness * (x.y - state.anchor[1]) - cp.tangential_damping * vp.y,
    ];
    let norm = (ft[0] * ft[0] + ft[1] * ft[1]).sqrt();
    let limit = cp.friction * fn_;
    let (kt, dtan) = if norm > limit {
        // Sliding: the force sits on the cone, the anchor follows the point.
        let s = limit / norm;
        let reversed = state.sliding && state.force.x * ft[0] + state.force.y * ft[1] < 0.0;
        ft = [ft[0] * s, ft[1] * s];
        state.anchor = [
            x.x + ft[0] / cp.tangential_stiffness,
            x.y + ft[1] / cp.tangential_stiffness,
        ];
        state.sliding = true;
        let damping = if reversed {
            s * (cp.tangential_damping + cp.tangential_stiffness * dt)
        } else {
            0.0
        };
        (0.0, damping)
    } else {
        state.sliding = false;
        (cp.tangential_stiffness, cp.tangential_damping)
    };
    Some((Vector3::new(ft[0], ft[1], fn_), kt, dtan))
}

/// A point's share of its body's step terms, added to `acc`: the force `f` less the
/// part the implicit stiffness will add back, as a wrench about the world origin, and
/// `A_p^T W A_p` with `W` the implicit weights of its springs and dampers.
/// `(kt, dtan)` are the tangential stiffness and damping `point_force` kept.
#[inline]
fn add_implicit_point_terms(
    acc: &mut ContactBody,
    cp: &ContactParams,
    dt: f64,
    x: &Vector3<f64>,
    vp: &Vector3<f64>,
    f: &Vector3<f64>,
    (kt, dtan): (f64, f64),
) {
    let g = f - Vector3::new(dt * kt * vp.x, dt * kt * vp.y, dt * cp.stiffness * vp.z);
    let w = Vector3::new(
        dt * dtan + dt * dt * kt,
        dt * dtan + dt * dt * kt,
        dt * cp.damping + dt * dt * cp.stiffness,
    );
    let m = x.cross(&g);
    acc.wrench += nalgebra::Vector6::new(g.x, g.y, g.z, m.x, m.y, m.z);
    add_point_matrix(&mut acc.matrix, &w, x);
}

/// `mat += A^T diag(w) A` with `A = [I, -[x]x]`: the blocks `W`, `-W [x]x`, its
/// transpose and `-[x]x W [x]x`, with only their non-zero products formed (the
/// skew matrix's diagonal is zero; the sums keep the matrix products' order, so the
/// values are those of the dense 3x3 products).
#[inline]
fn add_point_matrix(mat: &mut nalgebra::Matrix6<f64>, w: &Vector3<f64>, x: &Vector3<f64>) {
    let sx = twinloop_spatial::skew(x);
    for i in 0..3 {
        mat[(i, i)] += w[i];
        for j in 0..3 {
            if i != j {
                let wsx = w[i] * sx[(i, j)];
                mat[(i, 3 + j)] += -wsx;
                mat[(3 + j, i)] += -wsx;
            }
        }
    }
    for i in 0..3 {
        for j in 0..3 {
            let mut sum = 0.0;
            for k in 0..3 {
                if k != i && k != j {
                    sum += sx[(i, k)] * (w[k] * sx[(k, j)]);
                }
            }
            mat[(3 + i, 3 + j)] += -sum;
        }
    }
}

/// A robot simulated over the reduced-coordinate dynamics.
pub struct Simulator {
    pub model: Model,
    pub(crate) data: Data,
    pub config: SimConfig,
    pub contact_params: ContactParams,
    pub joint_limit_stiffness: f64,
    pub joint_limit_damping: f64,
    /// Configuration and velocity (Pinocchio's conventions, see `twinloop_dynamics`).
    pub q: Vec<f64>,
    pub v: Vec<f64>,
    /// Simulated time, s.
    pub time: f64,
    /// One actuator per joint (model joint order).
    pub actuators: Vec<Actuator>,
    /// Per joint: the position goal (servos) or the torque (torque actuators).
    pub goals: Vec<f64>,
    /// Viscous damping and Coulomb friction per joint from the description.
    pub joint_damping: Vec<f64>,
    pub joint_friction: Vec<f64>,
    /// The description's joint springs (MJCF `stiffness` about `springref`), per joint.
    pub joint_stiffness: Vec<f64>,
    pub joint_springref: Vec<f64>,
    /// The floating base's viscous damping (MJCF free joint `damping`): `-c v` on the
    /// six base velocities, MuJoCo's `qfrc_passive` (the same in its world-linear
    /// coordinates, the base frame being a rotation of them). 0 for a fixed base.
    pub base_damping: f64,
    friction_anchor: Vec<f64>,
    /// Per joint: the motor side of a servo with a backlash.
    pub gears: Vec<crate::backlash::Gear>,
    /// Per joint: the state of a servo with the full model of a parameter file.
    pub servo_states: Vec<crate::servo_model::ServoState>,
    /// Torque each actuator applied in the last step.
    pub applied: Vec<f64>,
    pub(crate) points: Vec<ContactPoint>,
    pub(crate) contacts: Vec<ContactState>,
    /// Links with mesh collisions only (no contact points).
    pub mesh_only_links: Vec<String>,
    /// Per body (index nbodies = the base): its DOFs and all ancestors', deepest first.
    chains: Vec<Vec<usize>>,
    /// The step matrix, then its factors (the tree's entries only).
    h: TreeMatrix,
    rhs: Vec<f64>,
    q_next: Vec<f64>,
    contact_bodies: Vec<ContactBody>,
    js: Vec<nalgebra::Vector6<f64>>,
    su: Vec<nalgebra::Vector6<f64>>,
    pub(crate) sensors: SensorState,
}

impl Simulator {
    /// A simulator of `robot` with a floating base, every joint passive, standing at the
    /// neutral configuration (call [`Simulator::place_on_ground`] to put it on the floor).
    pub fn new(robot: &Description, config: SimConfig) -> Result<Simulator, SimError> {
        let model = Model::from_description(robot)?;
        Simulator::from_model(robot, model, config)
    }

    /// As [`Simulator::new`] with a model compiled by the caller (e.g. a fixed base).
    pub fn from_model(
        robot: &Description,
        mut model: Model,
        config: SimConfig,
    ) -> Result<Simulator, SimError> {
        if !(config.dt > 0.0 && config.dt.is_finite()) {
            return Err(SimError::Input(format!(
                "the time step must be positive, not {}",
                config.dt
            )));
        }
        model.gravity = config.gravity;
        let data = Data::new(&model);
        let (points, mesh_only_links) = contact_points(robot, &model);
        let contact_params = config
            .contact
            .unwrap_or_else(|| ContactParams::for_robot(model.total_mass, 8, 1e-3));
        let nb = model.nbodies;
        let (dof_parent, chains) = dof_tree(&model);
        let max_chain = chains.iter().map(Vec::len).max().unwrap_or(0);
        let [
            joint_damping,
            joint_friction,
            joint_stiffness,
            joint_springref,
        ] = joint_passives(robot, &model);
        let weight = model.total_mass * config.gravity.norm();
        let limit_k = config
            .joint_limit_stiffness
            .unwrap_or(weight.max(1.0) * 1.0);
        let limit_d = config.joint_limit_damping.unwrap_or(0.1 * limit_k.sqrt());
        let q = model.neutral_configuration();
        let sensors = SensorState::new(&model, robot);
        Ok(Simulator {
            data,
            contact_params,
            joint_limit_stiffness: limit_k,
            joint_limit_damping: limit_d,
            v: vec![0.0; model.nv],
            q_next: q.clone(),
            q,
            time: 0.0,
            actuators: vec![Actuator::Passive; nb],
            goals: vec![0.0; nb],
            joint_damping,
            joint_friction,
            joint_stiffness,
            joint_springref,
            base_damping: if model.is_floating() {
                robot.base_damping.max(0.0)
            } else {
                0.0
            },
            friction_anchor: vec![0.0; nb],
            gears: vec![Default::default(); nb],
            servo_states: vec![Default::default(); nb],
            applied: vec![0.0; nb],
            contacts: vec![ContactState::default(); points.len()],
            points,
            mesh_only_links,
            chains,
            h: TreeMatrix::new(&dof_parent),
            rhs: vec![0.0; model.nv],
            contact_bodies: vec![ContactBody::default(); nb + 1],
            js: vec![nalgebra::Vector6::zeros(); max_chain],
            su: vec![nalgebra::Vector6::zeros(); max_chain],
            sensors,
            model,
            config,
        })
    }

    /// Index of a joint by name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.model.joint_index(name)
    }

    pub fn dt(&self) -> f64 {
        self.config.dt
    }

    /// Contact points (for inspection and tests).
    pub fn contact_points(&self) -> &[ContactPoint] {
        &self.points
    }

    pub fn contact_states(&self) -> &[ContactState] {
        &self.contacts
    }

    /// Set every joint's actuator.
    pub fn set_all_actuators(&mut self, a: Actuator) {
        self.actuators.iter_mut().for_each(|x| *x = a);
    }

    /// Set joint positions (the joint part of q in model order: one per joint, four
    /// (x, y, z, w) per ball joint, normalised here), keep the base where it is, zero
    /// velocities.
    pub fn set_joint_positions(&mut self, joints: &[f64]) -> Result<(), SimError> {
        let o = self.model.q_offset;
        if joints.len() != self.model.nq - o {
            return Err(SimError::Input(format!(
                "{} joint positions given, the robot has {} joints ({} coordinates)",
                joints.len(),
                self.model.nbodies,
                self.model.nq - o
            )));
        }
        self.q[o..].copy_from_slice(joints);
        twinloop_dynamics::configuration::normalize(&self.model, &mut self.q);
        for i in 0..self.model.nbodies {
            self.friction_anchor[i] = self.q[self.model.idx_q[i]];
        }
        self.v.iter_mut().for_each(|x| *x = 0.0);
        for (i, a) in self.actuators.iter_mut().enumerate() {
            if let Actuator::SeriesElastic(s) = a {
                s.theta = self.q[self.model.idx_q[i]];
                s.theta_dot = 0.0;
            }
            self.gears[i] = Default::default();
            self.servo_states[i].reset();
        }
        self.contacts
            .iter_mut()
            .for_each(|c| *c = ContactState::default());
        Ok(())
    }

    /// Put the robot upright on the ground: joints at `joints`, base orientation
    /// identity, the lowest contact point just touching z = 0, all at rest. Servo
    /// goals are set to the joint positions so it holds the pose.
    pub fn place_on_ground(&mut self, joints: &[f64]) -> Result<(), SimError> {
        self.set_joint_positions(joints)?;
        if self.model.is_floating() {
            self.q[0..3].copy_from_slice(&[0.0, 0.0, 0.0]);
            self.q[3..7].copy_from_slice(&[0.0, 0.0, 0.0, 1.0]);
            twinloop_dynamics::forward_kinematics(&self.model, &mut self.data, &self.q);
            let mut lowest = f64::INFINITY;
            for p in &self.points {
                lowest = lowest.min(self.body_placement(p.body).act_point(&p.local).z - p.radius);
            }
            if lowest.is_finite() {
                self.q[2] = -lowest;
            }
        }
        for (i, a) in self.actuators.iter().enumerate() {
            if !matches!(a, Actuator::Torque | Actuator::Passive) {
                self.goals[i] = self.q[self.model.idx_q[i]];
            }
        }
        self.sensors.reset();
        Ok(())
    }

    /// World placement of a body after the last kinematics pass.
    pub(crate) fn body_placement(&self, body: usize) -> Se3 {
        if body == BASE {
            self.data.base_placement
        } else {
            self.data.o_m_i[body]
        }
    }

    fn joint_drive(&mut self, i: usize) -> Drive {
        let dof = self.model.idx_v[i];
        let (q, v) = (self.q[self.model.idx_q[i]], self.v[dof]);
        let dt = self.config.dt;
        let mut d = match &self.actuators[i] {
            Actuator::Passive => Drive::default(),
            Actuator::Torque => Drive {
                tau: self.goals[i],
                k: 0.0,
                d: 0.0,
            },
            Actuator::Dynamixel(s) if s.full.is_some() => {
                let s = *s;
                self.full_servo_drive(i, &s, q, v)
            }
            Actuator::Dynamixel(s) if s.backlash > 0.0 => {
                let g = &mut self.gears[i];
                g.sync(s, q, v);
                let m = s.drive(self.goals[i], q, v);
                crate::backlash::output_drive(s, m, g, q, v, dt)
            }
            Actuator::Dynamixel(s) => s.drive(self.goals[i], q, v),
            Actuator::TwoLoop(s) => s.drive(self.goals[i], q, v),
            Actuator::SeriesElastic(s) => s.drive(q, v),
        };
        self.applied[i] = d.tau;
        // Description damping (viscous) and dry friction. Dry friction is a stick spring
        // to an anchor angle, capped at the friction torque (the anchor follows when it
        // slips), like the contacts' tangential model: a joint under a load below its
        // friction holds still instead of creeping, which velocity-smoothed Coulomb
        // friction cannot do.
        d.tau += self.passive_torque(i, q, v);
        d.d += self.joint_damping[i];
        d.k += self.joint_stiffness[i];
        let fr = self.joint_friction[i] + self.engaged_gear(i).1 + self.full_servo_friction(i, v);
        if fr > 0.0 {
            // Full friction torque at 0.1 mrad of deflection; damping for a crisp stick.
            let kf = fr / 1e-4;
            let df = 2.0 * fr / 1e-2;
            let anchor = &mut self.friction_anchor[i];
            let mut t = -kf * (q - *anchor) - df * v;
            if t.abs() > fr {
                t = fr * t.signum();
                *anchor = q + t / kf;
            } else {
                d.k += kf;
                d.d += df;
            }
            d.tau += t;
        }
        // Joint limits: a stiff spring-damper beyond the range.
        let (lo, hi) = (self.model.lower_limits[i], self.model.upper_limits[i]);
        let over = if q < lo {
            q - lo
        } else if q > hi {
            q - hi
        } else {
            0.0
        };
        if over != 0.0 {
            d.tau -= self.joint_limit_stiffness * over + self.joint_limit_damping * v;
            d.k += self.joint_limit_stiffness;
            d.d += self.joint_limit_damping;
        }
        d
    }

    /// The description's spring and viscous damping on 1-DoF joint `i` at position `q`
    /// and velocity `v`: `-stiffness (q - springref) - damping v`, MuJoCo's
    /// `qfrc_passive` for a hinge or slide (its dry `frictionloss` is a constraint there,
    /// the stick spring of `joint_drive` here).
    pub fn passive_torque(&self, i: usize, q: f64, v: f64) -> f64 {
        -self.joint_stiffness[i] * (q - self.joint_springref[i]) - self.joint_damping[i] * v
    }

    /// The inertia and Coulomb friction of joint `i`'s motor side where it moves with
    /// the joint (a servo with a backlash, gap closed and pushed), else zeros.
    fn engaged_gear(&self, i: usize) -> (f64, f64) {
        match &self.actuators[i] {
            Actuator::Dynamixel(s) if s.backlash > 0.0 && self.gears[i].engaged != 0.0 => {
                // A full model's gearbox friction is its budget (full_servo_friction).
                let coulomb = if s.full.is_some() {
                    0.0
                } else {
                    s.gear_friction
                };
                (s.motor_inertia, coulomb)
            }
            _ => (0.0, 0.0),
        }
    }

    /// Joint `i`'s angle as its servo senses it: for a full-model servo with a
    /// sensing delay the angle that long ago (what its Present Position reads),
    /// else the angle now, rad.
    pub fn sensed_joint_angle(&self, i: usize) -> f64 {
        let q = self.q[self.model.idx_q[i]];
        match &self.actuators[i] {
            Actuator::Dynamixel(s) => match s.full {
                Some(full) => self.servo_states[i].sensed(&full, self.time, q),
                None => q,
            },
            _ => q,
        }
    }

    /// Joint `i`'s full-model servo ([`crate::servo_model`]) at `q`, `v`: the
    /// firmware's cycle on the sensed counts, the motor's torque at the joint's
    /// speed (explicit in the duty, implicit in the back-EMF); behind a backlash, on
    /// the motor side.
    fn full_servo_drive(&mut self, i: usize, s: &crate::DynamixelServo, q: f64, v: f64) -> Drive {
        let Some(full) = s.full else {
            return Drive::default();
        };
        let dt = self.config.dt;
        let st = &mut self.servo_states[i];
        let duty = st.cycle(s, &full, self.goals[i], self.time, q, dt);
        let m = Drive {
            tau: full.torque(duty, v),
            k: 0.0,
            d: full.emf_damping(),
        };
        if s.backlash > 0.0 {
            let g = &mut self.gears[i];
            g.sync(s, q, v);
            st.motor_torque = full.torque(duty, g.vm);
            // The viscous friction is on the motor side: with the joint while engaged.
            let m = full.motor_side_drive(duty, v);
            crate::backlash::output_drive(s, m, g, q, v, dt)
        } else {
            st.motor_torque = m.tau;
            m
        }
    }

    /// The Coulomb budget of joint `i`'s full-model gearbox where it acts on the
    /// joint (no backlash, or the gap closed and pushed), at joint speed `v`
    /// (BAM's budget: base, Stribeck and load-dependent), else 0.
    fn full_servo_friction(&self, i: usize, v: f64) -> f64 {
        match &self.actuators[i] {
            Actuator::Dynamixel(s) if s.backlash <= 0.0 || self.gears[i].engaged != 0.0 => s
                .full
                .map_or(0.0, |f| f.friction(v, self.servo_states[i].motor_torque)),
            _ => 0.0,
        }
    }

    /// The gap of joint `i`'s backlash closed with its motor side arriving at `vm`:
    /// an inelastic impact, momentum kept, between the motor side (the armature) and
    /// the joint, whose effective inertia `1 / (H^-1)_ii` and response to the
    /// impulse `H^-1 e_i` come from the step matrix `H` still factorised (so the
    /// rest of the robot takes its share of the blow). Both sides leave at the
    /// common speed.
    fn gear_impact(&mut self, i: usize, vm: f64) {
        let jm = match &self.actuators[i] {
            Actuator::Dynamixel(s) => s.motor_inertia,
            _ => 0.0,
        };
        let iv = self.model.idx_v[i];
        self.rhs.iter_mut().for_each(|x| *x = 0.0);
        self.rhs[iv] = 1.0;
        self.h.solve(&mut self.rhs);
        let x = self.rhs[iv];
        let v = self.v[iv];
        if !(x > 0.0 && x.is_finite()) || jm <= 0.0 {
            self.gears[i].vm = v;
            return;
        }
        let jj = 1.0 / x;
        let common = (jm * vm + jj * v) / (jm + jj);
        let p = jj * (common - v);
        for (vk, xk) in self.v.iter_mut().zip(self.rhs.iter()) {
            *vk += p * xk;
        }
        self.gears[i].vm = self.v[iv];
    }

    /// Why the step matrix has no factor at velocity coordinate `k`: named by its
    /// joint, and when the mass matrix itself is singular there, said so.
    fn singular_step_message(&mut self, k: usize) -> String {
        let at = if k < self.model.v_offset {
            "the floating base".to_string()
        } else {
            let (i, _) = self.model.velocity_owner(k - self.model.v_offset);
            format!("joint \"{}\"", self.model.joint_names[i])
        };
        let why = match twinloop_dynamics::check_mass_matrix(&self.model, &mut self.data, &self.q) {
            Err(e) => format!(": {e}"),
            Ok(()) => String::new(),
        };
        format!("the step matrix is not positive definite at {at} (velocity coordinate {k}){why}")
    }

    /// A ball joint is passive: only the description's viscous damping acts on its
    /// three angular velocities (implicitly, like a 1-DoF joint's).
    fn damp_ball(&mut self, i: usize, dt: f64) {
        let c = self.joint_damping[i];
        self.applied[i] = 0.0;
        for dof in self.model.idx_v[i]..self.model.idx_v[i] + 3 {
            self.rhs[dof] -= c * self.v[dof];
            self.h.row_mut(dof)[0] += dt * c;
        }
    }

    /// Advance one time step.
    ///
    /// Linearly implicit Euler: with M the mass matrix (CRBA), b = C v + g (RNEA), and
    /// every spring-damper (servos, joint limits, contacts) linearised as stiffness K and
    /// damping D in joint space,
    /// `(M + dt D + dt^2 K) dv = dt (tau + J^T f - b - dt K v)`, then `v += dv`,
    /// `q = q (+) v dt`. Without springs this is semi-implicit Euler on ABA's
    /// accelerations; with them it stays stable for stiffness that an explicit step would
    /// need a far smaller dt for (MuJoCo's "implicitfast" idea, here including the
    /// contact springs). The matrix keeps the tree's sparsity, so it is factorised in
    /// O(n d^2) (`ltdl`).
    pub fn step(&mut self) -> Result<(), SimError> {
        let dt = self.config.dt;
        let nv = self.model.nv;
        // One kinematics pass (world placements and Jacobians for the contacts and
        // the IMU, base-frame ones for the dynamics), then the mass matrix and the
        // bias forces on it in one sweep (RNEA in base coordinates on CRBA's inertias).
        kinematics_pass(&self.model, &mut self.data, &self.q);
        self.sensors.observe(&self.model, &self.data, &self.v);
        let (m, nle) = crba_and_bias_from_kinematics(&self.model, &mut self.data, &self.v);
        // Its upper triangle, as crba fills it.
        self.h.set_from_upper(m);
        for i in 0..nv {
            self.rhs[i] = -nle[i];
        }
        // Joint actuators, damping, limits.
        for i in 0..self.model.nbodies {
            if self.model.joint_types[i] == JointType::Spherical {
                self.damp_ball(i, dt);
                continue;
            }
            let d = self.joint_drive(i);
            let dof = self.model.idx_v[i];
            self.rhs[dof] += d.tau - dt * d.k * self.v[dof];
            // The armature is already on the diagonal: crba adds it; an engaged
            // motor side behind a backlash joins it.
            self.h.row_mut(dof)[0] += dt * d.d + dt * dt * d.k + self.engaged_gear(i).0;
        }
        // The base's damping, implicit like a joint's (the armature is in crba's M).
        if self.model.is_floating() {
            for dof in 0..6 {
                self.rhs[dof] -= self.base_damping * self.v[dof];
                self.h.row_mut(dof)[0] += dt * self.base_damping;
            }
        }
        if self.config.ground {
            self.add_contacts(dt);
        }
        // Solve for the velocity change.
        if let Err(k) = self.h.factor() {
            return Err(SimError::Diverged {
                time: self.time,
                message: self.singular_step_message(k),
            });
        }
        for x in self.rhs.iter_mut() {
            *x *= dt;
        }
        self.h.solve(&mut self.rhs);
        for i in 0..nv {
            self.v[i] += self.rhs[i];
        }
        integrate(&self.model, &self.q, &self.v, dt, &mut self.q_next);
        std::mem::swap(&mut self.q, &mut self.q_next);
        // Series-elastic motors and the motor sides of servos with a backlash follow
        // their goals with the link at its new state.
        for i in 0..self.model.nbodies {
            let (iq, iv) = (self.model.idx_q[i], self.model.idx_v[i]);
            let closed = match &mut self.actuators[i] {
                Actuator::SeriesElastic(s) => {
                    s.advance_motor(self.goals[i], self.q[iq], self.v[iv], dt);
                    None
                }
                Actuator::Dynamixel(s) if s.backlash > 0.0 => {
                    let (goal, q) = (self.goals[i], self.q[iq]);
                    let g = &mut self.gears[i];
                    match s.full {
                        Some(full) => {
                            let duty = self.servo_states[i].duty;
                            let tau_m = full.torque(duty, g.vm);
                            let friction = full.friction(g.vm, tau_m);
                            let at = |vm: f64| full.motor_side_drive(duty, vm);
                            crate::backlash::advance_motor(s, g, at, friction, q, self.v[iv], dt)
                        }
                        None => {
                            let at = |vm: f64| s.drive(goal, q, vm);
                            let f = s.gear_friction;
                            crate::backlash::advance_motor(s, g, at, f, q, self.v[iv], dt)
                        }
                    }
                }
                _ => None,
            };
            if let Some(vm) = closed {
                self.gear_impact(i, vm);
            }
        }
        self.time += dt;
        if self.q.iter().chain(self.v.iter()).any(|x| !x.is_finite()) {
            return Err(SimError::Diverged {
                time: self.time,
                message: "the state is no longer finite".into(),
            });
        }
        Ok(())
    }

    /// Contact forces at the current state, and their stiffness and damping in the step
    /// matrix (see the module docs of `contact`).
    ///
    /// Points are gathered per body first: a point's Jacobian is `A_p J_body` with
    /// `A_p = [I, -[x_p]x]`, so the body's points add up to one 6x6 matrix and one wrench,
    /// and the joint-space terms are formed once per body instead of once per point.
    fn add_contacts(&mut self, dt: f64) {
        self.add_point_forces(dt);
        self.add_contact_terms();
    }

    /// Every point's contact force for the step, summed per body (`contact_bodies`)
    /// as a wrench about the world origin and the matrix `A_p^T W A_p` of its implicit
    /// spring and damper terms; `contacts` gets each point's state.
    fn add_point_forces(&mut self, dt: f64) {
        let cp = self.contact_params;
        let nb = self.model.nbodies;
        for acc in self.contact_bodies.iter_mut() {
            acc.active = false;
        }
        for k in 0..self.points.len() {
            let p = &self.points[k];
            let x =
                self.body_placement(p.body).act_point(&p.local) - Vector3::new(0.0, 0.0, p.radius);
            let bi = if p.body == BASE { nb } else { p.body };
            let state = &mut self.contacts[k];
            let pen = -x.z;
            if pen <= 0.0 {
                *state = ContactState {
                    position: x,
                    ..Default::default()
                };
                continue;
            }
            state.position = x;
            // The body's world twist, once per body and step.
            let acc = &mut self.contact_bodies[bi];
            if !acc.active {
                acc.active = true;
                acc.matrix = nalgebra::Matrix6::zeros();
                acc.wrench = nalgebra::Vector6::zeros();
                acc.twist = body_twist(&self.data.joint_jacobians, &self.chains[bi], &self.v);
            }
            let (lin, ang) = (
                acc.twist.fixed_rows::<3>(0).into_owned(),
                acc.twist.fixed_rows::<3>(3).into_owned(),
            );
            let vp = lin + ang.cross(&x);
            let Some((f, kt, dtan)) = point_force(&cp, dt, state, &x, &vp, pen) else {
                *state = ContactState {
                    position: x,
                    ..Default::default()
                };
                continue;
            };
            state.force = f;
            add_implicit_point_terms(acc, &cp, dt, &x, &vp, &f, (kt, dtan));
        }
    }

    /// Joint-space terms of each body in contact: `h[a][b] += j_b . (S j_a)`,
    /// `rhs[a] += j_a . wrench` over the DOFs of its chain.
    fn add_contact_terms(&mut self) {
        let nb = self.model.nbodies;
        for bi in 0..=nb {
            if !self.contact_bodies[bi].active {
                continue;
            }
            let acc = &self.contact_bodies[bi];
            let chain = &self.chains[bi];
            for (c, &dof) in chain.iter().enumerate() {
                let j = nalgebra::Vector6::from_column_slice(
                    self.data.joint_jacobians.column(dof).as_slice(),
                );
                self.js[c] = j;
                self.su[c] = acc.matrix * j;
                self.rhs[dof] += j.dot(&acc.wrench);
            }
            for (a, &da) in chain.iter().enumerate() {
                let u = self.su[a];
                // Row da's pattern is da and its ancestors: the rest of the chain.
                debug_assert_eq!(self.h.pattern(da), &chain[a..]);
                let row = self.h.row_mut(da);
                for (x, j) in row.iter_mut().zip(&self.js[a..chain.len()]) {
                    *x += j.dot(&u);
                }
            }
        }
    }

    /// Run for `duration` seconds of simulated time.
    pub fn run(&mut self, duration: f64) -> Result<(), SimError> {
        let n = (duration / self.config.dt).round() as u64;
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// Total mechanical energy: kinetic (from the mass matrix) plus gravitational.
    pub fn energy(&mut self) -> f64 {
        crba(&self.model, &mut self.data, &self.q);
        self.data.symmetrize_mass_matrix();
        let v = nalgebra::DVector::from_column_slice(&self.v);
        let kinetic = 0.5 * v.dot(&(&self.data.mass_matrix * &v));
        let com = twinloop_dynamics::center_of_mass(&self.model, &mut self.data, &self.q);
        kinetic - self.model.total_mass * self.config.gravity.dot(&com)
    }

    /// World placement of a description link at the current state.
    pub fn link_placement(&mut self, link: &str) -> Option<Se3> {
        let k = self.model.frame_index(link)?;
        twinloop_dynamics::frames_forward_kinematics(&self.model, &mut self.data, &self.q);
        Some(self.data.o_m_f[k])
    }

    /// Whole-body CoM at the current state.
    pub fn center_of_mass(&mut self) -> Vector3<f64> {
        twinloop_dynamics::center_of_mass(&self.model, &mut self.data, &self.q)
    }
}

/// Sensors: the settings live in [`SensorState`]; reading them is [`sensors::read`]
/// over the simulator's state.
impl Simulator {
    /// Give every joint a Dynamixel RX encoder (1024 counts over 300 degrees).
    pub fn use_dynamixel_encoders(&mut self) {
        self.sensors.use_dynamixel_encoders();
    }

    pub fn sensors_mut(&mut self) -> &mut SensorState {
        &mut self.sensors
    }

    pub fn sensors(&self) -> &SensorState {
        &self.sensors
    }

    /// Set the feet by link name.
    pub fn set_feet(&mut self, names: &[&str]) -> Result<(), SimError> {
        let mut feet = Vec::new();
        for n in names {
            let i = self
                .model
                .links
                .iter()
                .position(|l| l.name == *n)
                .ok_or_else(|| SimError::Input(format!("no link named \"{n}\" for a foot")))?;
            feet.push(i);
        }
        self.sensors.feet = feet;
        Ok(())
    }

    /// The exact angular velocity of a link in its own frame, rad/s: what a perfect gyro
    /// fixed to the link reads. For a second gyroscope (seed 003 has one MPU-6050 on each
    /// foot); the configured IMU applies quantisation and noise, this does not.
    pub fn link_angular_velocity(&mut self, link: &str) -> Option<Vector3<f64>> {
        let i = self.model.links.iter().position(|l| l.name == link)?;
        Some(sensors::link_angular_velocity(
            &self.model,
            &mut self.data,
            &self.q,
            &self.v,
            i,
        ))
    }

    /// Read every sensor into `state` (the `Robot` interface's measurement).
    pub fn read_sensors(&mut self, state: &mut RobotState) {
        let at = SensedState {
            time: self.time,
            dt: self.config.dt,
            q: &self.q,
            v: &self.v,
            applied: &self.applied,
            points: &self.points,
            contacts: &self.contacts,
        };
        sensors::read(&self.model, &mut self.data, &mut self.sensors, &at, state);
        // A full-model servo with a sensing delay reads the angle that long ago.
        for i in 0..self.model.nbodies {
            let delayed = match &self.actuators[i] {
                Actuator::Dynamixel(s) => s
                    .full
                    .is_some_and(|f| f.values[twinloop_actuator::params::SENSING_DELAY] > 0.0),
                _ => false,
            };
            if delayed {
                let k = self.model.idx_q[i] - self.model.q_offset;
                let q = self.sensed_joint_angle(i);
                state.positions[k] = match self.sensors.encoder_resolution[i] {
                    Some(r) => crate::sensors::quantize(q, r),
                    None => q,
                };
            }
        }
    }
}

/// The step matrix's tree over the DOFs: each DOF's parent DOF (the free flyer's six
/// chained, a body's first DOF after its parent body's last), and per body (index
/// `nbodies` = the base) its DOFs and all its ancestors', deepest first.
fn dof_tree(model: &Model) -> (Vec<usize>, Vec<Vec<usize>>) {
    let nb = model.nbodies;
    let off = model.v_offset;
    let mut dof_parent = vec![ltdl::NONE; model.nv];
    // The free flyer's six DOFs form a chain (its 6x6 block is dense).
    for (k, p) in dof_parent.iter_mut().enumerate().take(off).skip(1) {
        *p = k - 1;
    }
    // A body's DOFs chain from its parent's last one (a ball joint's three in order).
    let last_dof = |i: usize| model.idx_v[i] + model.joint_types[i].nv() - 1;
    for i in 0..nb {
        let p = model.parents[i];
        let first = model.idx_v[i];
        dof_parent[first] = if p == BASE {
            if off > 0 { off - 1 } else { ltdl::NONE }
        } else {
            last_dof(p)
        };
        for (d, p) in dof_parent
            .iter_mut()
            .enumerate()
            .take(last_dof(i) + 1)
            .skip(first + 1)
        {
            *p = d - 1;
        }
    }
    let mut chains = Vec::with_capacity(nb + 1);
    for i in 0..=nb {
        let mut c = Vec::new();
        let mut d = if i == nb {
            if off > 0 { off - 1 } else { ltdl::NONE }
        } else {
            last_dof(i)
        };
        while d != ltdl::NONE {
            c.push(d);
            d = dof_parent[d];
        }
        chains.push(c);
    }
    (dof_parent, chains)
}

/// Per joint, from the description: damping, friction, spring stiffness and the
/// spring's rest position (negative damping, friction and stiffness read as none).
fn joint_passives(robot: &Description, model: &Model) -> [Vec<f64>; 4] {
    let nb = model.nbodies;
    let mut joint_damping = vec![0.0; nb];
    let mut joint_friction = vec![0.0; nb];
    let (mut joint_stiffness, mut joint_springref) = (vec![0.0; nb], vec![0.0; nb]);
    for (i, name) in model.joint_names.iter().enumerate() {
        let Some(j) = robot.joint(name) else { continue };
        if let Some(dy) = j.dynamics {
            joint_damping[i] = dy.damping.unwrap_or(0.0).max(0.0);
            joint_friction[i] = dy.friction.unwrap_or(0.0).max(0.0);
        }
        joint_stiffness[i] = j.stiffness.max(0.0);
        joint_springref[i] = j.springref;
    }
    [
        joint_damping,
        joint_friction,
        joint_stiffness,
        joint_springref,
    ]
}
