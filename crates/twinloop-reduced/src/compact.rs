//! The compact compliant CoM model in x and z (seed 002, eq 9-11, 14-17).
//!
//! A single mass at the CoM hangs on the Cartesian spring-damper of the support leg(s)
//! (eq 9-10) and gravity. In the sagittal plane (eq 11), with the eight correction
//! factors of eq 14-15 in single support and the double-support scalings eta1, eta2 of
//! eq 16-17:
//!
//! ```text
//! x'' = eta1 (-a1 Kxx/m (x - xr) - b1 Kxz/m (z - zr) - g1 Dxx/m x' - e1 Dxz/m z')
//! z'' = -g + eta2 (-a2 Kzx/m (x - xr) - b2 Kzz/m (z - zr) - g2 Dzx/m x' - e2 Dzz/m z')
//! ```
//!
//! with eta1 = eta2 = 1 in single support. [`CompactModel::rollout`] integrates it over a
//! sampled reference by classical Runge-Kutta (the reference linearly interpolated
//! inside each sample interval, the phase that of the interval's first sample), from the
//! given initial position at rest.

use crate::error::{ReducedError, err};

/// m, g and the sagittal entries of K_C and D_C (seed 002, eq 11).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[allow(non_snake_case)]
pub struct SagittalCompliance {
    pub m: f64,
    pub g: f64,
    pub Kxx: f64,
    pub Kxz: f64,
    pub Kzx: f64,
    pub Kzz: f64,
    pub Dxx: f64,
    pub Dxz: f64,
    pub Dzx: f64,
    pub Dzz: f64,
}

impl SagittalCompliance {
    /// The plant of eq 11 from the x-z blocks of K_C and D_C (seed 002, eq 7-8), rows
    /// and columns in the order (x, z).
    pub fn from_xz(
        m: f64,
        g: f64,
        stiffness: &nalgebra::Matrix2<f64>,
        damping: &nalgebra::Matrix2<f64>,
    ) -> SagittalCompliance {
        let (k, d) = (stiffness, damping);
        SagittalCompliance {
            m,
            g,
            Kxx: k[(0, 0)],
            Kxz: k[(0, 1)],
            Kzx: k[(1, 0)],
            Kzz: k[(1, 1)],
            Dxx: d[(0, 0)],
            Dxz: d[(0, 1)],
            Dzx: d[(1, 0)],
            Dzz: d[(1, 1)],
        }
    }

    /// Checks the entries; the error names the one at fault.
    pub fn validate(&self) -> Result<(), ReducedError> {
        for (name, v) in [
            ("mass m", self.m),
            ("stiffness Kxx", self.Kxx),
            ("stiffness Kzz", self.Kzz),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return err(format!("{name} must be positive and finite, got {v}"));
            }
        }
        for (name, v) in [("damping Dxx", self.Dxx), ("damping Dzz", self.Dzz)] {
            if !(v.is_finite() && v >= 0.0) {
                return err(format!("{name} must be non-negative and finite, got {v}"));
            }
        }
        for (name, v) in [
            ("gravity g", self.g),
            ("stiffness Kxz", self.Kxz),
            ("stiffness Kzx", self.Kzx),
            ("damping Dxz", self.Dxz),
            ("damping Dzx", self.Dzx),
        ] {
            if !v.is_finite() {
                return err(format!("{name} must be finite, got {v}"));
            }
        }
        Ok(())
    }
}

/// The correction factors of eq 14-15 and the double-support scalings of eq 16-17.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Corrections {
    pub alpha1: f64,
    pub beta1: f64,
    pub gamma1: f64,
    pub epsilon1: f64,
    pub alpha2: f64,
    pub beta2: f64,
    pub gamma2: f64,
    pub epsilon2: f64,
    pub eta1: f64,
    pub eta2: f64,
}

impl Default for Corrections {
    /// All ones: the uncorrected model of eq 11.
    fn default() -> Self {
        Corrections::from_slice(&[1.0; 10])
    }
}

impl Corrections {
    /// Table 1 of seed 002 (eta1 = eta2 = 1: the seed does not list them).
    pub fn seed_table1() -> Corrections {
        Corrections::from_slice(&[
            0.9827, 1.0357, 1.0560, 1.1335, 0.9792, 0.9561, 1.0072, 1.1053, 1.0, 1.0,
        ])
    }

