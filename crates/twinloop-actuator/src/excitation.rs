//! What `experiment servo` drives a servo through, as a function of time: steps of
//! several sizes, a chirp, sinusoids at three loop gains, and a slow back-and-forth
//! through zero load (backlash). Each part excites what a parameter needs: steps and
//! the chirp the armature and the motor, sinusoids at several gains separate the
//! motor from the friction (BAM varies its kp for the same reason), the slow part the
//! Coulomb and Stribeck friction.

use crate::servo_type::{LoopFamily, ServoType};
use std::f64::consts::TAU;

/// One stretch of the sequence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Part {
    /// Hold `goal` (rad).
    Hold { goal: f64 },
    /// Linear chirp of `amplitude` rad from `f0` to `f1` Hz.
    Chirp { amplitude: f64, f0: f64, f1: f64 },
    /// Sinusoid of `amplitude` rad at `f` Hz.
    Sine { amplitude: f64, f: f64 },
    /// Triangle of `amplitude` rad at `speed` rad/s: 0, +a, -a, 0.
    Triangle { amplitude: f64, speed: f64 },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Excitation {
    pub servo: ServoType,
    /// (duration s, part, gain factor: the loop's stiffness over the factory one).
    pub parts: Vec<(f64, Part, f64)>,
}

impl Excitation {
    /// The standard sequence, about 31 s, scaled in amplitude by `amplitude` (1: the
    /// largest step 0.8 rad, for a pendulum free to swing to the horizontal).
    pub fn standard(servo: ServoType, amplitude: f64) -> Excitation {
        let a = amplitude;
        let mut parts = vec![(0.5, Part::Hold { goal: 0.0 }, 1.0)];
        for g in [0.15, -0.15, 0.4, -0.4, 0.8, 0.0] {
            parts.push((0.8, Part::Hold { goal: g * a }, 1.0));
        }
        parts.push((
            8.0,
            Part::Chirp {
                amplitude: 0.3 * a,
                f0: 0.3,
                f1: 3.0,
            },
            1.0,
        ));
        for gain in [0.5, 1.0, 2.0] {
            parts.push((
                3.0,
                Part::Sine {
                    amplitude: 0.5 * a,
                    f: 0.8,
                },
                gain,
            ));
        }
        parts.push((
            8.0,
            Part::Triangle {
                amplitude: 0.3 * a,
                speed: 0.15 * a,
            },
            1.0,
        ));
        parts.push((0.5, Part::Hold { goal: 0.0 }, 1.0));
        Excitation { servo, parts }
    }

    pub fn duration(&self) -> f64 {
        self.parts.iter().map(|p| p.0).sum()
    }

    /// The goal (rad) and the three firmware registers (raw) at time `t`; `None`
    /// after the end.
    pub fn at(&self, t: f64) -> Option<(f64, [f64; 3])> {
        let mut t0 = 0.0;
        for &(d, part, gain) in &self.parts {
            if t < t0 + d {
                let s = t - t0;
                let goal = match part {
                    Part::Hold { goal } => goal,
                    Part::Chirp { amplitude, f0, f1 } => {
                        let k = (f1 - f0) / d;
                        amplitude * (TAU * (f0 * s + 0.5 * k * s * s)).sin()
                    }
                    Part::Sine { amplitude, f } => amplitude * (TAU * f * s).sin(),
                    Part::Triangle { amplitude, speed } => {
                        triangle(s * speed / amplitude) * amplitude
                    }
                };
                return Some((goal, self.registers(gain)));
            }
            t0 += d;
        }
        None
    }

    /// The firmware registers for a loop `gain` times the factory stiffness: P gain
    /// times `gain`; RX compliance slope divided by it (the slope is the error of
    /// full drive).
    pub fn registers(&self, gain: f64) -> [f64; 3] {
        let mut r = self.servo.factory_firmware();
        match self.servo.family() {
            LoopFamily::Compliance => r[0] = (r[0] / gain).round(),
            LoopFamily::Pid => r[0] = (r[0] * gain).round(),
        }
        r
    }
}

/// Unit triangle wave of period 4 in `x`: 0 -> 1 -> -1 -> 0.
fn triangle(x: f64) -> f64 {
    let p = x.rem_euclid(4.0);
    if p < 1.0 {
        p
    } else if p < 3.0 {
        2.0 - p
    } else {
        p - 4.0
    }
}
