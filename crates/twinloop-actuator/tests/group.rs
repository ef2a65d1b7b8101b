//! Several servos of one type fitted together (shared and per-servo parameters),
//! known truth without a bus: virtual servos made by the bench from one drawn truth,
//! (a) with one parameter different per servo, (b) identical.

use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::group::{ServoData, compare, identify_servos};
use twinloop_actuator::params::*;
use twinloop_actuator::synthetic::synthetic_log;
use twinloop_actuator::{Excitation, Load, ModelLevel, Pendulum, ServoType};
use twinloop_random::SplitMix64;

fn truth(servo: ServoType, seed: u64) -> ServoParams {
    let mut rng = SplitMix64(seed);
    let mut p = defaults(servo, ModelLevel::M1);
    for &i in &ModelLevel::M1.parameters() {
        p.values[i] *= rng.uniform(0.7, 1.4);
    }
    p
}

const LOAD: Pendulum = Pendulum {
    mass: 0.5,
    length: 0.15,
    arm_inertia: 0.002,
};

/// One log per servo, each sampled with its own jitter.
fn servos(truths: &[ServoParams]) -> Vec<ServoData> {
    truths
        .iter()
        .enumerate()
        .map(|(k, t)| ServoData {
            name: format!("id {}", k + 1),
            logs: vec![synthetic_log(
                t,
                &Load::from(LOAD),
                &Excitation::standard(t.servo, 1.0),
                1e-3,
                2e-4,
                100 + k as u64,
            )],
            holdout: Vec::new(),
            load: LOAD,
        })
        .collect()
}

fn print(c: &twinloop_actuator::group::Comparison) {
    for s in &c.spreads {
        eprintln!(
            "  {:18} spread {:.4} sd {:.4} chi2 {:.2} dof {} p {:.2e} differs {}",
            s.name, s.relative_spread, s.relative_sd, s.chi2, s.dof, s.p_value, s.differs
        );
    }
    for (e, a) in c.each.servos.iter().zip(&c.all_shared.servos) {
        eprintln!(
            "  {}: held-out each {:.3} shared {:.3} mrad; sd/independent {:?}",
            e.name,
            e.heldout_rms_mrad,
            a.heldout_rms_mrad,
            e.params
                .uncertainty
                .unwrap()
                .iter()
                .zip(&e.sd_independent)
                .take(5)
                .map(|(a, b)| format!("{:.1}", a / b))
                .collect::<Vec<_>>()
        );
    }
    eprintln!(
        "  simulations each {} shared {}",
        c.each.simulations, c.all_shared.simulations
    );
}

/// (a) Four XM430s of one truth but for friction_base (0.75, 1, 1.25, 1.5 times):
/// the comparison names friction_base alone as differing, and the mixed fit
/// (friction_base per servo, the rest shared) recovers every parameter within 5 %.
#[test]
fn one_parameter_that_differs_per_servo_is_found_and_recovered() {
    let servo = ServoType::Xm430W350;
    let common = truth(servo, 31);
    let truths: Vec<ServoParams> = [0.75, 1.0, 1.25, 1.5]
        .iter()
        .map(|f| {
            let mut p = common.clone();
            p.values[FRICTION_BASE] *= f;
            p
        })
        .collect();
    let data = servos(&truths);
    let start = defaults(servo, ModelLevel::M1);
    let t0 = std::time::Instant::now();
    let id = identify_servos(&data, &start, None, 0.25, 2).unwrap();
    eprintln!("identify_servos: {:.2} s", t0.elapsed().as_secs_f64());
    print(&id.comparison);
    assert_eq!(id.comparison.differing(), vec![FRICTION_BASE]);
    let mixed = id.chosen;
    assert_eq!(mixed.per_servo, vec![FRICTION_BASE]);
    eprintln!(
        "mixed: {} iterations, {} simulations",
        mixed.iterations, mixed.simulations
    );
    for (s, t) in mixed.servos.iter().zip(&truths) {
        let sd = s.params.uncertainty.unwrap();
        for &i in &ModelLevel::M1.parameters() {
            let err = s.params.values[i] / t.values[i] - 1.0;
            eprintln!(
                "  {} {:18} truth {:.5} fit {:.5} sd {:.1e} err {:+.2} %",
                s.name,
                PARAM_NAMES[i],
                t.values[i],
                s.params.values[i],
                sd[i],
                100.0 * err
            );
            assert!(err.abs() < 0.05, "{} {}: {err}", s.name, PARAM_NAMES[i]);
        }
        eprintln!("  {} held-out {:.3} mrad", s.name, s.heldout_rms_mrad);
        assert!(s.heldout_rms_mrad < 1e3 * servo.resolution());
    }
}

/// (b) Four identical XM430s (logs differ only in their sampling): no parameter
/// differs, and one shared set scores as well held out as each servo's own.
#[test]
fn identical_servos_share_their_parameters() {
    let servo = ServoType::Xm430W350;
    let truths = vec![truth(servo, 32); 4];
    let data = servos(&truths);
    let start = defaults(servo, ModelLevel::M1);
    let t0 = std::time::Instant::now();
    let c = compare(&data, &start, 0.25, 2).unwrap();
    eprintln!("compare: {:.2} s", t0.elapsed().as_secs_f64());
    print(&c);
    assert!(c.differing().is_empty(), "{:?}", c.differing());
    for (e, a) in c.each.servos.iter().zip(&c.all_shared.servos) {
        assert!(a.heldout_rms_mrad < 1.1 * e.heldout_rms_mrad + 0.05);
    }
}

/// (b) on position-only logs: six identical RX-28s (5 mrad counts, no current).
#[test]
fn identical_position_only_servos_share_their_parameters() {
    let servo = ServoType::Rx28;
    let truths = vec![truth(servo, 33); 6];
    let data = servos(&truths);
    let start = defaults(servo, ModelLevel::M1);
    let t0 = std::time::Instant::now();
    let c = compare(&data, &start, 0.25, 2).unwrap();
    eprintln!("compare: {:.2} s", t0.elapsed().as_secs_f64());
    print(&c);
    assert!(c.differing().is_empty(), "{:?}", c.differing());
}
