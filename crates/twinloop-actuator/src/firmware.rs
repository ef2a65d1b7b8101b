//! The servo's own position loop, as its firmware runs it on encoder counts.

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
}

impl Firmware {
    pub fn new(servo: ServoType) -> Firmware {
        Firmware {
            servo,
            registers: servo.factory_firmware(),
            torque_limit: 1.0,
            integral: 0.0,
            previous_error: 0.0,
        }
    }

    /// Forget the I and D history (torque off, a reboot).
    pub fn reset(&mut self) {
        self.integral = 0.0;
        self.previous_error = 0.0;
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
}
