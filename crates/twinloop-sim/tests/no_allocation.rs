//! A simulation step allocates nothing once the simulator is built.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use twinloop_robot::{Robot, RobotState};
use twinloop_sim::{Actuator, DynamixelServo, SimConfig, Simulator};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn stepping_and_reading_do_not_allocate() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/op3/mjcf/op3.xml");
    let robot = twinloop_description::load(path).unwrap();
    let mut sim = Simulator::new(&robot, SimConfig::default()).unwrap();
    sim.set_all_actuators(Actuator::Dynamixel(DynamixelServo::rx28()));
    let n = sim.model.nbodies;
    sim.place_on_ground(&vec![0.0; n]).unwrap();
    let mut st = RobotState::default();
    let goals = vec![0.01; n];
    sim.run(0.05).unwrap();
    sim.read(&mut st).unwrap();
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for _ in 0..200 {
        sim.command_positions(&goals).unwrap();
        sim.step().unwrap();
        sim.read(&mut st).unwrap();
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert!(before > 0);
    assert_eq!(
        after - before,
        0,
        "{} allocations in 200 steps",
        after - before
    );
}

/// The full servo model of a parameter file (crate::servo_model), with both delays
/// (their rings sized when the servo is set), the profile and a backlash on every
/// other joint, goals changing every step.
fn the_full_servo_model_does_not_allocate() {
    use twinloop_actuator::params::{BACKLASH, BUS_DELAY, SENSING_DELAY};
    use twinloop_actuator::{ModelLevel, ServoType, datasheet::defaults};
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/op3/mjcf/op3.xml");
    let robot = twinloop_description::load(path).unwrap();
    let mut sim = Simulator::new(&robot, SimConfig::default()).unwrap();
    let n = sim.model.nbodies;
    for i in 0..n {
        let mut p = defaults(ServoType::Xm430W350, ModelLevel::M4);
        p.values[SENSING_DELAY] = 0.002;
        p.values[BUS_DELAY] = 0.003;
        if i % 2 == 0 {
            p.values[BACKLASH] = 0.005;
        }
        sim.set_servo_params(i, &p);
        if let Actuator::Dynamixel(s) = &mut sim.actuators[i] {
            let f = s.full.as_mut().unwrap();
            f.profile_velocity = 2.0;
            f.profile_acceleration = 20.0;
        }
    }
    sim.place_on_ground(&vec![0.0; n]).unwrap();
    let mut st = RobotState::default();
    let mut goals = vec![0.0; n];
    // Counted from the first step: the delay rings must not grow as they fill.
    sim.read(&mut st).unwrap();
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for k in 0..200 {
        goals.iter_mut().for_each(|g| *g = 1e-3 * k as f64);
        sim.command_positions(&goals).unwrap();
        sim.step().unwrap();
        sim.read(&mut st).unwrap();
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert_eq!(
        after - before,
        0,
        "{} allocations in 200 steps of the full model",
        after - before
    );
}

/// Runs without libtest's harness (Cargo.toml: `harness = false`): the harness's own
/// thread allocates while the test runs (its bookkeeping of running tests), and on a
/// loaded CI machine those allocations landed inside the counted window.
fn main() {
    stepping_and_reading_do_not_allocate();
    println!("test stepping_and_reading_do_not_allocate ... ok");
    the_full_servo_model_does_not_allocate();
    println!("test the_full_servo_model_does_not_allocate ... ok");
}
