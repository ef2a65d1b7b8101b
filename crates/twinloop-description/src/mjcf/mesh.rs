//! The mass properties of a triangle mesh (STL, OBJ or MuJoCo's MSH) as MuJoCo's compiler
//! computes them for a mesh geom: volume, centre of mass and inertia.
//!
//! The mesh is a union of pyramids from a centre to each face: from the
//! area-weighted face centroid for the centre of mass, then from the centre of
//! mass for the volume and the second moments (MuJoCo 4's order; the file's
//! single-precision vertices, the arithmetic in double). `inertia="legacy"`
//! (MuJoCo's default) counts every pyramid's volume as positive, `"exact"` signed
//! (right for closed meshes). `"shell"` puts the mass on the surface: the
//! area-weighted centroid, and each triangle's exact second moments as a thin
//! plate (`A/12 (sum v v^T + (sum v)(sum v)^T)`), density times area.
//! `"convex"` is `"exact"` on the mesh's convex hull ([`super::hull`]).

use super::inertia::{Mat, Vec3};
use std::path::Path;

/// Vertices and triangles.
pub(crate) struct TriMesh {
    pub vertices: Vec<Vec3>,
    pub faces: Vec<[usize; 3]>,
}

/// How pyramid volumes count (the mesh asset's `inertia`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Signed {
    /// `legacy`: absolute values.
    Legacy,
    /// `exact`: signed values.
    Exact,
}

/// Volume, centre of mass (mesh frame) and inertia about it at unit density.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MeshProps {
    pub volume: f64,
    pub com: Vec3,
    pub inertia: Mat,
}

/// Read an STL (binary or ASCII), OBJ or MSH file; the error says what is wrong.
pub(crate) fn read(path: &Path) -> Result<TriMesh, String> {
    let bytes = twinloop_io::input::read_bounded(path, twinloop_io::input::MAX_INPUT_BYTES)
        .map_err(|e| e.to_string())?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let mesh = match ext.as_str() {
        "stl" => read_stl(&bytes),
        "obj" => read_obj(&String::from_utf8_lossy(&bytes)),
        "msh" => read_msh(&bytes),
        _ => Err(format!(
            "mesh format .{ext} is not read (STL, OBJ and MSH are)"
        )),
    }
    .map_err(|e| format!("{}: {e}", path.display()))?;
    if let Some(f) = mesh
        .faces
        .iter()
        .flatten()
        .find(|&&i| i >= mesh.vertices.len())
    {
        return Err(format!(
            "{}: face refers to vertex {f} of {}",
            path.display(),
            mesh.vertices.len()
        ));
    }
    Ok(mesh)
}

fn read_stl(bytes: &[u8]) -> Result<TriMesh, String> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) {
            let mut vertices = Vec::with_capacity(3 * n);
            for t in 0..n {
                let at = 84 + 50 * t + 12; // skip the normal
                for v in 0..3 {
                    let p = at + 12 * v;
                    let c = |k: usize| {
                        let o = p + 4 * k;
                        f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]])
                            as f64
                    };
                    vertices.push([c(0), c(1), c(2)]);
                }
            }
            let faces = (0..n).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
            return Ok(TriMesh { vertices, faces });
        }
    }
    let text =
        std::str::from_utf8(bytes).map_err(|_| "neither binary nor ASCII STL".to_string())?;
    let mut vertices = Vec::new();
    for (line, l) in text.lines().enumerate() {
        let mut w = l.split_whitespace();
        if w.next() == Some("vertex") {
            let c: Vec<f64> = w
                .map(|x| x.parse::<f32>().map(f64::from))
                .collect::<Result<_, _>>()
                .map_err(|_| format!("line {}: bad vertex", line + 1))?;
            let [x, y, z] = c[..] else {
                return Err(format!("line {}: a vertex has 3 coordinates", line + 1));
            };
            vertices.push([x, y, z]);
        }
    }
    if vertices.is_empty() || vertices.len() % 3 != 0 {
        return Err("ASCII STL without whole triangles".to_string());
    }
    let faces = (0..vertices.len() / 3)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    Ok(TriMesh { vertices, faces })
}

