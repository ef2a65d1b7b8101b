//! What the browser tests share: loading a page in headless Chromium and reading its
//! status and rendered image, the test camera and its projection, the silhouette of
//! the drawn robot against the extent forward kinematics predicts for it (meshes read
//! from their STL or OBJ files), and recordings made for the tests.

use nalgebra::{Matrix3, Vector3};
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;
use twinloop_description::{Description, Geometry};
use twinloop_dynamics::{Data, Model, frames_forward_kinematics};
use twinloop_io::Table;
use twinloop_view::{Content, Scene, Server};

use super::chromium::{dump_dom, element_text, unescape_html};

/// An RGB image.
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[u8; 3]>,
}

pub struct Page {
    pub status: Value,
    pub image: Image,
}

pub fn decode_png(bytes: &[u8]) -> Image {
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
pub fn load(chromium: &Path, url: &str) -> Page {
    try_load(chromium, url).unwrap_or_else(|status| panic!("no #snapshot: {status}"))
}

/// [`load`], or the page's status when it drew no snapshot (a live page whose first
/// frame had not arrived when headless Chromium's virtual time ran out).
pub fn try_load(chromium: &Path, url: &str) -> Result<Page, Value> {
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
pub fn serve_with_misses(content: Content) -> (String, twinloop_view::server::Misses) {
    let server = Server::bind("127.0.0.1:0", content).unwrap();
    let (url, misses) = (server.url(), server.misses());
    std::thread::spawn(move || server.run());
    (url, misses)
}

/// No request of the page went unanswered (a 404 is a console error in the browser).
pub fn assert_no_misses(misses: &twinloop_view::server::Misses) {
    assert_eq!(
        misses.list(),
        Vec::<String>::new(),
        "the page asked for missing files"
    );
}

pub fn assert_clean(page: &Page) {
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
pub struct Camera {
    pub eye: Vector3<f64>,
    pub target: Vector3<f64>,
    pub fov_deg: f64,
}

pub const CAMERA: Camera = Camera {
    eye: Vector3::new(0.9, -1.5, 0.5),
    target: Vector3::new(0.0, 0.0, 0.25),
    fov_deg: 40.0,
};

/// For a robot of a person's height (G1: 1.3 m).
pub const TALL: Camera = Camera {
    eye: Vector3::new(2.4, -3.6, 1.4),
    target: Vector3::new(0.1, -0.2, 0.6),
    fov_deg: 40.0,
};

impl Camera {
    /// Page parameters: this camera, a magenta background, no overlays, the image
    /// in #snapshot.
    pub fn query(&self, t: f64) -> String {
        let (e, g) = (self.eye, self.target);
        format!(
            "?t={t}&bare=1&snapshot=1&bg=ff00ff&overlays=&fov={}&camera={},{},{},{},{},{}",
            self.fov_deg, e.x, e.y, e.z, g.x, g.y, g.z
        )
    }

    /// A world point in pixels (x right, y down), as three.js projects it: a
    /// perspective camera at `eye` looking at `target`, z up.
    pub fn project(&self, p: &Vector3<f64>, width: usize, height: usize) -> (f64, f64) {
        let f = (self.target - self.eye).normalize();
        let r = f.cross(&Vector3::z()).normalize();
        let u = r.cross(&f);
        let d = p - self.eye;
        let (x, y, z) = (d.dot(&r), d.dot(&u), d.dot(&f));
        let t = (self.fov_deg.to_radians() / 2.0).tan();
        let aspect = width as f64 / height as f64;
        let (nx, ny) = (x / (z * t * aspect), y / (z * t));
        (
            (nx + 1.0) / 2.0 * width as f64,
            (1.0 - ny) / 2.0 * height as f64,
        )
    }

    /// The projected extent of every visual of the served description at
    /// configuration `q`.
    pub fn extent(
        &self,
        drawn: &Drawn,
        q: &[f64],
        width: usize,
        height: usize,
    ) -> (f64, f64, f64, f64) {
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for w in drawn.world_points(q) {
            let (x, y) = self.project(&w, width, height);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
        (x0, y0, x1, y1)
    }
}

/// [`Camera::query`] of the test camera.
pub fn view_query(t: f64) -> String {
    CAMERA.query(t)
}

/// [`Camera::project`] of the test camera.
pub fn project(p: &Vector3<f64>, width: usize, height: usize) -> (f64, f64) {
    CAMERA.project(p, width, height)
}

/// Bounding box (x0, y0, x1, y1) of the pixels that are not the magenta background.
pub fn silhouette(img: &Image) -> (f64, f64, f64, f64) {
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

/// The served description as the page draws it, with the vertices of its mesh files.
pub struct Drawn {
    pub desc: Description,
    /// The vertices of each mesh file the page loads, by its URL (`mesh/N.ext`).
    meshes: HashMap<String, Vec<Vector3<f64>>>,
}

/// What the page of `scene` draws: its served URDF, and the vertices of the STL and
/// OBJ files it names (read here, independently of the page's loaders). A COLLADA
/// file is taken as the unit cube (the test fixtures' only DAE mesh is one).
pub fn drawn(scene: &Scene) -> Drawn {
    let desc = twinloop_description::urdf::from_str(&scene.urdf).unwrap();
    let mut meshes = HashMap::new();
    for m in &scene.info.meshes {
        let (Some(url), Some(path)) = (&m.url, &m.path) else {
            continue;
        };
        let points = if url.ends_with(".stl") {
            stl_vertices(path)
        } else if url.ends_with(".obj") {
            obj_vertices(path)
        } else {
            continue;
        };
        meshes.insert(url.clone(), points);
    }
    Drawn { desc, meshes }
}

/// The vertices of an STL file, binary or ASCII.
pub fn stl_vertices(path: &Path) -> Vec<Vector3<f64>> {
    let bytes = std::fs::read(path).unwrap();
    let binary_len = |n: usize| 84 + 50 * n;
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
        if bytes.len() == binary_len(n) {
            let f = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as f64;
            let mut out = Vec::with_capacity(3 * n);
            for t in 0..n {
                let o = 84 + 50 * t + 12;
                for v in 0..3 {
                    let o = o + 12 * v;
                    out.push(Vector3::new(f(o), f(o + 4), f(o + 8)));
                }
            }
            return out;
        }
    }
    let text = String::from_utf8_lossy(&bytes);
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("vertex "))
        .map(|v| {
            let c: Vec<f64> = v.split_whitespace().map(|x| x.parse().unwrap()).collect();
            Vector3::new(c[0], c[1], c[2])
        })
        .collect()
}

/// The vertices of an OBJ file (`v x y z` lines).
pub fn obj_vertices(path: &Path) -> Vec<Vector3<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|v| {
            let c: Vec<f64> = v.split_whitespace().map(|x| x.parse().unwrap()).collect();
            Vector3::new(c[0], c[1], c[2])
        })
        .collect()
}

impl Drawn {
    /// Points on a visual's geometry, in the visual's frame: its vertices for a mesh,
    /// corners for a box, rims for a cylinder, a dense sphere.
    pub fn geometry_points(&self, g: &Geometry) -> Vec<Vector3<f64>> {
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
            Geometry::Mesh { filename, scale } => {
                let s = Vector3::from(scale.unwrap_or([1.0; 3]));
                match self.meshes.get(filename) {
                    Some(points) => points.iter().map(|p| p.component_mul(&s)).collect(),
                    None => corners([s[0] / 2.0, s[1] / 2.0, s[2] / 2.0]).collect(),
                }
            }
        }
    }

    /// Every visual point in the world at configuration `q`, by twinloop-dynamics'
    /// frame placements.
    pub fn world_points(&self, q: &[f64]) -> Vec<Vector3<f64>> {
        let model = Model::from_description(&self.desc).unwrap();
        let mut data = Data::new(&model);
        frames_forward_kinematics(&model, &mut data, q);
        let mut out = Vec::new();
        for link in &self.desc.links {
            let o = &data.o_m_f[model.frame_index(&link.name).unwrap()];
            for v in &link.visuals {
                let r = matrix(v.origin.rotation());
                let t = Vector3::from(v.origin.xyz);
                for p in self.geometry_points(&v.geometry) {
                    out.push(o.rotation * (r * p + t) + o.translation);
                }
            }
        }
        out
    }
}

pub fn matrix(r: [[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| r[i][j])
}

/// [`Camera::extent`] of the test camera.
pub fn predicted_extent(
    drawn: &Drawn,
    q: &[f64],
    width: usize,
    height: usize,
) -> (f64, f64, f64, f64) {
    CAMERA.extent(drawn, q, width, height)
}

pub fn assert_extent_close(seen: (f64, f64, f64, f64), want: (f64, f64, f64, f64), what: &str) {
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
pub fn two_pose_table(model: &Model, a: &[f64], b: &[f64]) -> Table {
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
pub fn configuration(model: &Model, xyz: [f64; 3], yaw: f64, joints: &[(&str, f64)]) -> Vec<f64> {
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

pub fn km20() -> (Description, Model) {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let model = Model::from_description(&robot).unwrap();
    (robot, model)
}

pub fn pose_a(model: &Model) -> Vec<f64> {
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

pub fn pose_b(model: &Model) -> Vec<f64> {
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
