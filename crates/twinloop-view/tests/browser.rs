//! The page in a real headless browser (Chromium from the distribution): it loads
//! without console errors, and the robot is drawn where the data put it: the
//! silhouette in the rendered image spans what twinloop-dynamics' forward
//! kinematics projects through the same camera (primitives, and the vertices of the
//! mesh files read here), the CoM the page computes is twinloop-dynamics' CoM, a
//! ghost appears where its recording puts it, OP3 is drawn with its meshes or, without
//! them, with stand-ins and a warning each, and an exported file (meshes and all)
//! renders the same with no server.
//!
//! Without Chromium these tests print why and pass, unless
//! TWINLOOP_REQUIRE_ORACLES=1 (CI), where a missing browser fails them.

use serde_json::Value;
use std::path::Path;
use std::time::Duration;
use twinloop_dynamics::{Data, Model, center_of_mass};
use twinloop_io::Table;
use twinloop_view::{Content, Recording, Scene};

// ---------- the browser ----------

#[allow(dead_code)]
#[path = "support/cdp.rs"]
mod cdp;
#[path = "support/chromium.rs"]
mod chromium;
#[allow(dead_code)]
#[path = "support/page.rs"]
mod page;
use chromium::{browser, tempdir};
use page::*;

// ---------- the tests ----------

#[test]
fn km20_replay_draws_the_robot_where_forward_kinematics_puts_it() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let (a, b) = (pose_a(&model), pose_b(&model));
    let scene = Scene::new(&robot, None, &[]);
    let drawn = drawn(&scene);
    let rec = Recording::from_table(
        &two_pose_table(&model, &a, &b),
        Path::new("ab.csv"),
        &scene.info,
    )
    .unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![rec],
        live: None,
    });
    let mut data = Data::new(&model);
    for (t, q) in [(0.5, &a), (1.0, &b)] {
        let page = load(&chromium, &format!("{url}{}", view_query(t)));
        assert_clean(&page);
        assert_no_misses(&misses);
        // The CoM the page computes from the URDF's inertials, against the dynamics'.
        let com = center_of_mass(&model, &mut data, q);
        let seen: Vec<f64> = page.status["com"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        for k in 0..3 {
            assert!(
                (seen[k] - com[k]).abs() < 1e-5,
                "t={t}: CoM {seen:?} vs {com:?}"
            );
        }
        let img = &page.image;
        let want = predicted_extent(&drawn, q, img.width, img.height);
        assert_extent_close(silhouette(img), want, &format!("km20 at t={t}"));
    }
}

#[test]
fn a_second_recording_is_drawn_as_a_ghost_where_its_data_put_it() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let scene = Scene::new(&robot, None, &[]);
    let drawn = drawn(&scene);
    let a = pose_a(&model);
    // The ghost: pose B moved 0.35 m to the side.
    let mut b = pose_b(&model);
    b[1] += 0.35;
    let real = Recording::from_table(
        &two_pose_table(&model, &a, &a),
        Path::new("real.csv"),
        &scene.info,
    )
    .unwrap();
    let sim = Recording::from_table(
        &two_pose_table(&model, &b, &b),
        Path::new("sim.csv"),
        &scene.info,
    )
    .unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![real, sim],
        live: None,
    });
    let page = load(&chromium, &format!("{url}{}", view_query(0.0)));
    assert_clean(&page);
    assert_no_misses(&misses);
    assert_eq!(page.status["recordings"].as_array().unwrap().len(), 2);
    let img = &page.image;
    let (ea, eb) = (
        predicted_extent(&drawn, &a, img.width, img.height),
        predicted_extent(&drawn, &b, img.width, img.height),
    );
    let both = (
        ea.0.min(eb.0),
        ea.1.min(eb.1),
        ea.2.max(eb.2),
        ea.3.max(eb.3),
    );
    assert_extent_close(silhouette(img), both, "robot and ghost");
    // The ghost is translucent in its own colour (blue over the magenta background):
    // pixels where only the ghost is drawn are bluish, not grey.
    let ghost_only = img
        .rgb
        .iter()
        .filter(|p| (p[2] as i32) > 200 && (p[0] as i32) < 200 && (p[1] as i32) < 120)
        .count();
    assert!(ghost_only > 200, "{ghost_only} ghost-coloured pixels");
}

