//! Sensors: joint encoders with quantisation, a trunk IMU (MPU-6050 scales), joint
//! load, and foot force with centre of pressure.
//!
//! As in MuJoCo, sensors are functions of the model, the dynamics workspace, the
//! sensor settings ([`SensorState`]) and the simulated state ([`SensedState`]): they
//! never see the simulator, which calls them ([`read`]).

use crate::contact::{ContactPoint, ContactState};
use nalgebra::Vector3;
use twinloop_description::Description;
use twinloop_dynamics::{BASE, Data, Model, compute_joint_jacobians};
use twinloop_random::SplitMix64;
use twinloop_robot::{FootSensor, Imu, RobotState};
use twinloop_spatial::Se3;

/// MPU-6050 gyro scale at +-250 deg/s: 131 LSB per deg/s.
pub const MPU6050_GYRO_LSB_PER_DEG_S: f64 = 131.0;
/// MPU-6050 accelerometer scale at +-2 g: 16384 LSB per g.
pub const MPU6050_ACCEL_LSB_PER_G: f64 = 16384.0;
/// Dynamixel AX/RX/MX(1.0) encoder: 1024 counts over 300 degrees.
pub const DYNAMIXEL_RX_COUNTS_PER_300_DEG: f64 = 1024.0;

/// Sensor settings and state.
#[derive(Debug, Clone)]
pub struct SensorState {
    /// Per joint: encoder resolution in rad per count (`None`: exact).
    pub encoder_resolution: Vec<Option<f64>>,
    /// Description link carrying the IMU (default: the base link).
    pub imu_link: usize,
    /// Quantise the IMU like an MPU-6050 (131 LSB per deg/s, 16384 LSB per g).
    pub imu_quantize: bool,
    /// Gaussian noise standard deviations, rad/s and m/s^2.
    pub gyro_noise: f64,
    pub accel_noise: f64,
    /// Links whose contact forces are reported as feet.
    pub feet: Vec<usize>,
    rng: SplitMix64,
    imu_velocity: Vector3<f64>,
    imu_velocity_time: Option<f64>,
    g: Vector3<f64>,
}

/// What the sensors read of the simulated robot at one instant.
#[derive(Debug, Clone, Copy)]
pub struct SensedState<'a> {
    /// Simulated time, s.
    pub time: f64,
    /// Step, s (the IMU differentiates its point's velocity over one step).
    pub dt: f64,
    /// Configuration and velocity (Pinocchio's conventions).
    pub q: &'a [f64],
    pub v: &'a [f64],
    /// Torque each actuator applied in the last step.
    pub applied: &'a [f64],
    /// Contact points and their states, index for index.
    pub points: &'a [ContactPoint],
    pub contacts: &'a [ContactState],
}

/// World placement of a description link after a kinematics pass over `data`.
#[inline]
fn link_world_placement(model: &Model, data: &Data, link: usize) -> Se3 {
    let info = &model.links[link];
    (if info.body == BASE {
        data.base_placement
    } else {
        data.o_m_i[info.body]
    }) * info.placement
}

/// World linear velocity of a link's origin and world angular velocity of the link,
/// from the joint Jacobians in `data`.
fn imu_world_velocity(
    model: &Model,
    data: &Data,
    v: &[f64],
    link: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    let info = &model.links[link];
    let x = link_world_placement(model, data, link);
    let mut lin = Vector3::zeros();
    let mut ang = Vector3::zeros();
    let mut add = |dof: usize| {
        let c = data.joint_jacobians.column(dof);
        let l = Vector3::new(c[0], c[1], c[2]);
        let a = Vector3::new(c[3], c[4], c[5]);
        lin += (l + a.cross(&x.translation)) * v[dof];
        ang += a * v[dof];
    };
    for d in 0..model.v_offset {
        add(d);
    }
    if info.body != BASE {
        for b in model.ancestors(info.body) {
            for k in 0..model.joint_types[b].nv() {
                add(model.idx_v[b] + k);
            }
        }
    }
    (lin, ang)
}

impl SensorState {
    pub fn new(model: &Model, robot: &Description) -> Self {
        let imu_link = model
            .links
            .iter()
            .position(|l| l.name == model.base_link)
            .unwrap_or(0);
        // Feet by default: the two links owning the lowest collision boxes of the legs,
        // found by name first (common conventions), else none until set.
        let mut feet = Vec::new();
        for (i, l) in robot.links.iter().enumerate() {
            let n = l.name.to_lowercase();
            let has_box = l
                .collisions
                .iter()
                .any(|c| matches!(c.geometry, twinloop_description::Geometry::Box { .. }));
            if has_box
                && (n.contains("foot")
                    || n.contains("sole")
                    || n.contains("ank_roll")
                    || n.contains("ankle_roll"))
            {
                feet.push(i);
            }
        }
        SensorState {
            encoder_resolution: vec![None; model.nbodies],
            imu_link,
            imu_quantize: false,
            gyro_noise: 0.0,
            accel_noise: 0.0,
            feet,
            rng: SplitMix64(0x5EED_1234_ABCD_0001),
            imu_velocity: Vector3::zeros(),
            imu_velocity_time: None,
            g: model.gravity,
        }
    }

    pub(crate) fn reset(&mut self) {
        self.imu_velocity_time = None;
    }

