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

use crate::error::IdentError;
use crate::tipover::{
    SEED_000_CONSTANTS, SeedAngles, SeedConstants, TipAngles, exact_method, feet_mass,
    frontal_lever, seed_method,
};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use twinloop_description::Description;
use twinloop_description::builtin::FootGeometry;
use twinloop_dynamics::{BASE, Data};
use twinloop_experiments::tipover::{Direction, TipoverConfig, TipoverResult, run_direction};
use twinloop_robot::Robot;
use twinloop_sim::statics::{FlatFeet, hip_lean_signs, lean_signs};
use twinloop_sim::{Actuator, ContactParams, SimConfig, Simulator};
use twinloop_spatial::Se3;

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
    /// Servo model parameters (docs/servo-models.md) in place of the datasheet
    /// servos, where given.
    pub servo_params: twinloop_sim::servo_params::ServoParamsSet,
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
            servo_params: Default::default(),
        }
    }
}

fn nan() -> f64 {
    f64::NAN
}

/// JSON has no NaN (serde_json writes null, which no f64 reads back): an angle that
/// does not exist is left out, and a note beside it says why.
fn not_finite(v: &f64) -> bool {
    !v.is_finite()
}

/// One direction's outcome with its static reference.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DirectionReport {
    pub commanded_deg: f64,
    pub measured_deg: f64,
    pub time_s: f64,
    /// The model's static tipping angle for the joints as they were at the onset, deg;
    /// absent (NaN in memory) when the posture has none, and `static_note` says why.
    #[serde(default = "nan", skip_serializing_if = "not_finite")]
    pub static_deg: f64,
    /// Why there is no `static_deg`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub static_note: Option<String>,
    /// The robot's lean beyond what its joints explain at the onset (feet rolled onto
    /// their edges), deg; the static angle accounts for it.
    pub excess_deg: f64,
    /// The static tipping angle of the rigid model (standing pose, feet flat, no joint
    /// giving under the load), deg: what the robot would do with infinitely stiff
    /// servos. Absent when there is none, and `rigid_static_note` says why.
    #[serde(default = "nan", skip_serializing_if = "not_finite")]
    pub rigid_static_deg: f64,
    /// Why there is no `rigid_static_deg`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rigid_static_note: Option<String>,
    /// The trunk's lean from the standing pose at the onset (IMU), deg.
    pub lean_deg: f64,
    /// Every joint's position at the onset, rad, by name: the posture the static
    /// reference is taken at, which lets `adapt` recompute it for a candidate model
    /// (empty in files written before it was kept).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub onset_positions: BTreeMap<String, f64>,
}

/// CoM estimates, m, relative to the midpoint of the ankle pitch joints in the
/// standing pose (x forward, y left, z up).
#[derive(Debug, Clone, Serialize, Deserialize)]
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

#[derive(Debug, Clone, Serialize, Deserialize)]
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
    /// How the angles were measured when over a bus (absent in the simulator's study
    /// and in files written before it was kept): what it takes to run the same
    /// protocol on a model and see how it reads that model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub protocol: Option<BusProtocol>,
    /// Over a bus: how it held up (retries, discarded packets, reads repeated).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bus: Option<twinloop_experiments::guarded::BusHealth>,
}

/// The bus protocol a tip-over was measured by (`twinloop_ident::tipover_bus`):
/// enough to run it again, the same way, on a simulated model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BusProtocol {
    /// The servo mapping (`builtin:km20` or the mapping file's path).
    pub map: String,
    /// First ramp and creep, deg/s of robot time.
    pub ramp_deg_per_s: f64,
    pub slow_ramp_deg_per_s: f64,
    /// How stiff the holding servos and the ramped ankles were made, as RX Compliance
    /// Slopes (every family through the servo catalogue).
    pub compliance_slope: i32,
    pub ankle_slope: i32,
    pub creeps: usize,
    pub dither: bool,
    /// A creep's tip read as the mean over this long up to its onset, s of robot time
    /// (0, as before this was kept: the onset's sample).
    #[serde(default)]
    pub onset_average_s: f64,
    /// The host's control cycle, s of robot time (median over the run).
    pub cycle_s: f64,
    /// The servos were left as they were (`--soft-servos`), not stiffened: the
    /// angles include the servos' give (false in records from before this was kept,
    /// which only ran on RX robots, always stiffened).
    #[serde(default)]
    pub soft_servos: bool,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
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

/// A lower layer's error (simulator, dynamics, a tip-over run) as this crate's.
fn err(e: impl std::fmt::Display) -> IdentError {
    IdentError::new(e.to_string())
}

