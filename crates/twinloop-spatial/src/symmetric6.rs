use crate::{Force, Motion};
use nalgebra::{Matrix3, Matrix6};
use std::ops::{AddAssign, SubAssign};

/// A symmetric 6x6 operator from motions to forces, `[[a, b], [b^T, c]]`, linear
/// block first: `f = a v + b w`, `n = b^T v + c w`. Used for articulated-body
/// inertias, which are not rigid and need the full form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Symmetric6 {
    pub a: Matrix3<f64>,
    pub b: Matrix3<f64>,
    pub c: Matrix3<f64>,
}

impl Default for Symmetric6 {
    fn default() -> Self {
        Symmetric6::ZERO
    }
}

impl Symmetric6 {
    pub const ZERO: Symmetric6 = Symmetric6 {
        a: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        b: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        c: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    #[inline(always)]
    pub fn mul_motion(&self, m: &Motion) -> Force {
        Force {
            f: self.a * m.v + self.b * m.w,
            n: self.b.tr_mul(&m.v) + self.c * m.w,
        }
    }

    /// `self -= u u^T / d` for a force-valued column `u` (the articulated-inertia
    /// update of a 1-DoF joint).
    #[inline(always)]
    pub fn sub_rank1(&mut self, u: &Force, inv_d: f64) {
        let fs = u.f * inv_d;
        let ns = u.n * inv_d;
        self.a -= fs * u.f.transpose();
        self.b -= fs * u.n.transpose();
        self.c -= ns * u.n.transpose();
    }

    pub fn to_matrix6(&self) -> Matrix6<f64> {
        let mut m = Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.a);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.b);
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.b.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.c);
        m
    }
}

impl AddAssign for Symmetric6 {
    #[inline(always)]
    fn add_assign(&mut self, o: Symmetric6) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }
}

impl SubAssign for Symmetric6 {
    #[inline(always)]
    fn sub_assign(&mut self, o: Symmetric6) {
        self.a -= o.a;
        self.b -= o.b;
        self.c -= o.c;
    }
}
