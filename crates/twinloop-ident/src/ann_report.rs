//! The HTML report of `adapt train`: the methods' errors on the testing and validation
//! sets, rows in the style of seed 000's Tables VI and VII, the learning curve and the
//! static route against the simulated tip-over.

use crate::ann_adapt::{METHOD_NAMES, MethodErrors, SetEvaluation, TrainReport};
use twinloop_report::{Plot, Report};

fn errors_table(rep: &mut Report, set: &SetEvaluation) {
    let f = |v: [f64; 3], d: usize| format!("{:.d$} / {:.d$} / {:.d$}", v[0], v[1], v[2]);
    let rows = set
        .methods
        .iter()
        .map(|m: &MethodErrors| {
            vec![
                m.method.clone(),
                format!("{} ({} failed)", m.n, m.failed),
                f(m.position_mm, 2),
                f(m.hip_mm, 2),
                f(m.com_mm, 2),
                f(m.fall_deg, 3),
            ]
        })
        .collect();
    rep.table(
        vec![
            "method".into(),
            "changes".into(),
            "three-mass positions, mm".into(),
            "hip mass, mm".into(),
            "vCoM, mm".into(),
            "fall angles fw/bw, deg".into(),
        ],
        rows,
    );
}

fn rows_table(rep: &mut Report, set: &SetEvaluation) {
    let c = |v: [f64; 3]| format!("{:.1}, {:.1}, {:.1}", v[0] / 10.0, v[1] / 10.0, v[2] / 10.0);
    let a = |v: [f64; 2]| format!("{:.2} / {:.2}", v[0], v[1]);
    let mut header = vec![
        "change".into(),
        "part (Mp)".into(),
        "measured fw / bw".into(),
        "true vCoM (cm)".into(),
    ];
    for m in METHOD_NAMES {
        header.push(format!("{m}: vCoM (cm)"));
    }
    header.push("ANN: falling angles".into());
    header.push("true falling angles".into());
    let rows = set
        .rows
        .iter()
        .map(|r| {
            let mut row = vec![
                format!(
                    "{:.3} kg on {} at ({:.3}, {:.3}, {:.3})",
                    r.change.mass, r.change.link, r.change.xyz[0], r.change.xyz[1], r.change.xyz[2]
                ),
                r.part.clone(),
                a(r.measured_deg),
                c(r.com_mm[0]),
            ];
            row.extend(r.com_mm[1..].iter().map(|v| c(*v)));
            row.push(a(r.fall_deg[2]));
            row.push(a(r.true_deg));
            row
        })
        .collect();
    rep.table(header, rows);
}

/// The report.
pub fn train_html_report(r: &TrainReport) -> Report {
    let mut rep = Report::new(format!(
        "The seed's ANN on {}: training and evaluation",
        r.robot
    ));
    rep.paragraph(format!(
        "Seed 000 section V.C: a perceptron with hidden layers {:?} (layout {:?}) maps the \
         forward and backward fall angles{} and the body part of the change to the \
         positions of the three masses of the three-mass LIPM. {} random changes \
         ({}-{} kg, anywhere in a link's collision outline), fall angles by the static \
         tipping route with {} deg of noise; split {} training / {} testing (chooses the \
         epoch) / {} validation (never seen). {}. Wall time: data {:.1} s on {} threads, \
         training {:.1} s, evaluation {:.1} s.",
        &r.layout[1..r.layout.len() - 1],
        r.layout,
        if r.layout[0] > 2 + r.parts.len() {
            ", the weighed added mass"
        } else {
            ""
        },
        r.samples,
        r.mass_range[0],
        r.mass_range[1],
        r.noise_deg,
        r.split[0],
        r.split[1],
        r.split[2],
        r.optimiser,
        r.seconds[0],
        r.threads,
        r.seconds[1],
        r.seconds[2]
    ));
    rep.paragraph(
        "Errors are mean / 95th percentile / largest over the set. The positions' error is the \
         mean over the three masses of the distance from the changed robot's own three-mass \
         LIPM; the fall angles are the static forward and backward angles of each model's CoM \
         on the robot's feet, against the changed robot's.",
    );
    for set in [&r.testing, &r.validation] {
        rep.heading(format!(
            "{} set ({})",
            set.set,
            if set.set == "testing" {
                "seed Table VI"
            } else {
                "seed Table VII"
            }
        ));
        errors_table(&mut rep, set);
        rep.subheading("The first changes of the set");
        rows_table(&mut rep, set);
    }
    rep.heading("Learning curve");
    let epochs: Vec<f64> = (1..=r.log.train_mse.len()).map(|e| e as f64).collect();
    rep.plot(
        &Plot::new(
            format!(
                "Mean squared error (standardised outputs); best epoch {}",
                r.log.best_epoch
            ),
            "epoch",
            "MSE",
        )
        .line("training", &epochs, &r.log.train_mse)
        .line("testing", &epochs, &r.log.test_mse)
        .log_y(),
    );
    if !r.sim_check.is_empty() {
        rep.heading("The static route against the simulated tip-over");
        let rows = r
            .sim_check
            .iter()
            .map(|c| {
                let d = c.max_difference();
                let four =
                    |v: [f64; 4]| format!("{:.2} / {:.2} / {:.2} / {:.2}", v[0], v[1], v[2], v[3]);
                vec![
                    format!("{:.3} kg on {}", c.change.mass, c.change.link),
                    four(c.static_deg),
                    four(c.simulated_deg),
                    format!("{:.3}", d[0]),
                    format!("{:.3}", d[1]),
                ]
            })
            .collect();
        rep.table(
            vec![
                "change".into(),
                "static fw / bw / l / r, deg".into(),
                "simulated".into(),
                "largest fw/bw difference".into(),
                "largest l/r difference".into(),
            ],
            rows,
        );
    }
    rep
}