/// Ankle and foot names: a profile's `[roles]` (on the description,
/// [`Description::roles`]), else the built-in robot's, else found by name
/// (`*ank*pitch*` and `*ank*roll*` joints with a left/right prefix, said on stderr);
/// the feet are the roll joints' child links.
pub(crate) fn ankle_names(robot: &Description) -> Result<[String; 6], String> {
    let roles = [
        "left_ankle_pitch",
        "right_ankle_pitch",
        "left_ankle_roll",
        "right_ankle_roll",
    ];
    let from_roles = roles.map(|r| robot.roles.get(r).map(str::to_string));
    let [lp, rp, lr, rr] = if let [Some(a), Some(b), Some(c), Some(d)] = from_roles {
        [a, b, c, d]
    } else if let Some(f) = twinloop_description::builtin::foot_geometry(&robot.name) {
        return Ok([
            f.left_ankle_pitch,
            f.right_ankle_pitch,
            f.left_ankle_roll,
            f.right_ankle_roll,
            f.left_foot,
            f.right_foot,
        ]);
    } else {
        let found = [
            guess_joint(robot, &["ank", "pitch"], true, "left ankle pitch")?,
            guess_joint(robot, &["ank", "pitch"], false, "right ankle pitch")?,
            guess_joint(robot, &["ank", "roll"], true, "left ankle roll")?,
            guess_joint(robot, &["ank", "roll"], false, "right ankle roll")?,
        ];
        say_guessed(robot, &roles, &found);
        found
    };
    let child = |j: &str| -> Result<String, String> {
        robot
            .joint(j)
            .map(|j| j.child.clone())
            .ok_or_else(|| format!("no joint \"{j}\" in \"{}\" (a role names it)", robot.name))
    };
    let (lf, rf) = (child(&lr)?, child(&rr)?);
    Ok([lp, rp, lr, rr, lf, rf])
}

/// The links below each ankle pitch joint (left, right; the joint's child and every
/// link under it, in the description's order): a part on one of them stays on the
/// ground with its foot in the fore-aft lean, and the ankle cross (between the pitch
/// and roll joints) turns with the sideways lean only, so the CoM inversion, which
/// treats the robot above the ankles as one body, cannot place it (`adapt`'s other
/// places, `twinloop_loop::protocol_bias`).
pub fn links_below_ankles(robot: &Description) -> Result<[Vec<String>; 2], IdentError> {
    let n = ankle_names(robot).map_err(IdentError::new)?;
    Ok([links_below(robot, &n[0]), links_below(robot, &n[1])])
}

/// The feet (left, right): the links below both ankle joints of a side, in the
/// description's order. A part there stays on the ground in every lean of the
/// tip-over, so the angles see its horizontal place and not its height (the moment
/// about a tipping edge of a point that does not move is its weight times its
/// horizontal distance from the edge, at any height).
pub fn feet_links(robot: &Description) -> Result<[Vec<String>; 2], IdentError> {
    let n = ankle_names(robot).map_err(IdentError::new)?;
    let both = |pitch: &str, roll: &str| {
        let under_roll = links_below(robot, roll);
        links_below(robot, pitch)
            .into_iter()
            .filter(|l| under_roll.contains(l))
            .collect()
    };
    Ok([both(&n[0], &n[2]), both(&n[1], &n[3])])
}

/// The shins (left, right): each ankle pitch joint's parent link. With the ankle
/// cross below it, the links a part can sit on at the ankle axes, where it barely
/// moves in the lean (see [`feet_links`]).
pub fn shin_links(robot: &Description) -> Result<[String; 2], IdentError> {
    let n = ankle_names(robot).map_err(IdentError::new)?;
    let parent = |j: &str| {
        robot
            .joint(j)
            .map(|j| j.parent.clone())
            .ok_or_else(|| IdentError::new(format!("no joint \"{j}\" in \"{}\"", robot.name)))
    };
    Ok([parent(&n[0])?, parent(&n[1])?])
}

/// The links below each hip roll joint (left, right; its child and every link under
/// it, in the description's order): the legs. Sideways the tip-over turns the hip
/// rolls with the ankle rolls, so the legs lean as a parallelogram while the pelvis
/// stays level: a part on a thigh or a shin swings out by its own height above the
/// ankle roll, one on the trunk by the hips' height whatever its own. The CoM
/// inversion's one body cannot tell them apart (a Darwin-OP with 0.174 kg on a thigh
/// was placed on its back, the CoM 4.1 mm high, exit 0); `adapt`'s other places try
/// each of these links.
pub fn links_below_hips(robot: &Description) -> Result<[Vec<String>; 2], IdentError> {
    let n = hip_roll_names(robot).map_err(IdentError::new)?;
    Ok([links_below(robot, &n[0]), links_below(robot, &n[1])])
}

/// `joint`'s child and every link under it, in the description's order.
pub(crate) fn links_below(robot: &Description, joint: &str) -> Vec<String> {
    let mut under: Vec<&str> = robot
        .joint(joint)
        .map(|j| vec![j.child.as_str()])
        .unwrap_or_default();
    // The tree is small (tens of links): grow the set until no joint adds a child.
    let mut grew = true;
    while grew {
        grew = false;
        for j in &robot.joints {
            if under.contains(&j.parent.as_str()) && !under.contains(&j.child.as_str()) {
                under.push(&j.child);
                grew = true;
            }
        }
    }
    robot
        .links
        .iter()
        .filter(|l| under.contains(&l.name.as_str()))
        .map(|l| l.name.clone())
        .collect()
}

