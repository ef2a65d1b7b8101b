//! Step rate of km20 standing on its servos: the simple servo (the continuous loop
//! of `DynamixelServo::drive`, the datasheet's rating) against the full model of a
//! parameter file (`servo_model`: firmware on counts, friction budget) and the full
//! model with both delays and a 0.5 deg backlash. Alternating runs, median of 9.
//! `cargo bench --profile ci -p twinloop-sim --bench servo_model`

use std::time::Instant;
use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::params::{BACKLASH, BUS_DELAY, SENSING_DELAY};
use twinloop_actuator::{ModelLevel, ServoType};
use twinloop_sim::actuator::{RX_POSITION_UNIT, servo_for_joint};
use twinloop_sim::{Actuator, SimConfig, Simulator};

fn km20(full: bool, extras: bool) -> Simulator {
    let robot = twinloop_description::builtin::builtin("km20").unwrap();
    let mut sim = Simulator::new(&robot, SimConfig::default()).unwrap();
    for i in 0..sim.model.nbodies {
        sim.actuators[i] = Actuator::Dynamixel(servo_for_joint(&robot.name, &sim.model, i));
        let name = sim.model.joint_names[i].clone();
        if full
            && let Some(spec) = twinloop_description::builtin::servo_of_joint("km20", &name)
            && let Some(t) = ServoType::parse(spec.name)
        {
            let mut p = defaults(t, ModelLevel::M4);
            if extras {
                p.values[BACKLASH] = 0.5f64.to_radians();
                p.values[SENSING_DELAY] = 0.002;
                p.values[BUS_DELAY] = 0.002;
            }
            sim.set_servo_params(i, &p);
        }
    }
    // The factory slope: the backlash does not hunt (tests/backlash_km20.rs).
    for a in sim.actuators.iter_mut() {
        if let Actuator::Dynamixel(s) = a {
            s.compliance_slope = 32.0 * RX_POSITION_UNIT;
        }
    }
    let n = sim.model.nbodies;
    let standing: Vec<f64> = (0..n)
        .map(|i| 0f64.clamp(sim.model.lower_limits[i], sim.model.upper_limits[i]))
        .collect();
    sim.place_on_ground(&standing).unwrap();
    sim
}

/// Microseconds per step over 2000 steps (after 200 to settle).
fn run(full: bool, extras: bool) -> f64 {
    let mut sim = km20(full, extras);
    sim.run(0.2).unwrap();
    let t = Instant::now();
    for _ in 0..2000 {
        sim.step().unwrap();
    }
    t.elapsed().as_secs_f64() / 2000.0 * 1e6
}

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(|a, b| a.total_cmp(b));
    x[x.len() / 2]
}

fn main() {
    let (mut simple, mut full, mut extras) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..9 {
        simple.push(run(false, false));
        full.push(run(true, false));
        extras.push(run(true, true));
    }
    let (s, f, e) = (median(simple), median(full), median(extras));
    println!("km20 standing, us/step (median of 9):");
    println!("  simple servo (datasheet)            {s:.2}");
    println!(
        "  full model (m4, counts, budget)     {f:.2}  ({:.3}x)",
        f / s
    );
    println!(
        "  + delays 2 ms and backlash 0.5 deg  {e:.2}  ({:.3}x)",
        e / s
    );
}
