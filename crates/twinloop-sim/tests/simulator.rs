//! The simulator against the dynamics core and physics: energy, ABA, settling, servos.

use nalgebra::{DVector, Vector3};
use std::path::PathBuf;
use twinloop_description::{DescriptionBuilder, Geometry, Inertia, Pose};
use twinloop_dynamics::{BaseKind, Data, Model, aba};
use twinloop_robot::{Robot, RobotState};
use twinloop_sim::*;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A 3-link pendulum chain hanging from a fixed base, joints about skew axes.
fn pendulum() -> twinloop_description::Description {
    // The root has mass: a massless floating root would make M singular (its motion
    // about the first joint's axis could be undone by that joint, moving nothing).
    let mut b = DescriptionBuilder::new("chain")
        .link("root")
        .mass(0.5, [0.0; 3], Inertia::solid_sphere(0.5, 0.05))
        .done();
    let mut parent = "root".to_string();
    for k in 0..3 {
        let name = format!("l{k}");
        b = b
            .link(&name)
            .mass(
                1.0 + k as f64 * 0.3,
                [0.02, 0.0, -0.15],
                Inertia::solid_box(1.0, [0.05, 0.04, 0.3]),
            )
            .done()
            .revolute(format!("j{k}"), &parent, &name, [0.2, 1.0, 0.1 * k as f64])
            .origin(Pose::new([0.0, 0.0, -0.3], [0.1, 0.0, 0.0]))
            .done();
        parent = name;
    }
    b.build().unwrap()
}

#[test]
fn passive_pendulum_keeps_its_energy() {
    let robot = pendulum();
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    let sim = Simulator::from_model(
        &robot,
        model,
        SimConfig {
            ground: false,
            ..Default::default()
        },
    )
    .unwrap();
    // Energy scale: the chain's weight times its length (m g l).
    let scale = sim.model.total_mass * 9.81 * 0.9;
    let drift = |dt: f64| {
        let robot = pendulum();
        let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
        let cfg = SimConfig {
            ground: false,
            dt,
            ..Default::default()
        };
        let mut sim = Simulator::from_model(&robot, model, cfg).unwrap();
        sim.set_joint_positions(&[1.2, -0.7, 0.5]).unwrap();
        let e0 = sim.energy();
        let mut worst: f64 = 0.0;
        for _ in 0..50 {
            sim.run(0.1).unwrap();
            worst = worst.max((sim.energy() - e0).abs());
        }
        worst
    };
    let (e1, e2) = (drift(1e-3), drift(5e-4));
    // The stated bound (README): a passive chain swinging for 5 s at the default 1 ms
    // step keeps its energy within 1 % of m g l; the error is first order in the step
    // (semi-implicit Euler with a configuration-dependent mass matrix).
    assert!(e1 / scale < 1e-2, "energy error {e1} J, scale {scale} J");
    assert!(
        e2 < 0.6 * e1,
        "halving the step must about halve the error: {e1} -> {e2}"
    );
}

/// One step of the pendulum under torques with no springs or contacts, against
/// v' = v + dt * ABA(q, v, tau).
fn assert_free_step_is_aba(armature: &[f64]) {
    let robot = pendulum();
    let mut model = Model::from_description(&robot).unwrap();
    model.armature = armature.to_vec();
    let mut sim = Simulator::from_model(
        &robot,
        model.clone(),
        SimConfig {
            ground: false,
            ..Default::default()
        },
    )
    .unwrap();
    sim.set_all_actuators(Actuator::Torque);
    sim.goals = vec![0.3, -0.2, 0.1];
    let q0 = vec![0.1, 0.2, 0.3, 0.1, 0.2, 0.3, 0.9, 0.4, -0.3, 0.2];
    let mut q = q0.clone();
    twinloop_dynamics::configuration::normalize(&model, &mut q);
    sim.q = q.clone();
    sim.v = vec![0.1, -0.2, 0.3, 0.5, -0.4, 0.2, 1.0, -1.0, 0.5];
    let v0 = sim.v.clone();
    sim.step().unwrap();
    let mut data = Data::new(&model);
    let mut tau = vec![0.0; 6];
    tau.extend([0.3, -0.2, 0.1]);
    let a = aba(&model, &mut data, &q, &v0, &tau).clone();
    let expect = DVector::from_vec(v0) + a * sim.dt();
    let got = DVector::from_vec(sim.v.clone());
    assert!((expect - got).norm() < 1e-10);
}

