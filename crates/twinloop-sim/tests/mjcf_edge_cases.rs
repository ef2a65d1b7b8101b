//! The simulator on the MJCF edge cases of issue 30
//! (crates/twinloop-description/tests/data/mjcf/edges, MuJoCo's numbers in its
//! reference/edges, written by make_reference.py with MuJoCo 4).

use serde_json::Value;
use std::path::PathBuf;
use twinloop_dynamics::{BaseKind, Model};
use twinloop_sim::*;

fn edges() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../twinloop-description/tests/data/mjcf")
}

fn load(name: &str) -> twinloop_description::Description {
    twinloop_description::load(edges().join("edges").join(format!("{name}.xml"))).unwrap()
}

fn reference(name: &str) -> Value {
    let path = edges().join("reference/edges").join(format!("{name}.json"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Item 3: Cassie-like leaf springs (stiffness 1500 N m/rad about springref 0.2 rad,
/// and 40 about 0) with damping act as MuJoCo's `qfrc_passive` at its three random
/// states, to 1e-12; armature and frictionloss are modelled too (mass matrix, stick
/// friction), and the motors' force limits are MuJoCo's clamped actuator forces.
#[test]
fn joint_springs_and_actuator_limits_match_mujoco() {
    let robot = load("joint_springs");
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    let config = SimConfig {
        ground: false,
        ..SimConfig::default()
    };
    let sim = Simulator::from_model(&robot, model, config).unwrap();
    let refd = reference("joint_springs");
    for state in refd["states"].as_array().unwrap() {
        let (q, v, passive) = (
            numbers(&state["qpos"]),
            numbers(&state["qvel"]),
            numbers(&state["passive"]),
        );
        for i in 0..2 {
            let ours = sim.passive_torque(i, q[i], v[i]);
            assert!(
                (ours - passive[i]).abs() <= 1e-12 * passive[i].abs().max(1.0),
                "joint {i}: {ours} vs MuJoCo's {}",
                passive[i]
            );
        }
    }
    assert_eq!(sim.joint_friction, [0.0, 0.3]);
    assert_eq!(sim.model.armature, [0.01, 0.0]);
    assert_eq!(
        sim.model.effort_limits,
        numbers(&refd["saturated_actuator_force"])
    );
}

/// Item 4: Apollo-like soles that touch the floor only through `<contact><pair>`
/// (every geom contype=0 conaffinity=0) collide: the robot stands on them, its
/// lowest points the sole boxes' bottoms, 0.2 + 0.34 + 0.02 m below the base.
/// Without the pairs, the refusal says why instead of listing no links.
#[test]
fn pair_only_soles_stand_and_without_pairs_the_refusal_says_why() {
    let robot = load("pair_only_contacts");
    let mut sim = Simulator::new(&robot, SimConfig::default()).unwrap();
    sim.check_can_stand().unwrap();
    sim.place_on_ground(&[0.0; 4]).unwrap();
    let links: std::collections::BTreeSet<&str> = sim
        .contact_points()
        .iter()
        .map(|p| robot.links[p.link].name.as_str())
        .collect();
    assert_eq!(
        links.into_iter().collect::<Vec<_>>(),
        ["left_foot", "right_foot"]
    );
    assert!((sim.q[2] - 0.56).abs() < 1e-12, "base height {}", sim.q[2]);

    let text = std::fs::read_to_string(edges().join("edges/pair_only_contacts.xml")).unwrap();
    let start = text.rfind("<contact>").unwrap();
    let end = text.find("</contact>").unwrap() + "</contact>".len();
    let unpaired = format!("{}{}", &text[..start], &text[end..]);
    let robot = twinloop_description::mjcf::from_str(&unpaired).unwrap();
    let e = Simulator::new(&robot, SimConfig::default())
        .unwrap()
        .check_can_stand()
        .unwrap_err()
        .to_string();
    assert!(!e.contains("mesh-only links: )"), "{e}");
    assert!(e.contains("<contact><pair>"), "{e}");
}

/// Item 3 on a Menagerie humanoid: Unitree H1's `<motor ctrlrange>`s (gear 1) give every
/// joint the effort limit where MuJoCo saturates it (its `qfrc_actuator` with every
/// control at 1e6, MuJoCo 4.0.1, the mesh geoms removed: they carry no actuator),
/// where "actuator saturation is unknown" was said before.
#[test]
fn h1_motors_give_mujocos_saturation_as_effort_limits() {
    let mujoco: [(&str, f64); 19] = [
        ("left_hip_yaw", 200.0),
        ("left_hip_roll", 200.0),
        ("left_hip_pitch", 200.0),
        ("left_knee", 300.0),
        ("left_ankle", 40.0),
        ("right_hip_yaw", 200.0),
        ("right_hip_roll", 200.0),
        ("right_hip_pitch", 200.0),
        ("right_knee", 300.0),
        ("right_ankle", 40.0),
        ("torso", 200.0),
        ("left_shoulder_pitch", 40.0),
        ("left_shoulder_roll", 40.0),
        ("left_shoulder_yaw", 18.0),
        ("left_elbow", 18.0),
        ("right_shoulder_pitch", 40.0),
        ("right_shoulder_roll", 40.0),
        ("right_shoulder_yaw", 18.0),
        ("right_elbow", 18.0),
    ];
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models/unitree_h1/mjcf/h1_menagerie.xml");
    let robot = twinloop_description::load(path).unwrap();
    let model = Model::from_description(&robot).unwrap();
    for (name, effort) in mujoco {
        let i = model.joint_index(name).unwrap();
        assert_eq!(model.effort_limits[i], effort, "{name}");
    }
    let lint = twinloop_description::lint::lint(&robot);
    assert!(
        !format!("{lint:?}").contains("saturation is unknown"),
        "{lint:?}"
    );
}

/// The Menagerie humanoids' reference numbers (MuJoCo 4.0.1, written by
/// tools/oracle/robot_mjcf_reference.py), by the file's name.
fn menagerie(name: &str) -> (twinloop_description::Description, Value) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let json = dir.join(format!(
        "../twinloop-dynamics/tests/data/mujoco_models/{name}.json"
    ));
    let refd: Value = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    let xml = dir
        .join("../..")
        .join(refd["source_file"].as_str().unwrap());
    (twinloop_description::load(xml).unwrap(), refd)
}

/// Items 3 on the real files: Cassie's leaf springs (`stiffness` 1500 and 1250 N m/rad),
/// every hinge's damping and its ball joints' damping are MuJoCo's `qfrc_passive` at
/// its three seeded states (root held), to 1e-12.
#[test]
fn cassie_springs_and_dampers_are_mujocos_passive_forces() {
    let (robot, refd) = menagerie("agility_cassie_cassie");
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    let config = SimConfig {
        ground: false,
        ..SimConfig::default()
    };
    let sim = Simulator::from_model(&robot, model, config).unwrap();
    let (mut springs, mut balls) = (0, 0);
    for state in refd["states"].as_array().unwrap() {
        let (q, v, passive) = (
            numbers(&state["qpos"]),
            numbers(&state["qvel"]),
            numbers(&state["passive"]),
        );
        assert_eq!(passive.len(), sim.model.nv, "fixed-root state");
        for (i, name) in sim.model.joint_names.iter().enumerate() {
            let (iq, iv) = (sim.model.idx_q[i], sim.model.idx_v[i]);
            let (ours, theirs): (Vec<f64>, &[f64]) = if sim.model.joint_types[i].nv() == 3 {
                balls += 1;
                let c = sim.joint_damping[i];
                (
                    (iv..iv + 3).map(|k| -c * v[k]).collect(),
                    &passive[iv..iv + 3],
                )
            } else {
                springs += usize::from(sim.joint_stiffness[i] > 0.0);
                (
                    vec![sim.passive_torque(i, q[iq], v[iv])],
                    &passive[iv..iv + 1],
                )
            };
            for (a, b) in ours.iter().zip(theirs) {
                assert!(
                    (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                    "{name}: {a} vs MuJoCo's {b}"
                );
            }
        }
    }
    assert_eq!((springs, balls), (3 * 4, 3 * 2));
}

/// Item 3 on the real files: every Menagerie humanoid's actuators (Cassie's geared
/// motors, Apollo's position actuators with `forcerange`, T1's joints'
/// `actuatorfrcrange`, Open Duck Mini v2's default-class `<position forcerange>`, ...) give each joint the effort limit MuJoCo clamps its
/// actuator force to (`actuator_force_limit` of robot_mjcf_reference.py); a joint
/// no actuator drives has none (MuJoCo's 0, twinloop's infinity).
#[test]
fn menagerie_actuators_saturate_where_mujoco_does() {
    for name in [
        "agility_cassie_cassie",
        "apptronik_apollo_apptronik_apollo",
        "berkeley_humanoid_berkeley_humanoid",
        "booster_t1_t1",
        "fourier_n1_n1",
        "pndbotics_adam_lite_adam_lite",
        "limx_oli_oli",
        "limx_luna_luna",
        // Its servos' `forcerange` comes from `<default><position>`.
        "open_duck_mini_v2_open_duck_mini_v2",
    ] {
        let (robot, refd) = menagerie(name);
        let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
        let saturated = numbers(&refd["actuator_force_limit"]);
        let mut driven = 0;
        for (i, joint) in model.joint_names.iter().enumerate() {
            if model.joint_types[i].nv() != 1 {
                continue;
            }
            let theirs = saturated[6 + model.idx_v[i]];
            let ours = model.effort_limits[i];
            if theirs == 0.0 {
                assert!(ours.is_infinite(), "{name} {joint}: {ours}");
            } else {
                driven += 1;
                assert!(
                    (ours - theirs).abs() <= 1e-12 * theirs,
                    "{name} {joint}: {ours} vs {theirs}"
                );
            }
        }
        assert!(driven >= 10, "{name}: {driven}");
        println!("{name}: {driven} driven joints");
    }
}

/// Item 4 on the real file: Apollo's scene, whose soles touch the floor only through
/// `<contact><pair>` (every geom of the robot has contype 0), can stand: placed on the
/// ground at its neutral pose, it touches it with its two sole boxes and nothing else.
#[test]
fn apollo_scene_stands_on_its_pair_only_soles() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models/apptronik_apollo/mjcf/scene.xml");
    let robot = twinloop_description::load(path).unwrap();
    let mut sim = Simulator::new(&robot, SimConfig::default()).unwrap();
    sim.check_can_stand().unwrap();
    let zeros = vec![0.0; sim.model.nbodies];
    sim.place_on_ground(&zeros).unwrap();
    let links: std::collections::BTreeSet<&str> = sim
        .contact_points()
        .iter()
        .map(|p| robot.links[p.link].name.as_str())
        .collect();
    // Its four robot-robot pairs (arms against the pelvis, thigh against thigh,
    // shin against shin) are self-collisions: they must not touch the ground.
    assert_eq!(
        links.into_iter().collect::<Vec<_>>(),
        ["l_foot_link", "r_foot_link"]
    );
}

/// A free box (2 kg) whose free joint has armature 0.05 and damping 0.4 from the
/// default class (as BXI Elf2's does): dropped, it falls at `g m / (m + a)` (the
/// armature has inertia, no weight: MuJoCo's free-fall with armature); pushed along
/// x without gravity, the implicit damper takes `(m + a) / (m + a + dt c)` of the
/// velocity per step, exactly.
#[test]
fn free_joint_armature_and_damping_act_in_the_simulator() {
    let xml = r#"<mujoco model="box">
  <default><joint armature="0.05" damping="0.4" frictionloss="0.01"/></default>
  <worldbody>
    <body name="box" pos="0 0 1">
      <joint name="root" type="free"/>
      <inertial pos="0 0 0" mass="2" diaginertia="0.2 0.3 0.4"/>
    </body>
  </worldbody>
</mujoco>"#;
    let mut robot = twinloop_description::mjcf::from_str(xml).unwrap();
    assert_eq!((robot.base_armature, robot.base_damping), (0.05, 0.4));
    // The free joint's dry friction is not modelled: said by name.
    assert!(
        robot
            .unmodeled
            .iter()
            .any(|n| n.element.contains("root") && n.what.contains("frictionloss 0.01")),
        "{:?}",
        robot.unmodeled
    );
    robot.base_damping = 0.0;
    let config = SimConfig {
        ground: false,
        ..SimConfig::default()
    };
    let mut sim = Simulator::new(&robot, config.clone()).unwrap();
    let steps = 200;
    for _ in 0..steps {
        sim.step().unwrap();
    }
    let want = -9.81 * 2.0 / 2.05 * steps as f64 * 1e-3;
    assert!((sim.v[2] - want).abs() <= 1e-12, "{} vs {want}", sim.v[2]);
    robot.base_damping = 0.4;
    let config = SimConfig {
        gravity: nalgebra::Vector3::zeros(),
        ..config
    };
    let mut sim = Simulator::new(&robot, config).unwrap();
    sim.v[0] = 1.0;
    for _ in 0..steps {
        sim.step().unwrap();
    }
    let want = (2.05f64 / (2.05 + 1e-3 * 0.4)).powi(steps);
    assert!((sim.v[0] - want).abs() <= 1e-12, "{} vs {want}", sim.v[0]);
}
