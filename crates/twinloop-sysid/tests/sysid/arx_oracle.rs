//! ARX estimation, simulation and prediction against numpy (tools/oracle/sysid_reference.py).

use crate::common::*;
use twinloop_sysid::metrics::fit_percent;
use twinloop_sysid::{ArxOrders, estimate_arx};

#[test]
fn arx_coefficients_equal_numpy_lstsq() {
    let r = reference();
    let est = record("synthetic_est.csv");
    for case in r["arx"].as_array().unwrap() {
        let orders = ArxOrders {
            na: case["na"].as_u64().unwrap() as usize,
            nb: case["nb"].as_u64().unwrap() as usize,
            nk: case["nk"].as_u64().unwrap() as usize,
        };
        assert_eq!(
            orders.first_row(),
            case["first_row"].as_u64().unwrap() as usize
        );
        let m = estimate_arx(&est, orders).unwrap();
        let mut worst = 0.0f64;
        for (i, a) in case["A"].as_array().unwrap().iter().enumerate() {
            worst = worst.max(max_rel_err(&m.a[i], &matrix(a)));
        }
        for (j, b) in case["B"].as_array().unwrap().iter().enumerate() {
            worst = worst.max(max_rel_err(&m.b[j], &matrix(b)));
        }
        assert_eq!(m.a.len(), orders.na);
        assert_eq!(m.b.len(), orders.nb);
        assert!(worst < 1e-9, "{orders:?}: max coefficient error {worst:e}");
        let rms = case["residual_rms"].as_f64().unwrap();
        let ours = (m.noise_covariance.trace() / 6.0).sqrt();
        assert!(
            (ours - rms).abs() < 1e-9 * rms,
            "{orders:?}: residual rms {ours} vs {rms}"
        );
        eprintln!("{orders:?}: max |coef - numpy| / max(1,|numpy|) = {worst:.2e}");
    }
}

#[test]
fn arx_simulation_and_prediction_equal_reference_loops() {
    let r = reference();
    let est = record("synthetic_est.csv");
    let val = record("synthetic_val.csv");
    for case in r["arx"].as_array().unwrap() {
        let orders = ArxOrders {
            na: case["na"].as_u64().unwrap() as usize,
            nb: case["nb"].as_u64().unwrap() as usize,
            nk: case["nk"].as_u64().unwrap() as usize,
        };
        if case.get("val_simulation_first_50").is_none() {
            continue;
        }
        let m = estimate_arx(&est, orders).unwrap();
        let sim = m.simulate(&val.u).unwrap();
        let want = matrix(&case["val_simulation_first_50"]);
        let got = sim.columns(0, 50).transpose();
        assert!(max_rel_err(&got, &want) < 1e-9, "{orders:?} simulation");
        for h in [1usize, 2, 3] {
            let key = format!("val_prediction_{h}_first_50");
            if let Some(p) = case.get(&key) {
                let got = m.predict(&val, h).unwrap().columns(0, 50).transpose();
                let err = max_rel_err(&got, &matrix(p));
                assert!(err < 1e-9, "{orders:?} {h}-step prediction: {err:e}");
            }
        }
        if let Some(f) = case.get("val_fit_simulation") {
            let fit = fit_percent(&val.y, &sim);
            for (a, b) in fit.iter().zip(vector(f)) {
                assert!((a.unwrap() - b).abs() < 1e-9);
            }
            let fitp = fit_percent(&val.y, &m.predict(&val, 1).unwrap());
            for (a, b) in fitp.iter().zip(vector(&case["val_fit_prediction_1"])) {
                assert!((a.unwrap() - b).abs() < 1e-9);
            }
        }
    }
}

#[test]
fn arx_state_space_realisation_has_the_same_predictor_and_simulation() {
    let est = record("synthetic_est.csv");
    let val = record("synthetic_val.csv");
    for orders in [
        ArxOrders {
            na: 2,
            nb: 2,
            nk: 1,
        },
        ArxOrders {
            na: 3,
            nb: 2,
            nk: 0,
        },
        ArxOrders {
            na: 1,
            nb: 4,
            nk: 2,
        },
    ] {
        let m = estimate_arx(&est, orders).unwrap();
        let ss = m.to_state_space();
        assert_eq!(ss.n(), 6 * orders.na.max(orders.nb + orders.nk - 1));
        let e1 = m.residuals(&val).unwrap();
        let e2 = ss.residuals(&val).unwrap();
        assert!((e1 - e2).amax() < 1e-9, "{orders:?}: predictors differ");
        let s1 = m.simulate(&val.u).unwrap();
        let s2 = ss.simulate(&val.u, None).unwrap();
        assert!((s1 - s2).amax() < 1e-9, "{orders:?}: simulations differ");
        for h in [2, 4] {
            let p1 = m.predict(&val, h).unwrap();
            let p2 = ss.predict(&val, h).unwrap();
            assert!(
                (p1 - p2).amax() < 1e-9,
                "{orders:?}: {h}-step predictions differ"
            );
        }
        let w = 0.7;
        let g1 = m.frequency_response(w).unwrap();
        let g2 = ss.frequency_response(w).unwrap();
        assert!(
            (g1 - g2).camax() < 1e-9,
            "{orders:?}: frequency responses differ"
        );
    }
}
