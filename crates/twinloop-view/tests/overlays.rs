//! The overlays in a real headless browser, against what they should show: the page
//! reports (window.twinloop.overlays) the support polygon's vertices, the centre of
//! pressure and ground-reaction arrows, the link frames, the inertia boxes, the
//! joints at a limit and which overlays are on; these are checked against
//! twinloop-dynamics' forward kinematics and CoM, the recording's `foot:*` and
//! `grf.*` columns and the description's limits and inertias; then a real click on
//! each checkbox (DevTools protocol input) turns that overlay off.
//!
//! Without Chromium these tests print why and pass, unless
//! TWINLOOP_REQUIRE_ORACLES=1 (CI), where a missing browser fails them.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde_json::Value;
use std::path::Path;
use twinloop_description::{Description, Geometry};
use twinloop_dynamics::{Data, Model, center_of_mass, frames_forward_kinematics};
use twinloop_io::Table;
use twinloop_view::{Content, Recording, Scene};

#[allow(dead_code)]
#[path = "support/cdp.rs"]
mod cdp;
#[path = "support/chromium.rs"]
mod chromium;
#[allow(dead_code)]
#[path = "support/page.rs"]
mod page;
use chromium::browser;
use page::{Drawn, configuration, drawn, km20, matrix, serve_with_misses};

/// Height under which geometry touches the ground (the page's CONTACT_HEIGHT).
const CONTACT_HEIGHT: f64 = 0.01;

fn vec3(v: &Value) -> Vector3<f64> {
    let a = v.as_array().unwrap_or_else(|| panic!("not a vector: {v}"));
    Vector3::new(
        a[0].as_f64().unwrap(),
        a[1].as_f64().unwrap(),
        a[2].as_f64().unwrap(),
    )
}

/// The corners of each box visual in the world at `q` (the page's support polygon
/// takes the corners of each visual's bounding box; km20's feet are boxes). Every
/// other visual must stay well clear of the ground, or the polygon could not be
/// predicted from corners alone.
fn box_corners(drawn: &Drawn, model: &Model, q: &[f64]) -> Vec<Vector3<f64>> {
    let mut data = Data::new(model);
    frames_forward_kinematics(model, &mut data, q);
    let mut out = Vec::new();
    for link in &drawn.desc.links {
        let o = &data.o_m_f[model.frame_index(&link.name).unwrap()];
        for v in &link.visuals {
            let (r, t) = (matrix(v.origin.rotation()), Vector3::from(v.origin.xyz));
            let place = |p: Vector3<f64>| o.rotation * (r * p + t) + o.translation;
            if matches!(v.geometry, Geometry::Box { .. }) {
                out.extend(drawn.geometry_points(&v.geometry).into_iter().map(place));
                continue;
            }
            // The page's corners of anything else lie within the box around it.
            let h = match v.geometry {
                Geometry::Cylinder { radius, length } | Geometry::Capsule { radius, length } => {
                    [radius, radius, length / 2.0]
                }
                Geometry::Sphere { radius } => [radius; 3],
                _ => panic!("{}: a mesh in km20?", link.name),
            };
            let low = (0..8)
                .map(|i| {
                    let s = |b: usize, x: f64| if i & b == 0 { -x } else { x };
                    place(Vector3::new(s(1, h[0]), s(2, h[1]), s(4, h[2]))).z
                })
                .fold(f64::MAX, f64::min);
            assert!(
                low > CONTACT_HEIGHT + 1e-4,
                "{}: a non-box visual at z = {low}",
                link.name
            );
        }
    }
    out
}

/// The convex hull of 2-D points, counter-clockwise (gift wrapping: another method
/// than the page's monotone chain).
fn hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let start = (0..points.len())
        .min_by(|&a, &b| points[a][0].total_cmp(&points[b][0]))
        .unwrap();
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let mut out = vec![points[start]];
    loop {
        let p = *out.last().unwrap();
        let mut next = if points[0] == p { points[1] } else { points[0] };
        for &c in points {
            let turn = cross(p, next, c);
            // Clockwise of the candidate, or on its line and farther: the next vertex.
            if turn < -1e-12 || (turn.abs() <= 1e-12 && dist(p, c) > dist(p, next)) {
                next = c;
            }
        }
        if next == out[0] {
            return out;
        }
        out.push(next);
        assert!(out.len() <= points.len(), "hull did not close");
    }
}

