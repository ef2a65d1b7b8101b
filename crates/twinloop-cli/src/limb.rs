//! The load a servo turns when it moves one limb of a held robot: the subtree of
//! links beyond its joint, with the robot's base fixed (gravity's direction in the
//! base frame measured by the trunk's IMU board where the mapping has one, else the
//! trunk assumed upright: gravity along the base frame's -z) and every other joint
//! held at the pose read when the experiment began.
//!
//! Held so, the subtree is one rigid body turning about a fixed axis: its inertia
//! about the axis is a constant (the mass matrix's diagonal entry, CRBA, without the
//! joint's own armature: the servo's is fitted), and gravity's torque is exactly
//! `A sin q + B cos q` (twinloop_actuator::load). It is computed from the
//! description (RNEA's generalised gravity at twelve angles around the circle,
//! fitted by least squares; the fit's residual is the check, rounding only), and
//! expressed at the servo (servo angle = zero + direction x joint angle, torque
//! times direction).
//!
//! An `experiment servo` log of a limb carries what rebuilds it, in comment lines
//! after its first:
//!
//! ```text
//! # limb: robot builtin:km20
//! # limb: joint r_hip_pitch zero 0 direction 1
//! # limb: gravity 0 0 -9.81 (base frame, m/s^2; trunk assumed upright: no IMU board)
//! # limb: pose l_hip_yaw 0 l_hip_roll 0.0031 ... (every joint, rad)
//! # limb: load inertia 0.0123 gravity_sin -0.71 gravity_cos 0.002 gravity_const 0
//! ```
//!
//! (the last line as computed when recorded, for a reader; `identify servo`
//! recomputes it from the robot, joint and pose).

use crate::common::{hinges_only, load_description};
use crate::error::CliError;
use std::fmt::Write as _;
use twinloop_actuator::Load;
use twinloop_description::Description;
use twinloop_dynamics::{BaseKind, Data, Model, crba, generalized_gravity};

/// What a log says of its limb.
#[derive(Debug, Clone, PartialEq)]
pub struct Limb {
    /// The description: a file path or builtin:NAME.
    pub robot: String,
    pub joint: String,
    /// Servo angle (rad) at joint angle 0, and +1 or -1 (the mapping's).
    pub zero: f64,
    pub direction: f64,
    /// Every joint of the robot and its angle in the held pose, rad.
    pub pose: Vec<(String, f64)>,
    /// Gravity in the base (trunk) frame, m/s^2.
    pub gravity: [f64; 3],
    /// Where `gravity` comes from (words for the log).
    pub trunk: String,
}

const PREFIX: &str = "# limb: ";
/// Gravity in the base frame of an upright trunk, m/s^2.
pub const UPRIGHT: [f64; 3] = [0.0, 0.0, -twinloop_description::GRAVITY];
/// Angles around the circle at which gravity's torque is computed.
const SAMPLES: usize = 12;

impl Limb {
    /// The load at the servo and the RMS (N m) left by the gravity fit.
    pub fn load(&self, robot: &Description) -> Result<(Load, f64), CliError> {
        hinges_only(robot, &self.robot, "a limb load")?;
        let mut model = Model::from_description_with_base(robot, BaseKind::Fixed)
            .map_err(|e| CliError::new(format!("{}: {e}", self.robot)))?;
        model.gravity = nalgebra::Vector3::from(self.gravity);
        let j = model.joint_index(&self.joint).ok_or_else(|| {
            CliError::new(format!(
                "joint \"{}\" is not a joint of {} (its joints: {})",
                self.joint,
                self.robot,
                model.joint_names.join(", ")
            ))
        })?;
        let mut q = vec![0.0; model.nq];
        for (name, angle) in &self.pose {
            let k = model.joint_index(name).ok_or_else(|| {
                CliError::new(format!(
                    "held pose: \"{name}\" is not a joint of {}",
                    self.robot
                ))
            })?;
            q[model.idx_q[k]] = *angle;
        }
        let (iq, iv) = (model.idx_q[j], model.idx_v[j]);
        let mut data = Data::new(&model);
        let inertia = crba(&model, &mut data, &q)[(iv, iv)] - model.armature[j];
        let mut angles = [0.0; SAMPLES];
        let mut torques = [0.0; SAMPLES];
        for k in 0..SAMPLES {
            let servo = std::f64::consts::TAU * k as f64 / SAMPLES as f64 - std::f64::consts::PI;
            q[iq] = self.direction * (servo - self.zero);
            // g(q) holds the limb up; gravity's own torque is its negative.
            let tau_joint = -generalized_gravity(&model, &mut data, &q)[iv];
            angles[k] = servo;
            torques[k] = self.direction * tau_joint;
        }
        Load::fit_gravity(inertia, &angles, &torques)
            .ok_or_else(|| CliError::new("the limb's gravity torque could not be fitted"))
    }

