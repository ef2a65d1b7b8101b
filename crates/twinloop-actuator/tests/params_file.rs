//! The parameter and load files: round trip, and errors naming file and field.

use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::params::N_PARAMS;
use twinloop_actuator::{ModelLevel, Pendulum, ServoParams, ServoType};

#[test]
fn files_round_trip_and_errors_name_the_field() {
    for servo in ServoType::ALL {
        for level in ModelLevel::ALL {
            let mut p = defaults(servo, level);
            p.uncertainty = Some([0.5; N_PARAMS].map(|x| x * 1e-3));
            let back = ServoParams::parse(&p.to_toml("a comment"), "p.toml").unwrap();
            // Terms the rung lacks are neither written nor read back.
            let mut want = p.clone();
            let used = level.parameters();
            for i in 0..8 {
                if !used.contains(&i) {
                    want.uncertainty.as_mut().unwrap()[i] = 0.0;
                }
            }
            assert_eq!(back, want, "{servo} {level:?}");
        }
    }
    // Backlash and delays: on any rung, written where not 0, read back.
    let mut p = defaults(ServoType::Rx28, ModelLevel::M1);
    p.values[twinloop_actuator::params::BACKLASH] = 0.0087;
    p.values[twinloop_actuator::params::BUS_DELAY] = 0.002;
    let text = p.to_toml("");
    assert!(text.contains("backlash = 0.0087") && !text.contains("sensing_delay"));
    assert_eq!(ServoParams::parse(&text, "p.toml").unwrap(), p);
    let err = |text: &str| ServoParams::parse(text, "p.toml").unwrap_err().to_string();
    assert!(
        err("[servo]\nmodel = \"RX-28\"\n[params]\nbus_delay = 0.5\n")
            .starts_with("p.toml: [params] bus_delay: 0.5 s is above the 0.1 s")
    );
    assert_eq!(
        err("[servo]\nmodel = \"RX-99\"\n[params]\n"),
        "p.toml: [servo] model: unknown servo \"RX-99\" (known: RX-28, RX-64, MX-64(2.0), XM430-W350, XL330-M288-T)"
    );
    assert!(
        err("[servo]\nmodel = \"RX-28\"\n[params]\nkt = -1\n")
            .starts_with("p.toml: [params] kt: -1 is not")
    );
    assert!(
        err("[servo]\nmodel = \"RX-28\"\n[params]\nktt = 1\n")
            .starts_with("p.toml: [params] ktt: unknown parameter")
    );
    assert!(
        err("[servo]\nmodel = \"RX-28\"\n[params]\nload_friction = 0.1\n")
            .contains("model m1 has no load_friction")
    );
    assert!(err("[servo]\nmodel = \"RX-28\"\n").contains("[params]: missing table"));
    let load = |text: &str| Pendulum::parse(text, "load.toml");
    assert!(
        (load("mass = 0.5\nlength = 0.1\narm_inertia = 0.001\n")
            .unwrap()
            .inertia()
            - 0.006)
            .abs()
            < 1e-15
    );
    assert_eq!(
        load("mass = 0.5\nlength = 0.1\n").unwrap_err().to_string(),
        "load.toml: arm_inertia: missing (mass kg, length m, arm_inertia kg m^2)"
    );
    assert!(
        load("mass = \"x\"\nlength = 0.1\narm_inertia = 0\n")
            .unwrap_err()
            .to_string()
            .starts_with("load.toml: mass: must be a number")
    );
    // Broken TOML: the line and column of the fault (the parser's span), not only
    // what it is. Line 3 column 8 is the unterminated value; line 2 column 1 a key
    // with no `=`.
    let e = load("mass = 0.5\nlength = 0.1\narm_in = [0.001\n").unwrap_err();
    assert!(
        e.to_string().starts_with("load.toml: line 3, column "),
        "{e}"
    );
    assert_eq!(
        err("[servo]\nmodel\n")
            .split(": ")
            .take(2)
            .collect::<Vec<_>>(),
        ["p.toml", "line 2, column 6"]
    );
}