/// The one joint of `robot` whose lower-cased name holds every word of `words` and
/// starts with the side's letter (or holds "left"/"right"); else an error naming
/// the candidates and how to name the joint in a profile.
fn guess_joint(
    robot: &Description,
    words: &[&str],
    left: bool,
    what: &str,
) -> Result<String, String> {
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
            side && words.iter().all(|w| l.contains(w))
        })
        .collect();
    match hits.as_slice() {
        [one] => Ok(one.to_string()),
        _ => Err(format!(
            "cannot tell the {what} joint of \"{}\" by name (candidates: {:?}); \
             name it in a robot profile's [roles] ({} = \"JOINT\", docs/link.md) and pass the profile as --robot",
            robot.name,
            hits,
            what.replace(' ', "_")
        )),
    }
}

/// Say on stderr which joints were guessed by name, once per robot and role set, so
/// a wrong guess is seen before an experiment's numbers are trusted.
fn say_guessed(robot: &Description, roles: &[&str], joints: &[String]) {
    use std::sync::Mutex;
    static SAID: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let list: Vec<String> = roles
        .iter()
        .zip(joints)
        .map(|(r, j)| format!("{r} = \"{j}\""))
        .collect();
    let key = format!("{}: {}", robot.name, list.join(", "));
    let mut said = SAID.lock().unwrap_or_else(|p| p.into_inner());
    if !said.contains(&key) {
        eprintln!(
            "note: \"{}\" has no [roles] for these joints; guessed by name: {} (name them in a robot profile to be sure)",
            robot.name,
            list.join(", ")
        );
        said.push(key);
    }
}

/// The hip roll joints (left, right): a profile's `[roles]`, else found by name
/// (`*hip*roll*` with a left/right prefix, said on stderr).
pub(crate) fn hip_roll_names(robot: &Description) -> Result<[String; 2], String> {
    let roles = ["left_hip_roll", "right_hip_roll"];
    if let [Some(l), Some(r)] = roles.map(|k| robot.roles.get(k)) {
        return Ok([l.to_string(), r.to_string()]);
    }
    let why = " (the sideways lean turns the hip rolls with the ankle rolls)";
    let found = [
        guess_joint(robot, &["hip", "roll"], true, "left hip roll").map_err(|e| e + why)?,
        guess_joint(robot, &["hip", "roll"], false, "right hip roll").map_err(|e| e + why)?,
    ];
    if twinloop_description::builtin::foot_geometry(&robot.name).is_none() {
        say_guessed(robot, &roles, &found);
    }
    Ok(found)
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

/// The joints and links the protocol turns and reads, found by name.
struct StudyJoints {
    /// Ankle pitch (left, right), ankle roll (left, right), foot links (left, right):
    /// [`ankle_names`].
    names: [String; 6],
    /// Joint indices (left, right) of the ankle pitches, ankle rolls and hip rolls.
    pitch: [usize; 2],
    roll: [usize; 2],
    hip: [usize; 2],
    hip_names: [String; 2],
    /// Description links of the feet (left, right).
    feet: [usize; 2],
}

/// Which sign of each joint pair leans the standing robot forward (ankle pitches) and
/// to the left (ankle rolls, hip rolls).
struct LeanSigns {
    forward: [f64; 2],
    left: [f64; 2],
    hip_left: [f64; 2],
}

/// One direction's run: the result of the run with the creep, the static tipping
/// angle at its onset, deg, and the rigid robot's, deg.
/// A run, its static angle and the rigid model's (NaN where there is none), and why
/// each is missing.
type DirectionRun = (TipoverResult, f64, f64, [Option<String>; 2]);

/// The simulator of the study: the robot's servos (stiffened to the protocol's
/// compliance), optionally its encoders, standing on the ground at the zero pose
/// (clamped to the limits), which is returned.
fn study_simulator(
    robot: &Description,
    opts: &StudyOptions,
) -> Result<(Simulator, Vec<f64>), IdentError> {
    let mass = twinloop_dynamics::Model::from_description(robot)
        .map_err(err)?
        .total_mass;
    let cfg = SimConfig {
        dt: opts.dt,
        contact: Some(ContactParams::for_robot(mass, 8, opts.ground_sink)),
        ..Default::default()
    };
    let (mut sim, standing) = Simulator::standing_on_datasheet_servos(robot, cfg).map_err(err)?;
    if !opts.servo_params.is_empty() {
        sim.apply_servo_params(&robot.name, &opts.servo_params, "--servo-params")
            .map_err(err)?;
    }
    if let Some((slope, margin)) = opts.compliance_units {
        for a in sim.actuators.iter_mut() {
            if let Actuator::Dynamixel(servo) = a {
                servo.compliance_slope = slope * twinloop_sim::actuator::RX_POSITION_UNIT;
                servo.compliance_margin = margin * twinloop_sim::actuator::RX_POSITION_UNIT;
            }
        }
    }
    if opts.dynamixel_encoders {
        sim.use_dynamixel_encoders();
    }
    // Placed again: the servos' goals follow the pose with their settings.
    sim.place_on_ground(&standing).map_err(err)?;
    Ok((sim, standing))
}

/// The ankle, hip roll and foot names of `robot` resolved in the simulator's model.
fn find_study_joints(robot: &Description, sim: &Simulator) -> Result<StudyJoints, IdentError> {
    let names = ankle_names(robot)?;
    let joint = |n: &str| {
        sim.joint_index(n)
            .ok_or_else(|| IdentError::new(format!("no joint \"{n}\" in \"{}\"", robot.name)))
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
            .ok_or_else(|| IdentError::new(format!("no foot link \"{n}\" in \"{}\"", robot.name)))
    };
    let feet = [link(&names[4])?, link(&names[5])?];
    let hip_names = hip_roll_names(robot)?;
    let (lh, rh) = (joint(&hip_names[0])?, joint(&hip_names[1])?);
    Ok(StudyJoints {
        names,
        pitch: [lp, rp],
        roll: [lr, rr],
        hip: [lh, rh],
        hip_names,
        feet,
    })
}

/// Each foot must have a collision primitive: the simulator makes contacts from boxes,
/// spheres, cylinders and capsules only, and a foot without one (a mesh sole, as in the
/// ROBOTIS OP3 URDF) stands on whatever else touches the floor, so the robot never
/// tips the way the protocol assumes.
fn feet_can_touch(robot: &Description, sim: &Simulator, j: &StudyJoints) -> Result<(), IdentError> {
    for &foot in &j.feet {
        // By body: a sole on a link welded to the foot counts.
        let body = sim.model.links[foot].body;
        if sim.contact_points().iter().any(|p| p.body == body) {
            continue;
        }
        let name = &sim.model.links[foot].name;
        let why = if sim.mesh_only_links.iter().any(|l| l == name) {
            "its collision shapes are meshes, which the simulator does not collide"
        } else {
            "it has no <collision> at all"
        };
        return Err(IdentError::new(format!(
            "foot link \"{name}\" of \"{}\" has no collision primitive: {why}; the tip-over \
             needs box (or sphere, cylinder, capsule) soles: add a <collision> box under each \
             foot, or use a description that has them (for the OP3: models/op3/mjcf/op3.xml)",
            robot.name
        )));
    }
    Ok(())
}

/// The feet the estimators assume: the seed's constants on the KM-20, a built-in
/// robot's own feet, or feet measured on the model; with a label saying which.
fn study_feet(
    robot: &Description,
    sim: &Simulator,
    j: &StudyJoints,
) -> (FootGeometry, SeedConstants, &'static str) {
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
            let f = measure_feet(sim, &j.names, j.feet);
            let c = SeedConstants::from_foot(&f);
            (f, c, "the robot's own feet (measured)")
        }
    }
}

