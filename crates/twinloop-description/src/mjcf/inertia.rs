//! MuJoCo's compiler for a body's mass properties: the mass and inertia of
//! primitive geoms (solid or shell), their sum over a body, and the compiler's
//! `boundmass`, `boundinertia` and `balanceinertia` corrections.
//!
//! The formulas are MuJoCo's (its geom volume and inertia for each shape), so a
//! body without `<inertial>` weighs what MuJoCo says it weighs.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use std::f64::consts::PI;

pub(crate) type Mat = [[f64; 3]; 3];
pub(crate) type Vec3 = [f64; 3];

/// A primitive geom's shape, by MuJoCo's size parameters (half sizes).
#[derive(Debug, Clone, Copy)]
pub(crate) enum Solid {
    Sphere {
        radius: f64,
    },
    /// Along z: radius and half-length of the cylindrical part.
    Capsule {
        radius: f64,
        half: f64,
    },
    Cylinder {
        radius: f64,
        half: f64,
    },
    Ellipsoid {
        semi: Vec3,
    },
    Box {
        half: Vec3,
    },
}

/// Mass properties of a rigid part in a body frame: mass, centre of mass and
/// inertia tensor about the centre of mass (body axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MassProps {
    pub mass: f64,
    pub com: Vec3,
    pub inertia: Mat,
}

impl Solid {
    /// Volume, or surface area for a shell (`shellinertia`): what density multiplies.
    pub(crate) fn measure(&self, shell: bool) -> f64 {
        match (*self, shell) {
            (Solid::Sphere { radius: r }, false) => 4.0 * PI * r * r * r / 3.0,
            (Solid::Sphere { radius: r }, true) => 4.0 * PI * r * r,
            (Solid::Capsule { radius: r, half }, false) => {
                PI * (r * r * 2.0 * half + 4.0 * r * r * r / 3.0)
            }
            (Solid::Capsule { radius: r, half }, true) => {
                4.0 * PI * r * r + 2.0 * PI * r * 2.0 * half
            }
            (Solid::Cylinder { radius: r, half }, false) => PI * r * r * 2.0 * half,
            (Solid::Cylinder { radius: r, half }, true) => {
                2.0 * PI * r * r + 2.0 * PI * r * 2.0 * half
            }
            (Solid::Ellipsoid { semi: [a, b, c] }, false) => 4.0 * PI * a * b * c / 3.0,
            (Solid::Ellipsoid { semi: [a, b, c] }, true) => {
                // Thomsen's approximation of the surface area, as MuJoCo uses.
                let p = 1.6075;
                let t = (a * b).powf(p) + (b * c).powf(p) + (c * a).powf(p);
                4.0 * PI * (t / 3.0).powf(1.0 / p)
            }
            (Solid::Box { half: [a, b, c] }, false) => 8.0 * a * b * c,
            (Solid::Box { half: [a, b, c] }, true) => 8.0 * (a * b + b * c + c * a),
        }
    }

    /// Principal moments about the geom's centre along its axes, for `mass`.
    pub(crate) fn principal_inertia(&self, mass: f64, shell: bool) -> Vec3 {
        match *self {
            Solid::Sphere { radius: r } => {
                let k = if shell { 2.0 / 3.0 } else { 2.0 / 5.0 };
                [k * mass * r * r; 3]
            }
            Solid::Capsule { radius, half } if shell => capsule_shell(mass, radius, half),
            Solid::Capsule { radius, half } => capsule_solid(mass, radius, half),
            Solid::Cylinder { radius, half } if shell => cylinder_shell(mass, radius, half),
            Solid::Cylinder { radius: r, half } => {
                let h = 2.0 * half;
                let side = mass * (3.0 * r * r + h * h) / 12.0;
                [side, side, mass * r * r / 2.0]
            }
            Solid::Ellipsoid { semi } if shell => ellipsoid_shell(mass, semi),
            Solid::Ellipsoid { semi: [a, b, c] } => [
                mass * (b * b + c * c) / 5.0,
                mass * (a * a + c * c) / 5.0,
                mass * (a * a + b * b) / 5.0,
            ],
            Solid::Box { half } if shell => box_shell(mass, half),
            Solid::Box { half: [a, b, c] } => [
                mass * (b * b + c * c) / 3.0,
                mass * (a * a + c * c) / 3.0,
                mass * (a * a + b * b) / 3.0,
            ],
        }
    }
}

/// Solid capsule: a cylinder plus two hemispheres displaced along z.
fn capsule_solid(mass: f64, r: f64, half: f64) -> Vec3 {
    let h = 2.0 * half;
    let sphere_mass = mass * 4.0 * r / (4.0 * r + 3.0 * h);
    let cylinder_mass = mass - sphere_mass;
    let side = cylinder_mass * (3.0 * r * r + h * h) / 12.0;
    let axial = cylinder_mass * r * r / 2.0;
    let sphere = 2.0 * sphere_mass * r * r / 5.0;
    let shift = sphere_mass * h * (3.0 * r + 2.0 * h) / 8.0;
    [side + sphere + shift, side + sphere + shift, axial + sphere]
}

