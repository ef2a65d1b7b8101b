//! The page in a real headless browser (Chromium from the distribution): it loads
//! without console errors, and the robot is drawn where the data put it: the
//! silhouette in the rendered image spans what twinloop-dynamics' forward
//! kinematics projects through the same camera, the CoM the page computes is
//! twinloop-dynamics' CoM, a ghost appears where its recording puts it, and the
//! exported file renders the same with no server.
//!
//! Without Chromium these tests print why and pass, unless
//! TWINLOOP_REQUIRE_ORACLES=1 (CI), where a missing browser fails them.

use nalgebra::{Matrix3, Vector3};
use serde_json::Value;
use std::path::Path;
use std::time::Duration;
use twinloop_description::{Description, Geometry};
use twinloop_dynamics::{Data, Model, center_of_mass, frames_forward_kinematics};
use twinloop_io::Table;
use twinloop_view::{Content, Recording, Scene, Server};

// ---------- the browser ----------

#[path = "support/cdp.rs"]
mod cdp;
#[path = "support/chromium.rs"]
mod chromium;
use chromium::{browser, dump_dom, element_text, tempdir, unescape_html};

/// An RGB image.
struct Image {
    width: usize,
    height: usize,
    rgb: Vec<[u8; 3]>,
}

struct Page {
    status: Value,
    image: Image,
}

fn decode_png(bytes: &[u8]) -> Image {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let rgb = buf[..info.buffer_size()]
        .chunks(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Image {
        width: info.width as usize,
        height: info.height as usize,
        rgb,
    }
}

/// Load `url` in headless Chromium (software WebGL) and read the page's status
/// and its rendered image.
fn load(chromium: &Path, url: &str) -> Page {
    try_load(chromium, url).unwrap_or_else(|status| panic!("no #snapshot: {status}"))
}

/// [`load`], or the page's status when it drew no snapshot (a live page whose first
/// frame had not arrived when headless Chromium's virtual time ran out).
fn try_load(chromium: &Path, url: &str) -> Result<Page, Value> {
    let dom = dump_dom(chromium, url);
    let status = element_text(&dom, "status").unwrap_or_else(|| {
        panic!(
            "no #status in the page of {url}: {}",
            &dom[..dom.len().min(400)]
        )
    });
    let status: Value = serde_json::from_str(&unescape_html(status)).unwrap();
    let Some(snapshot) = element_text(&dom, "snapshot") else {
        return Err(status);
    };
    use base64::Engine;
    let png = base64::engine::general_purpose::STANDARD
        .decode(snapshot.trim().trim_start_matches("data:image/png;base64,"))
        .unwrap();
    Ok(Page {
        status,
        image: decode_png(&png),
    })
}

/// Serve `content`; the URL, and the paths the page asked for and did not get.
fn serve_with_misses(content: Content) -> (String, twinloop_view::server::Misses) {
    let server = Server::bind("127.0.0.1:0", content).unwrap();
    let (url, misses) = (server.url(), server.misses());
    std::thread::spawn(move || server.run());
    (url, misses)
}

/// No request of the page went unanswered (a 404 is a console error in the browser).
fn assert_no_misses(misses: &twinloop_view::server::Misses) {
    assert_eq!(
        misses.list(),
        Vec::<String>::new(),
        "the page asked for missing files"
    );
}

fn assert_clean(page: &Page) {
    let s = &page.status;
    assert_eq!(s["ready"], true, "the page did not finish loading: {s}");
    assert_eq!(
        s["errors"].as_array().unwrap().len(),
        0,
        "console errors: {s}"
    );
}

// ---------- the camera and the silhouette ----------

/// The test camera: where it is, where it looks, vertical field of view (deg).
struct Camera {
    eye: Vector3<f64>,
    target: Vector3<f64>,
    fov_deg: f64,
}

const CAMERA: Camera = Camera {
    eye: Vector3::new(0.9, -1.5, 0.5),
    target: Vector3::new(0.0, 0.0, 0.25),
    fov_deg: 40.0,
};

/// Page parameters: the test camera, a magenta background, no overlays, the
/// image in #snapshot.
fn view_query(t: f64) -> String {
    let (e, g) = (CAMERA.eye, CAMERA.target);
    format!(
        "?t={t}&bare=1&snapshot=1&bg=ff00ff&overlays=&fov={}&camera={},{},{},{},{},{}",
        CAMERA.fov_deg, e.x, e.y, e.z, g.x, g.y, g.z
    )
}

/// A world point in pixels (x right, y down), as three.js projects it: a
/// perspective camera at `eye` looking at `target`, z up.
fn project(p: &Vector3<f64>, width: usize, height: usize) -> (f64, f64) {
    let f = (CAMERA.target - CAMERA.eye).normalize();
    let r = f.cross(&Vector3::z()).normalize();
    let u = r.cross(&f);
    let d = p - CAMERA.eye;
    let (x, y, z) = (d.dot(&r), d.dot(&u), d.dot(&f));
    let t = (CAMERA.fov_deg.to_radians() / 2.0).tan();
    let aspect = width as f64 / height as f64;
    let (nx, ny) = (x / (z * t * aspect), y / (z * t));
    (
        (nx + 1.0) / 2.0 * width as f64,
        (1.0 - ny) / 2.0 * height as f64,
    )
}

/// Bounding box (x0, y0, x1, y1) of the pixels that are not the magenta background.
fn silhouette(img: &Image) -> (f64, f64, f64, f64) {
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for (k, p) in img.rgb.iter().enumerate() {
        let off = (255 - p[0] as i32).abs() + p[1] as i32 + (255 - p[2] as i32).abs();
        if off > 90 {
            let (x, y) = ((k % img.width) as f64, (k / img.width) as f64);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x + 1.0);
            y1 = y1.max(y + 1.0);
        }
    }
    assert!(x0 < x1, "nothing drawn");
    (x0, y0, x1, y1)
}

