use crate::{Force, Motion, Se3, Symmetric6, skew};
use nalgebra::{Matrix3, Vector3};
use std::ops::{Add, AddAssign};

/// Rigid-body spatial inertia in compact form: `mass`, centre of mass `com` and the
/// rotational inertia `inertia` about the CoM, all in the body's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertia {
    pub mass: f64,
    pub com: Vector3<f64>,
    pub inertia: Matrix3<f64>,
}

impl Default for Inertia {
    fn default() -> Self {
        Inertia::ZERO
    }
}

impl Inertia {
    pub const ZERO: Inertia = Inertia {
        mass: 0.0,
        com: Vector3::new(0.0, 0.0, 0.0),
        inertia: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    pub fn new(mass: f64, com: Vector3<f64>, inertia: Matrix3<f64>) -> Self {
        Inertia { mass, com, inertia }
    }

    /// `I * m`: the momentum of a body moving with `m`.
    #[inline(always)]
    pub fn mul_motion(&self, m: &Motion) -> Force {
        // Velocity of the CoM, then momentum about the origin.
        let f = (m.v - self.com.cross(&m.w)) * self.mass;
        Force {
            f,
            n: self.inertia * m.w + self.com.cross(&f),
        }
    }

    /// This inertia (given in frame b) expressed in frame a, where `x = aMb`.
    #[inline(always)]
    pub fn transformed(&self, x: &Se3) -> Inertia {
        Inertia {
            mass: self.mass,
            com: x.act_point(&self.com),
            inertia: x.rotation * self.inertia * x.rotation.transpose(),
        }
    }

    /// The 6x6 operator.
    #[inline(always)]
    pub fn to_symmetric6(&self) -> Symmetric6 {
        let m = self.mass;
        let c = self.com;
        let mc = c * m;
        // -m [c]x [c]x = m (|c|^2 I - c c^T)
        let cc = c.dot(&c);
        let parallel = Matrix3::new(
            m * cc - mc.x * c.x,
            -mc.x * c.y,
            -mc.x * c.z,
            -mc.y * c.x,
            m * cc - mc.y * c.y,
            -mc.y * c.z,
            -mc.z * c.x,
            -mc.z * c.y,
            m * cc - mc.z * c.z,
        );
        Symmetric6 {
            a: Matrix3::from_diagonal_element(m),
            b: -skew(&mc),
            c: self.inertia + parallel,
        }
    }

    /// Rotational inertia about the frame origin (parallel-axis theorem).
    pub fn inertia_about_origin(&self) -> Matrix3<f64> {
        let c = self.com;
        self.inertia + (Matrix3::from_diagonal_element(c.dot(&c)) - c * c.transpose()) * self.mass
    }

    /// The 10 dynamic parameters, Pinocchio's order: m, m c (3), then the inertia
    /// about the frame origin as Ixx, Ixy, Iyy, Ixz, Iyz, Izz.
    pub fn dynamic_parameters(&self) -> [f64; 10] {
        let i = self.inertia_about_origin();
        let h = self.com * self.mass;
        [
            self.mass,
            h.x,
            h.y,
            h.z,
            i[(0, 0)],
            i[(0, 1)],
            i[(1, 1)],
            i[(0, 2)],
            i[(1, 2)],
            i[(2, 2)],
        ]
    }

    /// Inverse of [`Inertia::dynamic_parameters`]. A zero mass gives a zero CoM.
    pub fn from_dynamic_parameters(p: &[f64; 10]) -> Inertia {
        let mass = p[0];
        let com = if mass != 0.0 {
            Vector3::new(p[1], p[2], p[3]) / mass
        } else {
            Vector3::zeros()
        };
        let io = Matrix3::new(p[4], p[5], p[7], p[5], p[6], p[8], p[7], p[8], p[9]);
        let inertia =
            io - (Matrix3::from_diagonal_element(com.dot(&com)) - com * com.transpose()) * mass;
        Inertia { mass, com, inertia }
    }
}

impl Add for Inertia {
    type Output = Inertia;
    /// Two bodies rigidly joined, both expressed in the same frame.
    fn add(self, o: Inertia) -> Inertia {
        let mass = self.mass + o.mass;
        if mass == 0.0 {
            return Inertia {
                mass,
                com: Vector3::zeros(),
                inertia: self.inertia + o.inertia,
            };
        }
        let com = (self.com * self.mass + o.com * o.mass) / mass;
        let d1 = self.com - com;
        let d2 = o.com - com;
        let shift = |d: Vector3<f64>, m: f64| {
            (Matrix3::from_diagonal_element(d.dot(&d)) - d * d.transpose()) * m
        };
        Inertia {
            mass,
            com,
            inertia: self.inertia + o.inertia + shift(d1, self.mass) + shift(d2, o.mass),
        }
    }
}

impl AddAssign for Inertia {
    fn add_assign(&mut self, o: Inertia) {
        *self = *self + o;
    }
}
