//! The simulator's servo from a parameter file against the bench of
//! twinloop-actuator (the model `identify servo` fits): the same pendulum, the same
//! goal steps, two implementations (the bench steps the firmware on encoder counts
//! and treats a closed backlash as rigid; the simulator's loop is continuous and its
//! closed backlash a stiff spring) must move alike.

use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::params::BACKLASH;
use twinloop_actuator::replay::advance;
use twinloop_actuator::{Bench, ModelLevel, Pendulum, ServoType};
use twinloop_description::{DescriptionBuilder, Inertia, Pose};
use twinloop_dynamics::{BaseKind, Model};
use twinloop_sim::{SimConfig, Simulator};

const MASS: f64 = 0.5;
const LENGTH: f64 = 0.15;
/// The link's own inertia about its centre: a small sphere (the bench's arm).
const RADIUS: f64 = 0.05;

fn pendulum_sim(dt: f64) -> Simulator {
    let robot = DescriptionBuilder::new("bench")
        .link("base")
        .mass(1.0, [0.0; 3], Inertia::solid_sphere(1.0, 0.05))
        .done()
        .link("arm")
        .mass(
            MASS,
            [0.0, 0.0, -LENGTH],
            Inertia::solid_sphere(MASS, RADIUS),
        )
        .done()
        .revolute("servo", "base", "arm", [0.0, 1.0, 0.0])
        .origin(Pose::new([0.0; 3], [0.0; 3]))
        .done()
        .build()
        .unwrap();
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    let cfg = SimConfig {
        ground: false,
        dt,
        ..Default::default()
    };
    Simulator::from_model(&robot, model, cfg).unwrap()
}

/// RMS and largest difference (rad) of the two over a sequence of goal steps.
fn compare(servo: ServoType, backlash: f64) -> (f64, f64) {
    let mut p = defaults(servo, ModelLevel::M1);
    p.values[BACKLASH] = backlash;
    let load = Pendulum {
        mass: MASS,
        length: LENGTH,
        arm_inertia: 0.4 * MASS * RADIUS * RADIUS,
    };
    let mut bench = Bench::new(p.clone(), load);
    bench.torque_on = true;
    let dt = 5e-4;
    let mut sim = pendulum_sim(dt);
    sim.set_servo_params(0, &p);
    let r = servo.resolution();
    let (mut sq, mut worst, mut n) = (0.0, 0.0f64, 0usize);
    for goal in [0.3, -0.2, 0.5, 0.0, 0.05, -0.02] {
        let g = (goal / r).round() * r;
        bench.send_goal(g);
        sim.goals[0] = g;
        for _ in 0..1500 {
            advance(&mut bench, dt);
            sim.step().unwrap();
            let e = bench.q - sim.q[0];
            sq += e * e;
            worst = worst.max(e.abs());
            n += 1;
        }
    }
    ((sq / n as f64).sqrt(), worst)
}

#[test]
fn the_simulators_servo_moves_as_the_bench() {
    for servo in [ServoType::Xm430W350, ServoType::Rx28] {
        for backlash in [0.0, 1e-7, 0.5f64.to_radians()] {
            let (rms, worst) = compare(servo, backlash);
            eprintln!(
                "{servo} backlash {:.2} deg: RMS {:.3} mrad, largest {:.3} mrad",
                backlash.to_degrees(),
                rms * 1e3,
                worst * 1e3
            );
            // Within two encoder counts RMS (the bench's loop acts on counts), and with
            // a backlash within twice its width more: inside the gap the output rests
            // where the last swing left it, and the gap opens on a contact test made
            // after the step on the bench, a step late here.
            assert!(
                rms < 2.0 * servo.resolution() + 2.0 * backlash,
                "{servo} backlash {backlash}: {rms}"
            );
        }
    }
}
