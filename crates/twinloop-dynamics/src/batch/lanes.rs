//! Lanes: the same scalar of `LANES` instances side by side (structure of arrays),
//! and the spatial types of twinloop-spatial built from them. Every operation is a
//! plain loop over the lanes, which LLVM turns into one vector instruction per
//! operation (AVX2: 4 doubles), and each lane does exactly the scalar code's
//! operations in the scalar code's order (nalgebra's for its products: a matrix
//! times a vector sums its columns in order, a 3-vector dot product is
//! `(a0 b0 + a1 b1) + a2 b2`), so a lane's result is the single call's bit for bit.
//! Rust never fuses a multiply and an add on its own, so enabling FMA keeps that.

use nalgebra::{Matrix3, Vector3};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};
use twinloop_spatial::{Inertia, LinearInertia, Se3};

/// Instances per lane group: four doubles fill an AVX2 register.
pub const LANES: usize = 4;

/// One scalar of `LANES` instances.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub struct W(pub [f64; LANES]);

impl W {
    pub const ZERO: W = W([0.0; LANES]);

    #[inline(always)]
    pub fn splat(x: f64) -> W {
        W([x; LANES])
    }

    #[inline(always)]
    pub fn sqrt(self) -> W {
        let mut r = self.0;
        for x in &mut r {
            *x = x.sqrt();
        }
        W(r)
    }
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $tra:ident, $fa:ident, $op:tt) => {
        impl $tr for W {
            type Output = W;
            #[inline(always)]
            fn $f(self, o: W) -> W {
                let mut r = self.0;
                for l in 0..LANES {
                    r[l] = self.0[l] $op o.0[l];
                }
                W(r)
            }
        }
        impl $tr<f64> for W {
            type Output = W;
            #[inline(always)]
            fn $f(self, o: f64) -> W {
                self $op W::splat(o)
            }
        }
        impl $tr<W> for f64 {
            type Output = W;
            #[inline(always)]
            fn $f(self, o: W) -> W {
                W::splat(self) $op o
            }
        }
        impl $tra for W {
            #[inline(always)]
            fn $fa(&mut self, o: W) {
                *self = *self $op o;
            }
        }
    };
}
lane_op!(Add, add, AddAssign, add_assign, +);
lane_op!(Sub, sub, SubAssign, sub_assign, -);
lane_op!(Mul, mul, MulAssign, mul_assign, *);
lane_op!(Div, div, DivAssign, div_assign, /);

impl Neg for W {
    type Output = W;
    #[inline(always)]
    fn neg(self) -> W {
        let mut r = self.0;
        for x in &mut r {
            *x = -*x;
        }
        W(r)
    }
}

/// A 3-vector of lanes.
#[derive(Debug, Clone, Copy)]
pub struct V3 {
    pub x: W,
    pub y: W,
    pub z: W,
}

impl V3 {
    pub const ZERO: V3 = V3 {
        x: W::ZERO,
        y: W::ZERO,
        z: W::ZERO,
    };

    #[inline(always)]
    pub fn new(x: W, y: W, z: W) -> V3 {
        V3 { x, y, z }
    }

    #[inline(always)]
    pub fn splat(v: &Vector3<f64>) -> V3 {
        V3::new(W::splat(v.x), W::splat(v.y), W::splat(v.z))
    }

    #[inline(always)]
    pub fn from_lanes(x: &[W]) -> V3 {
        V3::new(x[0], x[1], x[2])
    }

    #[inline(always)]
    pub fn get(&self, k: usize) -> W {
        [self.x, self.y, self.z][k]
    }

    /// nalgebra's cross product, term for term.
    #[inline(always)]
    pub fn cross(&self, b: &V3) -> V3 {
        V3::new(
            self.y * b.z - self.z * b.y,
            self.z * b.x - self.x * b.z,
            self.x * b.y - self.y * b.x,
        )
    }

    #[inline(always)]
    pub fn dot(&self, b: &V3) -> W {
        self.x * b.x + self.y * b.y + self.z * b.z
    }