#[test]
fn meshes_load_and_a_missing_one_is_a_box_with_a_warning() {
    let Some(chromium) = browser() else { return };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mesh_robot/urdf/robot.urdf");
    let robot = twinloop_description::load(&path).unwrap();
    let model = Model::from_description(&robot).unwrap();
    let scene = Scene::new(&robot, Some(&path), &[]);
    let drawn = drawn(&scene);
    let q = configuration(&model, [0.0, 0.0, 0.0], 0.0, &[("shoulder", 0.7)]);
    let rec = Recording::from_table(
        &two_pose_table(&model, &q, &q),
        Path::new("arm.csv"),
        &scene.info,
    )
    .unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![rec],
        live: None,
    });
    let page = load(&chromium, &format!("{url}{}", view_query(0.0)));
    assert_clean(&page);
    assert_no_misses(&misses);
    let warnings = page.status["warnings"].to_string();
    assert!(
        warnings.contains("hand.stl") && warnings.contains("file not found"),
        "{warnings}"
    );
    let img = &page.image;
    let want = predicted_extent(&drawn, &q, img.width, img.height);
    assert_extent_close(silhouette(img), want, "mesh robot");
}

#[test]
fn a_collada_mesh_is_drawn_where_and_as_large_as_the_description_says() {
    let Some(chromium) = browser() else { return };
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mesh_robot/urdf/dae_robot.urdf");
    let robot = twinloop_description::load(&path).unwrap();
    let model = Model::from_description(&robot).unwrap();
    let scene = Scene::new(&robot, Some(&path), &[]);
    assert_eq!(scene.info.warnings, Vec::<String>::new());
    let drawn = drawn(&scene);
    let q = configuration(&model, [0.0, 0.0, 0.0], 0.0, &[("shoulder", -0.9)]);
    let rec = Recording::from_table(
        &two_pose_table(&model, &q, &q),
        Path::new("arm.csv"),
        &scene.info,
    )
    .unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![rec],
        live: None,
    });
    let page = load(&chromium, &format!("{url}{}", view_query(0.0)));
    assert_clean(&page);
    assert_no_misses(&misses);
    assert_eq!(
        page.status["warnings"].as_array().unwrap().len(),
        0,
        "{}",
        page.status
    );
    let img = &page.image;
    let want = predicted_extent(&drawn, &q, img.width, img.height);
    assert_extent_close(silhouette(img), want, "DAE robot");
}

#[test]
fn g1_with_its_meshes_loads_and_its_com_follows_the_pose() {
    let Some(chromium) = browser() else { return };
    // The upstream meshes decimated (models/unitree_g1/decimate_meshes.py): 35 STL
    // files, 1.7 MB instead of 19.
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../models/unitree_g1/g1_29dof_rev_1_0.decimated.urdf");
    let robot = twinloop_description::load(&path).unwrap();
    let model = Model::from_description(&robot).unwrap();
    let scene = Scene::new(&robot, Some(&path), &[]);
    assert_eq!(
        scene.info.warnings,
        Vec::<String>::new(),
        "every mesh found"
    );
    let drawn = drawn(&scene);
    assert!(scene.info.meshes.len() >= 30, "{}", scene.info.meshes.len());
    let q = configuration(
        &model,
        [0.1, -0.2, 0.75],
        0.4,
        &[
            ("left_knee_joint", 0.9),
            ("left_hip_pitch_joint", -0.6),
            ("right_shoulder_roll_joint", -0.8),
            ("waist_yaw_joint", 0.3),
        ],
    );
    let rec = Recording::from_table(
        &two_pose_table(&model, &q, &q),
        Path::new("g1.csv"),
        &scene.info,
    )
    .unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![rec],
        live: None,
    });
    let page = load(&chromium, &format!("{url}{}", TALL.query(0.0)));
    assert_clean(&page);
    assert_no_misses(&misses);
    assert_eq!(
        page.status["warnings"].as_array().unwrap().len(),
        0,
        "{}",
        page.status
    );
    // The silhouette spans the mesh vertices placed by forward kinematics.
    let img = &page.image;
    let want = TALL.extent(&drawn, &q, img.width, img.height);
    assert_extent_close(silhouette(img), want, "G1 with its meshes");
    let com = center_of_mass(&model, &mut Data::new(&model), &q);
    let seen: Vec<f64> = page.status["com"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for k in 0..3 {
        assert!(
            (seen[k] - com[k]).abs() < 1e-5,
            "G1 CoM {seen:?} vs {com:?}"
        );
    }
}

