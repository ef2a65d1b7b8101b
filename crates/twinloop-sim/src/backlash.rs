//! A servo's gearbox with a dead band: the motor side (the last gear, at the
//! output's scale: angle `qm`, speed `vm`, inertia the armature) drives the output
//! only where the gap is closed. The closed gap is a stiff spring (the gear mesh,
//! [`GEAR_STIFFNESS`]) with damping; the open gap passes nothing. The loop acts on the
//! output's angle (the Dynamixels' encoder is on the output shaft); the back-EMF and
//! the gearbox's Coulomb friction act on the motor side.
//!
//! The bench of `twinloop-actuator` treats the closed gap as rigid (one body, with
//! inelastic impacts); here a stiff spring, so the link side stays in the
//! simulator's linearly implicit step. 2000 N m/rad is ten times the stiffest loop
//! (RX slope 2: 3.7 N m over 10 mrad), so the dead band, not the spring, shapes the
//! motion (an assumption: ROBOTIS gives no mesh stiffness).

use crate::actuator::{Drive, DynamixelServo};

/// The closed gap's stiffness, N m/rad.
pub const GEAR_STIFFNESS: f64 = 2000.0;

/// The motor side's state; `qm` NaN until the first step puts it at the output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gear {
    pub qm: f64,
    pub vm: f64,
    /// What the motor side felt beyond what the output received in the last step,
    /// N m: the output takes it in the next ([`advance_motor`]).
    pub owed: f64,
}

impl Default for Gear {
    fn default() -> Self {
        Gear {
            qm: f64::NAN,
            vm: 0.0,
            owed: 0.0,
        }
    }
}

impl Gear {
    /// Put the motor side at the output (gap centred) if it is not placed, or if the
    /// output was moved by more than the gap allows (a reset of the robot's pose).
    pub fn sync(&mut self, servo: &DynamixelServo, q: f64, v: f64) {
        if !(self.qm - q).is_finite() || (self.qm - q).abs() > 0.5 * servo.backlash + 0.05 {
            self.qm = q;
            self.vm = v;
            self.owed = 0.0;
        }
    }
}

/// The mesh's damping, N m s/rad: a damping ratio of 0.5 for the motor side alone.
fn mesh_damping(servo: &DynamixelServo) -> f64 {
    (GEAR_STIFFNESS * servo.motor_inertia.max(1e-6)).sqrt()
}

/// The torque the motor side puts on the output (and its stiffness and damping
/// with respect to the output's angle and speed): zero inside the gap, a push (never
/// a pull) where it is closed.
pub fn coupling(servo: &DynamixelServo, gear: &Gear, q: f64, v: f64) -> Drive {
    let half = 0.5 * servo.backlash;
    let delta = gear.qm - q;
    let over = if delta > half {
        delta - half
    } else if delta < -half {
        delta + half
    } else {
        return Drive::default();
    };
    let d = mesh_damping(servo);
    let tau = GEAR_STIFFNESS * over + d * (gear.vm - v);
    if tau * over <= 0.0 {
        return Drive::default();
    }
    Drive {
        tau,
        k: GEAR_STIFFNESS,
        d,
    }
}

/// The torque on the output: the gap's ([`coupling`]) plus what the motor side
/// felt beyond it in the last step.
pub fn output_drive(servo: &DynamixelServo, gear: &mut Gear, q: f64, v: f64) -> Drive {
    let mut d = coupling(servo, gear, q, v);
    d.tau += gear.owed;
    gear.owed = 0.0;
    d
}

/// Advance the motor side `dt` with the output at its new `q`, `v`: the loop's
/// torque (on the output's angle; back-EMF on the motor's speed) less the gap's
/// reaction, linearly implicit in the back-EMF and in the mesh's stiffness and
/// damping (the output held at its new state), so a stiff mesh on a light armature
/// stays stable; then the Coulomb friction takes what it can to stop it.
///
/// Staggered: the output's implicit step saw the gap at the motor's old state, the
/// motor's sees it at its new one. The difference (`K dt vm' + D (vm' - vm)` where
/// engaged) is owed to the output in the next step, so the pair keeps its momentum.
pub fn advance_motor(servo: &DynamixelServo, gear: &mut Gear, goal: f64, q: f64, v: f64, dt: f64) {
    let m = servo.drive(goal, q, gear.vm);
    let c = coupling(servo, gear, q, v);
    let (k, d) = (c.k, c.d);
    let h = servo.motor_inertia.max(1e-6) + dt * (m.d + d) + dt * dt * k;
    let free = gear.vm + dt * (m.tau - c.tau - dt * k * gear.vm) / h;
    let stop = free * h / dt;
    let friction = stop.clamp(-servo.gear_friction, servo.gear_friction);
    let vm = free - dt * friction / h;
    gear.owed = k * dt * vm + d * (vm - gear.vm);
    gear.vm = vm;
    gear.qm += dt * gear.vm;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gap_passes_nothing_and_pushes_only() {
        let mut s = DynamixelServo::rx28();
        s.backlash = 0.01;
        s.motor_inertia = 0.01;
        let mut g = Gear {
            qm: 0.004,
            vm: 0.0,
            owed: 0.0,
        };
        assert_eq!(coupling(&s, &g, 0.0, 0.0).tau, 0.0);
        g.qm = 0.006;
        let c = coupling(&s, &g, 0.0, 0.0);
        assert!((c.tau - GEAR_STIFFNESS * 0.001).abs() < 1e-9);
        // Separating faster than the spring pushes: no pull.
        g.vm = -10.0;
        assert_eq!(coupling(&s, &g, 0.0, 0.0).tau, 0.0);
    }
}