    /// In the order alpha1, beta1, gamma1, epsilon1, alpha2, beta2, gamma2, epsilon2, eta1, eta2.
    pub fn from_slice(p: &[f64; 10]) -> Corrections {
        Corrections {
            alpha1: p[0],
            beta1: p[1],
            gamma1: p[2],
            epsilon1: p[3],
            alpha2: p[4],
            beta2: p[5],
            gamma2: p[6],
            epsilon2: p[7],
            eta1: p[8],
            eta2: p[9],
        }
    }

    pub fn to_array(&self) -> [f64; 10] {
        [
            self.alpha1,
            self.beta1,
            self.gamma1,
            self.epsilon1,
            self.alpha2,
            self.beta2,
            self.gamma2,
            self.epsilon2,
            self.eta1,
            self.eta2,
        ]
    }
}

/// A reference sampled in time: CoM reference xr, zr and the phase (false single, true
/// double support).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SagittalReference {
    pub t: Vec<f64>,
    pub xr: Vec<f64>,
    pub zr: Vec<f64>,
    pub double_support: Vec<bool>,
}

impl SagittalReference {
    /// Checks lengths, finiteness and strictly increasing time; the error names the row.
    pub fn validate(&self) -> Result<(), ReducedError> {
        let n = self.t.len();
        if n < 2 {
            return err(format!("the reference needs at least 2 rows, has {n}"));
        }
        if self.xr.len() != n || self.zr.len() != n || self.double_support.len() != n {
            return err("the reference columns t, xr, zr, phase differ in length");
        }
        for i in 0..n {
            for (name, v) in [("t", self.t[i]), ("xr", self.xr[i]), ("zr", self.zr[i])] {
                if !v.is_finite() {
                    return err(format!(
                        "reference row {}: {name} is not finite ({v})",
                        i + 1
                    ));
                }
            }
            if i > 0 && self.t[i] <= self.t[i - 1] {
                return err(format!(
                    "reference row {}: time {} does not increase (previous {})",
                    i + 1,
                    self.t[i],
                    self.t[i - 1]
                ));
            }
        }
        Ok(())
    }
}

/// The compact model: K_C, D_C entries and the corrections.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompactModel {
    pub plant: SagittalCompliance,
    pub corrections: Corrections,
}

/// State [x, z, x', z'].
pub type State = [f64; 4];

impl CompactModel {
    /// The CoM accelerations (x'', z'') at state s, reference (xr, zr) and phase
    /// (seed 002, eq 14-15 in single support, eq 16-17 in double support).
    #[inline]
    pub fn acceleration(&self, s: &State, xr: f64, zr: f64, double_support: bool) -> [f64; 2] {
        let p = &self.plant;
        let c = &self.corrections;
        let (ex, ez) = (s[0] - xr, s[1] - zr);
        let fx = -c.alpha1 * p.Kxx * ex
            - c.beta1 * p.Kxz * ez
            - c.gamma1 * p.Dxx * s[2]
            - c.epsilon1 * p.Dxz * s[3];
        let fz = -c.alpha2 * p.Kzx * ex
            - c.beta2 * p.Kzz * ez
            - c.gamma2 * p.Dzx * s[2]
            - c.epsilon2 * p.Dzz * s[3];
        let (e1, e2) = if double_support {
            (c.eta1, c.eta2)
        } else {
            (1.0, 1.0)
        };
        [e1 * fx / p.m, -p.g + e2 * fz / p.m]
    }

    /// The CoM at rest under a constant reference (xr, zr): the spring carries the
    /// weight. None if the corrected stiffness block is singular.
    pub fn equilibrium(&self, xr: f64, zr: f64, double_support: bool) -> Option<[f64; 2]> {
        let p = &self.plant;
        let c = &self.corrections;
        let (e1, e2) = if double_support {
            (c.eta1, c.eta2)
        } else {
            (1.0, 1.0)
        };
        let k = nalgebra::Matrix2::new(
            e1 * c.alpha1 * p.Kxx,
            e1 * c.beta1 * p.Kxz,
            e2 * c.alpha2 * p.Kzx,
            e2 * c.beta2 * p.Kzz,
        );
        let e = k.try_inverse()? * nalgebra::Vector2::new(0.0, -p.m * p.g);
        Some([xr + e[0], zr + e[1]])
    }

