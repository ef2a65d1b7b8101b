//! Bad input gives a clear error or a warning in the result, never a panic.

use crate::common::*;
use nalgebra::DMatrix;
use twinloop_sysid::pem::{PemOptions, pem};
use twinloop_sysid::subspace::{SubspaceOptions, n4sid};
use twinloop_sysid::*;

fn names(p: &str, n: usize) -> Vec<String> {
    (1..=n).map(|i| format!("{p}{i}")).collect()
}

#[test]
fn fewer_samples_than_parameters() {
    let est = record("synthetic_est.csv");
    let short = IoData::new(
        est.input_names.clone(),
        est.output_names.clone(),
        est.u.columns(0, 300).into_owned(),
        est.y.columns(0, 300).into_owned(),
        est.sample_time,
    )
    .unwrap();
    let e = estimate_arx(
        &short,
        ArxOrders {
            na: 24,
            nb: 24,
            nk: 1,
        },
    )
    .unwrap_err();
    assert!(e.message.contains("384 parameters per output"), "{e}");
    assert!(e.message.contains("276 usable rows"), "{e}");
    let e = identify_state_space(
        &short,
        None,
        &SsOptions {
            order: 6,
            method: SsMethod::ArxReducePem,
            arx_orders: ArxOrders {
                na: 24,
                nb: 24,
                nk: 1,
            },
            ..Default::default()
        },
        &mut |_| {},
    )
    .unwrap_err();
    assert!(e.message.contains("parameters"), "{e}");
    let tiny = IoData::new(
        est.input_names.clone(),
        est.output_names.clone(),
        est.u.columns(0, 20).into_owned(),
        est.y.columns(0, 20).into_owned(),
        None,
    )
    .unwrap();
    let e = n4sid(
        &tiny,
        &SubspaceOptions {
            order: Some(6),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.message.contains("too few"), "{e}");
    let truth = true_system(&reference());
    let e = pem(&tiny, &truth, None, &PemOptions::default(), &mut |_| {}).unwrap_err();
    assert!(e.message.contains("more samples than parameters"), "{e}");
}

#[test]
fn constant_input_is_named() {
    let mut est = record("synthetic_est.csv");
    est.u.row_mut(3).fill(0.25);
    let e = identify_arx(
        &est,
        None,
        ArxOrders {
            na: 2,
            nb: 2,
            nk: 1,
        },
        &EvaluationOptions::default(),
    )
    .unwrap_err();
    assert!(e.message.contains("input \"u4\" is constant (0.25)"), "{e}");
    let e = identify_state_space(&est, None, &SsOptions::default(), &mut |_| {}).unwrap_err();
    assert!(e.message.contains("\"u4\""), "{e}");
}

#[test]
fn copied_input_is_named_as_rank_deficient() {
    let mut est = record("synthetic_est.csv");
    let c = est.u.row(0).into_owned();
    est.u.set_row(5, &c);
    let e = estimate_arx(
        &est,
        ArxOrders {
            na: 1,
            nb: 2,
            nk: 1,
        },
    )
    .unwrap_err();
    assert!(e.message.contains("rank-deficient"), "{e}");
    assert!(e.message.contains("input \"u6\" at lag 1"), "{e}");
}

#[test]
fn nan_row_is_named() {
    let columns: Vec<String> = ["t", "u1", "y1"].iter().map(|s| s.to_string()).collect();
    let mut rows: Vec<Vec<f64>> = (0..50)
        .map(|k| vec![k as f64 * 0.01, (k as f64).sin(), (k as f64).cos()])
        .collect();
    rows[41][2] = f64::NAN;
    let e = IoData::from_table(&columns, &rows, &["u1".into()], &["y1".into()]).unwrap_err();
    assert!(e.message.contains("data row 42"), "{e}");
    assert!(e.message.contains("output \"y1\""), "{e}");
    rows[41][2] = f64::INFINITY;
    let e = IoData::from_table(&columns, &rows, &["u1".into()], &["y1".into()]).unwrap_err();
    assert!(e.message.contains("data row 42"), "{e}");
}

/// y(k) = 1.02 y(k-1) + u(k-1) + e(k): an unstable plant, identified as such.
fn unstable_record() -> IoData {
    let mut rng = Gaussian::new(5);
    let n = 300;
    let u = DMatrix::from_fn(1, n, |_, _| rng.next());
    let mut y = DMatrix::zeros(1, n);
    for k in 1..n {
        y[(0, k)] = 1.02 * y[(0, k - 1)] + u[(0, k - 1)] + 0.1 * rng.next();
    }
    IoData::new(names("u", 1), names("y", 1), u, y, Some(0.01)).unwrap()
}

#[test]
fn unstable_identified_model_is_a_warning_not_a_panic() {
    let d = unstable_record();
    let id = identify_arx(
        &d,
        None,
        ArxOrders {
            na: 1,
            nb: 1,
            nk: 1,
        },
        &EvaluationOptions::default(),
    )
    .unwrap();
    assert!((id.model.a[0][(0, 0)] + 1.02).abs() < 0.01);
    let ev = &id.evaluation;
    assert!(!ev.stability.stable);
    assert_eq!(ev.stability.poles_outside_unit_circle, 1);
    assert!(ev.hankel_singular_values.is_none());
    assert!(
        ev.warnings
            .iter()
            .any(|w| w.contains("unstable") && w.contains("1.02")),
        "{:?}",
        ev.warnings
    );
    // The seed's route reduces the (stable) predictor instead and says so.
    let ss = identify_state_space(
        &d,
        None,
        &SsOptions {
            order: 1,
            method: SsMethod::ArxReducePem,
            arx_orders: ArxOrders {
                na: 2,
                nb: 2,
                nk: 1,
            },
            ..Default::default()
        },
        &mut |_| {},
    )
    .unwrap();
    assert!(
        ss.warnings.iter().any(|w| w.contains("unstable")),
        "{:?}",
        ss.warnings
    );
    assert!(!ss.evaluation.stability.stable);
    // JSON of such a result holds no infinities (they would not be valid JSON).
    assert!(
        ss.evaluation
            .fit_percent
            .simulation
            .iter()
            .all(|f| f.is_none_or(|x| x.is_finite()))
    );
}

#[test]
fn impossible_orders_are_errors() {
    let est = record("synthetic_est.csv");
    let e = estimate_arx(
        &est,
        ArxOrders {
            na: 0,
            nb: 0,
            nk: 1,
        },
    )
    .unwrap_err();
    assert!(e.message.contains("no parameters"), "{e}");
    let e = estimate_arx(
        &est,
        ArxOrders {
            na: 2,
            nb: 0,
            nk: 1,
        },
    )
    .unwrap_err();
    assert!(e.message.contains("nb = 0"), "{e}");
    // A pure FIR model (na = 0) and a static one (no states) still evaluate.
    let fir = identify_arx(
        &est,
        None,
        ArxOrders {
            na: 0,
            nb: 2,
            nk: 1,
        },
        &EvaluationOptions::default(),
    )
    .unwrap();
    assert_eq!(fir.model.to_state_space().n(), 6 * 2);
    let stat = identify_arx(
        &est,
        None,
        ArxOrders {
            na: 0,
            nb: 1,
            nk: 0,
        },
        &EvaluationOptions::default(),
    )
    .unwrap();
    assert_eq!(stat.model.to_state_space().n(), 0);
    assert!(
        stat.evaluation
            .fit_percent
            .simulation
            .iter()
            .all(|f| f.is_some())
    );
    let e = n4sid(
        &est,
        &SubspaceOptions {
            order: Some(200),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.message.contains("order 200"), "{e}");
    let e = identify_state_space(
        &est,
        None,
        &SsOptions {
            order: 0,
            ..Default::default()
        },
        &mut |_| {},
    )
    .unwrap_err();
    assert!(e.message.contains("at least 1"), "{e}");
    let e = identify_state_space(
        &est,
        None,
        &SsOptions {
            order: 30,
            method: SsMethod::ArxReducePem,
            arx_orders: ArxOrders {
                na: 2,
                nb: 2,
                nk: 1,
            },
            ..Default::default()
        },
        &mut |_| {},
    )
    .unwrap_err();
    assert!(
        e.message.contains("above the ARX realisation's 12 states"),
        "{e}"
    );
    let other = IoData::new(
        names("v", 10),
        est.output_names.clone(),
        est.u.clone(),
        est.y.clone(),
        None,
    )
    .unwrap();
    let e = identify_arx(
        &est,
        Some(&other),
        ArxOrders {
            na: 1,
            nb: 1,
            nk: 1,
        },
        &EvaluationOptions::default(),
    )
    .unwrap_err();
    assert!(e.message.contains("channels differ"), "{e}");
}

#[test]
fn pem_refuses_an_unstable_predictor() {
    let r = reference();
    let mut m = true_system(&r);
    m.k *= 40.0;
    let est = record("synthetic_est.csv");
    let e = pem(&est, &m, None, &PemOptions::default(), &mut |_| {}).unwrap_err();
    assert!(e.message.contains("predictor A - KC is unstable"), "{e}");
}

#[test]
fn data_of_another_shape_is_an_error_not_a_panic() {
    let r = reference();
    let truth = true_system(&r);
    let est = record("synthetic_est.csv");
    let fewer = IoData::new(
        names("u", 9),
        est.output_names.clone(),
        est.u.rows(0, 9).into_owned(),
        est.y.clone(),
        None,
    )
    .unwrap();
    for e in [
        truth.simulate(&fewer.u, None).unwrap_err(),
        truth.predict(&fewer, 3).unwrap_err(),
        truth.residuals(&fewer).unwrap_err(),
        evaluate(&truth, &fewer, "validation", &EvaluationOptions::default()).unwrap_err(),
        pem(&fewer, &truth, None, &PemOptions::default(), &mut |_| {}).unwrap_err(),
    ] {
        assert!(e.message.contains("10 inputs"), "{e}");
    }
    let arx = estimate_arx(
        &est,
        ArxOrders {
            na: 1,
            nb: 1,
            nk: 1,
        },
    )
    .unwrap();
    assert!(
        arx.simulate(&fewer.u)
            .unwrap_err()
            .message
            .contains("10 inputs")
    );
    assert!(arx.predict(&fewer, 2).is_err());
    let x0 = nalgebra::DVector::zeros(4);
    assert!(
        truth
            .simulate(&est.u, Some(&x0))
            .unwrap_err()
            .message
            .contains("initial state")
    );
}
