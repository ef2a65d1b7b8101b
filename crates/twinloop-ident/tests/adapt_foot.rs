//! A part on a foot, with a known truth: the served sweep's OP3 seed 2 (0.494 kg on
//! `r_ank_roll_link`, the right foot, at 5.7, 18.9, -23.1 mm in its frame) hidden on
//! the built-in OP3, its tip-over simulated in-process, the unchanged prior adapted
//! from it with the total mass. The truth is the simulator's CoM of the changed robot.
//!
//! A foot never moves in the lean, so the angles see the part's horizontal place and
//! not its height: the foot's fit keeps its height where it starts, now the middle of
//! the foot's outline (was a face of the outline grown by 10 mm: 10 mm above the sole
//! plate, the CoM 1.4 mm high in the served sweep). The shin and the ankle cross fit
//! the same angles with the part at the ankle axes, where it barely moves: their CoMs
//! lie millimetres from the truth, which is why `adapt`'s other places keep the foot
//! when all three fit (`twinloop_loop::other_places::a_foot_explains`).

use twinloop_description::builtin::{add_point_mass, resolve};
use twinloop_ident::adapt::{AdaptOptions, adapt};
use twinloop_ident::tipover_study::{StudyOptions, run_study};

const FOOT: &str = "r_ank_roll_link";
const CROSS: &str = "r_ank_pitch_link";
const MASS: f64 = 0.494;
const XYZ: [f64; 3] = [0.0057, 0.0189, -0.0231];

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

#[test]
fn a_part_on_a_foot_is_found_there_and_the_cross_fits_it_at_the_ankle_axes() {
    let prior = resolve("builtin:op3").unwrap();
    let mut robot = prior.clone();
    add_point_mass(&mut robot, FOOT, MASS, XYZ).unwrap();
    let study = run_study(&robot, &StudyOptions::default()).unwrap();
    let truth = study.com.truth;
    let on = |host: &str| {
        let opts = AdaptOptions {
            total_mass: Some(prior.total_mass() + MASS),
            host: Some(host.into()),
            ..Default::default()
        };
        adapt(&prior, &study, &opts).unwrap()
    };
    let (foot, cross) = std::thread::scope(|s| {
        let f = s.spawn(|| on(FOOT));
        let c = s.spawn(|| on(CROSS));
        (f.join().unwrap(), c.join().unwrap())
    });
    let (f, c) = (&foot.report, &cross.report);
    let (fa, ca) = (f.added.as_ref().unwrap(), c.added.as_ref().unwrap());
    let f_err = dist(f.adapted_com.unwrap(), truth);
    let c_err = dist(c.adapted_com.unwrap(), truth);
    eprintln!(
        "foot: part at {:?} (truth {XYZ:?}), CoM {:.2} mm off; cross: part {:?} standing \
         (ankle pitch midpoint), CoM {:.2} mm off; checks failed: foot {:?}, cross {:?}",
        fa.position_host,
        f_err * 1e3,
        ca.position,
        c_err * 1e3,
        f.failed_checks().map(|c| &c.name).collect::<Vec<_>>(),
        c.failed_checks().map(|c| &c.name).collect::<Vec<_>>()
    );
    // The foot: its checks pass, the part's height at the middle of the sole plates
    // (op3.xml: both boxes 8 mm thick at z -26.5 mm), the CoM within 1 mm.
    assert!(f.failed_checks().next().is_none());
    assert!((fa.position_host[2] + 0.0265).abs() < 1e-3, "{fa:?}");
    assert!(f_err < 1e-3, "foot: CoM {f_err} m from the truth");
    // The ankle cross fits the same angles with the part at the ankle pitch axes'
    // height (the standing frame's origin), where it barely moves, the CoM > 2 mm off.
    assert!(c.failed_checks().next().is_none());
    assert!(ca.position[2].abs() < 5e-3, "{ca:?}");
    assert!(c_err > 2e-3, "cross: CoM {c_err} m from the truth");
}
