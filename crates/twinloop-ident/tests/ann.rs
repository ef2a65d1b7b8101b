//! The seed's ANN (seed 000 section V.C) on km20: trained on simulated changes only, it
//! must beat the seed's manual method on held-out changes; the static route that makes
//! its data must agree with the full simulated tip-over; the data must not depend on
//! the thread count; the network file must read back exactly.

use twinloop_description::Description;
use twinloop_description::builtin::resolve;
use twinloop_ident::ann::{Mlp, TrainOptions, train};
use twinloop_ident::ann_adapt::{AnnModel, AnnTrainOptions, MethodErrors, train_ann};
use twinloop_ident::ann_data::{
    BodyParts, Change, DataOptions, check_against_simulation, generate,
};
use twinloop_ident::tipover_study::StudyOptions;

fn km20() -> Description {
    resolve("builtin:km20").unwrap()
}

fn small_options(samples: usize, mass_input: bool) -> AnnTrainOptions {
    AnnTrainOptions {
        mass_input,
        restarts: 2,
        data: DataOptions {
            samples,
            seed: 7,
            ..Default::default()
        },
        train: TrainOptions {
            max_epochs: 300,
            ..Default::default()
        },
    }
}

fn show(set: &str, m: &MethodErrors) {
    eprintln!(
        "{set:10} {:28} position {:6.2} / {:6.2} / {:6.2} mm, hip {:6.2} mm, vCoM {:6.2} / {:6.2} / {:6.2} mm, fall {:6.3} / {:6.3} / {:6.3} deg (mean / p95 / max), failed {}",
        m.method,
        m.position_mm[0],
        m.position_mm[1],
        m.position_mm[2],
        m.hip_mm[0],
        m.com_mm[0],
        m.com_mm[1],
        m.com_mm[2],
        m.fall_deg[0],
        m.fall_deg[1],
        m.fall_deg[2],
        m.failed
    );
}

/// The seed's own inputs (no mass): its data had one 0.2 kg battery, ours vary the
/// mass tenfold, which the angles alone cannot tell from its position. It still places
/// the CoM better than the manual method.
#[test]
fn with_the_seeds_inputs_alone_the_ann_still_beats_the_manual_com() {
    let (model, report) = train_ann(&km20(), &small_options(2000, false), &|_| {}).unwrap();
    assert_eq!(model.net.n_inputs(), 8);
    for set in [&report.testing, &report.validation] {
        for m in &set.methods {
            show(&set.set, m);
        }
        let (manual, ann) = (&set.methods[1], &set.methods[2]);
        assert!(ann.com_mm[0] < 0.5 * manual.com_mm[0]);
        assert!(ann.position_mm[0] < manual.position_mm[0]);
    }
}

#[test]
fn ann_beats_the_seeds_manual_method_on_held_out_changes() {
    let t = std::time::Instant::now();
    let (model, report) = train_ann(&km20(), &small_options(2000, true), &|_| {}).unwrap();
    eprintln!(
        "2000 changes: split {:?}, layout {:?}, best epoch {} of {}, {:?} s ({:.1} s total)",
        report.split,
        report.layout,
        report.log.best_epoch,
        report.log.train_mse.len(),
        report.seconds,
        t.elapsed().as_secs_f64()
    );
    assert_eq!(report.layout, vec![9, 5, 10, 5, 9]);
    assert_eq!(model.parts.names.len(), 6);
    for set in [&report.testing, &report.validation] {
        for m in &set.methods {
            show(&set.set, m);
        }
        let (manual, calibrated, ann, exact) = (
            &set.methods[0],
            &set.methods[1],
            &set.methods[2],
            &set.methods[3],
        );
        assert_eq!(ann.failed, 0);
        // Held out: the network never saw these changes. The seed's manual method:
        for m in [manual, calibrated] {
            assert!(
                ann.com_mm[0] < 0.5 * m.com_mm[0] && ann.com_mm[1] < 0.5 * m.com_mm[1],
                "{}: ANN vCoM error {:?} mm, {} {:?} mm",
                set.set,
                ann.com_mm,
                m.method,
                m.com_mm
            );
            assert!(ann.position_mm[0] < m.position_mm[0]);
        }
        // Its fall angles: far better than the seed's CoM as printed, and better than
        // the calibrated manual method, which inverts the two angles almost exactly.
        assert!(ann.fall_deg[0] < 0.1 * manual.fall_deg[0]);
        assert!(ann.fall_deg[0] < calibrated.fall_deg[0]);
        let _ = exact;
        // The exact inversion sees all four angles, the total mass and the link: on
        // changes above the ankles it is the better (on the feet its iteration of the
        // feet's mass share amplifies the noise).
        assert!(set.methods[4].com_mm[0] < ann.com_mm[0]);
        assert!(exact.com_mm[2] > set.methods[4].com_mm[2]);
    }
}

