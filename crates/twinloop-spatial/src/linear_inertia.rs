use crate::{Force, Inertia, Motion};
use nalgebra::{Matrix3, Vector3};

/// A rigid-body inertia in the linear form: mass `m`, first moment `h = m c` and
/// rotational inertia `i` about the frame origin. It is linear in the body's
/// parameters, so the inertia of rigidly joined bodies is the plain sum of theirs
/// ([`LinearInertia::add`]), which is what a composite (CRBA) pass accumulates;
/// [`Inertia`] keeps the CoM form, whose sum needs a division.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearInertia {
    pub m: f64,
    pub h: Vector3<f64>,
    pub i: Matrix3<f64>,
}

impl Default for LinearInertia {
    fn default() -> Self {
        LinearInertia::ZERO
    }
}

impl LinearInertia {
    pub const ZERO: LinearInertia = LinearInertia {
        m: 0.0,
        h: Vector3::new(0.0, 0.0, 0.0),
        i: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    /// The linear form of a CoM-form inertia (same frame).
    #[inline(always)]
    pub fn from_inertia(y: &Inertia) -> Self {
        let c = y.com;
        let h = c * y.mass;
        let cc = c.dot(&c);
        let mut i = y.inertia;
        // Parallel-axis theorem: I_O = I_c + m (|c|^2 1 - c c^T).
        i[(0, 0)] += y.mass * cc - h.x * c.x;
        i[(1, 1)] += y.mass * cc - h.y * c.y;
        i[(2, 2)] += y.mass * cc - h.z * c.z;
        let (xy, xz, yz) = (h.x * c.y, h.x * c.z, h.y * c.z);
        i[(0, 1)] -= xy;
        i[(1, 0)] -= xy;
        i[(0, 2)] -= xz;
        i[(2, 0)] -= xz;
        i[(1, 2)] -= yz;
        i[(2, 1)] -= yz;
        LinearInertia { m: y.mass, h, i }
    }

    /// Join body `o` (expressed in the same frame) to this one.
    #[inline(always)]
    pub fn add(&mut self, o: &LinearInertia) {
        self.m += o.m;
        self.h += o.h;
        self.i += o.i;
    }

    /// `I * s`: the momentum of the body moving with `s`.
    #[inline(always)]
    pub fn mul_motion(&self, s: &Motion) -> Force {
        Force {
            f: s.v * self.m - self.h.cross(&s.w),
            n: self.h.cross(&s.v) + self.i * s.w,
        }
    }
}
