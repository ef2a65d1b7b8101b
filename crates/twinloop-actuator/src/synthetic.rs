//! Logs made without a bus: the bench run through an excitation and sampled as a
//! host on a bus samples it (irregular periods, registers in whole units). For tests
//! of the fit and for the benchmark against SciPy; the known-truth test over a pty
//! goes through the real bus instead.

use crate::bench::Bench;
use crate::excitation::Excitation;
use crate::load::Load;
use crate::log::ServoLog;
use crate::params::ServoParams;
use crate::replay::advance;
use twinloop_random::SplitMix64;

/// Run `truth` on `load` through `excitation`, sampling every `period` s give or take
/// a uniform `jitter` s; positions, speeds, voltages and currents come back in the
/// register units a bus would give.
pub fn synthetic_log(
    truth: &ServoParams,
    load: &Load,
    excitation: &Excitation,
    period: f64,
    jitter: f64,
    seed: u64,
) -> ServoLog {
    let servo = truth.servo;
    let mut rng = SplitMix64(seed);
    let mut b = Bench::new(truth.clone(), *load);
    b.torque_on = true;
    let res = servo.resolution();
    let velocity_unit = match servo.family() {
        crate::servo_type::LoopFamily::Compliance => 0.111 * std::f64::consts::TAU / 60.0,
        crate::servo_type::LoopFamily::Pid => 0.229 * std::f64::consts::TAU / 60.0,
    };
    let q_units = |x: f64| (x / res).round() * res;
    let mut log = ServoLog {
        file: "synthetic".into(),
        servo: Some(servo),
        current: servo.current_unit().map(|_| Vec::new()),
        ..Default::default()
    };
    let mut t = 0.0;
    let mut t_goal = 0.0;
    let (mut goal, mut regs) = excitation.at(0.0).expect("a non-empty excitation");
    loop {
        // The row's read: what the servo measures now, with the goal in force.
        log.t.push(t);
        log.goal.push(goal);
        log.t_goal.push(t_goal);
        log.firmware.push(regs);
        log.q.push(b.sensed_position());
        log.v.push((b.v / velocity_unit).round() * velocity_unit);
        log.voltage.push((truth.voltage * 10.0).round() / 10.0);
        if let (Some(c), Some(unit)) = (log.current.as_mut(), servo.current_unit()) {
            c.push((b.current / unit).round() * unit);
        }
        // The next goal, written at once, in whole counts.
        let Some((g, r)) = excitation.at(t) else {
            break;
        };
        goal = q_units(g);
        regs = r;
        b.send_goal(goal);
        b.firmware.registers = regs;
        t_goal = t;
        let span = period + jitter * (2.0 * rng.next_f64() - 1.0);
        advance(&mut b, span);
        t += span;
    }
    log
}