    #[inline(always)]
    pub fn scale(&self, s: W) -> V3 {
        V3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Neg for V3 {
    type Output = V3;
    #[inline(always)]
    fn neg(self) -> V3 {
        V3::new(-self.x, -self.y, -self.z)
    }
}

impl AddAssign for V3 {
    #[inline(always)]
    fn add_assign(&mut self, o: V3) {
        *self = *self + o;
    }
}

/// A 3 x 3 matrix of lanes, `m[row][column]`.
#[derive(Debug, Clone, Copy)]
pub struct M3 {
    pub m: [[W; 3]; 3],
}

impl M3 {
    pub const ZERO: M3 = M3 {
        m: [[W::ZERO; 3]; 3],
    };

    #[inline(always)]
    pub fn splat(a: &Matrix3<f64>) -> M3 {
        let mut m = [[W::ZERO; 3]; 3];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = W::splat(a[(r, c)]);
            }
        }
        M3 { m }
    }

    #[inline(always)]
    pub fn from_columns(c: &[V3; 3]) -> M3 {
        let mut m = [[W::ZERO; 3]; 3];
        for (k, col) in c.iter().enumerate() {
            m[0][k] = col.x;
            m[1][k] = col.y;
            m[2][k] = col.z;
        }
        M3 { m }
    }

    #[inline(always)]
    pub fn column(&self, c: usize) -> V3 {
        V3::new(self.m[0][c], self.m[1][c], self.m[2][c])
    }

    #[inline(always)]
    pub fn transpose(&self) -> M3 {
        let mut m = self.m;
        for (r, row) in m.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = self.m[c][r];
            }
        }
        M3 { m }
    }

    /// `self * v`: the columns times v's entries, summed in order.
    #[inline(always)]
    pub fn mul_v(&self, v: &V3) -> V3 {
        let m = &self.m;
        V3::new(
            m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
        )
    }

    /// `self^T * v`: each column's dot product with v.
    #[inline(always)]
    pub fn tr_mul_v(&self, v: &V3) -> V3 {
        V3::new(
            self.column(0).dot(v),
            self.column(1).dot(v),
            self.column(2).dot(v),
        )
    }

    #[inline(always)]
    pub fn mul_m(&self, b: &M3) -> M3 {
        M3::from_columns(&[
            self.mul_v(&b.column(0)),
            self.mul_v(&b.column(1)),
            self.mul_v(&b.column(2)),
        ])
    }

    #[inline(always)]
    pub fn zip(&self, b: &M3, f: impl Fn(W, W) -> W) -> M3 {
        let mut m = self.m;
        for (r, row) in m.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = f(self.m[r][c], b.m[r][c]);
            }
        }
        M3 { m }
    }

    /// `self - u w^T`.
    #[inline(always)]
    pub fn sub_outer(&self, u: &V3, w: &V3) -> M3 {
        let mut m = self.m;
        for (r, row) in m.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x -= u.get(r) * w.get(c);
            }
        }
        M3 { m }
    }
}

/// Motion of lanes (linear part first).
#[derive(Debug, Clone, Copy)]
pub struct Mo {
    pub v: V3,
    pub w: V3,
}

/// Force of lanes (force, then moment).
#[derive(Debug, Clone, Copy)]
pub struct Fo {
    pub f: V3,
    pub n: V3,
}

impl Mo {
    pub const ZERO: Mo = Mo {
        v: V3::ZERO,
        w: V3::ZERO,
    };

    #[inline(always)]
    pub fn from_lanes(x: &[W]) -> Mo {
        Mo {
            v: V3::from_lanes(&x[0..3]),
            w: V3::from_lanes(&x[3..6]),
        }
    }

    #[inline(always)]
    pub fn cross(&self, m: &Mo) -> Mo {
        Mo {
            v: self.w.cross(&m.v) + self.v.cross(&m.w),
            w: self.w.cross(&m.w),
        }
    }

    #[inline(always)]
    pub fn cross_force(&self, f: &Fo) -> Fo {
        Fo {
            f: self.w.cross(&f.f),
            n: self.w.cross(&f.n) + self.v.cross(&f.f),
        }
    }

    #[inline(always)]
    pub fn dot(&self, f: &Fo) -> W {
        self.v.dot(&f.f) + self.w.dot(&f.n)
    }