/// The joints the protocol turns in direction `d`, with the sign that leans the robot
/// that way, and the lean's world direction: the static reference sweeps the same
/// joints from the onset.
fn turned_joints(
    d: Direction,
    j: &StudyJoints,
    s: &LeanSigns,
) -> (Vec<(usize, f64)>, Vector3<f64>) {
    let ([lp, rp], [lr, rr], [lh, rh]) = (j.pitch, j.roll, j.hip);
    let (fs, ls, hs) = (s.forward, s.left, s.hip_left);
    match d {
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
    }
}

/// Which feet the kinematics hold flat in direction `d`: sideways the one the robot
/// leans onto (the other unloads); forward and backward both stand, so both chains are
/// used and averaged (the legs give by slightly different amounts when the load is
/// off-centre, and one leg alone would read that as a tilt).
fn held_feet(d: Direction) -> &'static [usize] {
    match d {
        Direction::Left => &[0],
        Direction::Right => &[1],
        Direction::Forward | Direction::Backward => &[0, 1],
    }
}

/// The static tipping angles of one direction's run, deg: from the joint angles at the
/// onset with the feet as rolled as the IMU saw them (averaged over the held feet), and
/// the rigid robot's, from the standing pose with the feet flat.
fn static_tipping_angles(
    flat: &mut FlatFeet,
    data: &mut Data,
    r: &TipoverResult,
    standing: &[f64],
    helds: &[usize],
    turned: &[(usize, f64)],
    dir: Vector3<f64>,
) -> (f64, f64, [Option<String>; 2]) {
    let n_held = helds.len() as f64;
    let mut offset = 0.0;
    let mut notes = [None, None];
    for &h in helds {
        flat.held = h;
        flat.tilt = r.excess_deg.to_radians();
        match flat.tipping_angle(data, &r.positions_at_onset, turned, dir, -0.2, 0.2) {
            Ok(a) => offset += a.to_degrees() / n_held,
            Err(e) => {
                offset = f64::NAN;
                notes[0] = Some(format!("at the onset's posture: {e}"));
            }
        }
    }
    flat.held = helds[0];
    flat.tilt = 0.0;
    let rigid = match flat.tipping_angle(data, standing, turned, dir, 0.0, 1.2) {
        Ok(a) => a.to_degrees(),
        Err(e) => {
            notes[1] = Some(format!("standing, feet flat: {e}"));
            f64::NAN
        }
    };
    (offset, rigid, notes)
}

