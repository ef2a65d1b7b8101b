//! The catalogue against the ROBOTIS e-manual's numbers, typed here from the pages
//! (EM-RX28, EM-RX64, EM-MX28, EM-MX28-2, EM-XM430-W350, EM-XL430-W250), and the
//! stiffening values against the loops' own equations.

use twinloop_servos::{LoopFamily, Protocol, ServoModel};

#[test]
fn datasheets_are_the_e_manuals() {
    // (model, model number, protocol, stall N m, stall A, no-load rpm, V, gear ratio)
    let want = [
        (
            ServoModel::Rx28,
            28,
            Protocol::V1,
            3.7,
            1.9,
            85.0,
            18.5,
            193.0,
        ),
        (
            ServoModel::Mx28,
            29,
            Protocol::V1,
            2.5,
            1.4,
            55.0,
            12.0,
            193.0,
        ),
        (
            ServoModel::Mx28V2,
            30,
            Protocol::V2,
            2.5,
            1.4,
            55.0,
            12.0,
            193.0,
        ),
        (
            ServoModel::Xm430W350,
            1020,
            Protocol::V2,
            4.1,
            2.3,
            46.0,
            12.0,
            353.5,
        ),
        (
            ServoModel::Xl430W250,
            1060,
            Protocol::V2,
            1.5,
            1.4,
            61.0,
            12.0,
            258.5,
        ),
    ];
    for (m, number, protocol, torque, amps, rpm, volts, gear) in want {
        let s = m.spec();
        assert_eq!(m.model_number(), number, "{m}");
        assert_eq!(ServoModel::from_model_number(number), Some(m));
        assert_eq!(m.protocol(), protocol, "{m}");
        assert_eq!(
            (s.stall_torque, s.stall_current),
            (torque, Some(amps)),
            "{m}"
        );
        assert!((s.no_load_speed - rpm * std::f64::consts::TAU / 60.0).abs() < 1e-12);
        assert_eq!((s.voltage, s.gear_ratio), (volts, gear), "{m}");
    }
}

#[test]
fn encoders_and_loops() {
    // RX: 0.29 deg a count (1024 over 300 deg); MX and X: 0.088 deg (4096 a turn).
    assert!((ServoModel::Rx28.resolution().to_degrees() - 0.293).abs() < 1e-3);
    assert!((ServoModel::Xm430W350.resolution().to_degrees() - 0.088).abs() < 1e-3);
    assert!((ServoModel::Mx28.resolution().to_degrees() - 0.088).abs() < 1e-3);
    assert_eq!(ServoModel::Rx64.family(), Some(LoopFamily::Compliance));
    assert_eq!(ServoModel::Mx28.family(), Some(LoopFamily::Pid));
    assert_eq!(ServoModel::Cm730.family(), None);
    // K_p = P/8 (MX 1.0), K_P = P/128 (MX(2.0), X).
    assert_eq!(ServoModel::Mx64.p_gain_divisor(), Some(8.0));
    assert_eq!(ServoModel::Mx64V2.p_gain_divisor(), Some(128.0));
    assert_eq!(ServoModel::Rx28.p_gain_divisor(), None);
    // Factory gains: RX slope 32, margin 1, punch 32; MX P 32; MX(2.0) P 850;
    // XM430 P 800; XL430 P 640; I and D 0.
    assert_eq!(ServoModel::Rx28.factory_gains(), Some([32, 1, 32]));
    assert_eq!(ServoModel::Mx28.factory_gains(), Some([32, 0, 0]));
    assert_eq!(ServoModel::Mx106V2.factory_gains(), Some([850, 0, 0]));
    assert_eq!(ServoModel::Xm430W350.factory_gains(), Some([800, 0, 0]));
    assert_eq!(ServoModel::Xl430W250.factory_gains(), Some([640, 0, 0]));
}

#[test]
fn every_servo_has_a_known_way_to_stiffen_and_its_factory_values() {
    for m in ServoModel::SERVOS {
        let regs = m.loop_registers();
        assert!(!regs.is_empty(), "{m}");
        let gains = m.factory_gains().unwrap();
        // The registers' factory values are the loop's: RX margin 1 and slope 32,
        // MX/X the P gain.
        let factory: Vec<i32> = regs.iter().map(|r| r.factory).collect();
        match m.family().unwrap() {
            LoopFamily::Compliance => assert_eq!(factory, [gains[1], gains[1], gains[0], gains[0]]),
            LoopFamily::Pid => assert_eq!(factory, [gains[0]]),
        }
        assert!(m.stiff_values(2).is_some());
    }
    assert!(ServoModel::Cm730.loop_registers().is_empty());
    assert_eq!(ServoModel::Cm730.stiff_values(2), None);
}

#[test]
fn stiff_values_match_the_rx_slope() {
    // RX: margin 0, the slope asked.
    assert_eq!(ServoModel::Rx28.stiff_values(2), Some(vec![0, 0, 2, 2]));
    assert_eq!(ServoModel::Rx64.stiff_values(32), Some(vec![0, 0, 32, 32]));
    // MX (1.0): the e-manual's table, slope 32 is P 32 (the factory value), slope 8
    // is P 128; slope 2 asks 512 and gets the register's 254.
    assert_eq!(ServoModel::Mx28.stiff_values(32), Some(vec![32]));
    assert_eq!(ServoModel::Mx28.stiff_values(8), Some(vec![128]));
    assert_eq!(ServoModel::Mx28.stiff_values(2), Some(vec![254]));
    // X: full PWM (885) at the angle where an RX at slope s reaches full torque:
    // s * 0.293 deg. Slope 32 is 9.375 deg, 106.7 counts: P = 885*128/106.7 = 1062.
    let p32 = ServoModel::Xm430W350.stiff_values(32).unwrap()[0];
    let err = ServoModel::Xm430W350
        .full_output_error(p32)
        .unwrap()
        .to_degrees();
    assert_eq!(p32, 1062);
    assert!((err - 32.0 * 300.0 / 1024.0).abs() < 0.01, "{err}");
    // Slope 2 asks more than the register holds: 16383.
    assert_eq!(ServoModel::Xm430W350.stiff_values(2), Some(vec![16383]));
    // The factory XM430 (P 800) reaches full PWM at 141.6 counts, 12.4 deg.
    let f = ServoModel::Xm430W350.full_output_error(800).unwrap();
    assert!((f / ServoModel::Xm430W350.resolution() - 141.6).abs() < 1e-9);
    assert_eq!(
        ServoModel::Xm430W350.full_output_error(0),
        Some(f64::INFINITY)
    );
    assert_eq!(ServoModel::Mx28.full_output_error(32), None);
}