    /// Record the IMU point's world velocity at the start of a step.
    pub(crate) fn observe(&mut self, model: &Model, data: &Data, v: &[f64]) {
        self.imu_velocity = imu_world_velocity(model, data, v, self.imu_link).0;
        self.imu_velocity_time = Some(0.0);
    }

    fn normal(&mut self) -> f64 {
        self.rng.normal()
    }

    pub fn set_noise_seed(&mut self, seed: u64) {
        self.rng = SplitMix64(seed);
    }

    /// Give every joint a Dynamixel RX encoder (1024 counts over 300 degrees).
    pub fn use_dynamixel_encoders(&mut self) {
        let res = 300f64.to_radians() / DYNAMIXEL_RX_COUNTS_PER_300_DEG;
        self.encoder_resolution
            .iter_mut()
            .for_each(|r| *r = Some(res));
    }
}

/// Quantise to a step.
#[inline]
pub fn quantize(x: f64, step: f64) -> f64 {
    (x / step).round() * step
}

/// The exact angular velocity of a link in its own frame, rad/s: what a perfect gyro
/// fixed to the link reads (the configured IMU adds quantisation and noise, this does
/// not). Runs the joint Jacobians into `data`.
pub fn link_angular_velocity(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    link: usize,
) -> Vector3<f64> {
    compute_joint_jacobians(model, data, q);
    let (_, ang) = imu_world_velocity(model, data, v, link);
    let x = link_world_placement(model, data, link);
    x.rotation.transpose() * ang
}

/// Read every sensor into `out` (the `Robot` interface's measurement): encoders,
/// joint velocities and loads, the IMU, then the feet. Allocates only the first time
/// `out` is filled.
pub fn read(
    model: &Model,
    data: &mut Data,
    sensors: &mut SensorState,
    at: &SensedState,
    out: &mut RobotState,
) {
    out.time = at.time;
    read_joints(model, sensors, at, out);
    read_imu(model, data, sensors, at, out);
    read_feet(model, sensors, at, out);
}

/// Encoder positions (quantised where a resolution is set), velocities and applied torques.
fn read_joints(model: &Model, sensors: &SensorState, at: &SensedState, out: &mut RobotState) {
    let (qo, vo) = (model.q_offset, model.v_offset);
    // One position per 1-DoF joint; a ball joint's four quaternion entries as they are.
    out.positions.clear();
    out.positions.extend_from_slice(&at.q[qo..]);
    for i in 0..model.nbodies {
        if model.joint_types[i].nq() == 1 {
            let k = model.idx_q[i] - qo;
            if let Some(r) = sensors.encoder_resolution[i] {
                out.positions[k] = quantize(out.positions[k], r);
            }
        }
    }
    let vel = out.velocities.get_or_insert_with(Vec::new);
    vel.clear();
    vel.extend_from_slice(&at.v[vo..]);
    let eff = out.efforts.get_or_insert_with(Vec::new);
    eff.clear();
    eff.extend_from_slice(at.applied);
}

/// IMU: angular velocity and specific force in the IMU frame, with noise and
/// MPU-6050 quantisation when set, and the link's orientation.
fn read_imu(
    model: &Model,
    data: &mut Data,
    sensors: &mut SensorState,
    at: &SensedState,
    out: &mut RobotState,
) {
    compute_joint_jacobians(model, data, at.q);
    let link = sensors.imu_link;
    let (lin, ang) = imu_world_velocity(model, data, at.v, link);
    let x = link_world_placement(model, data, link);
    let accel_world = match sensors.imu_velocity_time {
        Some(_) => (lin - sensors.imu_velocity) / at.dt,
        None => Vector3::zeros(),
    };
    let rt = x.rotation.transpose();
    let mut gyro = rt * ang;
    let mut accel = rt * (accel_world - sensors.g);
    if sensors.gyro_noise > 0.0 || sensors.accel_noise > 0.0 {
        for k in 0..3 {
            gyro[k] += sensors.gyro_noise * sensors.normal();
            accel[k] += sensors.accel_noise * sensors.normal();
        }
    }
    if sensors.imu_quantize {
        let gstep = (1.0 / MPU6050_GYRO_LSB_PER_DEG_S).to_radians();
        let astep = twinloop_description::GRAVITY / MPU6050_ACCEL_LSB_PER_G;
        gyro = gyro.map(|w| quantize(w, gstep));
        accel = accel.map(|a| quantize(a, astep));
    }
    out.imu = Some(Imu {
        gyro: [gyro.x, gyro.y, gyro.z],
        accel: [accel.x, accel.y, accel.z],
        orientation: Some(twinloop_spatial::matrix_to_quaternion_xyzw(&x.rotation)),
    });
}

/// Feet: total normal force and centre of pressure of each foot link's contact points.
fn read_feet(model: &Model, sensors: &SensorState, at: &SensedState, out: &mut RobotState) {
    out.feet
        .resize_with(sensors.feet.len(), FootSensor::default);
    for (k, &link) in sensors.feet.iter().enumerate() {
        let (mut f, mut mx, mut my) = (0.0, 0.0, 0.0);
        for (p, c) in at.points.iter().zip(at.contacts) {
            if p.link == link && c.active {
                f += c.force.z;
                mx += c.force.z * c.position.x;
                my += c.force.z * c.position.y;
            }
        }
        let s = &mut out.feet[k];
        if s.name != model.links[link].name {
            s.name = model.links[link].name.clone();
        }
        s.force = f;
        s.cop = (f > 0.0).then(|| [mx / f, my / f]);
    }
}
