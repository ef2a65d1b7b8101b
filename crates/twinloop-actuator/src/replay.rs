//! The model run against a log: the logged goals and firmware registers drive a
//! [`Bench`] from the logged starting state, and the model's position (and current)
//! is sampled at the logged times.

use crate::bench::Bench;
use crate::load::Load;
use crate::log::ServoLog;
use crate::params::ServoParams;

/// Longest model step, s: the firmware cycle the models assume (the bench serves
/// with the same).
pub const MAX_STEP: f64 = 5e-4;

/// Simulate rows `rows` of `log` with `params` on `load`: the state starts at the
/// first row's measured position and speed; row `i`'s goal, registers and Torque
/// Enable act from its `t_goal` (between row `i-1`'s time and row `i`'s) plus the
/// bus delay on.
/// Writes the model's sensed position (as old as the sensing delay, not yet rounded
/// to counts) and current at each row into `q` and `current` (same length as `rows`).
pub fn replay(
    params: &ServoParams,
    load: &Load,
    log: &ServoLog,
    rows: std::ops::Range<usize>,
    q: &mut [f64],
    current: &mut [f64],
) {
    let mut b = Bench::new(params.clone(), *load);
    let start = rows.start;
    b.place(log.q[start], log.v[start]);
    b.torque_on = log.torque.as_ref().is_none_or(|t| t[start]);
    b.goal = log.goal[start];
    b.firmware.registers = log.firmware[start];
    q[0] = b.q;
    current[0] = f64::NAN;
    for (k, i) in rows.clone().enumerate().skip(1) {
        let switch = log.t_goal[i].clamp(log.t[i - 1], log.t[i]);
        advance(&mut b, switch - log.t[i - 1]);
        b.send_goal(log.goal[i]);
        b.firmware.registers = log.firmware[i];
        if let Some(torque) = &log.torque {
            // Torque Enable is written with the goal; off forgets the loop's history.
            if b.torque_on && !torque[i] {
                b.firmware.reset();
            }
            b.torque_on = torque[i];
        }
        advance(&mut b, log.t[i] - switch);
        q[k] = b.sensed_angle();
        current[k] = b.current;
    }
}

/// `span` seconds in equal steps of at most [`MAX_STEP`].
pub fn advance(b: &mut Bench, span: f64) {
    if span <= 0.0 {
        return;
    }
    let n = (span / MAX_STEP).ceil().max(1.0);
    let dt = span / n;
    for _ in 0..n as usize {
        b.step(dt);
    }
}