#[test]
fn the_data_do_not_depend_on_the_thread_count() {
    let opts = |threads| DataOptions {
        samples: 40,
        seed: 3,
        threads,
        ..Default::default()
    };
    let (_, a) = generate(&km20(), &opts(1), &|_| {}).unwrap();
    assert_eq!(a.len(), 40);
    // rayon's pool of 2 and of 5 workers (issue 32 item 4): the same samples, bit
    // for bit, in the same order.
    for threads in [2, 5] {
        let (_, b) = generate(&km20(), &opts(threads), &|_| {}).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.change, y.change);
            assert_eq!(x.measured_deg, y.measured_deg);
            assert_eq!(x.positions, y.positions);
            assert_eq!(x.com, y.com);
        }
    }
    // Every change is inside the mass range and on a known part.
    let parts = BodyParts::of(&km20()).unwrap();
    for s in &a {
        assert!((0.05..0.5).contains(&s.change.mass));
        assert_eq!(parts.part_of(&s.change.link), Some(s.part));
    }
}

#[test]
fn km20_body_parts_are_the_trunk_and_its_five_limbs() {
    let p = BodyParts::of(&km20()).unwrap();
    eprintln!("{:?} {:?}", p.names, p.three_mass_part);
    let part = |l: &str| p.names[p.part_of(l).unwrap()].clone();
    assert_eq!(part("torso"), "torso");
    assert_eq!(part("l_foot"), part("l_thigh"));
    assert_ne!(part("l_thigh"), part("r_thigh"));
    assert_eq!(part("l_upper_arm"), part("l_shoulder"));
    assert_eq!(part("head"), part("neck"));
    let mass_of = |l: &str| p.three_mass_part[p.part_of(l).unwrap()];
    assert_eq!(
        [
            mass_of("l_shin"),
            mass_of("r_foot"),
            mass_of("l_upper_arm"),
            mass_of("head")
        ],
        [0, 1, 2, 2]
    );
}

/// The static route against the full simulated tip-over study (0.5 deg/s ramp, 0.05
/// deg/s creep, stiffened servos) on changes of the kinds the data hold.
#[test]
fn the_static_route_agrees_with_the_simulated_tipover() {
    let changes = [
        Change {
            link: "torso".into(),
            mass: 0.45,
            xyz: [0.05, -0.03, 0.1],
        },
        Change {
            link: "l_thigh".into(),
            mass: 0.3,
            xyz: [0.02, 0.01, -0.05],
        },
        Change {
            link: "r_upper_arm".into(),
            mass: 0.2,
            xyz: [-0.01, -0.01, -0.03],
        },
    ];
    let checks =
        check_against_simulation(&km20(), &changes, &StudyOptions::default(), 0, &|_| {}).unwrap();
    for c in &checks {
        eprintln!(
            "{} {} kg: static {:?} simulated {:?} deg, max difference {:.3?} deg",
            c.change.link,
            c.change.mass,
            c.static_deg,
            c.simulated_deg,
            c.max_difference()
        );
        let [sagittal, frontal] = c.max_difference();
        // Forward and backward (the network's inputs): the ramp's lag and the servos'
        // give; sideways the legs' servos give more under the parallelogram lean.
        assert!(sagittal < 0.2, "{c:?}");
        assert!(frontal < 2.0, "{c:?}");
    }
}

#[test]
fn the_network_file_reads_back_exactly() {
    // A network trained on a known function, then written and read.
    let mut rng = twinloop_random::SplitMix64(5);
    let rows: Vec<Vec<f64>> = (0..400)
        .map(|_| vec![rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)])
        .collect();
    let f = |x: &[f64]| vec![x[0] * x[1] + 0.3 * x[0], (2.0 * x[1]).sin()];
    let ys: Vec<Vec<f64>> = rows.iter().map(|x| f(x)).collect();
    let (net, log) = train(
        &rows[..300],
        &ys[..300],
        &rows[300..],
        &ys[300..],
        &TrainOptions {
            max_epochs: 600,
            patience: 600,
            ..Default::default()
        },
    )
    .unwrap();
    // It learnt the function (held-out rows, standardised MSE).
    let best = log.test_mse[log.best_epoch - 1];
    eprintln!(
        "known function: best testing MSE {best:.2e} at epoch {}",
        log.best_epoch
    );
    assert!(best < 5e-3, "{best}");
    let back = Mlp::from_json(&net.to_json()).unwrap();
    assert_eq!(back, net);
    for x in &rows {
        let (a, b) = (net.predict(x), back.predict(x));
        assert!(a.iter().zip(&b).all(|(u, v)| u.to_bits() == v.to_bits()));
    }
    // The whole saved model too.
    let (model, _) = train_ann(&km20(), &small_options(100, true), &|_| {}).unwrap();
    let text = model.to_json();
    let back = AnnModel::from_json(&text).unwrap();
    assert_eq!(back, model);
    assert_eq!(back.to_json(), text);
    // A broken file names what is wrong.
    let bad = text.replacen("\"inputs\": 9", "\"inputs\": 7", 1);
    let e = AnnModel::from_json(&bad).unwrap_err().to_string();
    assert!(e.contains("layers[0]"), "{e}");
}
