//! State-space identification on the synthetic record of a known system
//! (tools/oracle/sysid_reference.py): predictions and metrics of the true system
//! against the oracle, then n4sid + PEM and the seed's ARX-reduce-PEM route.

use crate::common::*;
use twinloop_sysid::gramian::hankel_singular_values;
use twinloop_sysid::metrics::{fit_percent, seed_eq10_percent};
use twinloop_sysid::pem::{PemOptions, pem};
use twinloop_sysid::resid::{cross_correlation, residual_tests};
use twinloop_sysid::stats::{chi2_quantile, chi2_sf};
use twinloop_sysid::subspace::{SubspaceOptions, n4sid};
use twinloop_sysid::*;

fn close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (x, y) in a.iter().zip(b) {
        assert!(
            (x - y).abs() <= tol * y.abs().max(1.0),
            "{what}: {x} vs {y}"
        );
    }
}

fn unwrap_all(v: &[Option<f64>]) -> Vec<f64> {
    v.iter().map(|x| x.unwrap()).collect()
}

#[test]
fn true_model_predictions_and_fit_equal_reference() {
    let r = reference();
    let sys = true_system(&r);
    for name in ["est", "val"] {
        let d = record(&format!("synthetic_{name}.csv"));
        let t = &r["true_model"][name];
        let sim = sys.simulate(&d.u, None).unwrap();
        let p1 = sys.predict(&d, 1).unwrap();
        let p5 = sys.predict(&d, 5).unwrap();
        assert!(
            max_rel_err(
                &sim.columns(0, 50).transpose(),
                &matrix(&t["simulation_first_50"])
            ) < 1e-9
        );
        assert!(
            max_rel_err(
                &p5.columns(0, 50).transpose(),
                &matrix(&t["prediction_5_first_50"])
            ) < 1e-9
        );
        let cost = sys.prediction_cost(&d).unwrap();
        let want = t["prediction_cost"].as_f64().unwrap();
        assert!(
            (cost - want).abs() < 1e-9 * want,
            "{name}: cost {cost} vs {want}"
        );
        close(
            &unwrap_all(&fit_percent(&d.y, &sim)),
            &vector(&t["fit_simulation"]),
            1e-9,
            "fit sim",
        );
        close(
            &unwrap_all(&fit_percent(&d.y, &p1)),
            &vector(&t["fit_prediction_1"]),
            1e-9,
            "fit pred",
        );
        close(
            &unwrap_all(&fit_percent(&d.y, &p5)),
            &vector(&t["fit_prediction_5"]),
            1e-9,
            "fit pred 5",
        );
        close(
            &unwrap_all(&seed_eq10_percent(&d.y, &sim)),
            &vector(&t["eq10_simulation"]),
            1e-9,
            "eq10 sim",
        );
        close(
            &unwrap_all(&seed_eq10_percent(&d.y, &p1)),
            &vector(&t["eq10_prediction_1"]),
            1e-9,
            "eq10 pred",
        );
        // Residual correlations (mean-removed), lags -25..25.
        let e = sys.residuals(&d).unwrap();
        let row = |m: &nalgebra::DMatrix<f64>, i: usize| -> Vec<f64> {
            m.row(i).iter().copied().collect()
        };
        close(
            &cross_correlation(&row(&e, 0), &row(&e, 0), 25),
            &vector(&t["residual_autocorr_y1"]),
            1e-12,
            "acf",
        );
        close(
            &cross_correlation(&row(&e, 1), &row(&e, 4), 25),
            &vector(&t["residual_crosscorr_y2_y5"]),
            1e-12,
            "ccf",
        );
        close(
            &cross_correlation(&row(&e, 2), &row(&d.u, 6), 25),
            &vector(&t["residual_input_crosscorr_y3_u7"]),
            1e-12,
            "ccf u",
        );
    }
}

