//! The convex hull of a point set in 3-D (incremental construction: each point
//! outside the hull so far removes the faces it sees and is joined to their horizon;
//! de Berg et al., Computational Geometry, ch. 11), for MuJoCo's mesh
//! `inertia="convex"`: the hull's volume, CoM and inertia, computed exactly.
//!
//! Points within a tolerance (1e-10 of the point cloud's size) of a face count as
//! inside, so coplanar and duplicate vertices never make slivers. The cost is
//! O(points x hull faces), fine for the meshes of robot links.

use super::inertia::Vec3;
use super::mesh::TriMesh;

/// A triangle of the hull, counter-clockwise seen from outside, and its plane.
#[derive(Clone, Copy)]
struct Face {
    v: [usize; 3],
    normal: Vec3,
    offset: f64,
}

fn sub(a: &Vec3, b: &Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: &Vec3, b: &Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: &Vec3, b: &Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: &Vec3) -> f64 {
    dot(a, a).sqrt()
}

impl Face {
    fn new(v: [usize; 3], p: &[Vec3]) -> Face {
        let n = cross(&sub(&p[v[1]], &p[v[0]]), &sub(&p[v[2]], &p[v[0]]));
        let len = norm(&n);
        let normal = if len > 0.0 { n.map(|x| x / len) } else { n };
        Face {
            v,
            normal,
            offset: dot(&normal, &p[v[0]]),
        }
    }

    /// Signed distance of `x` above the face's plane (outside is positive).
    fn height(&self, x: &Vec3) -> f64 {
        dot(&self.normal, x) - self.offset
    }
}

/// Four points spanning a tetrahedron of non-negligible volume: the extremes along
/// x, the point farthest from their line, the point farthest from their plane.
fn initial_simplex(p: &[Vec3], eps: f64) -> Option<[usize; 4]> {
    let by = |f: &dyn Fn(usize) -> f64| (0..p.len()).max_by(|&a, &b| f(a).total_cmp(&f(b)));
    let a = by(&|i| -p[i][0])?;
    let b = by(&|i| norm(&sub(&p[i], &p[a])))?;
    let ab = sub(&p[b], &p[a]);
    let c = by(&|i| norm(&cross(&ab, &sub(&p[i], &p[a]))))?;
    let n = cross(&ab, &sub(&p[c], &p[a]));
    let d = by(&|i| dot(&n, &sub(&p[i], &p[a])).abs())?;
    let volume = dot(&n, &sub(&p[d], &p[a])).abs() / 6.0;
    let size = norm(&ab);
    (size > eps && volume > eps * size * size).then_some([a, b, c, d])
}

/// The convex hull of `points` as outward triangles over the hull's vertices, or
/// an error when the points are all (nearly) on one plane.
pub(crate) fn convex_hull(points: &[Vec3]) -> Result<TriMesh, &'static str> {
    let (lo, hi) = points.iter().fold(
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
        |(lo, hi), x| {
            (
                [0, 1, 2].map(|k| lo[k].min(x[k])),
                [0, 1, 2].map(|k| hi[k].max(x[k])),
            )
        },
    );
    let eps = 1e-10 * norm(&sub(&hi, &lo)).max(f64::MIN_POSITIVE);
    let [a, b, c, d] =
        initial_simplex(points, eps).ok_or("the mesh is flat: its convex hull has no volume")?;
    // Orient the first triangle so that d is below it, then the other three from it.
    let (b, c) = if Face::new([a, b, c], points).height(&points[d]) > 0.0 {
        (c, b)
    } else {
        (b, c)
    };
    let mut faces: Vec<Face> = [[a, b, c], [a, d, b], [b, d, c], [c, d, a]]
        .iter()
        .map(|&v| Face::new(v, points))
        .collect();
    let mut visible: Vec<bool> = Vec::new();
    let mut horizon: Vec<[usize; 2]> = Vec::new();
    for (i, x) in points.iter().enumerate() {
        visible.clear();
        visible.extend(faces.iter().map(|f| f.height(x) > eps));
        if !visible.iter().any(|&s| s) {
            continue;
        }
        // Directed edges of the visible faces whose reverse is not visible.
        horizon.clear();
        for (f, _) in faces.iter().zip(&visible).filter(|(_, s)| **s) {
            for k in 0..3 {
                let e = [f.v[k], f.v[(k + 1) % 3]];
                let shared = faces
                    .iter()
                    .zip(&visible)
                    .any(|(g, &s)| s && (0..3).any(|m| g.v[m] == e[1] && g.v[(m + 1) % 3] == e[0]));
                if !shared {
                    horizon.push(e);
                }
            }
        }
        let mut keep = visible.iter().map(|s| !s);
        faces.retain(|_| keep.next().unwrap_or(true));
        faces.extend(horizon.iter().map(|e| Face::new([e[0], e[1], i], points)));
    }
    // Renumber the vertices the hull uses.
    let mut index = vec![usize::MAX; points.len()];
    let mut vertices = Vec::new();
    let faces = faces
        .iter()
        .map(|f| {
            f.v.map(|v| {
                if index[v] == usize::MAX {
                    index[v] = vertices.len();
                    vertices.push(points[v]);
                }
                index[v]
            })
        })
        .collect();
    Ok(TriMesh { vertices, faces })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mjcf::mesh::Signed;

    /// A cube's corners plus points inside it and on its faces and edges: the hull
    /// is the cube (volume 1, inertia 1/6 about the centre).
    #[test]
    fn hull_of_a_filled_cube_is_the_cube() {
        let mut points: Vec<Vec3> = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        let mut s = 12345u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..300 {
            let mut x = [next(), next(), next()];
            if k % 3 == 0 {
                x[k % 3] = (k % 2) as f64; // on a face
            }
            points.push(x);
        }
        points.push([0.5, 0.0, 0.0]); // on an edge
        let hull = convex_hull(&points).unwrap();
        // The corners, and no point from inside (a starting point on a face may stay
        // a vertex of its coplanar triangles: harmless for the mass properties).
        assert!(hull.vertices.len() >= 8 && hull.vertices.len() <= 12);
        let on_boundary = |x: &Vec3| x.iter().any(|&c| c == 0.0 || c == 1.0);
        assert!(hull.vertices.iter().all(on_boundary));
        let props = hull.mass_properties(Signed::Exact).unwrap();
        assert!((props.volume - 1.0).abs() < 1e-12, "{}", props.volume);
        for k in 0..3 {
            assert!((props.com[k] - 0.5).abs() < 1e-12);
            assert!((props.inertia[k][k] - 1.0 / 6.0).abs() < 1e-12);
        }
    }

    #[test]
    fn flat_points_have_no_hull() {
        let points: Vec<Vec3> = (0..10).map(|i| [i as f64, (i * i) as f64, 0.0]).collect();
        assert!(convex_hull(&points).is_err());
    }
}
