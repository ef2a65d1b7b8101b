//! The servo's own position loop, as its firmware runs it on encoder counts.

use crate::profile::Profile;
use crate::servo_type::{LoopFamily, ServoType};

/// The loop's registers and state. `registers` are the raw values of the three
/// registers [`ServoType::firmware_columns`] names: RX compliance slope, margin and
/// punch; MX(2.0)/X Position P, I and D gain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Firmware {
    pub servo: ServoType,
    pub registers: [f64; 3],
    /// Torque Limit (RX) or PWM Limit (X) as a fraction of full PWM.
    pub torque_limit: f64,
    /// Sum of errors (counts x cycles) for the I term.
    pub integral: f64,
    pub previous_error: f64,
    /// The motion profile (Profile Velocity and Acceleration, RX Moving Speed).
    pub profile: Profile,
}

impl Firmware {
    pub fn new(servo: ServoType) -> Firmware {
        Firmware {
            servo,
            registers: servo.factory_firmware(),
            torque_limit: 1.0,
            integral: 0.0,
            previous_error: 0.0,
            profile: Profile::default(),
        }
    }

    /// Forget the I and D history and the profile's reference (torque off, a reboot).
    pub fn reset(&mut self) {
        self.integral = 0.0;
        self.previous_error = 0.0;
        self.profile.restart();
    }

    /// One firmware cycle of `dt` as the servo runs it, shared by the bench and the
    /// simulator: the profile's reference towards `goal`, the count error against
    /// the `sensed` angle (both rad, rounded to the encoder's counts), the duty.
    pub fn cycle(&mut self, goal: f64, sensed: f64, dt: f64) -> f64 {
        let r = self.servo.resolution();
        let reference = self.profile.reference(goal, sensed, dt);
        self.duty(round(reference / r) - round(sensed / r))
    }

    /// The PWM duty in [-1, 1] for an error of `error` counts (goal - present), one
    /// firmware cycle.
    pub fn duty(&mut self, error: f64) -> f64 {
        let raw = match self.servo.family() {
            LoopFamily::Compliance => {
                let [slope, margin, punch] = self.registers;
                compliance_duty(error, rx_slope_units(slope), margin, punch / 1023.0)
            }
            LoopFamily::Pid => {
                let [p, i, d] = self.registers;
                self.integral += error;
                let de = error - self.previous_error;
                self.previous_error = error;
                let pwm = p / self.servo.p_gain_divisor() * error
                    + i / 65536.0 * self.integral
                    + d / 16.0 * de;
                pwm / self.servo.pwm_max()
            }
        };
        raw.clamp(-self.torque_limit, self.torque_limit)
    }
}

/// `x.round()` (half away from zero, the sign of a zero kept) to the bit, without
/// the call into the library `round` that baseline x86-64 makes (no SSE4.1): the
/// truncation is one instruction, and `x - trunc(x)` is exact below 2^52.
#[inline]
pub fn round(x: f64) -> f64 {
    // 2^52: from there on every f64 is a whole number (and NaN, infinities pass).
    if x.is_nan() || x.abs() >= 4_503_599_627_370_496.0 {
        return x;
    }
    let whole = x as i64;
    let fraction = x - whole as f64;
    let r = if fraction >= 0.5 {
        whole + 1
    } else if fraction <= -0.5 {
        whole - 1
    } else {
        whole
    };
    (r as f64).copysign(x)
}

/// RX compliance (EM-RX28 "Compliance"): no drive within `margin` counts of the goal,
/// then at least `punch` (a fraction of full drive), reaching full drive `slope`
/// counts beyond the margin.
pub fn compliance_duty(error: f64, slope: f64, margin: f64, punch: f64) -> f64 {
    let beyond = error.abs() - margin;
    if beyond <= 0.0 {
        return 0.0;
    }
    error.signum() * (beyond / slope.max(1.0)).max(punch).min(1.0)
}

/// The slope an RX applies for a Compliance Slope register value: the power of two
/// at or below it, 2 to 128 (EM-RX28 "Compliance Slope": seven steps).
pub fn rx_slope_units(raw: f64) -> f64 {
    let v = (raw as i64).clamp(2, 255) as u32;
    let step = 1u32 << (31 - v.leading_zeros());
    step.min(128) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compliance_and_pid() {
        let mut rx = Firmware::new(ServoType::Rx28);
        assert_eq!(rx.duty(1.0), 0.0); // inside the 1-count margin
        assert!((rx.duty(2.0) - 32.0 / 1023.0).abs() < 1e-12); // punch
        assert!((rx.duty(-17.0) + 0.5).abs() < 1e-12); // 16 of 32 counts
        assert_eq!(rx.duty(100.0), 1.0);
        let mut x = Firmware::new(ServoType::Xm430W350);
        // P 800: K_P 6.25 PWM units per count, full PWM (885) at 141.6 counts.
        assert!((x.duty(100.0) - 625.0 / 885.0).abs() < 1e-12);
        assert_eq!(x.duty(200.0), 1.0);
    }

    /// [`round`] against the library's on the halves, their neighbours, signed
    /// zeros, 2^52's neighbourhood and non-numbers.
    #[test]
    fn round_is_the_library_round() {
        let mut xs = vec![0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 1e300];
        for k in -40..40 {
            let h = k as f64 + 0.5;
            xs.extend([h, h.next_up(), h.next_down(), k as f64, 0.3 * k as f64]);
        }
        let big = 4_503_599_627_370_496.0f64;
        xs.extend([
            big,
            big.next_down(),
            -big.next_down(),
            big - 0.5,
            0.5f64.next_down(),
        ]);
        for x in xs {
            let (a, b) = (round(x), x.round());
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{x}: {a} {b}"
            );
        }
    }
}