/// OP3's URDF and MJCF name 21 STL meshes each that are not in this repository.
/// Without them each visual is drawn as a stand-in (the link's collision primitive or
/// its inertia box, orange) with one warning per mesh, and the silhouette spans those
/// stand-ins placed by forward kinematics. With them (`TWINLOOP_OP3_MESHES=DIR`, the
/// ROBOTIS `op3_description` package folder holding `meshes/`, given as
/// `--package-dir op3_description=DIR`; `TWINLOOP_OP3_MJCF_ASSETS=DIR`, MuJoCo
/// Menagerie's `robotis_op3/assets`, put beside a copy of the MJCF) there is no
/// warning and the silhouette spans the meshes' vertices.
#[test]
fn op3_urdf_and_mjcf_load_with_their_meshes_or_stand_ins() {
    let Some(chromium) = browser() else { return };
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/op3");
    let urdf_meshes = std::env::var_os("TWINLOOP_OP3_MESHES").map(std::path::PathBuf::from);
    let mjcf_assets = std::env::var_os("TWINLOOP_OP3_MJCF_ASSETS").map(std::path::PathBuf::from);
    let tmp = tempdir("op3");
    for (file, meshes) in [
        ("robotis_op3.urdf", urdf_meshes),
        ("mjcf/op3.xml", mjcf_assets),
    ] {
        let mut path = models.join(file);
        let mut packages = Vec::new();
        match &meshes {
            Some(dir) if file.ends_with(".urdf") => packages.push(twinloop_view::PackageDir {
                name: "op3_description".into(),
                dir: dir.clone(),
            }),
            Some(dir) => {
                // The MJCF finds its meshes in `assets/` beside it.
                let copy = tmp.join("op3.xml");
                std::fs::copy(&path, &copy).unwrap();
                std::os::unix::fs::symlink(dir, tmp.join("assets")).unwrap();
                path = copy;
            }
            None => {}
        }
        let robot = twinloop_description::load(&path).unwrap();
        let model = Model::from_description(&robot).unwrap();
        let scene = Scene::new(&robot, Some(&path), &packages);
        let n_meshes = scene.info.meshes.len();
        assert!(n_meshes > 0, "{file}: no meshes named?");
        let drawn = drawn(&scene);
        let names = model.q_names();
        let q = configuration(
            &model,
            [0.0, 0.0, 0.3],
            0.3,
            &[(names[9].as_str(), 0.6), (names[20].as_str(), -0.7)],
        );
        let rec = Recording::from_table(
            &two_pose_table(&model, &q, &q),
            Path::new("op3.csv"),
            &scene.info,
        )
        .unwrap();
        let (url, misses) = serve_with_misses(Content {
            scene,
            recordings: vec![rec],
            live: None,
        });
        let page = load(&chromium, &format!("{url}{}", view_query(0.0)));
        assert_clean(&page);
        assert_no_misses(&misses);
        let warnings: Vec<&str> = page.status["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_str().unwrap())
            .collect();
        let what = if meshes.is_some() {
            assert_eq!(warnings, Vec::<&str>::new(), "{file} with its meshes");
            format!("{file} with its meshes")
        } else {
            // One grouped warning for the whole missing folder, not one per mesh.
            assert_eq!(warnings.len(), 1, "{file}: {warnings:?}");
            // A file beside the description is not found; a `package://` one names
            // the package to give.
            let head = format!("{n_meshes} meshes: ");
            assert!(
                warnings[0].starts_with(&format!("{head}file not found in "))
                    || (warnings[0].starts_with(&head)
                        && warnings[0].contains("is unknown (give --package-dir")),
                "{file}: {warnings:?}"
            );
            for w in &warnings {
                assert!(
                    w.contains(".stl")
                        && w.contains("drawn as its collision primitive or inertia box"),
                    "{file}: {w}"
                );
            }
            format!("{file} with stand-ins")
        };
        let img = &page.image;
        let want = predicted_extent(&drawn, &q, img.width, img.height);
        assert_extent_close(silhouette(img), want, &what);
    }
    let _ = std::fs::remove_dir_all(tmp);
}

#[test]
fn a_recording_without_some_joint_columns_says_which() {
    let Some(chromium) = browser() else { return };
    let (robot, _) = km20();
    let scene = Scene::new(&robot, None, &[]);
    let table = Table::parse("t,q:l_knee\n0,0.5\n1,0.6\n").unwrap();
    let rec = Recording::from_table(&table, Path::new("knee.csv"), &scene.info).unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![rec],
        live: None,
    });
    let page = load(&chromium, &format!("{url}{}", view_query(0.0)));
    assert_clean(&page);
    assert_no_misses(&misses);
    let missing = page.status["recordings"][0]["missing"].as_array().unwrap();
    assert_eq!(missing.len(), 19);
    assert!(page.status["warnings"].to_string().contains("q:r_knee"));
}