    #[inline(always)]
    pub fn scale(&self, s: W) -> Mo {
        Mo {
            v: self.v.scale(s),
            w: self.w.scale(s),
        }
    }

    #[inline(always)]
    pub fn add(&self, o: &Mo) -> Mo {
        Mo {
            v: self.v + o.v,
            w: self.w + o.w,
        }
    }
}

impl Fo {
    pub const ZERO: Fo = Fo {
        f: V3::ZERO,
        n: V3::ZERO,
    };

    #[inline(always)]
    pub fn from_lanes(x: &[W]) -> Fo {
        Fo {
            f: V3::from_lanes(&x[0..3]),
            n: V3::from_lanes(&x[3..6]),
        }
    }

    #[inline(always)]
    pub fn scale(&self, s: W) -> Fo {
        Fo {
            f: self.f.scale(s),
            n: self.n.scale(s),
        }
    }

    #[inline(always)]
    pub fn add(&self, o: &Fo) -> Fo {
        Fo {
            f: self.f + o.f,
            n: self.n + o.n,
        }
    }

    #[inline(always)]
    pub fn sub(&self, o: &Fo) -> Fo {
        Fo {
            f: self.f - o.f,
            n: self.n - o.n,
        }
    }

    #[inline(always)]
    pub fn lanes(&self) -> [W; 6] {
        [self.f.x, self.f.y, self.f.z, self.n.x, self.n.y, self.n.z]
    }
}

/// Rigid placement of lanes.
#[derive(Debug, Clone, Copy)]
pub struct X {
    pub r: M3,
    pub t: V3,
}

impl X {
    #[inline(always)]
    pub fn splat(x: &Se3) -> X {
        X {
            r: M3::splat(&x.rotation),
            t: V3::splat(&x.translation),
        }
    }

    #[inline(always)]
    pub fn act_point(&self, p: &V3) -> V3 {
        self.r.mul_v(p) + self.t
    }

    #[inline(always)]
    pub fn act_inv_motion(&self, m: &Mo) -> Mo {
        Mo {
            v: self.r.tr_mul_v(&(m.v - self.t.cross(&m.w))),
            w: self.r.tr_mul_v(&m.w),
        }
    }

    #[inline(always)]
    pub fn act_force(&self, f: &Fo) -> Fo {
        let ff = self.r.mul_v(&f.f);
        Fo {
            f: ff,
            n: self.r.mul_v(&f.n) + self.t.cross(&ff),
        }
    }
}

/// Rigid-body inertia of lanes in CoM form (twinloop_spatial::Inertia).
#[derive(Debug, Clone, Copy)]
pub struct In {
    pub mass: W,
    pub com: V3,
    pub inertia: M3,
}

impl In {
    #[inline(always)]
    pub fn splat(y: &Inertia) -> In {
        In {
            mass: W::splat(y.mass),
            com: V3::splat(&y.com),
            inertia: M3::splat(&y.inertia),
        }
    }

    #[inline(always)]
    pub fn mul_motion(&self, m: &Mo) -> Fo {
        let f = (m.v - self.com.cross(&m.w)).scale(self.mass);
        Fo {
            f,
            n: self.inertia.mul_v(&m.w) + self.com.cross(&f),
        }
    }

    #[inline(always)]
    pub fn transformed(&self, x: &X) -> In {
        In {
            mass: self.mass,
            com: x.act_point(&self.com),
            inertia: x.r.mul_m(&self.inertia).mul_m(&x.r.transpose()),
        }
    }

    /// The 6 x 6 operator, as `Inertia::to_symmetric6`.
    #[inline(always)]
    pub fn to_sym6(&self) -> S6 {
        let m = self.mass;
        let c = self.com;
        let mc = c.scale(m);
        let cc = c.dot(&c);
        let z = W::ZERO;
        let parallel = M3 {
            m: [
                [m * cc - mc.x * c.x, -mc.x * c.y, -mc.x * c.z],
                [-mc.y * c.x, m * cc - mc.y * c.y, -mc.y * c.z],
                [-mc.z * c.x, -mc.z * c.y, m * cc - mc.z * c.z],
            ],
        };
        // -skew(mc), negated entry by entry like nalgebra's (its zeros become -0).
        let b = M3 {
            m: [[-z, mc.z, -mc.y], [-mc.z, -z, mc.x], [mc.y, -mc.x, -z]],
        };
        S6 {
            a: M3 {
                m: [[m, z, z], [z, m, z], [z, z, m]],
            },
            b,
            c: self.inertia.zip(&parallel, |p, q| p + q),
        }
    }
}