/// A km20 standing on its left foot (turned out, so no two hull edges line up), the
/// right one lifted, its head and right elbow at a limit; one recorded row
/// repeated, with a left-foot load, an unloaded right foot and a plate reading.
struct Stand {
    robot: Description,
    model: Model,
    q: Vec<f64>,
    table: Table,
}

fn stand() -> Stand {
    let (robot, model) = km20();
    let limit = |name: &str| {
        robot
            .joints
            .iter()
            .find(|j| j.name == name)
            .unwrap()
            .limit
            .unwrap()
    };
    let head = limit("head_pan").lower.unwrap();
    let elbow = limit("r_elbow").upper.unwrap();
    // The right foot is lifted 3.5 cm, parallel to the ground: not in the polygon.
    let joints = [
        ("head_pan", head),
        ("r_elbow", elbow),
        ("l_hip_yaw", 0.3),
        ("r_hip_pitch", -0.6),
        ("r_knee", 1.2),
        ("r_ank_pitch", -0.6),
    ];
    let scene = Scene::new(&robot, None, &[]);
    let drawn = drawn(&scene);
    let low = drawn
        .world_points(&configuration(&model, [0.0; 3], 0.2, &joints))
        .iter()
        .map(|p| p.z)
        .fold(f64::MAX, f64::min);
    let q = configuration(&model, [0.02, -0.01, -low], 0.2, &joints);
    let mut columns = vec!["t".to_string()];
    columns.extend(model.q_names().iter().map(|n| format!("q:{n}")));
    let extra = [
        ("foot:l_foot.fz", 12.5),
        ("foot:l_foot.cop.x", 0.03125),
        ("foot:l_foot.cop.y", 0.046875),
        ("foot:r_foot.fz", 0.25),
        ("foot:r_foot.cop.x", 0.0),
        ("foot:r_foot.cop.y", -0.05),
        ("grf.fx", 3.0),
        ("grf.fy", -2.0),
        ("grf.fz", 30.0),
        ("cop.x", 0.015625),
        ("cop.y", -0.0078125),
    ];
    columns.extend(extra.iter().map(|(c, _)| c.to_string()));
    let mut table = Table::new(columns);
    for t in [0.0, 1.0] {
        let mut row = vec![t];
        row.extend_from_slice(&q);
        row.extend(extra.iter().map(|(_, v)| *v));
        table.rows.push(row);
    }
    Stand {
        robot,
        model,
        q,
        table,
    }
}

/// The overlays as the page reports them now.
fn overlays(page: &mut cdp::Browser) -> Value {
    let text = page.eval("JSON.stringify(window.twinloop.overlays)");
    serde_json::from_str(text.as_str().unwrap()).unwrap()
}

fn close(a: &Vector3<f64>, b: &Vector3<f64>, tol: f64) -> bool {
    (a - b).norm() <= tol
}