/// MuJoCo's binary MSH: four little-endian `i32` counts (vertices, normals,
/// texture coordinates, faces), then the vertices (3 `f32` each), normals (3),
/// texture coordinates (2) and faces (3 `i32` vertex indices, from 0). The file
/// must be exactly that long. Without faces MuJoCo would take the convex hull
/// of the points: refused here rather than guessed.
fn read_msh(bytes: &[u8]) -> Result<TriMesh, String> {
    let word = |k: usize| -> [u8; 4] { bytes[4 * k..4 * k + 4].try_into().unwrap() };
    if bytes.len() < 16 {
        return Err("MSH shorter than its 16-byte header".to_string());
    }
    let count = |k: usize| usize::try_from(i32::from_le_bytes(word(k))).ok();
    let (Some(nv), Some(nn), Some(nt), Some(nf)) = (count(0), count(1), count(2), count(3)) else {
        return Err("MSH header has a negative count".to_string());
    };
    let words = [
        3 * nv as u128,
        3 * nn as u128,
        2 * nt as u128,
        3 * nf as u128,
    ];
    let expected = 16 + 4 * words.iter().sum::<u128>();
    if expected != bytes.len() as u128 {
        return Err(format!(
            "MSH of {nv} vertices, {nn} normals, {nt} texture coordinates and {nf} faces \
             should be {expected} bytes, the file has {}",
            bytes.len()
        ));
    }
    if nf == 0 {
        return Err("MSH without faces (MuJoCo takes the convex hull of its points)".to_string());
    }
    let vertices = (0..nv)
        .map(|i| [0, 1, 2].map(|c| f32::from_le_bytes(word(4 + 3 * i + c)) as f64))
        .collect();
    let first = 4 + 3 * nv + 3 * nn + 2 * nt;
    let mut faces = Vec::with_capacity(nf);
    for f in 0..nf {
        let mut t = [0; 3];
        for (c, v) in t.iter_mut().enumerate() {
            let i = i32::from_le_bytes(word(first + 3 * f + c));
            *v = usize::try_from(i).map_err(|_| format!("face {f} has vertex index {i}"))?;
        }
        faces.push(t);
    }
    Ok(TriMesh { vertices, faces })
}

