//! Known-truth recovery without a bus: logs made by the bench with drawn parameters
//! (sampled as a bus host samples), fitted from the datasheet values.

use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::identify::{IdentifyOptions, identify, identify_with};
use twinloop_actuator::params::*;
use twinloop_actuator::synthetic::synthetic_log;
use twinloop_actuator::{Excitation, Load, ModelLevel, Pendulum, ServoType};
use twinloop_random::SplitMix64;

fn truth(servo: ServoType, level: ModelLevel, seed: u64) -> ServoParams {
    let mut rng = SplitMix64(seed);
    let mut p = defaults(servo, level);
    for &i in &level.parameters() {
        p.values[i] *= rng.uniform(0.7, 1.4);
    }
    p
}

#[test]
fn m1_recovered_for_each_type() {
    let load = Load::from(Pendulum {
        mass: 0.5,
        length: 0.15,
        arm_inertia: 0.002,
    });
    for (k, servo) in [ServoType::Rx28, ServoType::Mx64V2, ServoType::Xm430W350]
        .into_iter()
        .enumerate()
    {
        let truth = truth(servo, ModelLevel::M1, 7 + k as u64);
        let log = synthetic_log(
            &truth,
            &load,
            &Excitation::standard(servo, 1.0),
            1e-3,
            2e-4,
            3,
        );
        let start = defaults(servo, ModelLevel::M1);
        let t0 = std::time::Instant::now();
        let id = identify(&[log], &[], &load, &start, 0.25).unwrap();
        let took = t0.elapsed().as_secs_f64();
        let sd = id.params.uncertainty.unwrap();
        eprintln!(
            "{servo}: {took:.2} s, {} iterations, fit {:.3} mrad, held-out {:.3} mrad, undetermined {:?}, cond {:.3e}",
            id.iterations, id.fit_rms_mrad, id.heldout_rms_mrad, id.undetermined, id.condition
        );
        for &i in &ModelLevel::M1.parameters() {
            eprintln!(
                "  {:18} truth {:.5} fit {:.5} sd {:.5} err {:+.2} %",
                PARAM_NAMES[i],
                truth.values[i],
                id.params.values[i],
                sd[i],
                100.0 * (id.params.values[i] / truth.values[i] - 1.0)
            );
        }
        assert!(
            id.heldout_rms_mrad < 1e3 * servo.resolution(),
            "{servo}: held-out {} mrad",
            id.heldout_rms_mrad
        );
        for (name, value, sd) in &id.combinations {
            let want = match *name {
                "kt/resistance" => truth.values[KT] / truth.values[RESISTANCE],
                _ => {
                    truth.values[KT].powi(2) / truth.values[RESISTANCE]
                        + truth.values[FRICTION_VISCOUS]
                }
            };
            eprintln!(
                "  {name:34} truth {want:.5} fit {value:.5} sd {sd:.5} err {:+.2} %",
                100.0 * (value / want - 1.0)
            );
            assert!(
                (value / want - 1.0).abs() < 0.05,
                "{servo} {name}: {value} vs {want}"
            );
        }
        for &i in &ModelLevel::M1.parameters() {
            if id.undetermined.contains(&PARAM_NAMES[i]) {
                continue;
            }
            let err = (id.params.values[i] / truth.values[i] - 1.0).abs();
            assert!(
                err < 0.05 || (id.params.values[i] - truth.values[i]).abs() < 3.0 * sd[i],
                "{servo} {}: {} vs {} (sd {})",
                PARAM_NAMES[i],
                id.params.values[i],
                truth.values[i],
                sd[i]
            );
        }
    }
}

/// The ladder against BAM's finding: logs made by the richest rung (m4: Stribeck
/// and load-dependent friction) are fitted worse by m1 than by m4, held out.
#[test]
fn richer_rungs_are_needed_when_the_servo_has_their_friction() {
    let load = Load::from(Pendulum {
        mass: 0.5,
        length: 0.15,
        arm_inertia: 0.002,
    });
    let servo = ServoType::Xm430W350;
    let mut truth = truth(servo, ModelLevel::M4, 21);
    truth.values[LOAD_FRICTION] = 0.15;
    truth.values[FRICTION_STRIBECK] = 0.15;
    let log = synthetic_log(
        &truth,
        &load,
        &Excitation::standard(servo, 1.0),
        1e-3,
        2e-4,
        5,
    );
    let mut heldout = Vec::new();
    for level in ModelLevel::ALL {
        let id = identify(
            std::slice::from_ref(&log),
            &[],
            &load,
            &defaults(servo, level),
            0.25,
        )
        .unwrap();
        eprintln!(
            "{}: held-out {:.3} mrad RMS, fit {:.3}",
            level.name(),
            id.heldout_rms_mrad,
            id.fit_rms_mrad
        );
        heldout.push(id.heldout_rms_mrad);
    }
    // m4 is the truth's own model: within the encoder resolution; m1 misses by more
    // than twice as much (BAM: the richer models halve the error).
    assert!(heldout[3] < 1e3 * servo.resolution(), "{heldout:?}");
    assert!(heldout[0] > 2.0 * heldout[3], "{heldout:?}");
}