/// Points on a link's visual geometry, in the link's visual frame. Meshes in these
/// tests are the unit cube of tests/data/mesh_robot.
fn geometry_points(g: &Geometry) -> Vec<Vector3<f64>> {
    let circle = |r: f64, z: f64| {
        (0..64).map(move |k| {
            let a = k as f64 * std::f64::consts::TAU / 64.0;
            Vector3::new(r * a.cos(), r * a.sin(), z)
        })
    };
    let sphere = |r: f64, c: f64| {
        (0..400).map(move |k| {
            // Fibonacci sphere.
            let z = 1.0 - 2.0 * (k as f64 + 0.5) / 400.0;
            let a = k as f64 * 2.399_963;
            let s = (1.0 - z * z).sqrt();
            Vector3::new(r * s * a.cos(), r * s * a.sin(), c + r * z)
        })
    };
    let corners = |h: [f64; 3]| {
        (0..8).map(move |i| {
            Vector3::new(
                if i & 1 == 0 { -h[0] } else { h[0] },
                if i & 2 == 0 { -h[1] } else { h[1] },
                if i & 4 == 0 { -h[2] } else { h[2] },
            )
        })
    };
    match g {
        Geometry::Box { size } => corners(size.map(|s| s / 2.0)).collect(),
        Geometry::Cylinder { radius, length } => circle(*radius, -length / 2.0)
            .chain(circle(*radius, length / 2.0))
            .collect(),
        Geometry::Sphere { radius } => sphere(*radius, 0.0).collect(),
        // Drawn (by the URDF) as a cylinder.
        Geometry::Capsule { radius, length } => circle(*radius, -length / 2.0)
            .chain(circle(*radius, length / 2.0))
            .collect(),
        Geometry::Mesh { scale, .. } => {
            let s = scale.unwrap_or([1.0; 3]);
            corners([s[0] / 2.0, s[1] / 2.0, s[2] / 2.0]).collect()
        }
    }
}

fn matrix(r: [[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| r[i][j])
}

/// The projected extent of every visual of `drawn` (the served description) at
/// configuration `q`, by twinloop-dynamics' frame placements.
fn predicted_extent(
    drawn: &Description,
    q: &[f64],
    width: usize,
    height: usize,
) -> (f64, f64, f64, f64) {
    let model = Model::from_description(drawn).unwrap();
    let mut data = Data::new(&model);
    frames_forward_kinematics(&model, &mut data, q);
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for link in &drawn.links {
        let f = model.frame_index(&link.name).unwrap();
        let o = &data.o_m_f[f];
        for v in &link.visuals {
            let r = matrix(v.origin.rotation());
            let t = Vector3::from(v.origin.xyz);
            for p in geometry_points(&v.geometry) {
                let w = o.rotation * (r * p + t) + o.translation;
                let (x, y) = project(&w, width, height);
                x0 = x0.min(x);
                y0 = y0.min(y);
                x1 = x1.max(x);
                y1 = y1.max(y);
            }
        }
    }
    (x0, y0, x1, y1)
}

fn assert_extent_close(seen: (f64, f64, f64, f64), want: (f64, f64, f64, f64), what: &str) {
    // A pixel of rasterisation and one of antialiasing at each edge.
    let tol = 2.5;
    let (s, w) = (
        [seen.0, seen.1, seen.2, seen.3],
        [want.0, want.1, want.2, want.3],
    );
    for k in 0..4 {
        assert!(
            (s[k] - w[k]).abs() <= tol,
            "{what}: silhouette {seen:?} vs forward kinematics {want:?} (edge {k})"
        );
    }
}

// ---------- recordings made for the tests ----------

/// A table of two poses, at t = 0 and t = 1, for `model`'s coordinates.
fn two_pose_table(model: &Model, a: &[f64], b: &[f64]) -> Table {
    let mut columns = vec!["t".to_string()];
    columns.extend(model.q_names().iter().map(|n| format!("q:{n}")));
    let mut table = Table::new(columns);
    for (t, q) in [(0.0, a), (1.0, b)] {
        let mut row = vec![t];
        row.extend_from_slice(q);
        table.rows.push(row);
    }
    table
}

/// A configuration: base at `xyz` turned `yaw` about z, the named joints set, the
/// others at zero. Values are f32-exact (the page receives f32).
fn configuration(model: &Model, xyz: [f64; 3], yaw: f64, joints: &[(&str, f64)]) -> Vec<f64> {
    let mut q = vec![0.0; model.nq];
    let r = |x: f64| x as f32 as f64;
    q[..3].copy_from_slice(&xyz.map(r));
    let (s, c) = (yaw / 2.0).sin_cos();
    q[5] = r(s);
    q[6] = r(c);
    let names = model.q_names();
    for (name, v) in joints {
        let k = names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("{name}"));
        q[k] = r(*v);
    }
    q
}

