//! What the static identification can and cannot tell, and its input errors:
//! exact recovery of excited parameters from noise-free poses, an arm that never
//! moves reported as not excited (with poses suggested that move it), and clear
//! errors for a total mass below the fixed links, too few poses, unknown links.

use std::path::PathBuf;
use twinloop_description::Description;
use twinloop_dynamics::Model;
use twinloop_ident::plate::{PlateOptions, generate_static_poses};
use twinloop_ident::static_ident::{
    StaticProblem, StaticWorkspace, assemble, candidate_poses, solve, suggest_poses,
};
use twinloop_ident::{StaticOptions, StaticPose, identify_static};

fn load(rel: &str) -> Description {
    twinloop_description::load(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../models")
            .join(rel),
    )
    .unwrap()
}

fn poses_of(truth: &Description, count: usize, seed: u64, hold: Vec<usize>) -> Vec<StaticPose> {
    let tm = Model::from_description(truth).unwrap();
    let options = PlateOptions {
        count,
        seed,
        hold,
        ..PlateOptions::default()
    };
    generate_static_poses(truth, &tm, &options, |_| {})
        .unwrap()
        .poses
        .into_iter()
        .map(|g| g.pose)
        .collect()
}

/// Noise-free poses of the truth; the prior differs on three links whose parents are
/// kept at the truth, so their mass and first moment are all excited: recovered to 1e-6.
#[test]
fn noise_free_poses_recover_excited_parameters() {
    let truth = load("unitree_h1/h1.urdf");
    let mut prior = truth.clone();
    let changed = ["torso_link", "left_elbow_link", "right_knee_link"];
    for (k, name) in changed.iter().enumerate() {
        let i = prior.link_mut(name).unwrap().inertial.as_mut().unwrap();
        i.mass *= 0.8 + 0.1 * k as f64;
        i.origin.xyz[0] += 0.01;
        i.origin.xyz[1] -= 0.005 * k as f64;
        i.origin.xyz[2] += 0.02;
    }
    let pm = Model::from_description(&prior).unwrap();
    let poses = poses_of(&truth, 60, 5, Vec::new());
    let options = StaticOptions {
        links: Some(changed.iter().map(|s| s.to_string()).collect()),
        cop_sigma: 0.0,
        ..StaticOptions::default()
    };
    let r = identify_static(&prior, &pm, &poses, truth.total_mass(), &options).unwrap();
    assert_eq!(
        r.identifiability.rank, 12,
        "{:?}",
        r.identifiability.singular_values
    );
    assert!(r.identifiability.unidentifiable.is_empty());
    for l in &r.links {
        let t = truth.link(&l.name).unwrap().inertial.unwrap();
        assert!(
            (l.mass - t.mass).abs() < 1e-6 * t.mass,
            "{}: {} vs {}",
            l.name,
            l.mass,
            t.mass
        );
        for a in 0..3 {
            assert!(
                (l.com[a] - t.origin.xyz[a]).abs() < 1e-6,
                "{} com[{a}]: {} vs {}",
                l.name,
                l.com[a],
                t.origin.xyz[a]
            );
        }
        assert!(
            l.mass_determined > 0.999999,
            "{}: {}",
            l.name,
            l.mass_determined
        );
    }
    // And the model now reproduces every CoP.
    assert!(r.after.max < 1e-9, "{:?}", r.after);
}

fn left_arm(model: &Model) -> Vec<usize> {
    (0..model.nbodies)
        .filter(|&i| {
            let n = &model.joint_names[i];
            n.starts_with("left_shoulder") || n.starts_with("left_elbow")
        })
        .collect()
}