/// The fit's simulations run on rayon's pool (the Jacobian's columns, the CMA-ES
/// population; issue 32 item 4): on one worker and on three it finds the same
/// parameters, deviations and simulation counts, bit for bit. A 100 Hz log and a
/// short CMA-ES keep it to about a second.
#[test]
fn the_fit_does_not_depend_on_the_thread_count() {
    let load = Load::from(Pendulum {
        mass: 0.5,
        length: 0.15,
        arm_inertia: 0.002,
    });
    let servo = ServoType::Xm430W350;
    let mut truth = truth(servo, ModelLevel::M1, 41);
    truth.values[BACKLASH] = 0.6f64.to_radians();
    truth.values[SENSING_DELAY] = 1e-3;
    let log = synthetic_log(
        &truth,
        &load,
        &Excitation::standard(servo, 1.0),
        1e-2,
        2e-3,
        12,
    );
    let options = IdentifyOptions {
        nonsmooth: vec![BACKLASH, SENSING_DELAY],
        rounds: 1,
        cma_evaluations: 25,
    };
    let start = defaults(servo, ModelLevel::M1);
    let fit = |threads| {
        twinloop_optim::parallel::on_threads(threads, || {
            identify_with(
                std::slice::from_ref(&log),
                &[],
                &load,
                &start,
                0.25,
                &options,
            )
            .unwrap()
        })
    };
    let one = fit(1);
    let three = fit(3);
    assert!(
        one.evaluations > 50 && one.nonsmooth_evaluations > 10,
        "{one:?}"
    );
    assert_eq!(one.params.values, three.params.values);
    assert_eq!(one.params.uncertainty, three.params.uncertainty);
    assert_eq!(
        (one.evaluations, one.nonsmooth_evaluations, one.iterations),
        (
            three.evaluations,
            three.nonsmooth_evaluations,
            three.iterations
        )
    );
    assert_eq!(
        one.heldout_rms_mrad.to_bits(),
        three.heldout_rms_mrad.to_bits()
    );
}

/// Backlash (non-smooth: CMA-ES, alternating with LM) and the two delays (LM, with
/// the m1 parameters) come back from the excitation's slow back-and-forth through
/// zero load and its steps, on an XM430 (position and current). On an RX-28
/// (positions only, 5 mrad counts) the alternation stops in a local minimum
/// (docs/servo-models.md): not asserted here.
#[test]
fn backlash_and_delays_recovered() {
    let load = Load::from(Pendulum {
        mass: 0.5,
        length: 0.15,
        arm_inertia: 0.002,
    });
    let servo = ServoType::Xm430W350;
    let mut truth = truth(servo, ModelLevel::M1, 40);
    let mut rng = SplitMix64(90);
    truth.values[BACKLASH] = rng.uniform(0.3, 0.8).to_radians();
    truth.values[SENSING_DELAY] = rng.uniform(0.5e-3, 2e-3);
    truth.values[BUS_DELAY] = rng.uniform(0.5e-3, 3e-3);
    let log = synthetic_log(
        &truth,
        &load,
        &Excitation::standard(servo, 1.0),
        1e-3,
        2e-4,
        11,
    );
    let start = defaults(servo, ModelLevel::M1);
    let t0 = std::time::Instant::now();
    let options = IdentifyOptions {
        nonsmooth: NONSMOOTH.to_vec(),
        ..Default::default()
    };
    let id = identify_with(
        std::slice::from_ref(&log),
        &[],
        &load,
        &start,
        0.25,
        &options,
    )
    .unwrap();
    let took = t0.elapsed().as_secs_f64();
    // Without them, the same rung misses by more.
    let plain = identify(&[log], &[], &load, &start, 0.25).unwrap();
    let sd = id.params.uncertainty.unwrap();
    eprintln!(
        "{servo}: {took:.2} s ({} LM iterations, {} LM simulations, {} CMA-ES simulations), held-out {:.3} mrad (without backlash and delays {:.3}), undetermined {:?}",
        id.iterations,
        id.evaluations,
        id.nonsmooth_evaluations,
        id.heldout_rms_mrad,
        plain.heldout_rms_mrad,
        id.undetermined
    );
    for i in ModelLevel::M1.parameters().into_iter().chain(NONSMOOTH) {
        eprintln!(
            "  {:18} truth {:.6} fit {:.6} sd {:.6} err {:+.2} %",
            PARAM_NAMES[i],
            truth.values[i],
            id.params.values[i],
            sd[i],
            100.0 * (id.params.values[i] / truth.values[i] - 1.0)
        );
    }
    assert!(
        id.heldout_rms_mrad < 1e3 * servo.resolution(),
        "held-out {} mrad",
        id.heldout_rms_mrad
    );
    assert!(id.heldout_rms_mrad < plain.heldout_rms_mrad);
    assert!(id.undetermined.is_empty(), "{:?}", id.undetermined);
    for i in ModelLevel::M1.parameters().into_iter().chain(NONSMOOTH) {
        let err = (id.params.values[i] / truth.values[i] - 1.0).abs();
        assert!(
            err < 0.05 || (id.params.values[i] - truth.values[i]).abs() < 3.0 * sd[i],
            "{}: {} vs {} (sd {})",
            PARAM_NAMES[i],
            id.params.values[i],
            truth.values[i],
            sd[i]
        );
    }
}
