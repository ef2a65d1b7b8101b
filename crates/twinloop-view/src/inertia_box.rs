//! The equivalent box of a link's inertia: the solid box of the link's mass whose
//! inertia about its centre equals the link's, in the principal axes. Drawn as an
//! overlay (a wrong inertia is seen at a glance) and as the stand-in for a link
//! whose mesh is missing.

use nalgebra::{Matrix3, SymmetricEigen};
use twinloop_description::{Inertial, Pose};

/// A box placed in its link's frame.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PlacedBox {
    pub xyz: [f64; 3],
    /// The box's axes in the link frame, as roll-pitch-yaw for the browser.
    pub rpy: [f64; 3],
    /// The same rotation as a matrix (row-major): what the Rust side places with.
    #[serde(skip)]
    pub rotation: [[f64; 3]; 3],
    /// Full edge lengths along the box's own x, y, z, m.
    pub size: [f64; 3],
}

/// The equivalent box of an inertial, or `None` for a massless link.
///
/// A solid box of mass m and edges a, b, c has principal moments
/// I1 = m (b^2 + c^2) / 12 (and cyclically), so a^2 = 6 (I2 + I3 - I1) / m.
/// A principal moment sum that breaks the triangle inequality (not a physical
/// body) gives a zero edge rather than a NaN.
pub fn equivalent_box(inertial: &Inertial) -> Option<PlacedBox> {
    let m = inertial.mass;
    if m <= 0.0 || !m.is_finite() {
        return None;
    }
    let i = inertial.inertia.matrix();
    let local = Matrix3::from_fn(|r, c| i[r][c]);
    let eig = SymmetricEigen::new(local);
    let mut axes = eig.eigenvectors;
    // A right-handed frame, so it is a rotation.
    if axes.determinant() < 0.0 {
        axes.column_mut(2).neg_mut();
    }
    let p = eig.eigenvalues;
    let edge = |a: f64, b: f64, c: f64| (6.0 * (b + c - a) / m).max(0.0).sqrt();
    let size = [
        edge(p[0], p[1], p[2]),
        edge(p[1], p[2], p[0]),
        edge(p[2], p[0], p[1]),
    ];
    // Box frame in the link frame: R_link_inertial * R_inertial_principal.
    let r0 = inertial.origin.rotation();
    let r0 = Matrix3::from_fn(|r, c| r0[r][c]);
    let r = r0 * axes;
    let rows = [
        [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
        [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
        [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
    ];
    let pose = Pose::from_matrix(inertial.origin.xyz, rows);
    Some(PlacedBox {
        xyz: pose.xyz,
        rpy: pose.rpy(),
        rotation: rows,
        size,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use twinloop_description::Inertia;

    #[test]
    fn a_solid_box_gives_back_its_edges() {
        let size = [0.1, 0.2, 0.3];
        let inertial = Inertial {
            origin: Pose::from_xyz([0.01, 0.02, 0.03]),
            mass: 1.7,
            inertia: Inertia::solid_box(1.7, size),
        };
        let b = equivalent_box(&inertial).unwrap();
        let mut got = b.size;
        got.sort_by(f64::total_cmp);
        for (g, w) in got.iter().zip(size) {
            assert!((g - w).abs() < 1e-12, "{got:?}");
        }
        assert_eq!(b.xyz, [0.01, 0.02, 0.03]);
    }

    #[test]
    fn a_rotated_box_is_placed_along_its_principal_axes() {
        // Box 0.4 x 0.1 x 0.1 turned 90 deg about z: its long edge lies along y.
        let size = [0.4, 0.1, 0.1];
        let d = Inertia::solid_box(2.0, size);
        let inertial = Inertial {
            origin: Pose::new([0.0; 3], [0.0, 0.0, std::f64::consts::FRAC_PI_2]),
            mass: 2.0,
            inertia: d,
        };
        let b = equivalent_box(&inertial).unwrap();
        let r = twinloop_description::rpy_to_matrix(b.rpy);
        // The direction of the longest edge, in the link frame.
        let k = (0..3)
            .max_by(|&i, &j| b.size[i].total_cmp(&b.size[j]))
            .unwrap();
        let dir = [r[0][k], r[1][k], r[2][k]];
        assert!((b.size[k] - 0.4).abs() < 1e-12);
        assert!((dir[1].abs() - 1.0).abs() < 1e-9, "{dir:?}");
    }

    #[test]
    fn massless_links_have_no_box() {
        assert!(equivalent_box(&Inertial::default()).is_none());
    }
}