/// Capsule shell: a tube plus two hemispherical shells (centroid r/2 from the rim).
fn capsule_shell(mass: f64, r: f64, half: f64) -> Vec3 {
    let h = 2.0 * half;
    let a_sphere = 4.0 * PI * r * r;
    let a_tube = 2.0 * PI * r * h;
    let sphere_mass = mass * a_sphere / (a_sphere + a_tube);
    let tube_mass = mass - sphere_mass;
    let side = tube_mass * (6.0 * r * r + h * h) / 12.0;
    let axial = tube_mass * r * r;
    let sphere = 2.0 * sphere_mass * r * r / 3.0;
    let com = r / 2.0;
    let at = half + com;
    let shift = sphere_mass * (at * at - com * com);
    [side + sphere + shift, side + sphere + shift, axial + sphere]
}

/// Cylinder shell: a tube and two end disks.
fn cylinder_shell(mass: f64, r: f64, half: f64) -> Vec3 {
    let h = 2.0 * half;
    let a_disk = PI * r * r;
    let a_tube = 2.0 * PI * r * h;
    let disk_mass = mass * a_disk / (2.0 * a_disk + a_tube);
    let tube_mass = mass - 2.0 * disk_mass;
    let disk_side = disk_mass * r * r / 4.0 + disk_mass * half * half;
    let disk_axial = disk_mass * r * r / 2.0;
    let side = tube_mass * (6.0 * r * r + h * h) / 12.0 + 2.0 * disk_side;
    [side, side, tube_mass * r * r + 2.0 * disk_axial]
}

/// Ellipsoid shell: the solid grown by 1e-6 minus the solid, at equal density
/// (MuJoCo's approximation).
fn ellipsoid_shell(mass: f64, [a, b, c]: Vec3) -> Vec3 {
    let eps = 1e-6;
    let (ae, be, ce) = (a + eps, b + eps, c + eps);
    let va = 4.0 * PI * a * b * c / 3.0;
    let vb = 4.0 * PI * ae * be * ce / 3.0;
    let density = mass / (vb - va);
    let (ma, mb) = (va * density, vb * density);
    [
        mb * (be * be + ce * ce) / 5.0 - ma * (b * b + c * c) / 5.0,
        mb * (ae * ae + ce * ce) / 5.0 - ma * (a * a + c * c) / 5.0,
        mb * (ae * ae + be * be) / 5.0 - ma * (a * a + b * b) / 5.0,
    ]
}

/// Box shell: six thin plates, mass by area.
fn box_shell(mass: f64, [a, b, c]: Vec3) -> Vec3 {
    let (lx, ly, lz) = (2.0 * a, 2.0 * b, 2.0 * c);
    let (a0, a1, a2) = (lx * ly, ly * lz, lz * lx);
    let total = 2.0 * (a0 + a1 + a2);
    let (m0, m1, m2) = (mass * a0 / total, mass * a1 / total, mass * a2 / total);
    let ix = m0 * ly * ly / 12.0 + m1 * (ly * ly + lz * lz) / 12.0 + m2 * lz * lz / 12.0;
    let iy = m0 * lx * lx / 12.0 + m1 * lz * lz / 12.0 + m2 * (lx * lx + lz * lz) / 12.0;
    let iz = m0 * (lx * lx + ly * ly) / 12.0 + m1 * ly * ly / 12.0 + m2 * lx * lx / 12.0;
    [
        2.0 * (m0 * c * c + m2 * b * b + ix),
        2.0 * (m0 * c * c + m1 * a * a + iy),
        2.0 * (m1 * a * a + m2 * b * b + iz),
    ]
}

fn to_na(m: &Mat) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| m[r][c])
}

fn from_na(m: &Matrix3<f64>) -> Mat {
    [0, 1, 2].map(|r| [0, 1, 2].map(|c| m[(r, c)]))
}

impl MassProps {
    /// No mass at the origin.
    pub(crate) const NONE: MassProps = MassProps {
        mass: 0.0,
        com: [0.0; 3],
        inertia: [[0.0; 3]; 3],
    };

    /// A part whose inertia is `tensor` in the frame `rot` (columns: its axes in
    /// the body frame), centred at `pos`.
    pub(crate) fn rotated(mass: f64, pos: Vec3, rot: &Mat, tensor: Mat) -> Self {
        let r = to_na(rot);
        MassProps {
            mass,
            com: pos,
            inertia: from_na(&(r * to_na(&tensor) * r.transpose())),
        }
    }