    /// The comment lines a log carries (each ending in a newline), the load as
    /// computed now last.
    pub fn header(&self, load: &Load) -> String {
        let mut s = format!("{PREFIX}robot {}\n", self.robot);
        let _ = writeln!(
            s,
            "{PREFIX}joint {} zero {} direction {}",
            self.joint, self.zero, self.direction
        );
        let g = self.gravity;
        let _ = writeln!(
            s,
            "{PREFIX}gravity {} {} {} (base frame, m/s^2; {})",
            g[0], g[1], g[2], self.trunk
        );
        s.push_str(PREFIX);
        s.push_str("pose");
        for (name, angle) in &self.pose {
            let _ = write!(s, " {name} {angle}");
        }
        s.push('\n');
        let _ = writeln!(
            s,
            "{PREFIX}load inertia {} gravity_sin {} gravity_cos {} gravity_const {}",
            load.inertia, load.gravity_sin, load.gravity_cos, load.gravity_const
        );
        s
    }

    /// The limb of a log's comment lines; `None` if it has none (a bench log).
    pub fn from_log(text: &str, file: &str) -> Result<Option<Limb>, CliError> {
        let mut robot = None;
        let mut joint = None;
        let mut pose = None;
        let mut gravity = None;
        for (n, line) in text.lines().enumerate() {
            if !line.starts_with('#') {
                break;
            }
            let Some(rest) = line.strip_prefix(PREFIX) else {
                continue;
            };
            let bad = |what: &str| CliError::new(format!("{file}: line {}: {what}", n + 1));
            let (key, value) = rest.split_once(' ').unwrap_or((rest, ""));
            match key {
                "robot" => robot = Some(value.trim().to_string()),
                "joint" => {
                    let w: Vec<&str> = value.split_whitespace().collect();
                    let num = |k: usize| -> Result<f64, CliError> {
                        w.get(k)
                            .and_then(|x| x.parse::<f64>().ok())
                            .filter(|x| x.is_finite())
                            .ok_or_else(|| bad("expected \"joint NAME zero RAD direction 1|-1\""))
                    };
                    if w.len() < 5 || w[1] != "zero" || w[3] != "direction" {
                        return Err(bad("expected \"joint NAME zero RAD direction 1|-1\""));
                    }
                    let direction = num(4)?;
                    if direction != 1.0 && direction != -1.0 {
                        return Err(bad("direction must be 1 or -1"));
                    }
                    joint = Some((w[0].to_string(), num(2)?, direction));
                }
                "gravity" => {
                    let (numbers, trunk) = value.split_once('(').unwrap_or((value, ""));
                    let g: Vec<f64> = numbers
                        .split_whitespace()
                        .map(|x| x.parse::<f64>().ok().filter(|x| x.is_finite()))
                        .collect::<Option<_>>()
                        .filter(|g: &Vec<f64>| g.len() == 3)
                        .ok_or_else(|| bad("expected \"gravity GX GY GZ\" (m/s^2)"))?;
                    let trunk = trunk.trim_end().strip_suffix(')').unwrap_or(trunk);
                    let trunk = trunk.rsplit_once("; ").map_or(trunk, |t| t.1);
                    gravity = Some(([g[0], g[1], g[2]], trunk.to_string()));
                }
                "pose" => {
                    let w: Vec<&str> = value.split_whitespace().collect();
                    if !w.len().is_multiple_of(2) {
                        return Err(bad("pose: expected pairs \"JOINT RAD\""));
                    }
                    let mut p = Vec::with_capacity(w.len() / 2);
                    for pair in w.chunks(2) {
                        let a = pair[1]
                            .parse::<f64>()
                            .ok()
                            .filter(|x| x.is_finite())
                            .ok_or_else(|| bad(&format!("pose: {:?} is not an angle", pair[1])))?;
                        p.push((pair[0].to_string(), a));
                    }
                    pose = Some(p);
                }
                _ => {}
            }
        }
        match (robot, joint, pose, gravity) {
            (None, None, None, None) => Ok(None),
            (Some(robot), Some((joint, zero, direction)), Some(pose), Some((gravity, trunk))) => {
                Ok(Some(Limb {
                    robot,
                    joint,
                    zero,
                    direction,
                    pose,
                    gravity,
                    trunk,
                }))
            }
            _ => Err(CliError::new(format!(
                "{file}: the limb's comment lines need \"robot\", \"joint\", \"gravity\" and \"pose\" (written by experiment servo --map --joint)"
            ))),
        }
    }

