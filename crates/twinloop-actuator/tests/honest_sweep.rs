//! Servo identification reports no certainty it does not have (issue 30, item 9):
//! hidden random truths, every reported number within max(5 %, 3 sd) of the truth or
//! reported as not determined with the truth inside its interval. The in-CI part is
//! two truths (an RX and an X), a fit run to a bound, and two fits of late-sampled
//! logs the held-out check flags; `examples/servo_sweep.rs` runs the long sweep and
//! `bench/servo/honest_sweep.sh` the one over ptys, whose numbers
//! docs/servo-models.md gives.

use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::identify::{HELDOUT_COUNTS, identify};
use twinloop_actuator::log::ServoLog;
use twinloop_actuator::params::{FRICTION_VISCOUS, ModelLevel, PARAM_NAMES};
use twinloop_actuator::sweep::{bench_load, checks, draw_truth, run_case};
use twinloop_actuator::synthetic::synthetic_log;
use twinloop_actuator::{Excitation, Load, ServoType};

fn assert_honest(servo: ServoType, seed: u64) {
    let case = run_case(servo, seed, 1.0).unwrap();
    eprintln!("{servo} seed {seed}: fit in {:.2} s", case.seconds);
    for c in &case.checks {
        eprintln!(
            "  {:34} truth {:.5} fit {:.5} err {:+.2} % sd {:.2e} interval {:?}",
            c.name,
            c.truth,
            c.value,
            100.0 * c.error(),
            c.sd,
            c.interval
        );
        assert!(c.honest(), "{servo} seed {seed}: {c:?}");
    }
}

#[test]
fn rx28_hidden_truth_every_number_within_3_sd_or_not_determined() {
    // Position only: kt, resistance and friction_viscous are intervals.
    assert_honest(ServoType::Rx28, 101);
}

#[test]
fn xm430_hidden_truth_every_number_within_3_sd_or_not_determined() {
    assert_honest(ServoType::Xm430W350, 102);
}

#[test]
fn a_parameter_run_to_its_bound_is_not_determined_and_given_an_interval() {
    // A servo with no viscous friction: the fit runs friction_viscous towards 0, where
    // a deviation from the Jacobian means nothing; it must say so and give [0, hi].
    let servo = ServoType::Xm430W350;
    let mut truth = draw_truth(servo, 103);
    truth.values[FRICTION_VISCOUS] = 0.0;
    let load = Load::from(bench_load(servo));
    let excitation = Excitation::standard(servo, 1.0);
    let data = synthetic_log(&truth, &load, &excitation, 1e-3, 2e-4, 5);
    let id = identify(&[data], &[], &load, &defaults(servo, ModelLevel::M1), 0.25).unwrap();
    eprintln!(
        "undetermined {:?}, intervals {:?}, viscous {}",
        id.undetermined, id.intervals, id.params.values[FRICTION_VISCOUS]
    );
    let viscous = id
        .intervals
        .iter()
        .find(|(n, _, _)| *n == "friction_viscous")
        .expect("friction_viscous reported as not determined");
    assert_eq!(viscous.1, 0.0, "the interval reaches the bound");
    assert!(viscous.2 > 0.0, "{viscous:?}");
    assert!(
        id.params.uncertainty.unwrap()[FRICTION_VISCOUS].is_infinite(),
        "no finite deviation is claimed"
    );
    for c in checks(&id, &truth) {
        assert!(c.honest(), "{c:?}");
    }
}

/// What a bus host on an overloaded machine logs (the pty sweep at load 9-18): every
/// `every`-th read answered `lag` rows late, its time stamp that of the request.
fn late_samples(mut log: ServoLog, every: usize, lag: usize) -> ServoLog {
    let n = log.len();
    for k in (0..n.saturating_sub(lag)).step_by(every) {
        log.q[k] = log.q[k + lag];
        log.v[k] = log.v[k + lag];
        if let Some(c) = log.current.as_mut() {
            c[k] = c[k + lag];
        }
    }
    log
}

/// Issue 30 item 9 over ptys: fits of late-sampled logs came back 4.3-4.9 deviations
/// off while the held-out check warned. A fit the held-out check flags (over
/// HELDOUT_COUNTS encoder counts) must report every parameter as not determined, its
/// interval holding the truth, and widen the combinations' deviations until they
/// cover it.
#[test]
fn a_fit_the_heldout_check_flags_reports_every_parameter_as_not_determined() {
    for (servo, seed) in [(ServoType::Rx28, 104), (ServoType::Xm430W350, 105)] {
        let truth = draw_truth(servo, seed);
        let load = Load::from(bench_load(servo));
        let excitation = Excitation::standard(servo, 1.0);
        let log = |s| {
            late_samples(
                synthetic_log(&truth, &load, &excitation, 1e-3, 2e-4, s),
                7,
                15,
            )
        };
        let (data, holdout) = (log(2 * seed + 1), log(2 * seed + 2));
        let id = identify(
            &[data],
            &[holdout],
            &load,
            &defaults(servo, ModelLevel::M1),
            0.25,
        )
        .unwrap();
        eprintln!(
            "{servo} seed {seed}: held-out {:.2} counts, fit {:.2} mrad, intervals {:?}, combinations {:?}",
            id.heldout_counts, id.fit_rms_mrad, id.intervals, id.combinations
        );
        assert!(
            id.heldout_counts > HELDOUT_COUNTS,
            "{servo}: {}",
            id.heldout_counts
        );
        for &i in &id.fitted {
            assert!(
                id.undetermined.contains(&PARAM_NAMES[i]),
                "{servo}: {}",
                PARAM_NAMES[i]
            );
            assert!(id.params.uncertainty.unwrap()[i].is_infinite());
        }
        for c in checks(&id, &truth) {
            assert!(c.honest(), "{servo} seed {seed}: {c:?}");
        }
    }
}
