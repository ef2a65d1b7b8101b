use crate::Force;
use nalgebra::{Vector3, Vector6};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// Spatial motion (twist or spatial acceleration): linear part `v` (velocity of the
/// point at the frame origin), angular part `w`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    pub v: Vector3<f64>,
    pub w: Vector3<f64>,
}

impl Default for Motion {
    fn default() -> Self {
        Motion::ZERO
    }
}

impl Motion {
    pub const ZERO: Motion = Motion {
        v: Vector3::new(0.0, 0.0, 0.0),
        w: Vector3::new(0.0, 0.0, 0.0),
    };

    #[inline(always)]
    pub fn new(v: Vector3<f64>, w: Vector3<f64>) -> Self {
        Motion { v, w }
    }

    #[inline]
    pub fn from_vector6(x: &Vector6<f64>) -> Self {
        Motion {
            v: Vector3::new(x[0], x[1], x[2]),
            w: Vector3::new(x[3], x[4], x[5]),
        }
    }

    #[inline]
    pub fn from_slice(x: &[f64]) -> Self {
        Motion {
            v: Vector3::new(x[0], x[1], x[2]),
            w: Vector3::new(x[3], x[4], x[5]),
        }
    }

    #[inline]
    pub fn to_vector6(&self) -> Vector6<f64> {
        Vector6::new(self.v.x, self.v.y, self.v.z, self.w.x, self.w.y, self.w.z)
    }

    /// Motion cross product `self x m` (Featherstone's crm).
    #[inline(always)]
    pub fn cross(&self, m: &Motion) -> Motion {
        Motion {
            v: self.w.cross(&m.v) + self.v.cross(&m.w),
            w: self.w.cross(&m.w),
        }
    }

    /// Force cross product `self x* f` (Featherstone's crf).
    #[inline(always)]
    pub fn cross_force(&self, f: &Force) -> Force {
        Force {
            f: self.w.cross(&f.f),
            n: self.w.cross(&f.n) + self.v.cross(&f.f),
        }
    }

    /// Power pairing `m . f`.
    #[inline(always)]
    pub fn dot(&self, f: &Force) -> f64 {
        self.v.dot(&f.f) + self.w.dot(&f.n)
    }
}

impl Add for Motion {
    type Output = Motion;
    #[inline(always)]
    fn add(self, o: Motion) -> Motion {
        Motion {
            v: self.v + o.v,
            w: self.w + o.w,
        }
    }
}

impl Sub for Motion {
    type Output = Motion;
    #[inline(always)]
    fn sub(self, o: Motion) -> Motion {
        Motion {
            v: self.v - o.v,
            w: self.w - o.w,
        }
    }
}

impl AddAssign for Motion {
    #[inline(always)]
    fn add_assign(&mut self, o: Motion) {
        self.v += o.v;
        self.w += o.w;
    }
}

impl SubAssign for Motion {
    #[inline(always)]
    fn sub_assign(&mut self, o: Motion) {
        self.v -= o.v;
        self.w -= o.w;
    }
}

impl Mul<f64> for Motion {
    type Output = Motion;
    #[inline(always)]
    fn mul(self, s: f64) -> Motion {
        Motion {
            v: self.v * s,
            w: self.w * s,
        }
    }
}

impl Neg for Motion {
    type Output = Motion;
    #[inline(always)]
    fn neg(self) -> Motion {
        Motion {
            v: -self.v,
            w: -self.w,
        }
    }
}