/// A pose set in which the left arm never moves cannot tell its links from the torso:
/// the report must say so, and the suggested poses must move that arm.
#[test]
fn an_arm_that_never_moves_is_reported() {
    let truth = load("unitree_h1/h1.urdf");
    let tm = Model::from_description(&truth).unwrap();
    let held = left_arm(&tm);
    let left_links = [
        "left_shoulder_pitch_link",
        "left_shoulder_roll_link",
        "left_shoulder_yaw_link",
        "left_elbow_link",
    ];
    let options = StaticOptions {
        cop_sigma: 0.0,
        ..StaticOptions::default()
    };
    // Reference: the same number of poses with the arm moving: no group of arm links alone.
    let moving = poses_of(&truth, 120, 3, Vec::new());
    let r = identify_static(&truth, &tm, &moving, truth.total_mass(), &options).unwrap();
    let arm_only = |groups: &[twinloop_ident::static_ident::ParameterGroup]| {
        groups
            .iter()
            .filter(|g| g.links.iter().all(|l| left_links.contains(&l.as_str())))
            .count()
    };
    assert_eq!(
        arm_only(&r.identifiability.unidentifiable),
        0,
        "{:#?}",
        r.identifiability.unidentifiable
    );

    let still = poses_of(&truth, 120, 3, held.clone());
    for p in &still {
        for &j in &held {
            assert_eq!(
                p.q[tm.q_offset + j],
                0.0f64.clamp(tm.lower_limits[j], tm.upper_limits[j])
            );
        }
    }
    let r = identify_static(&truth, &tm, &still, truth.total_mass(), &options).unwrap();
    let id = &r.identifiability;
    assert!(arm_only(&id.unidentifiable) > 0, "{:#?}", id.unidentifiable);
    let named: Vec<&String> = id.unidentifiable.iter().flat_map(|g| &g.links).collect();
    for l in left_links {
        assert!(
            named.iter().any(|n| n.as_str() == l),
            "{l} not reported: {named:?}"
        );
    }
    assert!(id.rank < 42, "rank {}", id.rank);
    // The suggested poses move the held arm.
    let problem = StaticProblem::new(&truth, &tm, truth.total_mass(), &options).unwrap();
    let mut ws = StaticWorkspace::new(&tm, &problem, still.len());
    assemble(&tm, &problem, &still, &mut ws);
    let fit = solve(&problem, &ws).unwrap();
    let candidates = candidate_poses(&truth, &tm, 8, 9).unwrap();
    let suggested = suggest_poses(&tm, &problem, &fit.gram, &candidates, 3);
    assert_eq!(suggested.len(), 3);
    let moves_arm = |q: &[f64]| {
        held.iter().any(|&j| {
            (q[tm.q_offset + j] - 0.0f64.clamp(tm.lower_limits[j], tm.upper_limits[j])).abs() > 0.1
        })
    };
    assert!(
        moves_arm(&suggested[0].q),
        "first suggestion ({:?}) leaves the arm still",
        suggested[0].category
    );
    assert!(
        suggested[0].smallest_singular_value_after >= suggested[0].smallest_singular_value_before
    );
}

#[test]
fn bad_inputs_name_the_field() {
    let prior = load("unitree_h1/variants/h1_2025-06_a3b70ca.urdf");
    let pm = Model::from_description(&prior).unwrap();
    let poses = poses_of(&prior, 12, 1, Vec::new());
    let err = |total: f64, options: StaticOptions, poses: &[StaticPose]| {
        identify_static(&prior, &pm, poses, total, &options)
            .unwrap_err()
            .to_string()
    };
    // Total mass below the links kept fixed: only the torso is identified.
    let torso = StaticOptions {
        links: Some(vec!["torso_link".into()]),
        ..StaticOptions::default()
    };
    let e = err(30.0, torso.clone(), &poses);
    assert!(
        e.contains("option total_mass") && e.contains("kept fixed"),
        "{e}"
    );
    let e = err(f64::NAN, torso.clone(), &poses);
    assert!(e.contains("option total_mass"), "{e}");
    // Too few poses for every link.
    let e = err(55.0, StaticOptions::default(), &poses[..10]);
    assert!(
        e.contains("option poses") && e.contains("at least 40 poses"),
        "{e}"
    );
    // Unknown link, link without inertial.
    let e = err(
        55.0,
        StaticOptions {
            links: Some(vec!["waist_link".into()]),
            ..StaticOptions::default()
        },
        &poses,
    );
    assert!(
        e.contains("option links") && e.contains("waist_link"),
        "{e}"
    );
    let e = err(
        55.0,
        StaticOptions {
            links: Some(vec!["imu_link".into()]),
            ..StaticOptions::default()
        },
        &poses,
    );
    assert!(
        e.contains("option links") && e.contains("no <inertial>"),
        "{e}"
    );
    let e = err(
        55.0,
        StaticOptions {
            cop_sigma: -1.0,
            ..torso
        },
        &poses,
    );
    assert!(e.contains("option cop_sigma"), "{e}");
}

/// COMAN's camera and hands are welded to the trunk and wrists, its IMU to the pelvis:
/// reported as groups whose split the poses cannot see, and kept at the prior split.
#[test]
fn welded_links_are_reported_and_keep_their_split() {
    let prior = load("coman/coman.urdf");
    let pm = Model::from_description(&prior).unwrap();
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/coman10_poses.csv");
    let poses = twinloop_ident::read_static_poses(&data, &pm).unwrap();
    let r = identify_static(&prior, &pm, &poses, 42.05386, &StaticOptions::default()).unwrap();
    let welded = &r.identifiability.welded;
    let has = |names: &[&str]| {
        welded
            .iter()
            .any(|g| names.iter().all(|n| g.iter().any(|x| x == n)))
    };
    assert!(
        has(&["DWYTorso", "Xtion_body", "Xtion_cam_body"]),
        "{welded:?}"
    );
    assert!(has(&["Waist", "imu_link"]), "{welded:?}");
    assert!(has(&["LWrMot3", "LSoftHand"]), "{welded:?}");
    // The tiny IMU (10 g) keeps its prior: nothing in the data can move it apart.
    let imu = r.links.iter().find(|l| l.name == "imu_link").unwrap();
    assert!(imu.mass_determined < 0.05, "{}", imu.mass_determined);
}
