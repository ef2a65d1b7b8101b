//! The tip-over study on the simulator (seeds 000 and 001): run the experiment in all
//! four directions on a simulated robot and put its results beside what the model says:
//! the static tipping angle at each onset (CoM over the support edge, from the model
//! at the joint angles measured at the onset, turned further by the joints the protocol
//! turns: the ankle pitches, or the ankle and hip rolls; the feet as rolled as the IMU
//! saw them) and the CoM from the angles by the seed's method and the exact method,
//! next to the model's true CoM.
//!
//! Each direction runs twice: at the constant ramp (its time to fall is Table IV's),
//! then up to half a degree before that tip and on at a creep, which cuts the lag of
//! the onset detection tenfold (see [`TipoverConfig::slow_from_deg`]).

use crate::tipover::{
    SEED_000_CONSTANTS, SeedAngles, SeedConstants, TipAngles, exact_method, feet_mass,
    frontal_lever, seed_method,
};
use nalgebra::Vector3;
use serde::Serialize;
use twinloop_description::Description;
use twinloop_description::builtin::FootGeometry;
use twinloop_dynamics::{BASE, Data};
use twinloop_experiments::tipover::{Direction, TipoverConfig, TipoverResult, run_direction};
use twinloop_robot::RobotError;
use twinloop_sim::statics::{FlatFeet, hip_lean_signs, lean_signs};
use twinloop_sim::{Actuator, ContactParams, SimConfig, Simulator, servo_for_joint};

/// Settings of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyOptions {
    /// Ankle ramp speed, deg/s.
    pub ramp_deg_per_s: f64,
    /// How far the robot's weight sinks into the ground, m (the ground's stiffness):
    /// small, because the static reference assumes rigid soles on a rigid floor.
    pub ground_sink: f64,
    /// Ramp speed of the slow final approach, deg/s (see
    /// [`TipoverConfig::slow_from_deg`]).
    pub slow_ramp_deg_per_s: f64,
    /// Time step, s.
    pub dt: f64,
    /// Quantise joint readings like the robot's Dynamixel encoders (1024 over 300 deg).
    pub dynamixel_encoders: bool,
    /// The servos' compliance slope and margin during the experiment, in Dynamixel RX
    /// position units (0.29 deg). The CoM methods treat the robot as rigid, so the
    /// protocol stiffens the servos first, as one would on the real robot: slope 2 (the
    /// stiffest RX setting) and margin 0. `None` keeps each servo's own setting.
    pub compliance_units: Option<(f64, f64)>,
}

impl Default for StudyOptions {
    fn default() -> Self {
        StudyOptions {
            ramp_deg_per_s: 0.5,
            slow_ramp_deg_per_s: 0.05,
            ground_sink: 1e-5,
            dt: 1e-3,
            dynamixel_encoders: false,
            compliance_units: Some((2.0, 0.0)),
        }
    }
}

/// One direction's outcome with its static reference.
#[derive(Debug, Clone, Serialize)]
pub struct DirectionReport {
    pub commanded_deg: f64,
    pub measured_deg: f64,
    pub time_s: f64,
    /// The model's static tipping angle for the joints as they were at the onset, deg.
    pub static_deg: f64,
    /// The robot's lean beyond what its joints explain at the onset (feet rolled onto
    /// their edges), deg; the static angle accounts for it.
    pub excess_deg: f64,
    /// The static tipping angle of the rigid model (standing pose, feet flat, no joint
    /// giving under the load), deg: what the robot would do with infinitely stiff
    /// servos.
    pub rigid_static_deg: f64,
    /// The trunk's lean from the standing pose at the onset (IMU), deg.
    pub lean_deg: f64,
}