#[test]
fn chi_square_equals_scipy() {
    let c = &reference()["chi2"];
    for (i, k) in vector(&c["dof"]).iter().enumerate() {
        let q = chi2_quantile(0.99, *k);
        let want = vector(&c["q99"])[i];
        assert!((q - want).abs() < 1e-9 * want, "q99({k}) = {q} vs {want}");
        for (x, key) in [(*k, "sf_at_dof"), (2.0 * k, "sf_at_2dof")] {
            let (s, w) = (chi2_sf(x, *k), vector(&c[key])[i]);
            assert!(
                (s - w).abs() < 1e-10 * w.max(1e-300) + 1e-15,
                "sf({x}; {k}) = {s} vs {w}"
            );
        }
    }
}

#[test]
fn true_model_passes_residual_tests_and_underfit_fails() {
    let r = reference();
    let sys = true_system(&r);
    for name in ["est", "val"] {
        let d = record(&format!("synthetic_{name}.csv"));
        let t = residual_tests(
            &sys.residuals(&d).unwrap(),
            &d.u,
            &d.output_names,
            &d.input_names,
            25,
        );
        assert!(t.pass, "true model on {name}: {}", t.summary);
        assert_eq!(t.autocorrelation.len(), 6);
        assert_eq!(t.cross_correlation.len(), 15);
        assert_eq!(t.input_correlation.len(), 60);
    }
    let est = record("synthetic_est.csv");
    let val = record("synthetic_val.csv");
    let opts = SsOptions {
        order: 2,
        method: SsMethod::Pem,
        ..Default::default()
    };
    let id = identify_state_space(&est, Some(&val), &opts, &mut |_| {}).unwrap();
    assert!(
        !id.evaluation.residual_tests.pass,
        "an order-2 model of a 6th-order system must fail"
    );
    assert!(!id.evaluation.residual_tests.whiteness_pass);
}

#[test]
fn pem_reaches_the_true_cost_and_never_ends_worse() {
    let r = reference();
    let est = record("synthetic_est.csv");
    let truth = true_system(&r).prediction_cost(&est).unwrap();
    let init = n4sid(
        &est,
        &SubspaceOptions {
            order: Some(6),
            ..Default::default()
        },
    )
    .unwrap();
    let mut seen = Vec::new();
    let p = pem(&est, &init.model, None, &PemOptions::default(), &mut |pr| {
        seen.push(pr.cost)
    })
    .unwrap();
    eprintln!(
        "n4sid cost {:.6}, PEM cost {:.6} after {} iterations ({}), true system {:.6}: ratio {:.4}",
        p.initial_cost,
        p.final_cost,
        p.iterations,
        p.termination,
        truth,
        p.final_cost / truth
    );
    assert!(p.final_cost <= p.initial_cost);
    assert!(
        p.cost_history.windows(2).all(|w| w[1] <= w[0]),
        "cost went up: {:?}",
        p.cost_history
    );
    assert_eq!(seen.len(), p.iterations);
    assert!(
        p.final_cost <= 1.01 * truth,
        "PEM {} vs true {truth}",
        p.final_cost
    );
    // An unbiased fit of m free parameters lowers the cost below the truth's by about
    // m / (N ny) (here 132 / 6000): far below means something is wrong.
    let m = p.free_parameters as f64;
    assert_eq!(p.free_parameters, 6 * (6 + 10 + 6) + 6 * 6 - 36);
    assert!(p.final_cost >= truth * (1.0 - 3.0 * m / 6000.0));
    assert!((p.final_prediction_cost - p.final_cost).abs() < 1e-12 * p.final_cost);

    // Starting at the truth, PEM cannot end worse than the truth.
    let t = pem(
        &est,
        &true_system(&r),
        None,
        &PemOptions::default(),
        &mut |_| {},
    )
    .unwrap();
    assert!(t.final_cost <= t.initial_cost);
    assert!((t.initial_cost - truth).abs() < 1e-9 * truth);
    assert!(
        (t.final_cost - p.final_cost).abs() < 1e-4 * truth,
        "two starts, two optima: {} {}",
        t.final_cost,
        p.final_cost
    );
}