#[test]
fn the_exported_file_renders_the_same_without_a_server() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let (a, b) = (pose_a(&model), pose_b(&model));
    let scene = Scene::new(&robot, None, &[]);
    let rec = Recording::from_table(
        &two_pose_table(&model, &a, &b),
        Path::new("ab.csv"),
        &scene.info,
    )
    .unwrap();
    let content = Content {
        scene,
        recordings: vec![rec],
        live: None,
    };
    let html = twinloop_view::export_html(&content).unwrap();
    let dir = tempdir("export");
    let file = dir.join("replay.html");
    std::fs::write(&file, html).unwrap();
    let (url, misses) = serve_with_misses(content);
    let served = load(&chromium, &format!("{url}{}", view_query(1.0)));
    let exported = load(
        &chromium,
        &format!("file://{}{}", file.display(), view_query(1.0)),
    );
    assert_clean(&exported);
    assert_no_misses(&misses);
    assert_extent_close(
        silhouette(&exported.image),
        silhouette(&served.image),
        "exported vs served",
    );
    assert_eq!(exported.status["com"], served.status["com"]);
    let _ = std::fs::remove_dir_all(dir);
}

/// An export carries its meshes: G1 (35 decimated STL meshes) and the COLLADA test
/// robot, each written with `export_html` and opened from `file://` before any server
/// for it exists, draw no warning, span what forward kinematics puts their mesh
/// vertices at, and match the page served afterwards (silhouette and CoM).
#[test]
fn an_export_with_meshes_renders_with_no_server() {
    let Some(chromium) = browser() else { return };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let g1 = root.join("../../models/unitree_g1/g1_29dof_rev_1_0.decimated.urdf");
    let dae = root.join("tests/data/mesh_robot/urdf/dae_robot.urdf");
    let dir = tempdir("export-meshes");
    type Case<'a> = (&'a Path, &'a Camera, &'a [(&'a str, f64)]);
    let cases: [Case; 2] = [
        (
            &g1,
            &TALL,
            &[
                ("left_knee_joint", 0.9),
                ("right_shoulder_roll_joint", -0.8),
            ],
        ),
        (&dae, &CAMERA, &[("shoulder", -0.9)]),
    ];
    for (path, cam, joints) in cases {
        let robot = twinloop_description::load(path).unwrap();
        let model = Model::from_description(&robot).unwrap();
        let scene = Scene::new(&robot, Some(path), &[]);
        assert_eq!(
            scene.info.warnings,
            Vec::<String>::new(),
            "{}",
            path.display()
        );
        let drawn = drawn(&scene);
        let q = configuration(&model, [0.05, -0.1, 0.4], 0.3, joints);
        let rec = Recording::from_table(
            &two_pose_table(&model, &q, &q),
            Path::new("pose.csv"),
            &scene.info,
        )
        .unwrap();
        let content = Content {
            scene,
            recordings: vec![rec],
            live: None,
        };
        let file = dir.join(format!("{}.html", robot.name));
        std::fs::write(&file, twinloop_view::export_html(&content).unwrap()).unwrap();
        let exported = load(
            &chromium,
            &format!("file://{}{}", file.display(), cam.query(0.0)),
        );
        assert_clean(&exported);
        assert_eq!(
            exported.status["warnings"].as_array().unwrap().len(),
            0,
            "{}",
            exported.status
        );
        let img = &exported.image;
        let what = format!("{} exported", robot.name);
        assert_extent_close(
            silhouette(img),
            cam.extent(&drawn, &q, img.width, img.height),
            &what,
        );
        let (url, misses) = serve_with_misses(content);
        let served = load(&chromium, &format!("{url}{}", cam.query(0.0)));
        assert_clean(&served);
        assert_no_misses(&misses);
        assert_extent_close(silhouette(img), silhouette(&served.image), &what);
        assert_eq!(exported.status["com"], served.status["com"], "{what}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_live_page_draws_the_state_it_receives() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let a = pose_a(&model);
    let scene = Scene::new(&robot, None, &[]);
    let drawn = drawn(&scene);
    // The joints in the scene's order, from the model's configuration.
    let names = model.q_names();
    let joints: Vec<f64> = scene
        .info
        .joints
        .iter()
        .map(|j| a[names.iter().position(|n| *n == j.name).unwrap()])
        .collect();
    let base: [f64; 7] = a[..7].try_into().unwrap();
    let feed = twinloop_view::LiveFeed::new();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![],
        live: Some(feed.clone()),
    });
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let publisher = {
        let (feed, stop) = (feed.clone(), stop.clone());
        std::thread::spawn(move || {
            let mut t = 0.0;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                feed.publish(t, &joints, Some(base));
                t += 0.005;
                std::thread::sleep(Duration::from_millis(5));
            }
        })
    };
    // On a loaded machine the first frame can arrive after the page's virtual time ran
    // out: look again (the feed keeps publishing).
    let url = format!("{url}{}", view_query(0.0));
    let page = try_load(&chromium, &url)
        .or_else(|_| try_load(&chromium, &url))
        .unwrap_or_else(|_| load(&chromium, &url));
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    publisher.join().unwrap();
    assert_clean(&page);
    assert_no_misses(&misses);
    assert!(
        page.status["live"]["frames"].as_u64().unwrap() >= 1,
        "{}",
        page.status
    );
    let mut data = Data::new(&model);
    let com = center_of_mass(&model, &mut data, &a);
    let seen: Vec<f64> = page.status["com"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for k in 0..3 {
        assert!(
            (seen[k] - com[k]).abs() < 1e-5,
            "live CoM {seen:?} vs {com:?}"
        );
    }
    let img = &page.image;
    let want = predicted_extent(&drawn, &a, img.width, img.height);
    assert_extent_close(silhouette(img), want, "live km20");
}

#[test]
fn the_joint_sliders_pose_the_robot_and_its_com() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let scene = Scene::new(&robot, None, &[]);
    let drawn = drawn(&scene);
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![],
        live: None,
    });
    // Without a recording the robot stands on the ground at its zero pose: the root
    // is lifted by the depth of the lowest visual point below it.
    let zero = configuration(&model, [0.0; 3], 0.0, &[]);
    let lowest = drawn
        .world_points(&zero)
        .iter()
        .map(|p| p.z)
        .fold(f64::MAX, f64::min);
    let mut data = Data::new(&model);
    let joints = [("l_sho_pitch", -1.0), ("r_knee", 0.9), ("head_pan", 0.6)];
    let q = configuration(&model, [0.0, 0.0, -lowest], 0.0, &joints);
    let pose: Vec<String> = joints.iter().map(|(j, v)| format!("{j}:{v}")).collect();
    let page = load(
        &chromium,
        &format!("{url}{}&pose={}", view_query(0.0), pose.join(",")),
    );
    assert_clean(&page);
    assert_no_misses(&misses);
    let com = center_of_mass(&model, &mut data, &q);
    let seen: Vec<f64> = page.status["com"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for k in 0..3 {
        assert!(
            (seen[k] - com[k]).abs() < 1e-5,
            "slider CoM {seen:?} vs {com:?}"
        );
    }
    let img = &page.image;
    let want = predicted_extent(&drawn, &q, img.width, img.height);
    assert_extent_close(silhouette(img), want, "km20 posed by sliders");
}

