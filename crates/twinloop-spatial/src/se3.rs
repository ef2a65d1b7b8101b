use crate::{Force, Motion};
use nalgebra::{Matrix3, Vector3};
use std::ops::Mul;

/// Rigid placement `aMb`: `rotation` maps b-coordinates to a-coordinates and
/// `translation` is the origin of b in a. A point: `p_a = R p_b + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Se3 {
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
}

impl Default for Se3 {
    fn default() -> Self {
        Se3::IDENTITY
    }
}

impl Se3 {
    pub const IDENTITY: Se3 = Se3 {
        rotation: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        translation: Vector3::new(0.0, 0.0, 0.0),
    };

    #[inline(always)]
    pub fn new(rotation: Matrix3<f64>, translation: Vector3<f64>) -> Self {
        Se3 {
            rotation,
            translation,
        }
    }

    #[inline]
    pub fn inverse(&self) -> Se3 {
        let rt = self.rotation.transpose();
        Se3 {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    /// Point in b mapped to a.
    #[inline(always)]
    pub fn act_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * p + self.translation
    }

    /// Point in a mapped to b.
    #[inline(always)]
    pub fn act_inv_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation.tr_mul(&(p - self.translation))
    }

    /// Motion expressed in b, re-expressed in a.
    #[inline(always)]
    pub fn act_motion(&self, m: &Motion) -> Motion {
        let w = self.rotation * m.w;
        Motion {
            v: self.rotation * m.v + self.translation.cross(&w),
            w,
        }
    }

    /// Motion expressed in a, re-expressed in b.
    #[inline(always)]
    pub fn act_inv_motion(&self, m: &Motion) -> Motion {
        Motion {
            v: self.rotation.tr_mul(&(m.v - self.translation.cross(&m.w))),
            w: self.rotation.tr_mul(&m.w),
        }
    }

    /// Force expressed in b, re-expressed in a.
    #[inline(always)]
    pub fn act_force(&self, f: &Force) -> Force {
        let ff = self.rotation * f.f;
        Force {
            f: ff,
            n: self.rotation * f.n + self.translation.cross(&ff),
        }
    }

    /// Force expressed in a, re-expressed in b.
    #[inline(always)]
    pub fn act_inv_force(&self, f: &Force) -> Force {
        Force {
            f: self.rotation.tr_mul(&f.f),
            n: self.rotation.tr_mul(&(f.n - self.translation.cross(&f.f))),
        }
    }

    /// Relative placement `self^-1 * other`.
    #[inline]
    pub fn inv_mul(&self, other: &Se3) -> Se3 {
        Se3 {
            rotation: self.rotation.tr_mul(&other.rotation),
            translation: self
                .rotation
                .tr_mul(&(other.translation - self.translation)),
        }
    }
}

impl Mul for Se3 {
    type Output = Se3;
    #[inline(always)]
    fn mul(self, b: Se3) -> Se3 {
        Se3 {
            rotation: self.rotation * b.rotation,
            translation: self.rotation * b.translation + self.translation,
        }
    }
}

impl Mul<&Se3> for &Se3 {
    type Output = Se3;
    #[inline(always)]
    fn mul(self, b: &Se3) -> Se3 {
        Se3 {
            rotation: self.rotation * b.rotation,
            translation: self.rotation * b.translation + self.translation,
        }
    }
}