/// Symmetric 6 x 6 operator of lanes (twinloop_spatial::Symmetric6).
#[derive(Debug, Clone, Copy)]
pub struct S6 {
    pub a: M3,
    pub b: M3,
    pub c: M3,
}

impl S6 {
    pub const ZERO: S6 = S6 {
        a: M3::ZERO,
        b: M3::ZERO,
        c: M3::ZERO,
    };

    #[inline(always)]
    pub fn mul_motion(&self, m: &Mo) -> Fo {
        Fo {
            f: self.a.mul_v(&m.v) + self.b.mul_v(&m.w),
            n: self.b.tr_mul_v(&m.v) + self.c.mul_v(&m.w),
        }
    }

    #[inline(always)]
    pub fn sub_rank1(&mut self, u: &Fo, inv_d: W) {
        let fs = u.f.scale(inv_d);
        let ns = u.n.scale(inv_d);
        self.a = self.a.sub_outer(&fs, &u.f);
        self.b = self.b.sub_outer(&fs, &u.n);
        self.c = self.c.sub_outer(&ns, &u.n);
    }

    #[inline(always)]
    pub fn add_assign(&mut self, o: &S6) {
        self.a = self.a.zip(&o.a, |p, q| p + q);
        self.b = self.b.zip(&o.b, |p, q| p + q);
        self.c = self.c.zip(&o.c, |p, q| p + q);
    }

    /// The full matrix `[[a, b], [b^T, c]]`, `m[row][column]`.
    #[inline(always)]
    pub fn to_matrix6(&self) -> [[W; 6]; 6] {
        let mut m = [[W::ZERO; 6]; 6];
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] = self.a.m[r][c];
                m[r][c + 3] = self.b.m[r][c];
                m[r + 3][c] = self.b.m[c][r];
                m[r + 3][c + 3] = self.c.m[r][c];
            }
        }
        m
    }
}

/// Rigid-body inertia of lanes in linear form (twinloop_spatial::LinearInertia).
#[derive(Debug, Clone, Copy)]
pub struct Li {
    pub m: W,
    pub h: V3,
    pub i: M3,
}

impl Li {
    pub const ZERO: Li = Li {
        m: W::ZERO,
        h: V3::ZERO,
        i: M3::ZERO,
    };

    #[inline(always)]
    pub fn splat(y: &LinearInertia) -> Li {
        Li {
            m: W::splat(y.m),
            h: V3::splat(&y.h),
            i: M3::splat(&y.i),
        }
    }

    /// As `LinearInertia::from_inertia`.
    #[inline(always)]
    pub fn from_inertia(y: &In) -> Li {
        let c = y.com;
        let h = c.scale(y.mass);
        let cc = c.dot(&c);
        let mut i = y.inertia.m;
        i[0][0] += y.mass * cc - h.x * c.x;
        i[1][1] += y.mass * cc - h.y * c.y;
        i[2][2] += y.mass * cc - h.z * c.z;
        let (xy, xz, yz) = (h.x * c.y, h.x * c.z, h.y * c.z);
        i[0][1] -= xy;
        i[1][0] -= xy;
        i[0][2] -= xz;
        i[2][0] -= xz;
        i[1][2] -= yz;
        i[2][1] -= yz;
        Li {
            m: y.mass,
            h,
            i: M3 { m: i },
        }
    }

    #[inline(always)]
    pub fn add(&mut self, o: &Li) {
        self.m += o.m;
        self.h += o.h;
        self.i = self.i.zip(&o.i, |p, q| p + q);
    }

    #[inline(always)]
    pub fn mul_motion(&self, s: &Mo) -> Fo {
        Fo {
            f: s.v.scale(self.m) - self.h.cross(&s.w),
            n: self.h.cross(&s.v) + self.i.mul_v(&s.w),
        }
    }
}