/// CoM estimates, m, relative to the midpoint of the ankle pitch joints in the
/// standing pose (x forward, y left, z up).
#[derive(Debug, Clone, Serialize)]
pub struct ComReport {
    #[serde(rename = "true")]
    pub truth: [f64; 3],
    pub seed_method: [f64; 3],
    pub exact_method: [f64; 3],
    /// Distance of each estimate from the true CoM, m.
    pub seed_error: f64,
    pub exact_error: f64,
    /// The sideways lean's lever S (m; see `twinloop_reduced::FrontalLever`): the
    /// model's, and what the exact method found beside the CoM.
    pub frontal_lever_true: f64,
    pub frontal_lever_exact: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct StudyReport {
    pub robot: String,
    pub forward: DirectionReport,
    pub backward: DirectionReport,
    pub left: DirectionReport,
    pub right: DirectionReport,
    pub com: ComReport,
    /// Which constants the seed method used: the seed's own (km20) or the robot's feet.
    pub seed_constants: String,
    /// The foot geometry the estimators used.
    pub foot: FootReport,
}

#[derive(Debug, Clone, Serialize)]
pub struct FootReport {
    pub front: f64,
    pub back: f64,
    pub ankle_height: f64,
    pub roll_axis_height: f64,
    pub ankle_half_spacing: f64,
    pub outer: f64,
    pub inner: f64,
    /// The feet (everything below the ankle pitch joints): share of the robot's mass
    /// and CoM [x, z] relative to the ankle midpoint, m.
    pub feet_mass_fraction: f64,
    pub feet_com: [f64; 2],
}

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// Ankle and foot names: the built-in robot's, or found by name in a description
/// (`*ank*pitch*` and `*ank*roll*` joints with a left/right prefix; the feet are the
/// roll joints' child links).
fn ankle_names(robot: &Description) -> Result<[String; 6], String> {
    if let Some(f) = twinloop_description::builtin::foot_geometry(&robot.name) {
        return Ok([
            f.left_ankle_pitch,
            f.right_ankle_pitch,
            f.left_ankle_roll,
            f.right_ankle_roll,
            f.left_foot,
            f.right_foot,
        ]);
    }
    let find = |kind: &str, left: bool| -> Result<String, String> {
        let hits: Vec<&str> = robot
            .joints
            .iter()
            .map(|j| j.name.as_str())
            .filter(|n| {
                let l = n.to_lowercase();
                let side = if left {
                    l.starts_with('l') || l.contains("left")
                } else {
                    l.starts_with('r') || l.contains("right")
                };
                (l.contains("ank") || l.contains("ankle")) && l.contains(kind) && side
            })
            .collect();
        match hits.as_slice() {
            [one] => Ok(one.to_string()),
            _ => Err(format!(
                "cannot tell the {} ankle {kind} joint of \"{}\" by name (candidates: {:?})",
                if left { "left" } else { "right" },
                robot.name,
                hits
            )),
        }
    };
    let (lp, rp, lr, rr) = (
        find("pitch", true)?,
        find("pitch", false)?,
        find("roll", true)?,
        find("roll", false)?,
    );
    let child = |j: &str| robot.joint(j).map(|j| j.child.clone()).unwrap_or_default();
    let (lf, rf) = (child(&lr), child(&rr));
    Ok([lp, rp, lr, rr, lf, rf])
}

/// The hip roll joints (left, right), found by name: `*hip*roll*` with a left/right
/// prefix.
fn hip_roll_names(robot: &Description) -> Result<[String; 2], String> {
    let find = |left: bool| -> Result<String, String> {
        let hits: Vec<&str> = robot
            .joints
            .iter()
            .map(|j| j.name.as_str())
            .filter(|n| {
                let l = n.to_lowercase();
                let side = if left {
                    l.starts_with('l') || l.contains("left")
                } else {
                    l.starts_with('r') || l.contains("right")
                };
                l.contains("hip") && l.contains("roll") && side
            })
            .collect();
        match hits.as_slice() {
            [one] => Ok(one.to_string()),
            _ => Err(format!(
                "cannot tell the {} hip roll joint of \"{}\" by name (candidates: {:?}); \
                 the sideways lean turns the hip rolls with the ankle rolls",
                if left { "left" } else { "right" },
                robot.name,
                hits
            )),
        }
    };
    Ok([find(true)?, find(false)?])
}

/// The foot geometry measured on the model in the standing pose: sole points of the feet
/// and ankle joint origins.
fn measure_feet(sim: &Simulator, names: &[String; 6], feet: [usize; 2]) -> FootGeometry {
    let model = sim.model.clone();
    let mut data = Data::new(&model);
    let q = sim.q.clone();
    twinloop_dynamics::frames_forward_kinematics(&model, &mut data, &q);
    let joint_pos = |n: &str| data.o_m_i[model.joint_index(n).unwrap_or(0)].translation;
    let (lp, rp, lr, rr) = (
        joint_pos(&names[0]),
        joint_pos(&names[1]),
        joint_pos(&names[2]),
        joint_pos(&names[3]),
    );
    let sole = |foot: usize| -> Vec<Vector3<f64>> {
        let body = model.links[foot].body;
        let pts: Vec<Vector3<f64>> = sim
            .contact_points()
            .iter()
            .filter(|p| p.body == body)
            .map(|p| {
                (if p.body == BASE {
                    data.base_placement
                } else {
                    data.o_m_i[p.body]
                })
                .act_point(&p.local)
                    - Vector3::new(0.0, 0.0, p.radius)
            })
            .collect();
        let zmin = pts.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
        pts.into_iter().filter(|p| p.z < zmin + 1e-6).collect()
    };
    // The left sole gives the geometry; the feet are mirror images.
    let ls = sole(feet[0]);
    let max = |v: &[Vector3<f64>], f: fn(&Vector3<f64>) -> f64| {
        v.iter().map(f).fold(f64::NEG_INFINITY, f64::max)
    };
    let min = |v: &[Vector3<f64>], f: fn(&Vector3<f64>) -> f64| {
        v.iter().map(f).fold(f64::INFINITY, f64::min)
    };
    let mid = (lp + rp) * 0.5;
    let sole_z = min(&ls, |p| p.z);
    FootGeometry {
        front: max(&ls, |p| p.x) - mid.x,
        back: mid.x - min(&ls, |p| p.x),
        ankle_height: mid.z - sole_z,
        roll_axis_height: 0.5 * (lr.z + rr.z) - sole_z,
        ankle_half_spacing: 0.5 * (lr.y - rr.y),
        outer: max(&ls, |p| p.y) - lr.y,
        inner: lr.y - min(&ls, |p| p.y),
        left_foot: model.links[feet[0]].name.clone(),
        right_foot: model.links[feet[1]].name.clone(),
        left_ankle_pitch: names[0].clone(),
        right_ankle_pitch: names[1].clone(),
        left_ankle_roll: names[2].clone(),
        right_ankle_roll: names[3].clone(),
        forward_lean_sign: 0.0,
        left_lean_sign: 0.0,
    }
}

/// Run the study on `robot` (a built-in robot gets its own servos and foot data).
pub fn run_study(robot: &Description, opts: &StudyOptions) -> Result<StudyReport, String> {
    let mass = twinloop_dynamics::Model::from_description(robot)
        .map_err(err)?
        .total_mass;
    let cfg = SimConfig {
        dt: opts.dt,
        contact: Some(ContactParams::for_robot(mass, 8, opts.ground_sink)),
        ..Default::default()
    };
    let mut sim = Simulator::new(robot, cfg).map_err(err)?;
    for i in 0..sim.model.nbodies {
        let mut servo = servo_for_joint(&robot.name, &sim.model, i);
        if let Some((slope, margin)) = opts.compliance_units {
            servo.compliance_slope = slope * twinloop_sim::actuator::RX_POSITION_UNIT;
            servo.compliance_margin = margin * twinloop_sim::actuator::RX_POSITION_UNIT;
        }
        sim.actuators[i] = Actuator::Dynamixel(servo);
    }
    if opts.dynamixel_encoders {
        sim.use_dynamixel_encoders();
    }
    let n = sim.model.nbodies;
    let standing: Vec<f64> = (0..n)
        .map(|i| 0f64.clamp(sim.model.lower_limits[i], sim.model.upper_limits[i]))
        .collect();
    sim.place_on_ground(&standing).map_err(err)?;
    let names = ankle_names(robot)?;
    let joint = |n: &str| {
        sim.joint_index(n)
            .ok_or_else(|| format!("no joint \"{n}\" in \"{}\"", robot.name))
    };
    let (lp, rp, lr, rr) = (
        joint(&names[0])?,
        joint(&names[1])?,
        joint(&names[2])?,
        joint(&names[3])?,
    );
    let link = |n: &str| {
        sim.model
            .links
            .iter()
            .position(|l| l.name == n)
            .ok_or_else(|| format!("no foot link \"{n}\" in \"{}\"", robot.name))
    };
    let feet = [link(&names[4])?, link(&names[5])?];
    let hip_names = hip_roll_names(robot)?;
    let (lh, rh) = (joint(&hip_names[0])?, joint(&hip_names[1])?);
    let sim_feet: Vec<&str> = vec![names[4].as_str(), names[5].as_str()];
    sim.set_feet(&sim_feet).map_err(err)?;
    let (foot, seed_constants, label) =
        match twinloop_description::builtin::foot_geometry(&robot.name) {
            Some(f) if robot.name == twinloop_description::builtin::km20::NAME => (
                f,
                SEED_000_CONSTANTS,
                "seed 000 (F1 3.5 cm, F2 9.5 cm, L0 3.1 cm)",
            ),
            Some(f) => {
                let c = SeedConstants::from_foot(&f);
                (f, c, "the robot's own feet")
            }
            None => {
                let f = measure_feet(&sim, &names, feet);
                let c = SeedConstants::from_foot(&f);
                (f, c, "the robot's own feet (measured)")
            }
        };
    let model = sim.model.clone();
    let points = sim.contact_points().to_vec();
    let place = |s: &mut Simulator, l: &str| {
        s.link_placement(l)
            .ok_or_else(|| format!("no link \"{l}\""))
    };
    let foot_world = [place(&mut sim, &names[4])?, place(&mut sim, &names[5])?];
    let mut flat = FlatFeet {
        model: &model,
        feet,
        points: &points,
        foot_world,
        held: 0,
        tilt: 0.0,
    };
    let mut data = Data::new(&model);
    let mut q0 = model.neutral_configuration();
    q0[model.q_offset..].copy_from_slice(&standing);
    let fs = lean_signs(&model, &mut data, &q0, [lp, rp], Vector3::x());
    let ls = lean_signs(&model, &mut data, &q0, [lr, rr], Vector3::y());
    let hs = hip_lean_signs(&model, &mut data, &q0, [lh, rh], Vector3::y());
    let mut cfg = TipoverConfig::new([lp, rp], [lr, rr], fs, ls);
    cfg.hip_roll = Some([lh, rh]);
    cfg.hip_left_sign = hs;
    cfg.ramp_deg_per_s = opts.ramp_deg_per_s;
    let imu_link = sim.sensors().imu_link;
    let mut results: Vec<(TipoverResult, f64, f64)> = Vec::new();
    let mut pdata = Data::new(&model);
    for d in Direction::ALL {
        // Which foot the kinematics hold flat: sideways the one the robot leans onto
        // (the other unloads); forward and backward both stand, so both chains are used
        // and averaged (the legs give by slightly different amounts when the load is
        // off-centre, and one leg alone would read that as a tilt).
        let helds: &[usize] = match d {
            Direction::Left => &[0],
            Direction::Right => &[1],
            Direction::Forward | Direction::Backward => &[0, 1],
        };
        let n_held = helds.len() as f64;
        // A first run at the constant ramp (its time to fall is seed 000's Table IV
        // quantity), then a second that comes up to half a degree before that tip and
        // creeps (see `TipoverConfig::slow_from_deg`).
        let mut run = |cfg: &TipoverConfig, sim: &mut Simulator| {
            sim.place_on_ground(&standing).map_err(err)?;
            let mut predict = |j: &[f64]| {
                let mut t = [0.0; 2];
                for &h in helds {
                    flat.held = h;
                    let x = flat.link_tilt(&mut pdata, j, imu_link);
                    t[0] += x[0] / n_held;
                    t[1] += x[1] / n_held;
                }
                t
            };
            run_direction(sim, &standing, d, cfg, Some(&mut predict))
                .map_err(|e: RobotError| e.to_string())
        };
        let first = run(&cfg, &mut sim)?;
        let mut slow = cfg.clone();
        slow.slow_from_deg = Some((first.commanded_deg - 0.5).max(0.0));
        slow.slow_ramp_deg_per_s = opts.slow_ramp_deg_per_s;
        let mut r = run(&slow, &mut sim)?;
        r.time_s = first.time_s;
        // The joints the protocol turns, with the sign that leans the robot the way of
        // `d`: the static reference sweeps the same joints from the onset.
        let (turned, dir): (Vec<(usize, f64)>, _) = match d {
            Direction::Forward => (vec![(lp, fs[0]), (rp, fs[1])], Vector3::x()),
            Direction::Backward => (vec![(lp, -fs[0]), (rp, -fs[1])], -Vector3::x()),
            Direction::Left => (
                vec![(lr, ls[0]), (rr, ls[1]), (lh, hs[0]), (rh, hs[1])],
                Vector3::y(),
            ),
            Direction::Right => (
                vec![(lr, -ls[0]), (rr, -ls[1]), (lh, -hs[0]), (rh, -hs[1])],
                -Vector3::y(),
            ),
        };
        let mut offset = 0.0;
        for &h in helds {
            flat.held = h;
            flat.tilt = r.excess_deg.to_radians();
            offset += flat
                .tipping_angle(&mut data, &r.positions_at_onset, &turned, dir, -0.2, 0.2)
                .map(f64::to_degrees)
                .unwrap_or(f64::NAN)
                / n_held;
        }
        // The rigid robot's: from the standing pose, feet flat, no joint giving.
        flat.held = helds[0];
        flat.tilt = 0.0;
        let rigid = flat
            .tipping_angle(&mut data, &standing, &turned, dir, 0.0, 1.2)
            .map(f64::to_degrees)
            .unwrap_or(f64::NAN);
        results.push((r.clone(), r.measured_deg + offset, rigid));
    }
    // The CoM by the two estimators from the measured angles, and the truth.
    let pick = |d: Direction, f: fn(&TipoverResult) -> f64| {
        results
            .iter()
            .find(|r| r.0.direction == d)
            .map(|r| f(&r.0))
            .unwrap_or(f64::NAN)
    };
    let deg = |d: Direction| pick(d, |r| r.measured_deg);
    let (f, b, l, r) = (
        deg(Direction::Forward),
        deg(Direction::Backward),
        deg(Direction::Left),
        deg(Direction::Right),
    );
    let seed = seed_method(
        &SeedAngles {
            alpha1: f,
            beta1: b,
            alpha2: l,
            beta2: r,
        },
        &seed_constants,
    )
    .map_err(err)?;
    // The exact method takes the ankle angles and the feet's roll onto the edge at each
    // tip (the IMU's tilt beyond the joints), and the feet's mass (they stay on the
    // ground while the body turns; part of the robot's fixed geometry, like their
    // outline).
    let rad = std::f64::consts::PI / 180.0;
    let angles = TipAngles {
        forward: f * rad,
        backward: b * rad,
        left: l * rad,
        right: r * rad,
        forward_roll: pick(Direction::Forward, |r| r.excess_deg) * rad,
        backward_roll: pick(Direction::Backward, |r| r.excess_deg) * rad,
        left_roll: pick(Direction::Left, |r| r.excess_deg) * rad,
        right_roll: pick(Direction::Right, |r| r.excess_deg) * rad,
    };
    let feet = feet_mass(&model, &q0, [&names[0], &names[1]]).map_err(err)?;
    let exact = exact_method(&angles, &feet, &foot).map_err(err)?;
    let lever = frontal_lever(
        &model,
        &q0,
        [&hip_names[0], &hip_names[1]],
        [&names[2], &names[3]],
    )
    .map_err(err)?;
    let truth =
        twinloop_reduced::com_relative_to_ankles(&model, &q0, &names[0], &names[1]).map_err(err)?;
    let dist = |a: [f64; 3]| {
        ((a[0] - truth[0]).powi(2) + (a[1] - truth[1]).powi(2) + (a[2] - truth[2]).powi(2)).sqrt()
    };
    let rep = |d: Direction| {
        let (r, s, rigid) = results
            .iter()
            .find(|r| r.0.direction == d)
            .expect("all four ran");
        DirectionReport {
            commanded_deg: r.commanded_deg,
            measured_deg: r.measured_deg,
            time_s: r.time_s,
            static_deg: *s,
            rigid_static_deg: *rigid,
            lean_deg: r.lean_deg,
            excess_deg: r.excess_deg,
        }
    };
    Ok(StudyReport {
        robot: robot.name.clone(),
        forward: rep(Direction::Forward),
        backward: rep(Direction::Backward),
        left: rep(Direction::Left),
        right: rep(Direction::Right),
        com: ComReport {
            truth,
            seed_method: seed.com,
            exact_method: exact.com,
            seed_error: dist(seed.com),
            exact_error: dist(exact.com),
            frontal_lever_true: lever.sin,
            frontal_lever_exact: exact.frontal_lever,
        },
        seed_constants: label.to_string(),
        foot: FootReport {
            front: foot.front,
            back: foot.back,
            ankle_height: foot.ankle_height,
            roll_axis_height: foot.roll_axis_height,
            ankle_half_spacing: foot.ankle_half_spacing,
            outer: foot.outer,
            inner: foot.inner,
            feet_mass_fraction: feet.fraction,
            feet_com: [feet.x, feet.z],
        },
    })
}