#[test]
fn identified_model_matches_truth_within_the_noise() {
    let r = reference();
    let truth = true_system(&r);
    let noise = r["noise_std"].as_f64().unwrap();
    let hsv_true = vector(&r["hsv"]);
    let est = record("synthetic_est.csv");
    let val = record("synthetic_val.csv");
    let opts = SsOptions {
        order: 6,
        method: SsMethod::Pem,
        ..Default::default()
    };
    let id = identify_state_space(&est, Some(&val), &opts, &mut |_| {}).unwrap();
    assert!(
        id.evaluation.residual_tests.pass,
        "{}",
        id.evaluation.residual_tests.summary
    );
    let hsv = id.evaluation.hankel_singular_values.clone().unwrap();
    let fit = unwrap_all(&id.evaluation.fit_percent.simulation);
    let fit_true = vector(&r["true_model"]["val"]["fit_simulation"]);
    // The spread of the estimates from noise alone: the same identification on
    // fresh records of the true system (Monte Carlo, 6 runs).
    let runs = 6;
    let mut rng = Gaussian::new(17);
    let mut hsv_err = vec![Vec::new(); 6];
    let mut fit_err = vec![Vec::new(); 6];
    for _ in 0..runs {
        let e = draw_record(&truth, 1000, noise, &mut rng);
        let v = draw_record(&truth, 1000, noise, &mut rng);
        let m = identify_state_space(&e, Some(&v), &opts, &mut |_| {}).unwrap();
        let h = hankel_singular_values(&m.model).unwrap();
        let ft = fit_percent(&v.y, &truth.simulate(&v.u, None).unwrap());
        for i in 0..6 {
            hsv_err[i].push(h[i] - hsv_true[i]);
            fit_err[i].push(m.evaluation.fit_percent.simulation[i].unwrap() - ft[i].unwrap());
        }
    }
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    for i in 0..6 {
        let (sh, sf) = (rms(&hsv_err[i]), rms(&fit_err[i]));
        let (dh, df) = (hsv[i] - hsv_true[i], fit[i] - fit_true[i]);
        eprintln!(
            "HSV {}: {:.4} vs true {:.4} (error {dh:+.4}, noise spread {sh:.4}); FIT y{}: {:.2} vs true {:.2} ({df:+.2}, spread {sf:.2})",
            i + 1,
            hsv[i],
            hsv_true[i],
            i + 1,
            fit[i],
            fit_true[i]
        );
        assert!(
            dh.abs() <= 4.0 * sh,
            "HSV {} off by {dh} with spread {sh}",
            i + 1
        );
        assert!(
            df.abs() <= 4.0 * sf,
            "FIT y{} off by {df} with spread {sf}",
            i + 1
        );
    }
}

#[test]
fn seed_route_arx_reduce_pem_reaches_the_same_optimum() {
    let est = record("synthetic_est.csv");
    let val = record("synthetic_val.csv");
    let base = SsOptions {
        order: 6,
        ..Default::default()
    };
    let a = identify_state_space(
        &est,
        Some(&val),
        &SsOptions {
            method: SsMethod::Pem,
            ..base
        },
        &mut |_| {},
    )
    .unwrap();
    let b = identify_state_space(
        &est,
        Some(&val),
        &SsOptions {
            method: SsMethod::ArxReducePem,
            ..base
        },
        &mut |_| {},
    )
    .unwrap();
    let (ca, cb) = (a.estimation_prediction_cost, b.estimation_prediction_cost);
    eprintln!("PEM from n4sid {ca:.6}, from reduced ARX {cb:.6}");
    assert!((ca - cb).abs() < 1e-4 * ca);
    assert_eq!(b.stages.len(), 2);
    assert!(b.stages[0].name.starts_with("arx"));
    assert_eq!(b.stages[0].order, 6 * 10);
    assert_eq!(b.stages[1].order, 6);
    let p = b.pem.as_ref().unwrap();
    assert!(p.final_cost <= p.initial_cost);
    assert!(
        (p.initial_cost - b.stages[1].estimation_prediction_cost).abs() < 1e-12 * p.initial_cost
    );
    assert_eq!(b.arx_hankel_singular_values.as_ref().unwrap().len(), 60);
    // Final model is better than the reduced ARX model it started from on validation data.
    for (f, s) in b
        .evaluation
        .fit_percent
        .prediction
        .iter()
        .zip(&b.stages[1].fit_percent.prediction)
    {
        assert!(f.unwrap() >= s.unwrap() - 0.5);
    }
}