#[test]
fn a_click_on_the_plot_seeks_the_timeline_there() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let scene = Scene::new(&robot, None, &[]);
    // 8 s of km20 at 10 Hz, its first joint swinging, the rest standing.
    let mut columns = vec!["t".to_string()];
    columns.extend(model.q_names().iter().map(|n| format!("q:{n}")));
    let mut table = Table::new(columns);
    let (t0, t1) = (2.0, 10.0);
    for k in 0..=80 {
        let t = t0 + 0.1 * k as f64;
        let mut q = pose_a(&model);
        q[7] = 0.5 * (t * 0.8).sin();
        table.rows.push(std::iter::once(t).chain(q).collect());
    }
    let rec = Recording::from_table(&table, Path::new("swing.csv"), &scene.info).unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![rec],
        live: None,
    });
    let mut page = cdp::Browser::open(&chromium, &url);
    page.wait_for(
        "!!(window.twinloop && window.twinloop.ready && document.querySelector('#plot .u-over'))",
        120,
    );
    let rect = page.eval(
        "(() => { const r = document.querySelector('#plot .u-over').getBoundingClientRect(); \
         return [r.left, r.top, r.width, r.height]; })()",
    );
    let r: Vec<f64> = rect
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(r[2] > 100.0 && r[3] > 50.0, "plot area {r:?}");
    for fraction in [0.7, 0.25] {
        let x = (r[0] + fraction * r[2]).round();
        page.click(x, r[1] + 0.5 * r[3]);
        // The plot's x axis spans the recording's time: the pixel clicked is a time.
        let want = t0 + (x - r[0]) / r[2] * (t1 - t0);
        let px = (t1 - t0) / r[2];
        page.wait_for(
            &format!(
                "Math.abs(Number(document.getElementById('scrub').value) - {want}) < {}",
                2.0 * px
            ),
            20,
        );
        let clock = page.eval("document.getElementById('clock').textContent");
        let shown: f64 = clock
            .as_str()
            .unwrap()
            .trim_end_matches(" s")
            .parse()
            .unwrap();
        assert!(
            (shown - want).abs() < 2.0 * px,
            "clicked at {want:.3} s, the clock says {clock}"
        );
        // The plot's cursor is drawn where the click was.
        let cursor =
            page.eval("parseFloat(document.querySelector('#plot .cursor-line').style.left)");
        let cursor = cursor.as_f64().unwrap();
        assert!(
            (cursor - (x - r[0])).abs() < 2.0,
            "cursor at {cursor} px, clicked at {} px",
            x - r[0]
        );
    }
    let status = page.eval("JSON.stringify(window.twinloop)");
    let status: Value = serde_json::from_str(status.as_str().unwrap()).unwrap();
    assert_eq!(status["errors"].as_array().unwrap().len(), 0, "{status}");
    assert_no_misses(&misses);
}