#[test]
fn a_free_step_is_aba() {
    assert_free_step_is_aba(&[0.0; 3]);
}

#[test]
fn a_free_step_with_rotor_inertia_is_aba() {
    // Armature (reflected rotor inertia) enters the step once, as it enters ABA once.
    assert_free_step_is_aba(&[0.02, 0.05, 0.01]);
}

fn brick() -> twinloop_description::Description {
    DescriptionBuilder::new("brick")
        .link("brick")
        .mass(2.0, [0.0; 3], Inertia::solid_box(2.0, [0.2, 0.1, 0.05]))
        .collision(
            Pose::IDENTITY,
            Geometry::Box {
                size: [0.2, 0.1, 0.05],
            },
        )
        .done()
        .build()
        .unwrap()
}

#[test]
fn a_brick_settles_without_drift_even_on_a_slope_of_gravity() {
    // Gravity tilted 20 degrees: friction (mu = 1) must hold the brick without creep.
    let g = Vector3::new(
        9.81 * 20f64.to_radians().sin(),
        0.0,
        -9.81 * 20f64.to_radians().cos(),
    );
    let mut sim = Simulator::new(
        &brick(),
        SimConfig {
            gravity: g,
            ..Default::default()
        },
    )
    .unwrap();
    sim.place_on_ground(&[]).unwrap();
    sim.run(0.5).unwrap();
    let x0 = sim.q[0];
    sim.run(2.0).unwrap();
    let creep = (sim.q[0] - x0).abs();
    assert!(creep < 1e-6, "creep {creep} m");
    // Resting depth: weight on 4 corner springs.
    let k = sim.contact_params.stiffness;
    let depth = 2.0 * 9.81 * 20f64.to_radians().cos() / (4.0 * k);
    let z = sim.q[2] - 0.025;
    assert!((z + depth).abs() < 1e-5, "rest height {z} vs -{depth}");
    // And at rest: velocities vanish (no jitter).
    assert!(sim.v.iter().all(|x| x.abs() < 1e-6));
}

#[test]
fn a_brick_slides_beyond_the_friction_cone() {
    let g = Vector3::new(
        9.81 * 50f64.to_radians().sin(),
        0.0,
        -9.81 * 50f64.to_radians().cos(),
    );
    let mut sim = Simulator::new(
        &brick(),
        SimConfig {
            gravity: g,
            ..Default::default()
        },
    )
    .unwrap();
    sim.place_on_ground(&[]).unwrap();
    sim.run(1.0).unwrap();
    // Sliding acceleration g (sin - mu cos) along x.
    let a = 9.81 * (50f64.to_radians().sin() - 50f64.to_radians().cos());
    let v = sim.v[0] * sim.q[6].signum(); // base frame = world for an unrotated brick
    assert!((v - a * 1.0).abs() < 0.05 * a, "sliding speed {v} vs {a}");
}

#[test]
fn a_sliding_brick_decelerates_at_mu_g_and_comes_to_rest() {
    // Pushed at 0.5 m/s on flat ground (mu = 1): Coulomb friction decelerates it at
    // mu g, so it stops after v0 / (mu g) = 51 ms, then rests. On the default floor
    // (1 mm sink) and on the tip-over study's stiff one (10 um), where a point's
    // friction impulse over a step, mu f_n dt, exceeds what stops it: there an
    // explicit sliding force reversed every step and the brick never came to rest.
    for sink in [1e-3, 1e-5] {
        sliding_brick_on(sink);
    }
}