/// The standing robot as the static analysis holds it: the model, its contact points
/// and each foot's world placement with the robot placed standing.
struct StandingModel {
    model: twinloop_dynamics::Model,
    points: Vec<twinloop_sim::ContactPoint>,
    foot_world: [Se3; 2],
    feet: [usize; 2],
}

impl StandingModel {
    fn new(sim: &mut Simulator, standing: &[f64], j: &StudyJoints) -> Result<Self, IdentError> {
        sim.place_on_ground(standing).map_err(err)?;
        let mut place = |l: &str| {
            sim.link_placement(l)
                .ok_or_else(|| IdentError::new(format!("no link \"{l}\"")))
        };
        let foot_world = [place(&j.names[4])?, place(&j.names[5])?];
        Ok(StandingModel {
            model: sim.model.clone(),
            points: sim.contact_points().to_vec(),
            foot_world,
            feet: j.feet,
        })
    }

    /// The feet held flat at their standing places (the left one held, no roll).
    fn flat(&self) -> FlatFeet<'_> {
        FlatFeet {
            model: &self.model,
            feet: self.feet,
            points: &self.points,
            foot_world: self.foot_world,
            held: 0,
            tilt: 0.0,
        }
    }
}

fn lean_signs_of(model: &twinloop_dynamics::Model, j: &StudyJoints, q0: &[f64]) -> LeanSigns {
    let mut data = Data::new(model);
    LeanSigns {
        forward: lean_signs(model, &mut data, q0, j.pitch, Vector3::x()),
        left: lean_signs(model, &mut data, q0, j.roll, Vector3::y()),
        hip_left: hip_lean_signs(model, &mut data, q0, j.hip, Vector3::y()),
    }
}

