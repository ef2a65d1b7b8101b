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