/// `v x y z` and `f a b c ...` (1-based or negative indices, `a/t/n` forms);
/// polygons are split into a fan of triangles (the volume does not depend on how).
fn read_obj(text: &str) -> Result<TriMesh, String> {
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for (line, l) in text.lines().enumerate() {
        let bad = |what: &str| format!("line {}: {what}", line + 1);
        let mut w = l.split_whitespace();
        match w.next() {
            Some("v") => {
                let c: Vec<f64> = w
                    .take(3)
                    .map(str::parse)
                    .collect::<Result<_, _>>()
                    .map_err(|_| bad("bad vertex"))?;
                let [x, y, z] = c[..] else {
                    return Err(bad("a vertex has 3 coordinates"));
                };
                vertices.push([x, y, z].map(|v: f64| v as f32 as f64));
            }
            Some("f") => {
                let mut idx = Vec::new();
                for item in w {
                    let i: i64 = item
                        .split('/')
                        .next()
                        .unwrap_or("")
                        .parse()
                        .map_err(|_| bad("bad face index"))?;
                    let n = vertices.len() as i64;
                    let k = if i < 0 { n + i } else { i - 1 };
                    if k < 0 || k >= n {
                        return Err(bad("face index out of range"));
                    }
                    idx.push(k as usize);
                }
                for k in 1..idx.len().saturating_sub(1) {
                    faces.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(TriMesh { vertices, faces })
}

/// Area, unit normal and centre of a triangle (a degenerate one has no area).
fn triangle(d: &Vec3, e: &Vec3, f: &Vec3) -> (f64, Vec3, Vec3) {
    let cen = [0, 1, 2].map(|i| (d[i] + e[i] + f[i]) / 3.0);
    let b = [0, 1, 2].map(|i| e[i] - d[i]);
    let c = [0, 1, 2].map(|i| f[i] - d[i]);
    let n = [
        b[1] * c[2] - b[2] * c[1],
        b[2] * c[0] - b[0] * c[2],
        b[0] * c[1] - b[1] * c[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len < 1e-15 {
        return (0.0, [0.0; 3], cen);
    }
    (len / 2.0, n.map(|v| v / len), cen)
}

fn dot(a: &Vec3, b: &Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl TriMesh {
    /// MuJoCo's mesh `scale`.
    pub(crate) fn scaled(mut self, scale: Vec3) -> Self {
        for v in &mut self.vertices {
            for k in 0..3 {
                v[k] *= scale[k];
            }
        }
        self
    }

    /// Volume, CoM and inertia about the CoM at unit density: pyramids from the
    /// area-weighted face centroid give the CoM; the mesh is moved there and the
    /// pyramids from the CoM give the volume and the second moments.
    /// The shell (surface) mass properties at unit surface density: `volume` is the
    /// area, the measure a density multiplies.
    pub(crate) fn shell_properties(&self) -> Result<MeshProps, &'static str> {
        const K: [[usize; 2]; 6] = [[0, 0], [1, 1], [2, 2], [0, 1], [0, 2], [1, 2]];
        let (mut area, mut first) = (0.0, [0.0; 3]);
        let mut p = [0.0; 6];
        for t in &self.faces {
            let (d, e, f) = (
                &self.vertices[t[0]],
                &self.vertices[t[1]],
                &self.vertices[t[2]],
            );
            let (a, _, cen) = triangle(d, e, f);
            area += a;
            for j in 0..3 {
                first[j] += a * cen[j];
            }
            let sum = [0, 1, 2].map(|i| d[i] + e[i] + f[i]);
            for (j, &[x, y]) in K.iter().enumerate() {
                let vv = d[x] * d[y] + e[x] * e[y] + f[x] * f[y];
                p[j] += a / 12.0 * (vv + sum[x] * sum[y]);
            }
        }
        if area < 1e-15 {
            return Err("mesh surface area is too small");
        }
        let com = first.map(|c| c / area);
        // Second moments about the CoM (parallel axes), then the inertia tensor.
        for (j, &[x, y]) in K.iter().enumerate() {
            p[j] -= area * com[x] * com[y];
        }
        let inertia = [
            [p[1] + p[2], -p[3], -p[4]],
            [-p[3], p[0] + p[2], -p[5]],
            [-p[4], -p[5], p[0] + p[1]],
        ];
        Ok(MeshProps {
            volume: area,
            com,
            inertia,
        })
    }

    pub(crate) fn mass_properties(&self, signed: Signed) -> Result<MeshProps, &'static str> {
        let count = |v: f64| if signed == Signed::Legacy { v.abs() } else { v };
        let tri = |t: &[usize; 3], vs: &[Vec3]| triangle(&vs[t[0]], &vs[t[1]], &vs[t[2]]);
        let (mut facecen, mut area) = ([0.0; 3], 0.0);
        for t in &self.faces {
            let (a, _, cen) = tri(t, &self.vertices);
            for j in 0..3 {
                facecen[j] += a * cen[j];
            }
            area += a;
        }
        if area < 1e-15 {
            return Err("mesh surface area is too small");
        }
        facecen = facecen.map(|c| c / area);
        let (mut volume, mut com) = (0.0, [0.0; 3]);
        for t in &self.faces {
            let (a, n, cen) = tri(t, &self.vertices);
            let vec = [
                cen[0] - facecen[0],
                cen[1] - facecen[1],
                cen[2] - facecen[2],
            ];
            let vol = count(dot(&vec, &n) * a / 3.0);
            volume += vol;
            for j in 0..3 {
                com[j] += vol * (cen[j] * 3.0 / 4.0 + facecen[j] / 4.0);
            }
        }
        if volume < 1e-15 {
            return Err("mesh volume is too small (or negative: misoriented triangles)");
        }
        com = com.map(|c| c / volume);
        let moved: Vec<Vec3> = self
            .vertices
            .iter()
            .map(|v| [0, 1, 2].map(|j| v[j] - com[j]))
            .collect();
        let (volume, p) = second_moments(&self.faces, &moved, count);
        if volume < 1e-15 {
            return Err("mesh volume is too small");
        }
        let inertia = [
            [p[1] + p[2], -p[3], -p[4]],
            [-p[3], p[0] + p[2], -p[5]],
            [-p[4], -p[5], p[0] + p[1]],
        ];
        Ok(MeshProps {
            volume,
            com,
            inertia,
        })
    }
}

/// Volume and the second moments xx, yy, zz, xy, xz, yz of the pyramids from the
/// origin, at unit density.
fn second_moments(
    faces: &[[usize; 3]],
    vs: &[Vec3],
    count: impl Fn(f64) -> f64,
) -> (f64, [f64; 6]) {
    const K: [[usize; 2]; 6] = [[0, 0], [1, 1], [2, 2], [0, 1], [0, 2], [1, 2]];
    let mut volume = 0.0;
    let mut p = [0.0; 6];
    for t in faces {
        let (d, e, f) = (&vs[t[0]], &vs[t[1]], &vs[t[2]]);
        let (a, n, cen) = triangle(d, e, f);
        let vol = count(dot(&cen, &n) * a / 3.0);
        volume += vol;
        for (j, &[x, y]) in K.iter().enumerate() {
            let s = 2.0 * (d[x] * d[y] + e[x] * e[y] + f[x] * f[y])
                + d[x] * e[y]
                + d[y] * e[x]
                + d[x] * f[y]
                + d[y] * f[x]
                + e[x] * f[y]
                + e[y] * f[x];
            p[j] += vol / 20.0 * s;
        }
    }
    (volume, p)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit cube, as 12 outward triangles.
    fn cube() -> TriMesh {
        let vertices = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let faces = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        TriMesh { vertices, faces }
    }

    #[test]
    fn unit_cube_has_the_textbook_numbers() {
        for signed in [Signed::Legacy, Signed::Exact] {
            let p = cube()
                .scaled([2.0, 1.0, 1.0])
                .mass_properties(signed)
                .unwrap();
            assert!((p.volume - 2.0).abs() < 1e-12, "{}", p.volume);
            assert!((p.com[0] - 1.0).abs() < 1e-7 && (p.com[1] - 0.5).abs() < 1e-7);
            // Box 2 x 1 x 1 of mass 2: Ixx = 2 (1 + 1) / 12, Iyy = Izz = 2 (4 + 1) / 12.
            assert!(
                (p.inertia[0][0] - 4.0 / 12.0).abs() < 1e-7,
                "{:?}",
                p.inertia
            );
            assert!((p.inertia[1][1] - 10.0 / 12.0).abs() < 1e-7);
            assert!(p.inertia[0][1].abs() < 1e-7);
        }
    }

    #[test]
    fn inside_out_cube_is_refused_unless_legacy() {
        let mut m = cube();
        for f in &mut m.faces {
            f.swap(1, 2);
        }
        assert!(m.mass_properties(Signed::Exact).is_err());
        assert!((m.mass_properties(Signed::Legacy).unwrap().volume - 1.0).abs() < 1e-12);
    }

    /// The cube as MuJoCo's MSH (with 8 normals and no texture coordinates),
    /// read back to the same mesh; a wrong length, no faces or a bad index is
    /// refused with what is wrong.
    #[test]
    fn msh_reads_the_cube() {
        let c = cube();
        let mut b = Vec::new();
        for n in [8, 8, 0, c.faces.len() as i32] {
            b.extend(n.to_le_bytes());
        }
        for v in c.vertices.iter().chain(&c.vertices) {
            for x in v {
                b.extend((*x as f32).to_le_bytes());
            }
        }
        for f in &c.faces {
            for &i in f {
                b.extend((i as i32).to_le_bytes());
            }
        }
        let m = read_msh(&b).unwrap();
        assert_eq!((m.vertices, m.faces), (c.vertices, c.faces));
        let e = read_msh(&b[..b.len() - 1]).err().unwrap();
        assert!(e.contains("should be 352 bytes, the file has 351"), "{e}");
        let mut bad = b.clone();
        bad[b.len() - 4..].copy_from_slice(&(-1i32).to_le_bytes());
        assert_eq!(read_msh(&bad).err().unwrap(), "face 11 has vertex index -1");
        let e = read_msh(&[8, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]).err();
        assert!(e.unwrap().contains("should be 112 bytes"));
        let mut pts = vec![1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
        pts.extend([0; 12]);
        assert!(read_msh(&pts).err().unwrap().contains("without faces"));
    }

    #[test]
    fn obj_faces_and_negative_indices() {
        let m = read_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 4/4\nf -4 -2 -1\n")
            .unwrap();
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
    }
}