fn km20() -> (Description, Model) {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let model = Model::from_description(&robot).unwrap();
    (robot, model)
}

fn pose_a(model: &Model) -> Vec<f64> {
    configuration(
        model,
        [0.05, -0.03, 0.30],
        0.3,
        &[
            ("l_sho_pitch", -1.2),
            ("r_sho_roll", -0.8),
            ("l_knee", 0.7),
            ("l_hip_pitch", -0.5),
        ],
    )
}

fn pose_b(model: &Model) -> Vec<f64> {
    configuration(
        model,
        [-0.04, 0.02, 0.28],
        -0.4,
        &[
            ("r_sho_pitch", 1.3),
            ("l_sho_roll", 0.9),
            ("head_pan", 0.5),
            ("r_knee", 1.0),
        ],
    )
}

// ---------- the tests ----------

#[test]
fn km20_replay_draws_the_robot_where_forward_kinematics_puts_it() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let (a, b) = (pose_a(&model), pose_b(&model));
    let scene = Scene::new(&robot, None, &[]);
    let drawn = twinloop_description::urdf::from_str(&scene.urdf).unwrap();
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
    let drawn = twinloop_description::urdf::from_str(&scene.urdf).unwrap();
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
    let drawn = twinloop_description::urdf::from_str(&scene.urdf).unwrap();
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
    let drawn = twinloop_description::urdf::from_str(&scene.urdf).unwrap();
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
    let page = load(&chromium, &format!("{url}{}", view_query(0.0)));
    assert_clean(&page);
    assert_no_misses(&misses);
    assert_eq!(
        page.status["warnings"].as_array().unwrap().len(),
        0,
        "{}",
        page.status
    );
    silhouette(&page.image);
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

#[test]
fn op3_urdf_and_mjcf_load_without_console_errors() {
    let Some(chromium) = browser() else { return };
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/op3");
    for file in ["robotis_op3.urdf", "mjcf/op3.xml"] {
        let path = models.join(file);
        let robot = twinloop_description::load(&path).unwrap();
        let scene = Scene::new(&robot, Some(&path), &[]);
        let n_missing = scene.info.meshes.len();
        assert!(n_missing > 0, "{file}: no meshes named?");
        let (url, misses) = serve_with_misses(Content {
            scene,
            recordings: vec![],
            live: None,
        });
        let page = load(&chromium, &format!("{url}{}", view_query(0.0)));
        assert_clean(&page);
        assert_no_misses(&misses);
        let warnings = page.status["warnings"].as_array().unwrap();
        assert_eq!(warnings.len(), n_missing, "{file}: {warnings:?}");
        silhouette(&page.image);
    }
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

#[test]
fn the_live_page_draws_the_state_it_receives() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let a = pose_a(&model);
    let scene = Scene::new(&robot, None, &[]);
    let drawn = twinloop_description::urdf::from_str(&scene.urdf).unwrap();
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
    let drawn = twinloop_description::urdf::from_str(&scene.urdf).unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![],
        live: None,
    });
    // Without a recording the robot stands on the ground at its zero pose: the root
    // is lifted by the depth of the lowest visual point below it.
    let zero = configuration(&model, [0.0; 3], 0.0, &[]);
    let mut data = Data::new(&model);
    frames_forward_kinematics(&model, &mut data, &zero);
    let mut lowest = f64::MAX;
    for link in &drawn.links {
        let o = &data.o_m_f[model.frame_index(&link.name).unwrap()];
        for v in &link.visuals {
            let (r, t) = (matrix(v.origin.rotation()), Vector3::from(v.origin.xyz));
            for p in geometry_points(&v.geometry) {
                lowest = lowest.min((o.rotation * (r * p + t) + o.translation).z);
            }
        }
    }
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