/// Tips the robot over in all four directions, each twice: at the constant ramp (its
/// time to fall is seed 000's Table IV quantity), then up to half a degree before that
/// tip and on at a creep (see `TipoverConfig::slow_from_deg`). The second run's result,
/// with the first run's time to fall, per direction.
fn tip_all_directions(
    sim: &mut Simulator,
    standing: &[f64],
    j: &StudyJoints,
    q0: &[f64],
    opts: &StudyOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<TipoverResult>, IdentError> {
    let sm = StandingModel::new(sim, standing, j)?;
    let model = &sm.model;
    let mut flat = sm.flat();
    let signs = lean_signs_of(model, j, q0);
    let mut cfg = TipoverConfig::new(j.pitch, j.roll, signs.forward, signs.left);
    cfg.hip_roll = Some(j.hip);
    cfg.hip_left_sign = signs.hip_left;
    cfg.ramp_deg_per_s = opts.ramp_deg_per_s;
    let imu_link = sim.sensors().imu_link;
    let mut results = Vec::new();
    let mut pdata = Data::new(model);
    for d in Direction::ALL {
        let mut run = |cfg: &TipoverConfig, sim: &mut Simulator| {
            sim.place_on_ground(standing).map_err(err)?;
            let mut predict = |jq: &[f64]| flat_tilt(&mut flat, &mut pdata, jq, imu_link, d);
            run_direction(sim, standing, d, cfg, Some(&mut predict)).map_err(err)
        };
        progress(&format!("{}: ramp", d.name()));
        let first = run(&cfg, sim)?;
        let mut slow = cfg.clone();
        slow.slow_from_deg = Some((first.commanded_deg - 0.5).max(0.0));
        slow.slow_ramp_deg_per_s = opts.slow_ramp_deg_per_s;
        progress(&format!(
            "{}: creep from {:.1} deg",
            d.name(),
            slow.slow_from_deg.unwrap_or(0.0)
        ));
        let mut r = run(&slow, sim)?;
        r.time_s = first.time_s;
        results.push(r);
    }
    Ok(results)
}

/// Each run beside the model's static tipping angles (at its onset, and of the rigid
/// robot): `runs[k].positions_at_onset` are in the simulator's joint order.
fn with_static_references(
    sim: &mut Simulator,
    standing: &[f64],
    j: &StudyJoints,
    q0: &[f64],
    runs: Vec<TipoverResult>,
) -> Result<Vec<DirectionRun>, IdentError> {
    let sm = StandingModel::new(sim, standing, j)?;
    let mut flat = sm.flat();
    let signs = lean_signs_of(&sm.model, j, q0);
    let mut data = Data::new(&sm.model);
    let mut out = Vec::with_capacity(runs.len());
    for r in runs {
        let (turned, dir) = turned_joints(r.direction, j, &signs);
        let (offset, rigid, notes) = static_tipping_angles(
            &mut flat,
            &mut data,
            &r,
            standing,
            held_feet(r.direction),
            &turned,
            dir,
        );
        let s = r.measured_deg + offset;
        out.push((r, s, rigid, notes));
    }
    Ok(out)
}

/// The CoM by the two estimators from the measured angles, next to the model's true
/// CoM, and the feet's mass the exact method used.
fn estimate_com(
    results: &[DirectionRun],
    model: &twinloop_dynamics::Model,
    q0: &[f64],
    j: &StudyJoints,
    foot: &FootGeometry,
    seed_constants: &SeedConstants,
) -> Result<(ComReport, crate::tipover::FeetMass), IdentError> {
    let names = &j.names;
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
        seed_constants,
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
    let feet = feet_mass(model, q0, [&names[0], &names[1]]).map_err(err)?;
    let exact = exact_method(&angles, &feet, foot).map_err(err)?;
    let lever = frontal_lever(
        model,
        q0,
        [&j.hip_names[0], &j.hip_names[1]],
        [&names[2], &names[3]],
    )
    .map_err(err)?;
    let truth =
        twinloop_reduced::com_relative_to_ankles(model, q0, &names[0], &names[1]).map_err(err)?;
    let dist = |a: [f64; 3]| {
        ((a[0] - truth[0]).powi(2) + (a[1] - truth[1]).powi(2) + (a[2] - truth[2]).powi(2)).sqrt()
    };
    let com = ComReport {
        truth,
        seed_method: seed.com,
        exact_method: exact.com,
        seed_error: dist(seed.com),
        exact_error: dist(exact.com),
        frontal_lever_true: lever.sin,
        frontal_lever_exact: exact.frontal_lever,
    };
    Ok((com, feet))
}

fn direction_report(results: &[DirectionRun], d: Direction, names: &[String]) -> DirectionReport {
    let (r, s, rigid, notes) = results
        .iter()
        .find(|r| r.0.direction == d)
        .expect("all four ran");
    DirectionReport {
        onset_positions: names
            .iter()
            .cloned()
            .zip(r.positions_at_onset.iter().copied())
            .collect(),
        commanded_deg: r.commanded_deg,
        measured_deg: r.measured_deg,
        time_s: r.time_s,
        static_deg: *s,
        static_note: notes[0].clone(),
        rigid_static_deg: *rigid,
        rigid_static_note: notes[1].clone(),
        lean_deg: r.lean_deg,
        excess_deg: r.excess_deg,
    }
}

/// The study's simulator and what the estimators need of the model.
struct Prepared {
    sim: Simulator,
    standing: Vec<f64>,
    j: StudyJoints,
    foot: FootGeometry,
    seed_constants: SeedConstants,
    label: &'static str,
    q0: Vec<f64>,
}

fn prepare(robot: &Description, opts: &StudyOptions) -> Result<Prepared, IdentError> {
    let (mut sim, standing) = study_simulator(robot, opts)?;
    let j = find_study_joints(robot, &sim)?;
    let sim_feet: Vec<&str> = vec![j.names[4].as_str(), j.names[5].as_str()];
    sim.set_feet(&sim_feet).map_err(err)?;
    feet_can_touch(robot, &sim, &j)?;
    let (foot, seed_constants, label) = study_feet(robot, &sim, &j);
    let mut q0 = sim.model.neutral_configuration();
    q0[sim.model.q_offset..].copy_from_slice(&standing);
    Ok(Prepared {
        sim,
        standing,
        j,
        foot,
        seed_constants,
        label,
        q0,
    })
}

/// Run the study on `robot` (a built-in robot gets its own servos and foot data).
pub fn run_study(robot: &Description, opts: &StudyOptions) -> Result<StudyReport, IdentError> {
    run_study_with_progress(robot, opts, &mut |_| {})
}

/// The simulated tip-overs the study makes: four directions, each a ramp and a creep.
pub const STUDY_RUNS: usize = 8;

/// [`run_study`], calling `progress` before each of its [`STUDY_RUNS`] simulated
/// tip-overs with what it starts ("forward: ramp", "forward: creep from 7.4 deg").
pub fn run_study_with_progress(
    robot: &Description,
    opts: &StudyOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<StudyReport, IdentError> {
    let mut p = prepare(robot, opts)?;
    let runs = tip_all_directions(&mut p.sim, &p.standing, &p.j, &p.q0, opts, progress)?;
    let results = with_static_references(&mut p.sim, &p.standing, &p.j, &p.q0, runs)?;
    assemble(robot, &p, &results)
}

/// The study's report for runs made outside the simulator (a robot over its bus, one
/// result per direction, in any order): the same JSON as [`run_study`], the static
/// references and CoM estimates from `robot`'s model. `joint_names` orders the
/// results' `positions_at_onset`. `com.true` is then the model's CoM, not the robot's:
/// the comparison `adapt` makes.
pub fn report_for_runs(
    robot: &Description,
    runs: &[TipoverResult],
    joint_names: &[String],
) -> Result<StudyReport, IdentError> {
    let mut p = prepare(robot, &StudyOptions::default())?;
    let mut ordered = Vec::with_capacity(4);
    for d in Direction::ALL {
        let Some(r) = runs.iter().find(|r| r.direction == d) else {
            return Err(IdentError::new(format!(
                "no {} run: the CoM needs all four directions",
                d.name()
            )));
        };
        let mut r = r.clone();
        let mut q = p.standing.clone();
        for (name, &v) in joint_names.iter().zip(&r.positions_at_onset) {
            if let Some(i) = p.sim.joint_index(name) {
                q[i] = v;
            }
        }
        r.positions_at_onset = q;
        ordered.push(r);
    }
    let results = with_static_references(&mut p.sim, &p.standing, &p.j, &p.q0, ordered)?;
    assemble(robot, &p, &results)
}

/// `robot`'s static tipping angle in each direction (forward, backward, left, right;
/// deg) at the postures and feet rolls the robot had at its onsets in `report`: the
/// angles this model says the robot should have measured (`static_deg` of a report
/// made with this model). Needs the report's `onset_positions`.
pub fn static_angles_at_onsets(
    robot: &Description,
    report: &StudyReport,
) -> Result<[f64; 4], IdentError> {
    report.check_onset_joints(robot)?;
    let mut p = prepare(robot, &StudyOptions::default())?;
    let mut runs = Vec::with_capacity(4);
    for d in Direction::ALL {
        let r = report.direction(d);
        if r.onset_positions.is_empty() {
            return Err(IdentError::new(format!(
                "the {} run has no onset_positions (a tip-over file from before they were kept)",
                d.name()
            )));
        }
        let mut q = p.standing.clone();
        for (name, &v) in &r.onset_positions {
            if let Some(i) = p.sim.joint_index(name) {
                q[i] = v;
            }
        }
        runs.push(TipoverResult {
            direction: d,
            commanded_deg: r.commanded_deg,
            measured_deg: r.measured_deg,
            time_s: r.time_s,
            excess_deg: r.excess_deg,
            lean_deg: r.lean_deg,
            fall_confirmed_s: r.time_s,
            positions_at_onset: q,
        });
    }
    let results = with_static_references(&mut p.sim, &p.standing, &p.j, &p.q0, runs)?;
    let mut out = [0.0; 4];
    for (k, (_, s, _, _)) in results.iter().enumerate() {
        out[k] = *s;
    }
    Ok(out)
}

impl StudyReport {
    /// Every joint an onset posture names must be a joint of `robot`: the posture is
    /// where the robot stood when it tipped, and a joint left out (a misspelt or
    /// another robot's name) would be taken at its standing angle, giving angles that
    /// match nothing (issue 29, class 3). The error names the direction, the joint and
    /// the nearest of the robot's joints.
    pub fn check_onset_joints(&self, robot: &Description) -> Result<(), IdentError> {
        let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
        for d in Direction::ALL {
            let r = self.direction(d);
            for (name, v) in &r.onset_positions {
                let field = format!("{}.onset_positions.{name}", d.name());
                if robot.joint(name).is_none() {
                    return Err(IdentError::new(format!(
                        "\"{name}\" is not a joint of \"{}\"; did you mean {}?",
                        robot.name,
                        twinloop_io::nearest(name, &names, 3).join(", ")
                    ))
                    .field(field));
                }
                if !v.is_finite() {
                    return Err(IdentError::new(format!("{v} is not an angle")).field(field));
                }
            }
        }
        Ok(())
    }

    /// Refuse a report whose measured tip angles cannot be tip angles: each is in
    /// (0, 90) degrees (a robot standing on its feet tips before lying flat). Checked
    /// where a file is read, so the error names its field (`forward.measured_deg`),
    /// in degrees as the file gives it; the caller adds the file.
    pub fn check_measured(&self) -> Result<(), IdentError> {
        for d in Direction::ALL {
            let v = self.direction(d).measured_deg;
            if !(v.is_finite() && v > 0.0 && v < 90.0) {
                return Err(IdentError::new(format!(
                    "{} deg is not a tip angle: a robot tips between 0 and 90 deg",
                    twinloop_report::number(v)
                ))
                .field(format!("{}.measured_deg", d.name())));
            }
        }
        Ok(())
    }

    /// One direction's outcome.
    pub fn direction(&self, d: Direction) -> &DirectionReport {
        match d {
            Direction::Forward => &self.forward,
            Direction::Backward => &self.backward,
            Direction::Left => &self.left,
            Direction::Right => &self.right,
        }
    }
}

fn assemble(
    robot: &Description,
    p: &Prepared,
    results: &[DirectionRun],
) -> Result<StudyReport, IdentError> {
    let (com, feet) = estimate_com(
        results,
        &p.sim.model,
        &p.q0,
        &p.j,
        &p.foot,
        &p.seed_constants,
    )?;
    let foot = &p.foot;
    let names = p.sim.joint_names();
    Ok(StudyReport {
        robot: robot.name.clone(),
        forward: direction_report(results, Direction::Forward, names),
        backward: direction_report(results, Direction::Backward, names),
        left: direction_report(results, Direction::Left, names),
        right: direction_report(results, Direction::Right, names),
        com,
        seed_constants: p.label.to_string(),
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
        protocol: None,
        bus: None,
    })
}

/// The model's prediction of the trunk IMU's tilt from the measured joint angles with
/// the feet flat: the reference the tip-over compares the IMU with, for a robot over
/// its bus (the study's simulator predicts the same way). Joint positions come in the
/// robot's order (`joint_names`), joints the model lacks stay at the standing pose.
pub struct TiltModel {
    standing: StandingModel,
    imu_link: usize,
    data: Data,
    /// Model joint of each of the robot's joints.
    index: Vec<Option<usize>>,
    /// Joint positions in the model's order (sized once).
    q: Vec<f64>,
}

impl TiltModel {
    /// `imu_link`: the link the IMU is on (a `[[board]]`'s `link`).
    pub fn new(
        robot: &Description,
        joint_names: &[String],
        imu_link: &str,
    ) -> Result<TiltModel, IdentError> {
        let mut p = prepare(robot, &StudyOptions::default())?;
        let standing = StandingModel::new(&mut p.sim, &p.standing, &p.j)?;
        let imu = standing
            .model
            .links
            .iter()
            .position(|l| l.name == imu_link)
            .ok_or_else(|| {
                IdentError::new(format!(
                    "no link \"{imu_link}\" (the IMU's) in \"{}\"",
                    robot.name
                ))
            })?;
        Ok(TiltModel {
            imu_link: imu,
            data: Data::new(&standing.model),
            index: joint_names.iter().map(|n| p.sim.joint_index(n)).collect(),
            q: p.standing.clone(),
            standing,
        })
    }

    /// Trunk pitch and roll (rad; forward and left positive) with the feet flat, the
    /// foot the robot leans onto held (both averaged leaning forward or backward).
    pub fn predict(&mut self, direction: Direction, positions: &[f64]) -> [f64; 2] {
        for (k, &v) in positions.iter().enumerate() {
            if let Some(Some(i)) = self.index.get(k) {
                self.q[*i] = v;
            }
        }
        let mut flat = self.standing.flat();
        flat_tilt(&mut flat, &mut self.data, &self.q, self.imu_link, direction)
    }
}

/// The IMU link's tilt with the feet flat, the foot the robot leans onto held (both,
/// averaged, leaning forward or backward; see [`held_feet`]).
fn flat_tilt(
    flat: &mut FlatFeet,
    data: &mut Data,
    q: &[f64],
    imu_link: usize,
    direction: Direction,
) -> [f64; 2] {
    let helds = held_feet(direction);
    let mut t = [0.0; 2];
    for &h in helds {
        flat.held = h;
        let x = flat.link_tilt(data, q, imu_link);
        t[0] += x[0] / helds.len() as f64;
        t[1] += x[1] / helds.len() as f64;
    }
    t
}

/// The protocol's configuration for a robot whose joints come in `joint_names` order (a
/// bus mapping's): the study's joints (ankle pitches and rolls, hip rolls) and lean
/// signs, from `robot`'s model, at `ramp_deg_per_s`.
pub fn tipover_config(
    robot: &Description,
    joint_names: &[String],
    ramp_deg_per_s: f64,
) -> Result<TipoverConfig, IdentError> {
    let p = prepare(robot, &StudyOptions::default())?;
    let model = &p.sim.model;
    let signs = lean_signs_of(model, &p.j, &p.q0);
    let at = |pair: [usize; 2]| -> Result<[usize; 2], IdentError> {
        let one = |i: usize| {
            let n = &model.joint_names[i];
            joint_names.iter().position(|x| x == n).ok_or_else(|| {
                IdentError::new(format!(
                    "no servo drives joint \"{n}\" (the tip-over turns it)"
                ))
            })
        };
        Ok([one(pair[0])?, one(pair[1])?])
    };
    let mut cfg = TipoverConfig::new(at(p.j.pitch)?, at(p.j.roll)?, signs.forward, signs.left);
    cfg.hip_roll = Some(at(p.j.hip)?);
    cfg.hip_left_sign = signs.hip_left;
    cfg.ramp_deg_per_s = ramp_deg_per_s;
    Ok(cfg)
}

#[cfg(test)]
mod onset_tests {
    use super::*;

    /// Issue 29, class 3: an onset posture naming a joint the robot lacks is refused
    /// with the direction, the name and the joint meant.
    #[test]
    fn an_onset_posture_naming_an_unknown_joint_is_refused() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../twinloop-cli/tests/data/bus_tipover_seed1.json"
        );
        let text = std::fs::read_to_string(path).unwrap();
        let km20 = twinloop_description::builtin::resolve("builtin:km20").unwrap();
        let tip: StudyReport = serde_json::from_str(&text).unwrap();
        tip.check_onset_joints(&km20).unwrap();
        let typo: StudyReport =
            serde_json::from_str(&text.replace("\"l_knee\"", "\"l_kne\"")).unwrap();
        let e = typo.check_onset_joints(&km20).unwrap_err().to_string();
        assert!(
            e.contains("forward.onset_positions.l_kne") && e.contains("did you mean l_knee"),
            "{e}"
        );
    }
}
