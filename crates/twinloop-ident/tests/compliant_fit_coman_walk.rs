//! Issue 7's full-model check: the compact model (seed 002, eq 14-17) fitted by
//! Levenberg-Marquardt to COMAN walking in the full simulator (the committed 30 s
//! datasets of `twinloop experiment compliant-walk`) must beat the all-ones model on the training
//! gait and on the two other gaits it was not fitted to (seed 002: "the set of parameters
//! found has been also used to perform walking with different gaits").
//!
//! K_C and D_C come from COMAN's URDF at the pose and joint compliance the walk used
//! (knee bend 0.6 rad, K_s 300, d_stiff 100, d_compliant 5). With the pelvis free (the
//! x-z stiffness under forces alone) the fit generalises; with the pelvis held the x-z
//! block is nearly singular, the corrections wander and one of the two other gaits gets
//! worse (docs/compliant-fit.md): that result is printed, not asserted.

use std::path::{Path, PathBuf};
use twinloop_ident::compliant_fit::{
    self as fit, Dataset, FitOptions, FitProblem, Method, generalisation, parse_model_file,
};
use twinloop_reduced::compact::Corrections;

fn data(name: &str) -> Dataset {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    Dataset::read(&p).unwrap()
}

fn plant(pelvis: &str) -> twinloop_reduced::compact::SagittalCompliance {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = format!(
        "urdf = \"models/coman/coman.urdf\"\nsupport = \"left\"\nknee_bend = 0.6\n\
         k_harmonic = 8000.0\nk_series = 300.0\nd_stiff = 100.0\nd_compliant = 5.0\n\
         pelvis = \"{pelvis}\"\n"
    );
    parse_model_file(&text, &repo).unwrap()
}

fn fit_and_validate(pelvis: &str) -> (fit::FitResult, Vec<fit::Validation>) {
    let train = data("coman_walk_sl0.03_tss0.5.csv");
    let others = [
        data("coman_walk_sl0.02_tss0.4.csv"),
        data("coman_walk_sl0.04_tss0.6.csv"),
    ];
    let ones = Corrections::from_slice(&[1.0; 10]);
    let problem = FitProblem::new(plant(pelvis), &train, ones, &[0, 1, 2, 3, 4, 5, 6, 7]).unwrap();
    let mut options = FitOptions::for_method(Method::Lm);
    options.max_evaluations = 2000;
    let result = fit::fit(&problem, Method::Lm, &options, &mut |_| {}).unwrap();
    let val = generalisation(&problem.plant, &ones, &result.params, &others);
    eprintln!(
        "pelvis {pelvis}: training MSE {:.3e} -> {:.3e} m^2 ({} evaluations, {})",
        result.mse_before, result.mse_after, result.evaluations, result.stop
    );
    for v in &val {
        eprintln!(
            "  {}: {:.3e} -> {:.3e} m^2",
            v.source, v.mse_before, v.mse_after
        );
    }
    (result, val)
}

#[test]
fn fitted_model_beats_all_ones_on_training_and_two_other_gaits() {
    let (result, val) = fit_and_validate("free");
    assert!(result.mse_after < 0.01 * result.mse_before, "{result:?}");
    assert_eq!(val.len(), 2);
    for v in &val {
        assert!(v.mse_after < 0.1 * v.mse_before, "{v:?}");
    }
}

#[test]
fn held_pelvis_fit_lowers_the_training_error() {
    let (result, _) = fit_and_validate("held");
    assert!(result.mse_after < result.mse_before, "{result:?}");
}

/// The committed 30 s datasets (written by `twinloop experiment compliant-walk`): 30 000 rows at 1 kHz with the seed's columns.
#[test]
fn committed_datasets_are_30_s_at_1_khz() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data");
    for name in [
        "coman_walk_sl0.03_tss0.5.csv",
        "coman_walk_sl0.02_tss0.4.csv",
        "coman_walk_sl0.04_tss0.6.csv",
    ] {
        let text = std::fs::read_to_string(format!("{dir}/{name}")).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("t,xr,zr,x,z,phase"), "{name}");
        let mut n = 0;
        for (i, line) in lines.enumerate() {
            let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            assert_eq!(f[0], i as f64 / 1000.0, "{name} row {i}");
            assert!(f[5] == 0.0 || f[5] == 1.0);
            assert!(
                (f[3] - f[1]).abs() < 0.03 && (f[4] - f[2]).abs() < 0.01,
                "{name} row {i}"
            );
            n += 1;
        }
        assert_eq!(n, 30_000, "{name}");
    }
}
