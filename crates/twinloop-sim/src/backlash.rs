//! A servo's gearbox with a dead band: the motor side (the last gear, at the
//! output's scale: angle `qm`, speed `vm`, inertia the armature) drives the output
//! only where the gap is closed. The loop acts on the output's angle (the
//! Dynamixels' encoder is on the output shaft); the back-EMF and the gearbox's
//! Coulomb friction act on the motor side.
//!
//! As the bench of `twinloop-actuator` does: closed and pushed (the loop's torque
//! pushes into the closed side), the motor side moves with the output as one body
//! (its inertia joins the joint's in the step, its friction the joint's); open, or
//! pulled, the output feels nothing and the motor side moves alone under the loop's
//! torque and its friction; when it reaches the other edge the gap closes with an
//! inelastic impact, momentum kept (the simulator's step resolves it against the
//! joint's effective inertia). A
//! simplification against the bench: the bench opens the gap when the contact
//! torque would pull (after the step), here when the loop's torque does (before it:
//! the contact torque of a multibody step is known only after it).

use crate::actuator::{Drive, DynamixelServo};

/// The motor side's state; `qm` NaN until the first step puts it at the output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gear {
    pub qm: f64,
    pub vm: f64,
    /// Whether the last drive moved the motor side with the output (+1 or -1: the
    /// closed side) or not (0).
    pub engaged: f64,
    /// The output's speed at the last drive (its acceleration tells whether the
    /// motor side pushes it).
    pub v_last: f64,
}

impl Default for Gear {
    fn default() -> Self {
        Gear {
            qm: f64::NAN,
            vm: 0.0,
            engaged: 0.0,
            v_last: f64::NAN,
        }
    }
}

impl Gear {
    /// Put the motor side at the output (gap centred) if it is not placed, or if the
    /// output was moved by more than the gap allows (a reset of the robot's pose).
    pub fn sync(&mut self, servo: &DynamixelServo, q: f64, v: f64) {
        if !(self.qm - q).is_finite() || (self.qm - q).abs() > 0.5 * servo.backlash + 1e-3 {
            self.qm = q;
            self.vm = v;
        }
    }
}

/// The torque on the output at `q`, `v` (time step `dt`): the loop's, `m` (the
/// motor's drive at the output's speed), when the gap is closed and the motor side
/// pushes into it (then `gear.engaged` is the closed side and the motor side's
/// inertia and friction join the joint's), else none. Pushes: the loop's torque less
/// what the motor side's inertia takes at the output's last acceleration,
/// `tau - J_m a`, has the closed side's sign (the bench's contact test, a step late).
pub fn output_drive(
    servo: &DynamixelServo,
    m: Drive,
    gear: &mut Gear,
    q: f64,
    v: f64,
    dt: f64,
) -> Drive {
    let half = 0.5 * servo.backlash;
    let delta = gear.qm - q;
    let side = if delta >= half - 1e-9 {
        1.0
    } else if delta <= -half + 1e-9 {
        -1.0
    } else {
        0.0
    };
    let a = if gear.v_last.is_finite() {
        (v - gear.v_last) / dt
    } else {
        0.0
    };
    gear.v_last = v;
    gear.engaged = if side != 0.0 && (m.tau - servo.motor_inertia * a) * side > 0.0 {
        side
    } else {
        0.0
    };
    if gear.engaged != 0.0 {
        m
    } else {
        Drive::default()
    }
}

/// After the step, with the output at its new `q`, `v`: an engaged motor side
/// follows the output; a free one moves under the loop's torque `drive_at(vm)`
/// (implicit in the back-EMF) and its Coulomb friction `friction`. Where it reaches
/// an edge moving into it the gap closes: it is put at the edge and its speed
/// returned for the caller's impact (`Simulator` resolves it against the joint's
/// effective inertia, momentum kept, as the bench does), which sets `gear.vm`.
pub fn advance_motor(
    servo: &DynamixelServo,
    gear: &mut Gear,
    drive_at: impl Fn(f64) -> Drive,
    friction: f64,
    q: f64,
    v: f64,
    dt: f64,
) -> Option<f64> {
    let half = 0.5 * servo.backlash;
    if gear.engaged != 0.0 {
        gear.qm = q + gear.engaged * half;
        gear.vm = v;
        return None;
    }
    let m = drive_at(gear.vm);
    let h = servo.motor_inertia.max(1e-6) + dt * m.d;
    let free = gear.vm + dt * m.tau / h;
    let stop = free * h / dt;
    let friction = stop.clamp(-friction, friction);
    gear.vm = free - dt * friction / h;
    gear.qm += dt * gear.vm;
    // The gap closes where the motor side reaches an edge moving into it.
    let delta = gear.qm - q;
    let closing = (gear.vm - v) * delta.signum() > 0.0;
    if delta.abs() >= half && closing {
        gear.qm = q + half * delta.signum();
        return Some(gear.vm);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gap_passes_nothing_and_pushes_only() {
        let mut s = DynamixelServo::rx28();
        s.backlash = 0.01;
        s.motor_inertia = 0.01;
        // Inside the gap: nothing.
        let mut g = Gear {
            qm: 0.004,
            vm: 0.0,
            ..Default::default()
        };
        let at = |goal: f64| s.drive(goal, 0.0, 0.0);
        assert_eq!(output_drive(&s, at(1.0), &mut g, 0.0, 0.0, 1e-3).tau, 0.0);
        // Closed on the + side and the loop pushes +: the loop's torque.
        g.qm = 0.005;
        let d = output_drive(&s, at(1.0), &mut g, 0.0, 0.0, 1e-3);
        assert!(d.tau > 0.0 && g.engaged == 1.0);
        // The loop pulls back (goal behind): the gap opens, nothing passes.
        assert_eq!(output_drive(&s, at(-1.0), &mut g, 0.0, 0.0, 1e-3).tau, 0.0);
        assert_eq!(g.engaged, 0.0);
        // The free motor side crosses the gap and closes it on the other side.
        for _ in 0..200 {
            let f = s.gear_friction;
            if advance_motor(&s, &mut g, |vm| s.drive(-1.0, 0.0, vm), f, 0.0, 0.0, 1e-3).is_some() {
                g.vm = 0.0; // an output held still takes the impact
            }
        }
        assert!((g.qm + 0.005).abs() < 1e-12 && g.vm == 0.0);
    }
}
