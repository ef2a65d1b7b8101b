//! The study recorded in docs/compliant-fit.md: evaluations each fit method needs to bring
//! the largest of the eight correction errors below 1e-2 and 1e-3, on noise-free data of the
//! seed's gait (sl 0.03 m, Tss 0.5 s, 30 s at 1 kHz) made by the compact model with seed 002's
//! Table 1, from all ones, on the same budget.
//!
//! ```sh
//! cargo run --release -p twinloop-compliant --example fit_method_comparison [BUDGET]
//! ```
//! (6000 evaluations by default; the doc's long run used 60000.)

use std::path::Path;
use twinloop_gait::GaitPlan;
use twinloop_ident::compliant_fit::synthetic::{gait_reference, simulate};
use twinloop_ident::compliant_fit::{
    FitOptions, FitProblem, Method, Progress, SEED_PARAMETERS, fit, parse_model_file,
};
use twinloop_reduced::compact::{CompactModel, Corrections};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let budget: usize = match std::env::args().nth(1) {
        Some(a) => a.parse().map_err(|e| format!("BUDGET {a:?}: {e}"))?,
        None => 6000,
    };
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let plan = GaitPlan {
        step_length: 0.03,
        t_single: 0.5,
        steps: 60,
        ..GaitPlan::default()
    };
    let reference = gait_reference(&plan, 1e-3, 30.0)?;
    let want = Corrections::seed_table1().to_array();
    let max_err = |p: &[f64; 10]| (0..8).map(|i| (p[i] - want[i]).abs()).fold(0.0, f64::max);
    println!(
        "| plant | method | seed | evals to 1e-2 | evals to 1e-3 | evaluations | final max error (8) | MSE after [m^2] |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for pelvis in ["free", "held"] {
        // COMAN's left support leg in a 0.5 rad crouch, K_h 8000, K_s 100, damping 1
        // (seed 002, eq 7-8): what `twinloop compliant stiffness` reports.
        let text = format!(
            "urdf = \"models/coman/coman.urdf\"\nknee_bend = 0.5\nk_series = 100.0\n\
             d_stiff = 1.0\nd_compliant = 1.0\npelvis = \"{pelvis}\"\n"
        );
        let plant = parse_model_file(&text, &repo)?;
        let truth = CompactModel {
            plant,
            corrections: Corrections::seed_table1(),
        };
        let data = simulate(&truth, reference.clone(), 0.0, 0, "seed gait")?;
        let problem = FitProblem::new(plant, &data, Corrections::default(), &SEED_PARAMETERS)?;
        for method in [Method::Lm, Method::Cmaes, Method::Power] {
            let seeds: &[u64] = if method == Method::Lm {
                &[0]
            } else {
                &[1, 2, 3]
            };
            for &seed in seeds {
                let mut o = FitOptions::for_method(method);
                o.max_evaluations = budget;
                o.seed = seed;
                let (mut first2, mut first3) = (None, None);
                let r = fit(&problem, method, &o, &mut |p: &Progress| {
                    let e = max_err(&p.params);
                    if e < 1e-2 && first2.is_none() {
                        first2 = Some(p.evaluations);
                    }
                    if e < 1e-3 && first3.is_none() {
                        first3 = Some(p.evaluations);
                    }
                })?;
                let show =
                    |v: Option<usize>| v.map_or("not reached".to_string(), |v| v.to_string());
                println!(
                    "| pelvis {pelvis} | {method:?} | {seed} | {} | {} | {} | {:.2e} | {:.2e} |",
                    show(first2),
                    show(first3),
                    r.evaluations,
                    max_err(&r.params.to_array()),
                    r.mse_after
                );
            }
        }
    }
    Ok(())
}
