use nalgebra::{Vector3, Vector6};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// Spatial force (wrench): force `f` and moment `n` about the frame origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Force {
    pub f: Vector3<f64>,
    pub n: Vector3<f64>,
}

impl Default for Force {
    fn default() -> Self {
        Force::ZERO
    }
}

impl Force {
    pub const ZERO: Force = Force {
        f: Vector3::new(0.0, 0.0, 0.0),
        n: Vector3::new(0.0, 0.0, 0.0),
    };

    #[inline(always)]
    pub fn new(f: Vector3<f64>, n: Vector3<f64>) -> Self {
        Force { f, n }
    }

    #[inline]
    pub fn from_slice(x: &[f64]) -> Self {
        Force {
            f: Vector3::new(x[0], x[1], x[2]),
            n: Vector3::new(x[3], x[4], x[5]),
        }
    }

    #[inline]
    pub fn to_vector6(&self) -> Vector6<f64> {
        Vector6::new(self.f.x, self.f.y, self.f.z, self.n.x, self.n.y, self.n.z)
    }

    #[inline]
    pub fn write_to(&self, out: &mut [f64]) {
        out[0] = self.f.x;
        out[1] = self.f.y;
        out[2] = self.f.z;
        out[3] = self.n.x;
        out[4] = self.n.y;
        out[5] = self.n.z;
    }
}

impl Add for Force {
    type Output = Force;
    #[inline(always)]
    fn add(self, o: Force) -> Force {
        Force {
            f: self.f + o.f,
            n: self.n + o.n,
        }
    }
}

impl Sub for Force {
    type Output = Force;
    #[inline(always)]
    fn sub(self, o: Force) -> Force {
        Force {
            f: self.f - o.f,
            n: self.n - o.n,
        }
    }
}

impl AddAssign for Force {
    #[inline(always)]
    fn add_assign(&mut self, o: Force) {
        self.f += o.f;
        self.n += o.n;
    }
}

impl SubAssign for Force {
    #[inline(always)]
    fn sub_assign(&mut self, o: Force) {
        self.f -= o.f;
        self.n -= o.n;
    }
}

impl Mul<f64> for Force {
    type Output = Force;
    #[inline(always)]
    fn mul(self, s: f64) -> Force {
        Force {
            f: self.f * s,
            n: self.n * s,
        }
    }
}

impl Neg for Force {
    type Output = Force;
    #[inline(always)]
    fn neg(self) -> Force {
        Force {
            f: -self.f,
            n: -self.n,
        }
    }
}
