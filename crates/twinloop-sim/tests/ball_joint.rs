//! A ball joint in the simulator: a spherical pendulum against its analytic small
//! oscillation period and its conserved quantities.

use twinloop_dynamics::{BaseKind, JointType, Model};
use twinloop_sim::*;

const MASS: f64 = 1.0;
const LENGTH: f64 = 0.5;
const I_COM: f64 = 0.01;

/// A point-like bob on a rod hanging from a ball joint at the origin.
fn spherical_pendulum() -> (twinloop_description::Description, Model) {
    let xml = format!(
        r#"<mujoco><worldbody><body name="bob">
             <joint name="pivot" type="ball"/>
             <inertial pos="0 0 -{LENGTH}" mass="{MASS}" diaginertia="{I_COM} {I_COM} {I_COM}"/>
           </body></worldbody></mujoco>"#
    );
    let robot = twinloop_description::mjcf::from_str(&xml).unwrap();
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    assert_eq!(model.joint_types[0], JointType::Spherical);
    (robot, model)
}

fn simulator(dt: f64) -> Simulator {
    let (robot, model) = spherical_pendulum();
    let config = SimConfig {
        dt,
        ground: false,
        ..SimConfig::default()
    };
    Simulator::from_model(&robot, model, config).unwrap()
}

/// Tilt angle about world x of the bob (from the rotation's z column).
fn tilt_x(q: &[f64]) -> f64 {
    let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
    // Third column of R: (2(xz + wy), 2(yz - wx), 1 - 2(x^2 + y^2)).
    let c = [
        2.0 * (x * z + w * y),
        2.0 * (y * z - w * x),
        1.0 - 2.0 * (x * x + y * y),
    ];
    (-c[1]).atan2(c[2])
}

#[test]
fn small_swings_have_the_physical_pendulum_period() {
    let dt = 1e-4;
    let mut sim = simulator(dt);
    let a0: f64 = 0.02;
    let (s, c) = (a0 / 2.0).sin_cos();
    sim.set_joint_positions(&[s, 0.0, 0.0, c]).unwrap();
    // Zero crossings of the tilt, downward.
    let mut crossings = Vec::new();
    let mut prev = tilt_x(&sim.q);
    for k in 1..=40_000 {
        sim.step().unwrap();
        let now = tilt_x(&sim.q);
        if prev > 0.0 && now <= 0.0 {
            crossings.push(k as f64 * dt - dt * now / (now - prev));
        }
        prev = now;
    }
    let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let pivot_inertia = I_COM + MASS * LENGTH * LENGTH;
    let analytic = 2.0 * std::f64::consts::PI * (pivot_inertia / (MASS * 9.81 * LENGTH)).sqrt();
    // Small-angle period (amplitude 0.02 rad adds 2.5e-5 relative); the step adds O(dt).
    assert!(
        ((period - analytic) / analytic).abs() < 1e-3,
        "period {period} s vs analytic {analytic} s"
    );
}

#[test]
fn a_conical_swing_keeps_a_unit_quaternion_and_its_vertical_momentum() {
    let mut sim = simulator(1e-4);
    let a0: f64 = 0.6;
    let (s, c) = (a0 / 2.0).sin_cos();
    sim.set_joint_positions(&[s, 0.0, 0.0, c]).unwrap();
    // Spin about the rod (local z) and swing sideways.
    sim.v.copy_from_slice(&[0.0, 1.5, 2.0]);
    let lz = |sim: &mut Simulator| {
        // World angular momentum about the pivot, z component: R (I_pivot w).
        let q = sim.q.clone();
        let w = nalgebra::Vector3::new(sim.v[0], sim.v[1], sim.v[2]);
        let ip = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(
            I_COM + MASS * LENGTH * LENGTH,
            I_COM + MASS * LENGTH * LENGTH,
            I_COM,
        ));
        let r = twinloop_spatial::quaternion_xyzw_to_matrix(q[0], q[1], q[2], q[3]);
        (r * ip * w).z
    };
    let l0 = lz(&mut sim);
    let e0 = sim.energy();
    for _ in 0..20_000 {
        sim.step().unwrap();
    }
    let n = sim.q.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((n - 1.0).abs() < 1e-14, "|q| = {n}");
    let (l1, e1) = (lz(&mut sim), sim.energy());
    assert!((l1 - l0).abs() < 1e-3 * l0.abs(), "L_z {l0} -> {l1}");
    assert!((e1 - e0).abs() < 1e-2 * e0.abs(), "energy {e0} -> {e1}");
}

#[test]
fn a_massless_ball_is_refused_naming_its_joint() {
    // A point mass at the ball's centre: nothing resists the ball's rotation.
    let xml = r#"<mujoco><worldbody><body name="bob">
                   <joint name="pivot" type="ball"/>
                   <inertial pos="0 0 0" mass="1" diaginertia="0 0 0"/>
                 </body></worldbody></mujoco>"#;
    let robot = twinloop_description::mjcf::from_str(xml).unwrap();
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    let config = SimConfig {
        ground: false,
        ..SimConfig::default()
    };
    let mut sim = Simulator::from_model(&robot, model, config).unwrap();
    let e = sim.step().unwrap_err().to_string();
    assert!(e.contains("joint \"pivot\""), "{e}");
    assert!(
        e.contains("mass matrix is singular at joint \"pivot\""),
        "{e}"
    );
}