#[test]
fn a_missing_mesh_is_named_on_the_page_and_in_the_console() {
    let Some(chromium) = browser() else { return };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mesh_robot/urdf/robot.urdf");
    let robot = twinloop_description::load(&path).unwrap();
    let scene = Scene::new(&robot, Some(&path), &[]);
    let (url, _) = serve_with_misses(Content {
        scene,
        recordings: Vec::new(),
        live: None,
    });
    let mut page = cdp::Browser::open(&chromium, &url);
    page.wait_for("!!(window.twinloop && window.twinloop.ready)", 120);
    // What a user sees: the warnings box of the page, as drawn.
    let shown = page.eval("document.getElementById('warnings').innerText");
    let shown = shown.as_str().unwrap_or_default().to_string();
    assert!(
        shown.contains("hand.stl") && shown.contains("file not found"),
        "the page shows: {shown:?}"
    );
    let visible = page.eval(
        "(() => { const r = document.getElementById('warnings').getBoundingClientRect(); \
         return r.width > 0 && r.height > 0; })()",
    );
    assert_eq!(
        visible,
        Value::Bool(true),
        "the warnings box is not visible"
    );
    // What a developer sees: a console warning naming the file.
    page.eval("0"); // any answer flushes the console events before it
    assert!(
        page.console
            .iter()
            .any(|(level, text)| level == "warning" && text.contains("hand.stl")),
        "console: {:?}",
        page.console
    );
}
