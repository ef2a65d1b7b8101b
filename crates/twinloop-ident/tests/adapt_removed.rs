//! A part taken off (seed 000's scenario b: the robot without a battery its model
//! has) is found as naturally as one added, and the checks `adapt` makes before it
//! writes a model catch what no real change can be. Known truth: km20's motor
//! battery (0.15 kg on the torso, at its box's centre) is taken off the simulated
//! robot, its tip-over study is the measurement, and the unchanged prior is adapted.

use std::sync::OnceLock;
use twinloop_description::Description;
use twinloop_description::builtin::{add_point_mass, resolve};
use twinloop_ident::adapt::{AdaptOptions, adapt};
use twinloop_ident::adapt_checks::MAX_PART_FRACTION;
use twinloop_ident::tipover_study::{StudyOptions, StudyReport, run_study};

const HOST: &str = "torso";
/// km20's motor battery: 0.15 kg, its box centred here in the torso's frame
/// (`builtin/km20.rs`).
const MASS: f64 = 0.15;
const XYZ: [f64; 3] = [-0.025, 0.0, 0.082];

fn prior() -> Description {
    resolve("builtin:km20").unwrap()
}

fn prior_mass() -> f64 {
    twinloop_dynamics::Model::from_description(&prior())
        .unwrap()
        .total_mass
}

fn truth() -> &'static StudyReport {
    static T: OnceLock<StudyReport> = OnceLock::new();
    T.get_or_init(|| {
        let mut robot = prior();
        add_point_mass(&mut robot, HOST, -MASS, XYZ).unwrap();
        let study = run_study(&robot, &StudyOptions::default()).unwrap();
        let json = serde_json::to_string(&study).unwrap();
        serde_json::from_str(&json).unwrap()
    })
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn a_battery_taken_off_is_found_on_its_link_with_the_checks_passed() {
    let study = truth();
    let opts = AdaptOptions {
        total_mass: Some(prior_mass() - MASS),
        ..Default::default()
    };
    let a = adapt(&prior(), study, &opts).unwrap();
    let r = &a.report;
    let part = r.added.as_ref().unwrap();
    let com_err = dist(r.adapted_com.unwrap(), study.com.truth);
    let pos_err = dist(part.position_host, XYZ);
    eprintln!(
        "removed: {:.3} kg on {} at {:?} (truth {XYZ:?}): {:.1} mm; CoM error {:.2} mm; checks {:?}",
        part.mass,
        part.host,
        part.position_host,
        pos_err * 1e3,
        com_err * 1e3,
        r.checks
    );
    assert!((part.mass + MASS).abs() < 1e-9, "mass {}", part.mass);
    assert_eq!(part.host, HOST);
    assert!(com_err < 3e-3, "CoM error {com_err}");
    assert!(pos_err < 3e-2, "position error {pos_err}");
    assert!(r.failed_checks().next().is_none(), "{:?}", r.checks);
    assert_eq!(r.checks.len(), 4, "{:?}", r.checks);
    // The adapted model is lighter by the part, and its torso keeps a valid inertia.
    let adapted = a.robot.as_ref().unwrap();
    assert!((adapted.total_mass() - (prior_mass() - MASS)).abs() < 1e-9);
    let lint = twinloop_description::lint::lint(adapted);
    assert!(!lint.has_errors(), "{lint:?}");
}

#[test]
fn a_scale_reading_three_times_the_model_fails_the_mass_check_naming_it() {
    let a = adapt(
        &prior(),
        truth(),
        &AdaptOptions {
            total_mass: Some(3.0 * prior_mass()),
            ..Default::default()
        },
    )
    .unwrap();
    let failed: Vec<_> = a.report.failed_checks().map(|c| c.name.as_str()).collect();
    assert!(failed.contains(&"part-mass-plausible"), "{failed:?}");
    let c = a
        .report
        .checks
        .iter()
        .find(|c| c.name == "part-mass-plausible")
        .unwrap();
    assert!(
        c.detail.contains(&format!("{:.3} kg", 2.0 * prior_mass())),
        "{}",
        c.detail
    );
    const { assert!(MAX_PART_FRACTION < 2.0) };
}

#[test]
fn a_part_too_light_for_the_shift_lands_outside_the_robot_and_fails() {
    // 20 g cannot move the CoM as far as 150 g taken off did: the inversion puts it
    // decimetres away, outside the robot.
    let a = adapt(
        &prior(),
        truth(),
        &AdaptOptions {
            total_mass: Some(prior_mass() + 0.02),
            ..Default::default()
        },
    )
    .unwrap();
    let failed: Vec<_> = a.report.failed_checks().map(|c| c.name.as_str()).collect();
    eprintln!("{:?}", a.report.checks);
    assert!(failed.contains(&"part-within-reach"), "{failed:?}");
}

#[test]
fn a_part_heavier_than_its_link_cannot_come_off_it() {
    let mut robot = prior();
    let e = add_point_mass(&mut robot, "l_foot", -5.0, [0.0; 3]).unwrap_err();
    assert!(e.to_string().contains("l_foot"), "{e}");
}

#[test]
fn taking_a_point_off_is_the_parallel_axis_theorem_backwards() {
    let mut robot = prior();
    let before = robot.link(HOST).unwrap().inertial.unwrap();
    add_point_mass(&mut robot, HOST, -MASS, XYZ).unwrap();
    let after = robot.link(HOST).unwrap().inertial.unwrap();
    // Mass and first moment: m' = m - m_p, m' c' = m c - m_p p.
    assert!((after.mass - (before.mass - MASS)).abs() < 1e-12);
    for (i, x) in XYZ.iter().enumerate() {
        let moment = before.mass * before.origin.xyz[i] - MASS * x;
        assert!((after.mass * after.origin.xyz[i] - moment).abs() < 1e-12);
    }
    // Putting it back restores the link.
    add_point_mass(&mut robot, HOST, MASS, XYZ).unwrap();
    let back = robot.link(HOST).unwrap().inertial.unwrap();
    assert!((back.mass - before.mass).abs() < 1e-12);
    for i in 0..3 {
        assert!((back.origin.xyz[i] - before.origin.xyz[i]).abs() < 1e-12);
    }
}