#[test]
fn overlays_show_what_kinematics_and_the_columns_say_and_each_turns_off() {
    let Some(chromium) = browser() else { return };
    let Stand {
        robot,
        model,
        q,
        table,
    } = stand();
    let scene = Scene::new(&robot, None, &[]);
    let drawn = drawn(&scene);
    let total_mass = scene.info.total_mass;
    let rec = Recording::from_table(&table, Path::new("stand.csv"), &scene.info).unwrap();
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings: vec![rec],
        live: None,
    });
    let all = "grid,com,support,cop,limits,frames,inertia";
    let mut page = cdp::Browser::open(&chromium, &format!("{url}?t=0.5&overlays={all}"));
    page.wait_for(
        "!!(window.twinloop && window.twinloop.ready && window.twinloop.overlays.frames.length)",
        120,
    );
    let o = overlays(&mut page);
    for name in all.split(',') {
        assert_eq!(o["on"][name], true, "{name}: {o}");
    }
    assert_eq!(o["grid"], true);

    // The CoM, against twinloop-dynamics'.
    let mut data = Data::new(&model);
    let com = center_of_mass(&model, &mut data, &q);
    assert!(
        close(&vec3(&o["com"]), &com, 1e-6),
        "CoM {} vs {com}",
        o["com"]
    );

    // The support polygon: the hull of the box corners on the ground.
    let mut ground: Vec<[f64; 2]> = Vec::new();
    for p in box_corners(&drawn, &model, &q) {
        if p.z < CONTACT_HEIGHT
            && !ground
                .iter()
                .any(|g| (g[0] - p.x).abs() + (g[1] - p.y).abs() < 1e-12)
        {
            ground.push([p.x, p.y]);
        }
    }
    assert!(ground.len() >= 4, "{} corners on the ground", ground.len());
    let (left_foot, right_foot) = {
        let mut data = Data::new(&model);
        frames_forward_kinematics(&model, &mut data, &q);
        let z = |l: &str| data.o_m_f[model.frame_index(l).unwrap()].translation.z;
        (z("l_foot"), z("r_foot"))
    };
    assert!(
        right_foot - left_foot > 0.03,
        "the right foot is not lifted"
    );
    let want = hull(&ground);
    let seen: Vec<[f64; 2]> = o["support"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
        .collect();
    assert_eq!(seen.len(), want.len(), "support {seen:?} vs {want:?}");
    for w in &want {
        assert!(
            seen.iter()
                .any(|s| (s[0] - w[0]).abs() < 1e-6 && (s[1] - w[1]).abs() < 1e-6),
            "hull vertex {w:?} not in the page's {seen:?}"
        );
    }

    // CoP and ground reaction: where and what the columns say; an unloaded foot has none.
    let scale = 0.4 / (total_mass * 9.81);
    let cops = o["cop"].as_array().unwrap();
    assert_eq!(cops.len(), 3, "{o}");
    for (name, shown, at, force) in [
        ("foot:l_foot", true, [0.03125, 0.046875], [0.0, 0.0, 12.5]),
        ("foot:r_foot", false, [0.0, 0.0], [0.0, 0.0, 0.25]),
        ("grf", true, [0.015625, -0.0078125], [3.0, -2.0, 30.0]),
    ] {
        let c = cops.iter().find(|c| c["name"] == name).unwrap();
        assert_eq!(c["shown"], shown, "{c}");
        let f = Vector3::from(force);
        assert!(close(&vec3(&c["force"]), &f, 1e-9), "{c}");
        if !shown {
            continue;
        }
        assert!(
            close(&vec3(&c["at"]), &Vector3::new(at[0], at[1], 0.003), 1e-9),
            "{c}"
        );
        assert!(close(&vec3(&c["direction"]), &f.normalize(), 1e-6), "{c}");
        let length = (f.norm() * scale).max(0.02);
        assert!(
            (c["length"].as_f64().unwrap() - length).abs() < 1e-9,
            "{c}: length {length}"
        );
    }

    // Joints at a limit: those within 0.1 % of the range of one, by the description.
    let names = model.q_names();
    let mut at_limit: Vec<String> = Vec::new();
    for j in &robot.joints {
        let Some(l) = j.limit else { continue };
        let (Some(lo), Some(hi)) = (l.lower, l.upper) else {
            continue;
        };
        let Some(k) = names.iter().position(|n| *n == j.name) else {
            continue;
        };
        let tol = (1e-3 * (hi - lo)).max(1e-4);
        if q[k] <= lo + tol || q[k] >= hi - tol {
            at_limit.push(j.name.clone());
        }
    }
    let mut seen: Vec<String> = o["limits"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    seen.sort();
    at_limit.sort();
    assert!(
        at_limit.contains(&"head_pan".to_string()) && at_limit.contains(&"r_elbow".to_string())
    );
    assert_eq!(seen, at_limit, "joints at a limit");
    assert_eq!(o["limit_coloured"], o["limits"], "drawn red: {o}");

    // Link frames at the links' placements; inertia boxes at the links' CoMs, each a
    // solid box with the link's principal moments.
    frames_forward_kinematics(&model, &mut data, &q);
    let frames = o["frames"].as_array().unwrap();
    assert_eq!(frames.len(), robot.links.len());
    for f in frames {
        let at = &data.o_m_f[model.frame_index(f["link"].as_str().unwrap()).unwrap()];
        assert!(close(&vec3(&f["at"]), &at.translation, 1e-6), "{f}");
    }
    let boxes = o["inertia"].as_array().unwrap();
    let massive: Vec<_> = robot
        .links
        .iter()
        .filter(|l| l.inertial.is_some_and(|i| i.mass > 0.0))
        .collect();
    assert_eq!(boxes.len(), massive.len());
    for link in massive {
        let b = boxes
            .iter()
            .find(|b| b["link"] == link.name.as_str())
            .unwrap();
        let i = link.inertial.unwrap();
        let o_l = &data.o_m_f[model.frame_index(&link.name).unwrap()];
        let centre = o_l.rotation * Vector3::from(i.origin.xyz) + o_l.translation;
        assert!(close(&vec3(&b["at"]), &centre, 1e-6), "{b} vs {centre}");
        let s = vec3(&b["size"]);
        let m = i.mass;
        let mut box_moments = [
            m * (s.y * s.y + s.z * s.z) / 12.0,
            m * (s.x * s.x + s.z * s.z) / 12.0,
            m * (s.x * s.x + s.y * s.y) / 12.0,
        ];
        // Principal moments do not depend on the frame the tensor is written in.
        let tensor = Matrix3::from_fn(|a, c| i.inertia.matrix()[a][c]);
        let mut moments: Vec<f64> = SymmetricEigen::new(tensor)
            .eigenvalues
            .iter()
            .copied()
            .collect();
        moments.sort_by(f64::total_cmp);
        box_moments.sort_by(f64::total_cmp);
        for k in 0..3 {
            assert!(
                (moments[k] - box_moments[k]).abs() <= 1e-6 * moments[2] + 1e-12,
                "{}: box moments {box_moments:?} vs {moments:?}",
                link.name
            );
        }
    }

    // A real click on each checkbox turns its overlay off.
    let off: [(&str, &str); 7] = [
        ("grid", "o.grid === false"),
        ("com", "o.com === null"),
        ("support", "o.support.length === 0"),
        ("cop", "o.cop.every((c) => !c.shown)"),
        (
            "limits",
            "o.limits.length === 0 && o.limit_coloured.length === 0",
        ),
        ("frames", "o.frames.length === 0"),
        ("inertia", "o.inertia.length === 0"),
    ];
    for (name, gone) in off {
        click_overlay(&mut page, name);
        page.wait_for(
            &format!("(() => {{ const o = window.twinloop.overlays; return o.on.{name} === false && {gone}; }})()"),
            20,
        );
    }
    // And on again: the joints at a limit are red again.
    click_overlay(&mut page, "limits");
    page.wait_for("window.twinloop.overlays.limit_coloured.length > 0", 20);
    let o = overlays(&mut page);
    assert_eq!(o["limit_coloured"], o["limits"]);
    let status = page.eval("JSON.stringify(window.twinloop.errors)");
    assert_eq!(status, Value::String("[]".into()));
    assert_eq!(misses.list(), Vec::<String>::new());
}

/// Click the checkbox of overlay `name` where the page draws it.
fn click_overlay(page: &mut cdp::Browser, name: &str) {
    let (x, y, width) = page.centre(&format!("[data-overlay={name}]"));
    assert!(width > 0.0, "the {name} checkbox is not drawn");
    page.click(x, y);
}

#[test]
fn the_gift_wrapping_hull_of_a_square_with_inner_points_is_its_corners() {
    let pts = [
        [0.0, 0.0],
        [1.0, 0.0],
        [0.5, 0.5],
        [1.0, 1.0],
        [0.0, 1.0],
        [0.5, 0.0],
        [0.2, 0.7],
    ];
    let h = hull(&pts);
    assert_eq!(h.len(), 4, "{h:?}");
    for c in [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
        assert!(h.contains(&c), "{h:?}");
    }
}