    /// A part with principal moments `principal` along the axes `rot` (columns), centred at `pos`.
    pub(crate) fn placed(mass: f64, pos: Vec3, rot: &Mat, principal: Vec3) -> Self {
        let [a, b, c] = principal;
        MassProps::rotated(
            mass,
            pos,
            rot,
            [[a, 0.0, 0.0], [0.0, b, 0.0], [0.0, 0.0, c]],
        )
    }

    /// The parts as one body (MuJoCo: one part is copied; several are summed about
    /// their mass-weighted centre with the parallel-axis theorem). `None` for no part.
    pub(crate) fn combine(parts: &[MassProps]) -> Option<MassProps> {
        match parts {
            [] => None,
            [one] => Some(*one),
            _ => {
                let mass: f64 = parts.iter().map(|p| p.mass).sum();
                let mut com = Vector3::zeros();
                for p in parts {
                    com += p.mass * Vector3::from(p.com);
                }
                com /= mass;
                let mut total = Matrix3::zeros();
                for p in parts {
                    let d = Vector3::from(p.com) - com;
                    total += to_na(&p.inertia)
                        + p.mass * (Matrix3::identity() * d.dot(&d) - d * d.transpose());
                }
                Some(MassProps {
                    mass,
                    com: com.into(),
                    inertia: from_na(&total),
                })
            }
        }
    }

    /// MuJoCo's lower bounds and balancing: mass at least `bound_mass`, every
    /// principal moment at least `bound_inertia`, and, with `balance`, principal
    /// moments that violate the triangle inequality replaced by their mean.
    /// The tensor is rebuilt only when a moment changes.
    pub(crate) fn bounded(self, bound_mass: f64, bound_inertia: f64, balance: bool) -> Self {
        let mut out = self;
        out.mass = out.mass.max(bound_mass);
        if bound_inertia <= 0.0 && !balance {
            return out;
        }
        let eig = SymmetricEigen::new(to_na(&self.inertia));
        let mut moments = eig.eigenvalues.map(|v| v.max(bound_inertia));
        let (a, b, c) = (moments[0], moments[1], moments[2]);
        if balance && (a + b < c || a + c < b || b + c < a) {
            moments.fill((a + b + c) / 3.0);
        }
        if moments != eig.eigenvalues {
            let v = eig.eigenvectors;
            out.inertia = from_na(&(v * Matrix3::from_diagonal(&moments) * v.transpose()));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shell formulas integrate to the thin-shell limits: a hollow sphere's
    /// 2/3 m r^2, and a cube shell's 5/18 m a^2 (a the full edge).
    #[test]
    fn shells_match_textbook_limits() {
        let s = Solid::Sphere { radius: 0.3 }.principal_inertia(2.0, true);
        assert!((s[0] - 2.0 / 3.0 * 2.0 * 0.09).abs() < 1e-15);
        let b = Solid::Box { half: [0.5; 3] }.principal_inertia(6.0, true);
        assert!((b[0] - 5.0 / 18.0 * 6.0).abs() < 1e-14, "{b:?}");
    }

    /// A capsule of zero cylinder length is a sphere; of zero radius a rod.
    #[test]
    fn capsule_limits() {
        let c = Solid::Capsule {
            radius: 0.2,
            half: 0.0,
        }
        .principal_inertia(3.0, false);
        let s = Solid::Sphere { radius: 0.2 }.principal_inertia(3.0, false);
        for k in 0..3 {
            assert!((c[k] - s[k]).abs() < 1e-15);
        }
        let v = Solid::Capsule {
            radius: 0.2,
            half: 0.0,
        }
        .measure(false);
        assert!((v - Solid::Sphere { radius: 0.2 }.measure(false)).abs() < 1e-15);
    }

    /// Two point-like halves of a dumbbell: mass 2m, inertia 2 m d^2 across the bar.
    #[test]
    fn combine_is_parallel_axis() {
        let p = |x| {
            MassProps::placed(
                1.0,
                [x, 0.0, 0.0],
                &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                [0.0; 3],
            )
        };
        let c = MassProps::combine(&[p(-1.0), p(1.0)]).unwrap();
        assert_eq!(c.mass, 2.0);
        assert_eq!(c.com, [0.0; 3]);
        assert_eq!(c.inertia[1][1], 2.0);
        assert_eq!(c.inertia[0][0], 0.0);
    }

    #[test]
    fn balance_replaces_impossible_moments_by_their_mean() {
        let m = MassProps::placed(
            1.0,
            [0.0; 3],
            &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [1.0, 1.0, 3.0],
        );
        let b = m.bounded(0.0, 0.0, true);
        for k in 0..3 {
            assert!((b.inertia[k][k] - 5.0 / 3.0).abs() < 1e-14);
        }
        let kept = m.bounded(2.0, 0.5, false);
        assert_eq!(kept.mass, 2.0);
        assert_eq!(kept.inertia, m.inertia);
    }
}