fn sliding_brick_on(sink: f64) {
    let config = SimConfig {
        contact: Some(ContactParams::for_robot(2.0, 4, sink)),
        ..Default::default()
    };
    let mut sim = Simulator::new(&brick(), config).unwrap();
    sim.place_on_ground(&[]).unwrap();
    sim.run(0.2).unwrap();
    let (v0, g, dt) = (0.5, 9.81, sim.dt());
    sim.v[0] = v0;
    let mut v = Vec::new();
    for _ in 0..400 {
        sim.step().unwrap();
        v.push(sim.v[0]);
    }
    // Deceleration over the slide from 0.4 to 0.1 m/s.
    let at = |x: f64| v.iter().position(|&s| s < x).unwrap();
    let (a, b) = (at(0.4), at(0.1));
    let decel = (v[a] - v[b]) / ((b - a) as f64 * dt);
    assert!(
        (decel - g).abs() < 0.03 * g,
        "sink {sink}: deceleration {decel} m/s^2 vs {g}"
    );
    let t_stop = (at(0.0) + 1) as f64 * dt;
    assert!(
        (t_stop - v0 / g).abs() < 0.003,
        "sink {sink}: stopped after {t_stop} s"
    );
    // Then it rests: the soles' sheared springs give back their millimetre and settle;
    // no point keeps sliding, nothing jitters.
    let worst = v[300..].iter().fold(0.0f64, |m, s| m.max(s.abs()));
    assert!(worst < 1e-5, "sink {sink}: speed at rest up to {worst} m/s");
    let states = sim.contact_states();
    assert_eq!(
        states.iter().filter(|c| c.active).count(),
        4,
        "the four bottom corners touch"
    );
    assert!(states.iter().all(|c| !c.sliding));
}

#[test]
fn two_loop_servo_settles_in_about_200_ms_without_overshoot() {
    // One joint, link inertia 2e-3 kg m^2 about the axis, no gravity.
    let robot = DescriptionBuilder::new("arm")
        .link("base")
        .done()
        .link("arm")
        .mass(0.2, [0.0; 3], Inertia::diagonal(2e-3, 2e-3, 2e-3))
        .done()
        .revolute("j", "base", "arm", [0.0, 0.0, 1.0])
        .done()
        .build()
        .unwrap();
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    let mut sim = Simulator::from_model(
        &robot,
        model,
        SimConfig {
            ground: false,
            gravity: Vector3::zeros(),
            ..Default::default()
        },
    )
    .unwrap();
    let servo = TwoLoopServo {
        kp_position: 20.0,
        kv: 4.0 * 2e-3 * 20.0 * 1.5,
        max_speed: 20.0,
        max_torque: 1.5,
    };
    sim.set_all_actuators(Actuator::TwoLoop(servo));
    sim.goals = vec![0.5];
    let mut peak: f64 = 0.0;
    let mut settled_at = None;
    for k in 0..600 {
        sim.step().unwrap();
        let q = sim.q[0];
        peak = peak.max(q);
        if settled_at.is_none() && (q - 0.5).abs() < 0.02 * 0.5 {
            settled_at = Some(k as f64 * sim.dt());
        }
    }
    let t = settled_at.expect("settles");
    assert!(peak <= 0.5 + 1e-9, "overshoot to {peak}");
    assert!((0.15..0.30).contains(&t), "2 % settling time {t} s");
}

