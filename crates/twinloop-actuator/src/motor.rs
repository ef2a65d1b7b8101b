//! The DC motor behind the gearbox, seen at the output shaft.

/// Motor torque at the output for a PWM duty `duty` in [-1, 1] at supply `voltage`
/// and output speed `v`: the winding sees `duty V - kt v` (back-EMF), its current is
/// that over `resistance`, and the torque is `kt` times the current:
/// `tau = kt (duty V - kt v) / R`. Returns (torque N m, current A).
pub fn motor_torque(kt: f64, resistance: f64, voltage: f64, duty: f64, v: f64) -> (f64, f64) {
    let current = (duty * voltage - kt * v) / resistance;
    (kt * current, current)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stall_and_no_load() {
        // RX-28 datasheet: 3.7 N m at 1.9 A from 18.5 V.
        let (kt, r) = (3.7 / 1.9, 18.5 / 1.9);
        let (tau, i) = motor_torque(kt, r, 18.5, 1.0, 0.0);
        assert!((tau - 3.7).abs() < 1e-12 && (i - 1.9).abs() < 1e-12);
        let (tau, _) = motor_torque(kt, r, 18.5, 1.0, 18.5 / kt);
        assert!(tau.abs() < 1e-12);
    }
}
