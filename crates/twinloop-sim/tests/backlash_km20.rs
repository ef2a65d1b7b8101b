//! Why km20 with a backlash at the study's stiff compliance (slope 2, margin 0) does
//! not stand still: the model's position loop hunts across the dead band. The bench
//! of twinloop-actuator (one pendulum, the contact resolved exactly) shows the same
//! limit cycle, and it stops where the loop's own dead band covers the backlash
//! (margin 2 counts > 0.5 deg = 1.7 counts) or the slope is gentle; so it is the
//! equations' behaviour, not the simulator's step.

use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::params::BACKLASH;
use twinloop_actuator::{Bench, ModelLevel, Pendulum, ServoType};
use twinloop_sim::actuator::{RX_POSITION_UNIT, servo_for_joint};
use twinloop_sim::{Actuator, SimConfig, Simulator};

fn km20(backlash: f64, slope_units: f64, margin_units: f64) -> Simulator {
    let robot = twinloop_description::builtin::builtin("km20").unwrap();
    let mut sim = Simulator::new(&robot, SimConfig::default()).unwrap();
    for i in 0..sim.model.nbodies {
        sim.actuators[i] = Actuator::Dynamixel(servo_for_joint(&robot.name, &sim.model, i));
        let name = sim.model.joint_names[i].clone();
        if let Some(spec) = twinloop_description::builtin::servo_of_joint("km20", &name)
            && let Some(t) = ServoType::parse(spec.name)
        {
            let mut p = defaults(t, ModelLevel::M1);
            p.values[BACKLASH] = backlash;
            sim.set_servo_params(i, &p);
        }
    }
    // As the tip-over study sets them (twinloop-ident's tipover_study.rs).
    for a in sim.actuators.iter_mut() {
        if let Actuator::Dynamixel(s) = a {
            s.compliance_slope = slope_units * RX_POSITION_UNIT;
            s.compliance_margin = margin_units * RX_POSITION_UNIT;
        }
    }
    let n = sim.model.nbodies;
    let standing: Vec<f64> = (0..n)
        .map(|i| 0f64.clamp(sim.model.lower_limits[i], sim.model.upper_limits[i]))
        .collect();
    sim.place_on_ground(&standing).unwrap();
    sim
}

/// RMS joint speed over every joint in the last second of 2 s standing, rad/s.
fn standing_speed(backlash: f64, slope: f64, margin: f64) -> f64 {
    let mut sim = km20(backlash, slope, margin);
    let (mut sq, mut n) = (0.0, 0usize);
    for k in 0..2000 {
        sim.step().unwrap_or_else(|e| panic!("step {k}: {e}"));
        if k >= 1000 {
            for i in 0..sim.model.nbodies {
                let v = sim.v[sim.model.idx_v[i]];
                sq += v * v;
                n += 1;
            }
        }
    }
    (sq / n as f64).sqrt()
}

/// RMS speed of the bench's RX-28 holding a light pendulum over its last second.
fn bench_speed(backlash: f64, slope: f64, margin: f64) -> f64 {
    let mut p = defaults(ServoType::Rx28, ModelLevel::M1);
    p.values[BACKLASH] = backlash;
    let load = Pendulum {
        mass: 0.05,
        length: 0.1,
        arm_inertia: 0.0,
    };
    let mut b = Bench::new(p, load);
    b.firmware.registers = [slope, margin, 32.0];
    b.torque_on = true;
    b.send_goal(0.3);
    let (mut sq, mut n) = (0.0, 0usize);
    for k in 0..4000 {
        b.step(5e-4);
        if k >= 2000 {
            sq += b.v * b.v;
            n += 1;
        }
    }
    (sq / n as f64).sqrt()
}

#[test]
fn a_stiff_loop_hunts_across_a_backlash_on_the_bench_and_on_km20() {
    let gap = 0.5f64.to_radians();
    // The bench: hunting at slope 2 and 4 with margin 0 or 1 count; still once the
    // margin (2 counts) exceeds the gap (1.7 counts) or at slope 8 and beyond.
    for (slope, margin, hunts) in [
        (2.0, 0.0, true),
        (2.0, 1.0, true),
        (4.0, 0.0, true),
        (2.0, 2.0, false),
        (8.0, 0.0, false),
        (32.0, 1.0, false),
    ] {
        let v = bench_speed(gap, slope, margin);
        eprintln!("bench slope {slope} margin {margin}: speed RMS {v:.3} rad/s");
        assert_eq!(v > 0.5, hunts, "bench slope {slope} margin {margin}: {v}");
    }
    assert!(bench_speed(0.0, 2.0, 0.0) < 0.05);
    // km20 standing: the step stays finite for 2 s in every case; its joints hunt
    // as the bench's do at slope 2, margin 0, and stand still without the backlash,
    // with the margin over the gap, or at the factory slope.
    let hunting = standing_speed(gap, 2.0, 0.0);
    let rigid = standing_speed(0.0, 2.0, 0.0);
    let margin = standing_speed(gap, 2.0, 2.0);
    let factory = standing_speed(gap, 32.0, 1.0);
    eprintln!(
        "km20 joint speed RMS: backlash slope 2 {hunting:.3}, no backlash {rigid:.3}, margin 2 {margin:.3}, slope 32 {factory:.3} rad/s"
    );
    assert!(hunting > 0.5, "{hunting}");
    assert!(rigid < 0.1 && margin < 0.1 && factory < 0.1);
}