    #[inline]
    fn derivative(&self, s: &State, xr: f64, zr: f64, ds: bool) -> State {
        let a = self.acceleration(s, xr, zr, ds);
        [s[2], s[3], a[0], a[1]]
    }

    /// Integrates the model along the reference from (x0, z0) at rest by RK4; writes the
    /// CoM (x, z) at every reference time into `x` and `z` (resized). Checks the inputs.
    pub fn rollout(
        &self,
        reference: &SagittalReference,
        x0: f64,
        z0: f64,
        x: &mut Vec<f64>,
        z: &mut Vec<f64>,
    ) -> Result<(), ReducedError> {
        self.plant.validate()?;
        for (i, v) in self.corrections.to_array().iter().enumerate() {
            if !v.is_finite() {
                return err(format!("correction parameter {} is not finite", i + 1));
            }
        }
        reference.validate()?;
        if !(x0.is_finite() && z0.is_finite()) {
            return err("initial CoM position is not finite");
        }
        self.rollout_unchecked(reference, x0, z0, x, z);
        self.check_bounded(reference, x0, z0, x, z)
    }

    /// A rollout that left its bounds: a plant too stiff for the reference's step (RK4
    /// is unstable once the step times the plant's fastest rate passes about 2.8) grows
    /// without end into infinities and NaN. That is an error naming the time and the
    /// rate, never a file of NaN (issue 29, class 3). The bound: 1 km from the start.
    fn check_bounded(
        &self,
        r: &SagittalReference,
        x0: f64,
        z0: f64,
        x: &[f64],
        z: &[f64],
    ) -> Result<(), ReducedError> {
        let away = |i: usize| (x[i] - x0).hypot(z[i] - z0);
        let Some(i) = (0..x.len()).find(|&i| away(i).is_nan() || away(i) > 1e3) else {
            return Ok(());
        };
        let p = &self.plant;
        // The fastest rate of the stiffness and damping per unit mass (a bound on the
        // eigenvalues: the largest absolute row sum).
        let k = (p.Kxx.abs() + p.Kxz.abs()).max(p.Kzx.abs() + p.Kzz.abs()) / p.m;
        let d = (p.Dxx.abs() + p.Dxz.abs()).max(p.Dzx.abs() + p.Dzz.abs()) / p.m;
        let rate = k.sqrt().max(d);
        let h = r.t[i.max(1)] - r.t[i.max(1) - 1];
        err(format!(
            "the CoM left the reference at t = {} s (sample {}: x {}, z {} m): the plant's \
             stiffness and damping (rate up to {rate:.3e} 1/s) are too stiff for the \
             reference's {h} s step (step x rate = {:.3e}; RK4 needs it below about 2.8): \
             check the plant's units or sample the reference finer",
            r.t[i],
            i + 1,
            x[i],
            z[i],
            h * rate
        ))
    }

    /// [`Self::rollout`] without the checks, for optimisers that call it many times.
    pub fn rollout_unchecked(
        &self,
        r: &SagittalReference,
        x0: f64,
        z0: f64,
        x: &mut Vec<f64>,
        z: &mut Vec<f64>,
    ) {
        let n = r.t.len();
        x.clear();
        z.clear();
        x.reserve(n);
        z.reserve(n);
        let mut s: State = [x0, z0, 0.0, 0.0];
        x.push(s[0]);
        z.push(s[1]);
        for i in 1..n {
            s = self.rk4_step(&s, r, i);
            x.push(s[0]);
            z.push(s[1]);
        }
    }

