//! Stiffening over the bus (`twinloop_experiments::stiffen`) on a simulated robot
//! behind the virtual bus: km20 with its RX servos swapped for XM430-W350 (OP3's
//! servos, Protocol 2.0) or MX-28 (Darwin-OP's, Protocol 1.0). The experiment reads
//! each servo's loop register, raises it, and writes back what it found; the values
//! are read back over the bus register by register (bytes decoded here, little
//! endian as EM-P1/EM-P2 say), and the stiffer loop must visibly hold the pose.

use twinloop_experiments::stiffen::{
    check_stiffenable, restore_loops, save_loops, stiffen, unstiffenable,
};
use twinloop_link::{DynamixelRobot, ReadMethod, RobotMapping, ServoModel};
use twinloop_robot::{Robot, RobotState};
use twinloop_virtual::{Lockstep, VirtualRobot, VirtualRobotOptions};

type BusRobot = twinloop_experiments::guarded::BusRobot;

/// km20 with every servo `model` (the CM-730 board stays).
fn km20_with(model: &str) -> BusRobot {
    let text = include_str!("../../twinloop-link/src/mappings/km20.toml")
        .replace("\"RX-28\"", &format!("\"{model}\""))
        .replace("\"RX-64\"", &format!("\"{model}\""));
    let mapping = RobotMapping::parse(&text, "km20-test.toml").unwrap();
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let vr = VirtualRobot::new(&robot, &mapping, &VirtualRobotOptions::default()).unwrap();
    let (clock, client) = Lockstep::new(vr, 0.01).unwrap();
    let mut bot = DynamixelRobot::new(client, mapping, ReadMethod::Auto).unwrap();
    bot.set_clock(Box::new(clock));
    bot
}

/// Each joint's loop register (the catalogue's only one on MX and X), read over the
/// bus.
fn read_gains(bot: &mut BusRobot) -> Vec<i32> {
    let joints: Vec<_> = bot
        .mapping()
        .joints
        .iter()
        .map(|j| (j.id, j.protocol, j.model))
        .collect();
    joints
        .into_iter()
        .map(|(id, protocol, model)| {
            let reg = model.loop_registers()[0];
            let mut b = [0u8; 2];
            let b = &mut b[..reg.size as usize];
            bot.client.read(protocol, id, reg.address, b).unwrap();
            b.iter().rev().fold(0, |v, &x| (v << 8) | i32::from(x))
        })
        .collect()
}

/// The largest gap between a joint's goal (standing, 0) and where it sits after
/// `s` seconds holding the pose, deg.
fn sag_deg(bot: &mut BusRobot, s: f64) -> f64 {
    let standing = vec![0.0; bot.joint_names().len()];
    let mut st = RobotState::default();
    let t0 = bot.time();
    while bot.time() - t0 < s {
        bot.command_positions(&standing).unwrap();
        bot.advance(0.01).unwrap();
    }
    bot.read(&mut st).unwrap();
    st.positions
        .iter()
        .fold(0.0f64, |m, q| m.max(q.abs()))
        .to_degrees()
}

fn raise_and_restore(model: &str, factory: i32, stiff: i32) -> (f64, f64) {
    let mut bot = km20_with(model);
    check_stiffenable(bot.mapping()).unwrap();
    bot.set_torque(true).unwrap();
    let soft = sag_deg(&mut bot, 1.5);
    let saved = save_loops(&mut bot, std::time::Duration::from_secs(1)).unwrap();
    assert!(saved.values().all(|(_, _, v)| v == factory));
    assert_eq!(saved.values().count(), 20);
    stiffen(&mut bot, 2, |_| true).unwrap();
    assert!(read_gains(&mut bot).iter().all(|&p| p == stiff), "{model}");
    let firm = sag_deg(&mut bot, 1.5);
    restore_loops(&mut bot, &saved).unwrap();
    assert!(
        read_gains(&mut bot).iter().all(|&p| p == factory),
        "{model}"
    );
    (soft, firm)
}

#[test]
fn an_xm430_robot_is_stiffened_by_its_position_p_gain_and_put_back() {
    // XM430-W350: Position P Gain 800 (factory) -> 16383 -> 800.
    let (soft, firm) = raise_and_restore("XM430-W350", 800, 16383);
    // Full PWM at 141.6 counts against 6.9: the pose sags far less.
    // Standing km20 loads its servos lightly: a count of sag (0.088 deg) soft.
    assert!(soft > 0.05, "{soft}");
    assert!(
        firm < soft / 4.0,
        "sag {soft:.3} deg soft, {firm:.3} deg stiff"
    );
}

#[test]
fn an_mx28_robot_on_protocol_1_is_stiffened_by_its_p_gain_and_put_back() {
    // MX-28 (1.0): P Gain 32 (factory) -> 254 (the register's top) -> 32.
    let (soft, firm) = raise_and_restore("MX-28", 32, 254);
    assert!(soft > 0.05, "{soft}");
    assert!(
        firm < soft / 2.0,
        "sag {soft:.3} deg soft, {firm:.3} deg stiff"
    );
}

#[test]
fn a_servo_with_no_known_way_to_stiffen_is_refused_by_id_and_model() {
    // Every catalogue servo has a way; a board in a joint's place stands for one
    // that has none (the mapping file itself refuses a board as a joint).
    let mut mapping = RobotMapping::builtin("op3").unwrap();
    assert!(check_stiffenable(&mapping).is_ok());
    mapping.joints[3].model = ServoModel::Cm730;
    let id = mapping.joints[3].id;
    assert_eq!(unstiffenable(&mapping), vec![(id, ServoModel::Cm730)]);
    let e = check_stiffenable(&mapping).unwrap_err().to_string();
    assert!(e.contains(&format!("servo id {id} (CM-730)")), "{e}");
    assert!(e.contains("--soft-servos"), "{e}");
}