#[test]
fn op3_stands_still_on_its_servos() {
    let robot = twinloop_description::load(repo().join("models/op3/mjcf/op3.xml")).unwrap();
    let mut sim = Simulator::new(&robot, SimConfig::default()).unwrap();
    // OP3's XM430-W350: stall 4.1 N m, 46 rpm at 12 V (ROBOTIS e-manual).
    // Its position loop: kp 21.1 N m/rad (the Menagerie model), no dead band (X series PID).
    let mut servo = DynamixelServo::with_rating(4.1, 46.0 * std::f64::consts::TAU / 60.0);
    servo.compliance_slope = 4.1 / 21.1;
    servo.compliance_margin = 0.0;
    sim.set_all_actuators(Actuator::Dynamixel(servo));
    let n = sim.model.nbodies;
    sim.place_on_ground(&vec![0.0; n]).unwrap();
    assert!(
        sim.contact_points().len() >= 16,
        "foot boxes give contact points"
    );
    // The MJCF's joint friction (frictionloss) makes the last millimetre a slow,
    // exponentially decaying creep (time constant about 2 s), as dry friction does.
    sim.run(6.0).unwrap();
    let x0 = sim.q.clone();
    sim.run(2.0).unwrap();
    let drift = ((sim.q[0] - x0[0]).powi(2) + (sim.q[1] - x0[1]).powi(2)).sqrt();
    assert!(drift < 1e-5, "base drifted {drift} m in 2 s");
    assert!(
        sim.contact_states().iter().all(|c| !c.sliding),
        "no foot point slides"
    );
    let vmax = sim.v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(vmax < 1e-4, "jitter: max |v| = {vmax}");
    // Feet carry the weight.
    let mut st = RobotState::default();
    sim.read(&mut st).unwrap();
    let weight = sim.model.total_mass * 9.81;
    let on_feet: f64 = st.feet.iter().map(|f| f.force).sum();
    assert_eq!(st.feet.len(), 2, "both ankle-roll links are feet");
    assert!(
        (on_feet - weight).abs() < 1e-3 * weight,
        "{on_feet} N on the feet, weight {weight} N"
    );
    // At rest the accelerometer reads gravity's reaction, +9.81 m/s^2 along world up
    // seen in the (slightly leaning) trunk frame; the gyro reads nothing.
    let imu = st.imu.unwrap();
    let [x, y, z, w] = imu.orientation.unwrap();
    let r = twinloop_spatial::quaternion_xyzw_to_matrix(x, y, z, w);
    let expect = r.transpose() * Vector3::new(0.0, 0.0, 9.81);
    let got = Vector3::new(imu.accel[0], imu.accel[1], imu.accel[2]);
    assert!((got - expect).norm() < 1e-3, "{got:?} vs {expect:?}");
    assert!(imu.gyro.iter().all(|w| w.abs() < 1e-4), "{imu:?}");
}

#[test]
fn link_angular_velocity_is_what_an_exact_gyro_on_that_link_reads() {
    let robot = pendulum();
    let model = Model::from_description_with_base(&robot, BaseKind::Floating).unwrap();
    let mut sim = Simulator::from_model(
        &robot,
        model,
        SimConfig {
            ground: false,
            ..Default::default()
        },
    )
    .unwrap();
    // A tumbling, swinging chain: every joint and the base move.
    for (i, v) in sim.v.iter_mut().enumerate() {
        *v = 0.3 + 0.17 * i as f64;
    }
    sim.run(0.05).unwrap();
    let link = sim.model.links.iter().position(|l| l.name == "l2").unwrap();
    sim.sensors_mut().imu_link = link;
    let mut st = RobotState::default();
    sim.read_sensors(&mut st);
    let g = st.imu.unwrap().gyro;
    let w = sim.link_angular_velocity("l2").unwrap();
    assert!(w.norm() > 0.1, "the link moves: {w}");
    for k in 0..3 {
        assert!((g[k] - w[k]).abs() < 1e-12, "{k}: {} vs {}", g[k], w[k]);
    }
    // A different link turns differently; an unknown link is None.
    assert!((sim.link_angular_velocity("l0").unwrap() - w).norm() > 1e-3);
    assert!(sim.link_angular_velocity("nope").is_none());
}