    /// One classical Runge-Kutta step from sample `i - 1` to sample `i` of the reference
    /// (reference linearly interpolated, phase of sample `i - 1`).
    #[inline]
    pub fn rk4_step(&self, s: &State, r: &SagittalReference, i: usize) -> State {
        let h = r.t[i] - r.t[i - 1];
        let ds = r.double_support[i - 1];
        let (xa, za) = (r.xr[i - 1], r.zr[i - 1]);
        let (xb, zb) = (r.xr[i], r.zr[i]);
        let (xm, zm) = (0.5 * (xa + xb), 0.5 * (za + zb));
        let k1 = self.derivative(s, xa, za, ds);
        let s2 = std::array::from_fn(|k| s[k] + 0.5 * h * k1[k]);
        let k2 = self.derivative(&s2, xm, zm, ds);
        let s3 = std::array::from_fn(|k| s[k] + 0.5 * h * k2[k]);
        let k3 = self.derivative(&s3, xm, zm, ds);
        let s4 = std::array::from_fn(|k| s[k] + h * k3[k]);
        let k4 = self.derivative(&s4, xb, zb, ds);
        std::array::from_fn(|k| s[k] + h / 6.0 * (k1[k] + 2.0 * k2[k] + 2.0 * k3[k] + k4[k]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    fn plant() -> SagittalCompliance {
        // COMAN-like entries (a 0.5 rad crouch, forces-only x-z stiffness)
        SagittalCompliance {
            m: 32.05,
            g: twinloop_description::GRAVITY,
            Kxx: 441.0,
            Kxz: -2173.0,
            Kzx: -2173.0,
            Kzz: 60061.0,
            Dxx: 14.5,
            Dxz: -3.3,
            Dzx: -3.3,
            Dzz: 667.0,
        }
    }

    fn model() -> CompactModel {
        let mut c = Corrections::seed_table1();
        c.eta1 = 1.3;
        c.eta2 = 0.8;
        CompactModel {
            plant: plant(),
            corrections: c,
        }
    }

    /// Exact solution for a reference moving linearly, xr = xr0 + ux t, zr = zr0 + uz t, by
    /// the matrix exponential of the augmented linear system [x z x' z' xr zr 1].
    #[allow(clippy::too_many_arguments)]
    fn exact(
        m: &CompactModel,
        ds: bool,
        xr0: f64,
        zr0: f64,
        ux: f64,
        uz: f64,
        x0: f64,
        z0: f64,
        t: f64,
    ) -> [f64; 2] {
        let p = m.plant;
        let c = m.corrections;
        let (e1, e2) = if ds { (c.eta1, c.eta2) } else { (1.0, 1.0) };
        let mut a = DMatrix::<f64>::zeros(7, 7);
        a[(0, 2)] = 1.0;
        a[(1, 3)] = 1.0;
        let rows = [
            (
                2,
                e1,
                [
                    c.alpha1 * p.Kxx,
                    c.beta1 * p.Kxz,
                    c.gamma1 * p.Dxx,
                    c.epsilon1 * p.Dxz,
                ],
                0.0,
            ),
            (
                3,
                e2,
                [
                    c.alpha2 * p.Kzx,
                    c.beta2 * p.Kzz,
                    c.gamma2 * p.Dzx,
                    c.epsilon2 * p.Dzz,
                ],
                -p.g,
            ),
        ];
        for (r, e, k, g) in rows {
            a[(r, 0)] = -e * k[0] / p.m;
            a[(r, 1)] = -e * k[1] / p.m;
            a[(r, 2)] = -e * k[2] / p.m;
            a[(r, 3)] = -e * k[3] / p.m;
            a[(r, 4)] = e * k[0] / p.m;
            a[(r, 5)] = e * k[1] / p.m;
            a[(r, 6)] = g;
        }
        a[(4, 6)] = ux;
        a[(5, 6)] = uz;
        let s0 = DVector::from_vec(vec![x0, z0, 0.0, 0.0, xr0, zr0, 1.0]);
        let s = (a * t).exp() * s0;
        [s[0], s[1]]
    }

    fn ramp(n: usize, h: f64, ux: f64, uz: f64, ds: bool) -> SagittalReference {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * h).collect();
        SagittalReference {
            xr: t.iter().map(|t| 0.01 + ux * t).collect(),
            zr: t.iter().map(|t| 0.5 + uz * t).collect(),
            double_support: vec![ds; n],
            t,
        }
    }

    #[test]
    fn rollout_matches_the_exact_solution_of_eq_14_17() {
        let m = model();
        let (mut x, mut z) = (Vec::new(), Vec::new());
        for ds in [false, true] {
            let (ux, uz) = (0.05, -0.01);
            let r = ramp(1001, 1e-3, ux, uz, ds);
            m.rollout(&r, 0.0, 0.49, &mut x, &mut z).unwrap();
            let mut worst: f64 = 0.0;
            for i in (0..1001).step_by(50) {
                let e = exact(&m, ds, 0.01, 0.5, ux, uz, 0.0, 0.49, r.t[i]);
                worst = worst.max((x[i] - e[0]).abs()).max((z[i] - e[1]).abs());
            }
            assert!(worst < 1e-9, "double support {ds}: {worst:e}");
        }
    }

    /// Issue 29, class 3: a plant 1e8 times too stiff for a 1 ms step (RK4's limit is
    /// step x rate near 2.8; here sqrt(6e12 / 32) x 1e-3 = 433) diverges: an error
    /// naming the time and the step, not a rollout of NaN.
    #[test]
    fn a_plant_too_stiff_for_the_step_is_an_error_not_nan() {
        let mut m = model();
        m.plant.Kzz = 6e12;
        let (mut x, mut z) = (Vec::new(), Vec::new());
        let r = ramp(1001, 1e-3, 0.05, -0.01, false);
        let e = m.rollout(&r, 0.0, 0.49, &mut x, &mut z).unwrap_err();
        let e = e.to_string();
        assert!(e.contains("too stiff") && e.contains("0.001 s step"), "{e}");
        // The model as it is stays well inside the bound.
        m.plant.Kzz = 60061.0;
        m.rollout(&r, 0.0, 0.49, &mut x, &mut z).unwrap();
    }

    #[test]
    fn rk4_converges_at_fourth_order() {
        let m = model();
        let (mut x, mut z) = (Vec::new(), Vec::new());
        let e = exact(&m, false, 0.01, 0.5, 0.0, 0.0, 0.0, 0.49, 0.5);
        let mut errs = Vec::new();
        for n in [201, 401] {
            let r = ramp(n, 0.5 / (n - 1) as f64, 0.0, 0.0, false);
            m.rollout(&r, 0.0, 0.49, &mut x, &mut z).unwrap();
            errs.push((x[n - 1] - e[0]).abs().max((z[n - 1] - e[1]).abs()));
        }
        let ratio = errs[0] / errs[1];
        assert!(
            ratio > 12.0 && ratio < 20.0,
            "ratio {ratio}, errors {errs:?}"
        );
    }

    #[test]
    fn eta_scales_only_double_support_and_equilibrium_holds() {
        let mut m = model();
        let s = [0.0, 0.5, 0.0, 0.0];
        let single = m.acceleration(&s, 0.01, 0.51, false);
        let double = m.acceleration(&s, 0.01, 0.51, true);
        assert!((double[0] - 1.3 * single[0]).abs() < 1e-12);
        assert!((double[1] + m.plant.g - 0.8 * (single[1] + m.plant.g)).abs() < 1e-12);
        // static equilibrium under gravity (eq 11 with all ones)
        m.corrections = Corrections::default();
        let p = m.plant;
        let k = nalgebra::Matrix2::new(p.Kxx, p.Kxz, p.Kzx, p.Kzz);
        let e = k.try_inverse().unwrap() * nalgebra::Vector2::new(0.0, -p.m * p.g);
        let (xr, zr) = (0.02, 0.5);
        let a = m.acceleration(&[xr + e[0], zr + e[1], 0.0, 0.0], xr, zr, false);
        assert!(a[0].abs() < 1e-10 && a[1].abs() < 1e-10, "{a:?}");
    }

    #[test]
    fn bad_input_is_named() {
        let m = model();
        let (mut x, mut z) = (Vec::new(), Vec::new());
        let mut r = ramp(10, 1e-3, 0.0, 0.0, false);
        r.xr[4] = f64::NAN;
        let e = m.rollout(&r, 0.0, 0.5, &mut x, &mut z).unwrap_err();
        assert!(
            e.message.contains("row 5") && e.message.contains("xr"),
            "{e}"
        );
        let mut r = ramp(10, 1e-3, 0.0, 0.0, false);
        r.t[6] = r.t[5];
        assert!(
            m.rollout(&r, 0.0, 0.5, &mut x, &mut z)
                .unwrap_err()
                .message
                .contains("row 7")
        );
        let mut bad = m;
        bad.plant.Kzz = 0.0;
        let r = ramp(10, 1e-3, 0.0, 0.0, false);
        assert!(
            bad.rollout(&r, 0.0, 0.5, &mut x, &mut z)
                .unwrap_err()
                .message
                .contains("Kzz")
        );
    }
}
