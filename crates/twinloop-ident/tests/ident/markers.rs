//! IK marker fitting (seed 004, eq 7) against known configurations: markers computed
//! from a squat of the truth model are fitted back, the first frame from a pelvis pose
//! turned half around; then the fitted motion goes through the inverse-dynamics
//! validation. Plus the marker-file errors.

use nalgebra::{Matrix3, Rotation3, Vector3};
use std::path::PathBuf;
use twinloop_dynamics::{Data, Model};
use twinloop_ident::markers::{
    Marker, MarkerIk, kabsch, marker_positions, markers_to_toml, parse_markers,
};
use twinloop_ident::validate::{Motion, Smoothing, SquatOptions, residual_wrench, squat_motion};
use twinloop_random::SplitMix64;

fn h1() -> (twinloop_description::Description, Model) {
    let robot = twinloop_description::load(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/unitree_h1/h1.urdf"),
    )
    .unwrap();
    let model = Model::from_description(&robot).unwrap();
    (robot, model)
}

/// Three markers per link with mass, four on the pelvis.
fn marker_set(model: &Model) -> Vec<Marker> {
    let mut out = Vec::new();
    for (l, info) in model.links.iter().enumerate() {
        if info.inertia.mass <= 0.0 {
            continue;
        }
        let c = info.inertia.com;
        let mut offsets = vec![
            Vector3::new(0.05, 0.0, 0.0),
            Vector3::new(0.0, 0.05, 0.02),
            Vector3::new(-0.03, -0.04, 0.05),
        ];
        if info.body == twinloop_dynamics::BASE {
            offsets.push(Vector3::new(0.02, -0.06, -0.03));
        }
        for (k, d) in offsets.into_iter().enumerate() {
            out.push(Marker {
                name: format!("{}_{k}", info.name),
                link: l,
                position: c + d,
            });
        }
    }
    out
}

#[test]
fn kabsch_recovers_a_rotation() {
    let r = Rotation3::from_euler_angles(2.5, -0.7, 1.9).into_inner();
    let p = Vector3::new(0.3, -1.0, 2.0);
    let a: Vec<Vector3<f64>> = [
        Vector3::new(0.1, 0.0, 0.0),
        Vector3::new(0.0, 0.2, 0.0),
        Vector3::new(0.0, 0.0, 0.3),
        Vector3::new(0.1, 0.1, 0.1),
    ]
    .to_vec();
    let b: Vec<Vector3<f64>> = a.iter().map(|x| r * x + p).collect();
    let (rr, pp) = kabsch(&a, &b).unwrap();
    assert!((rr - r).amax() < 1e-12 && (pp - p).amax() < 1e-12);
    assert!((rr.determinant() - 1.0).abs() < 1e-12);
    // Collinear points do not fix a rotation.
    let line: Vec<Vector3<f64>> = (0..4).map(|k| Vector3::new(k as f64, 0.0, 0.0)).collect();
    assert!(kabsch(&line, &line).is_none());
    let _ = Matrix3::<f64>::identity();
}

fn short_squat(robot: &twinloop_description::Description, model: &Model) -> Motion {
    squat_motion(
        robot,
        model,
        &SquatOptions {
            rest: 0.3,
            duration: 2.0,
            rate: 100.0,
            ..SquatOptions::default()
        },
        |_, _| {},
    )
    .unwrap()
}

#[test]
fn fits_squat_markers_back_exactly() {
    let (robot, model) = h1();
    let motion = short_squat(&robot, &model);
    let markers = marker_set(&model);
    // Turn the whole recording half around the vertical: the first frame must start
    // from the pelvis markers, not from the identity.
    let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), 3.0);
    let mut data = Data::new(&model);
    let mut fitter = MarkerIk::new(&model, markers.clone()).unwrap();
    let mut worst: f64 = 0.0;
    let mut fitted = Motion {
        t: motion.t.clone(),
        q: Vec::new(),
        plate: None,
    };
    for (k, q) in motion.q.iter().enumerate() {
        twinloop_dynamics::forward_kinematics(&model, &mut data, q);
        let seen: Vec<Option<Vector3<f64>>> = marker_positions(&model, &data, &markers)
            .into_iter()
            .map(|p| Some(turn * p))
            .collect();
        let (qf, fit) = fitter.fit(&seen, k).unwrap();
        let qf = qf.to_vec();
        assert!(fit.rms < 1e-9, "frame {k}: rms {}", fit.rms);
        // Joints equal; the base turned.
        for i in model.q_offset..model.nq {
            worst = worst.max((qf[i] - q[i]).abs());
        }
        for i in 0..model.nbodies {
            let x = qf[model.q_offset + i];
            assert!(x >= model.lower_limits[i] - 1e-12 && x <= model.upper_limits[i] + 1e-12);
        }
        fitted.q.push(qf);
    }
    assert!(worst < 1e-7, "largest joint error {worst:e}");
    // The fitted (turned) motion has the same dynamics: with the plate turned too, the
    // truth model leaves only the differentiation error.
    let plate = motion.plate.as_ref().unwrap();
    fitted.plate = Some(
        plate
            .iter()
            .map(|p| {
                let f = turn * Vector3::from(p.force);
                let c = turn * Vector3::new(p.cop[0], p.cop[1], 0.0);
                twinloop_ident::validate::PlateSample {
                    force: f.into(),
                    cop: [c.x, c.y],
                    free_moment: p.free_moment,
                }
            })
            .collect(),
    );
    let r = residual_wrench(&model, &fitted, None).unwrap();
    assert!(r.summary.mean_abs[2] < 0.05, "{:?}", r.summary);
}