    /// [`Limb::load`] of the description `self.robot` (or `robot`, overriding it).
    pub fn load_from(&self, robot: Option<&str>) -> Result<(Load, f64), CliError> {
        let spec = robot.unwrap_or(&self.robot);
        let (description, _) = load_description(spec)?;
        self.load(&description)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use twinloop_dynamics::forward_kinematics;

    /// The subtree beyond r_hip_pitch of km20, trunk tilted, knee bent: gravity's
    /// torque is `(c - p) x m g` about the axis, with `r` the
    /// subtree's centre of mass (from the links' own placements, not RNEA).
    #[test]
    fn km20_hip_pitch_load_matches_the_subtree_com() {
        let robot = twinloop_description::builtin::builtin("km20").unwrap();
        let joint = "r_hip_pitch";
        let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
        let pose: Vec<(String, f64)> = model
            .joint_names
            .iter()
            .map(|n| (n.clone(), if n == "r_knee" { 0.4 } else { 0.0 }))
            .collect();
        let limb = Limb {
            robot: "builtin:km20".into(),
            joint: joint.into(),
            zero: 0.1,
            direction: -1.0,
            pose: pose.clone(),
            // The trunk pitched 10 deg and rolled 4: gravity off the base's -z.
            gravity: {
                let (p, r) = (10f64.to_radians(), 4f64.to_radians());
                let g = twinloop_description::GRAVITY;
                [g * p.sin(), -g * p.cos() * r.sin(), -g * p.cos() * r.cos()]
            },
            trunk: "test".into(),
        };
        let (load, rms) = limb.load(&robot).unwrap();
        assert!(rms < 1e-12, "{rms}");
        assert!(load.gravity_const.abs() < 1e-12, "{load:?}");
        // Independent: the subtree's mass and CoM from the bodies' placements.
        let j = model.joint_index(joint).unwrap();
        let mut q = vec![0.0; model.nq];
        for (n, a) in &pose {
            q[model.idx_q[model.joint_index(n).unwrap()]] = *a;
        }
        let jq = 0.3;
        q[model.idx_q[j]] = jq;
        let mut data = Data::new(&model);
        forward_kinematics(&model, &mut data, &q);
        let (mut m, mut mc) = (0.0, nalgebra::Vector3::zeros());
        for b in j..model.subtree_end[j] {
            let i = &model.inertias[b];
            let c = data.o_m_i[b].act_point(&i.com);
            m += i.mass;
            mc += i.mass * c;
        }
        let c = mc / m;
        let axis = data.o_m_i[j].rotation * model.axes[j];
        let p = data.o_m_i[j].translation;
        let gravity = m * nalgebra::Vector3::from(limb.gravity);
        let tau_joint = axis.dot(&(c - p).cross(&gravity));
        let servo = limb.zero + limb.direction * jq;
        let tau_servo = limb.direction * tau_joint;
        assert!(
            (load.gravity_torque(servo) - tau_servo).abs() < 1e-10,
            "{} vs {tau_servo}",
            load.gravity_torque(servo)
        );
        assert!(load.inertia > 0.0);
    }

    #[test]
    fn header_reads_back() {
        let limb = Limb {
            robot: "builtin:km20".into(),
            joint: "r_knee".into(),
            zero: -0.25,
            direction: -1.0,
            pose: vec![("a".into(), 0.125), ("b".into(), -1.5)],
            gravity: [0.5, -0.25, -9.7],
            trunk: "from board \"trunk_imu\" (id 200)".into(),
        };
        let load = Load {
            inertia: 1.0,
            gravity_sin: 2.0,
            gravity_cos: 3.0,
            gravity_const: 0.0,
        };
        let text = format!(
            "# twinloop experiment servo: RX-28 id 3 on x\n{}t,goal\n",
            limb.header(&load)
        );
        assert_eq!(Limb::from_log(&text, "f").unwrap(), Some(limb));
        assert_eq!(Limb::from_log("# x\nt\n", "f").unwrap(), None);
    }
}
