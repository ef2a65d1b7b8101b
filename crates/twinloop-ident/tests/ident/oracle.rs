//! The static identification against an independent implementation of the same fit:
//! Pinocchio's link placements and scipy.optimize.least_squares over (m, c) with box
//! bounds (tools/oracle/static_ident_reference.py). The fixtures hold the poses (made
//! by the virtual force plate: H1 truth with 1 mm CoP and 0.1 degree joint noise;
//! COMAN with 10 kg hidden) and the reference answer, so no Python is needed here.

use serde_json::Value;
use std::path::{Path, PathBuf};
use twinloop_dynamics::Model;
use twinloop_ident::{StaticOptions, identify_static, read_static_poses};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn check(urdf: &str, poses: &str, reference: &str, mass_tol: f64, com_tol: f64) {
    let robot = twinloop_description::load(root().join(urdf)).unwrap();
    let model = Model::from_description(&robot).unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let poses = read_static_poses(&data.join(poses), &model).unwrap();
    let refd: Value =
        serde_json::from_str(&std::fs::read_to_string(data.join(reference)).unwrap()).unwrap();
    let options = StaticOptions {
        cop_sigma: refd["cop_sigma"].as_f64().unwrap(),
        com_margin: refd["com_margin"].as_f64().unwrap(),
        ..StaticOptions::default()
    };
    let total = refd["total_mass"].as_f64().unwrap();
    let r = identify_static(&robot, &model, &poses, total, &options).unwrap();
    let links = refd["links"].as_array().unwrap();
    assert_eq!(links.len(), r.links.len());
    let (mut dm, mut dc): (f64, f64) = (0.0, 0.0);
    let mut moved: f64 = 0.0;
    for (want, got) in links.iter().zip(&r.links) {
        assert_eq!(want["name"].as_str().unwrap(), got.name);
        dm = dm.max((want["mass"].as_f64().unwrap() - got.mass).abs());
        for a in 0..3 {
            dc = dc.max((want["com"][a].as_f64().unwrap() - got.com[a]).abs());
        }
        moved = moved.max((got.mass - got.prior_mass).abs());
    }
    println!(
        "{urdf}: largest difference to the reference: mass {dm:.3e} kg, CoM {dc:.3e} m (masses moved up to {moved:.3} kg)"
    );
    assert!(dm < mass_tol, "mass differs by {dm:e}");
    assert!(dc < com_tol, "CoM differs by {dc:e}");
    assert!((refd["lambda"].as_f64().unwrap() - r.identifiability.noise_level).abs() < 1e-12);
}

#[test]
fn h1_matches_pinocchio_and_scipy() {
    check(
        "models/unitree_h1/variants/h1_2025-06_a3b70ca.urdf",
        "h1_poses.csv",
        "h1_static_reference.json",
        1e-6,
        1e-7,
    );
}

#[test]
fn coman_matches_pinocchio_and_scipy() {
    check(
        "models/coman/coman.urdf",
        "coman10_poses.csv",
        "coman10_static_reference.json",
        1e-7,
        1e-8,
    );
}