#[test]
fn noisy_markers_and_smoothing() {
    let (robot, model) = h1();
    let motion = short_squat(&robot, &model);
    let markers = marker_set(&model);
    let mut data = Data::new(&model);
    let mut rng = SplitMix64(4);
    let mut fitter = MarkerIk::new(&model, markers.clone()).unwrap();
    let mut fitted = motion.clone();
    let mut rms = 0.0;
    for (k, q) in motion.q.iter().enumerate() {
        twinloop_dynamics::forward_kinematics(&model, &mut data, q);
        let mut seen: Vec<Option<Vector3<f64>>> = marker_positions(&model, &data, &markers)
            .into_iter()
            .map(|p| Some(p + Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 5e-4))
            .collect();
        // One marker occluded now and then.
        if k % 7 == 0 {
            seen[5] = None;
        }
        let (qf, fit) = fitter.fit(&seen, k).unwrap();
        rms += fit.rms / motion.q.len() as f64;
        fitted.q[k] = qf.to_vec();
    }
    // The fit cannot beat the noise (0.5 mm per axis, ~0.87 mm per marker) by much.
    assert!(rms > 3e-4 && rms < 1e-3, "{rms}");
    // With the seed's 10 Hz filter the vertical residual of the truth stays small,
    // while a model 7.7 kg light is far off.
    let r = residual_wrench(&model, &fitted, Some(Smoothing::default())).unwrap();
    assert!(r.summary.mean_abs[2] < 5.0, "{:?}", r.summary);
}

#[test]
fn marker_file_errors() {
    let (_, model) = h1();
    let markers = marker_set(&model);
    let text = markers_to_toml(&model, &markers);
    assert_eq!(parse_markers(&text, &model).unwrap(), markers);
    let e = parse_markers(
        &text.replacen("link = \"pelvis\"", "link = \"hips\"", 1),
        &model,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("pelvis_0") && e.contains(".link") && e.contains("hips"),
        "{e}"
    );
    let e = parse_markers(
        &text.replacen("position = [", "position = [1.0, ", 1),
        &model,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("pelvis_0") && e.contains(".position"), "{e}");
    let e = parse_markers(&text.replacen("name = ", "nmae = ", 1), &model)
        .unwrap_err()
        .to_string();
    assert!(e.contains("line") && e.contains("nmae"), "{e}");
    let e = parse_markers(
        "[[marker]]\nname = \"a\"\nlink = \"pelvis\"\nposition = [0, 0, 0]\n",
        &model,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("at least 3"), "{e}");
    // The first frame needs three base markers for the pelvis pose.
    let mut fitter = MarkerIk::new(&model, markers.clone()).unwrap();
    let seen: Vec<Option<Vector3<f64>>> = markers
        .iter()
        .map(|m| (model.links[m.link].name != "pelvis").then(Vector3::zeros))
        .collect();
    let e = fitter.fit(&seen, 0).unwrap_err().to_string();
    assert!(e.contains("data row 1") && e.contains("base body"), "{e}");
}

/// Separate static poses are not a continuous motion: where the previous frame's
/// solution leads into the wrong basin, the fitter starts again from the pelvis pose
/// (joints aligned one by one, then at zero). Not every pose is rescued (local minima
/// with joints on their limits), but most are, and each is no worse than warm-started.
#[test]
fn fits_separate_static_poses() {
    let (robot, model) = h1();
    let poses = twinloop_ident::plate::generate_static_poses(
        &robot,
        &model,
        &twinloop_ident::plate::PlateOptions {
            count: 20,
            categories: vec![twinloop_ident::PoseCategory::Arm],
            ..Default::default()
        },
        |_| {},
    )
    .unwrap()
    .poses;
    let markers = marker_set(&model);
    let mut data = Data::new(&model);
    let frames: Vec<Vec<Option<Vector3<f64>>>> = poses
        .iter()
        .map(|p| {
            twinloop_dynamics::forward_kinematics(&model, &mut data, &p.q_true);
            marker_positions(&model, &data, &markers)
                .into_iter()
                .map(Some)
                .collect()
        })
        .collect();
    let exact = |restart: f64| {
        let mut fitter = MarkerIk::new(&model, markers.clone()).unwrap();
        fitter.restart_distance = restart;
        frames
            .iter()
            .enumerate()
            .filter(|(k, f)| fitter.fit(f, *k).unwrap().1.max < 1e-6)
            .count()
    };
    let (warm_only, with_restart) = (exact(f64::INFINITY), exact(0.02));
    println!(
        "separate poses fitted exactly: {warm_only}/20 warm-started, {with_restart}/20 with restarts"
    );
    // Measured: 6/20 warm-started, 15/20 with restarts (deterministic poses).
    assert!(with_restart >= 14, "{with_restart}");
    assert!(with_restart > warm_only, "{with_restart} vs {warm_only}");
}
