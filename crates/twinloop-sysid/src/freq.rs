//! Singular values of the frequency response (seed 003, Figs 52 and 55): the
//! gains of the transfer matrix `G(e^{jw})` from the inputs to the outputs, with
//! the peak gain in dB and the bandwidth.

use crate::arx::ArxModel;
use crate::ss::StateSpace;
use nalgebra::{Complex, DMatrix, SVD};

/// Anything with a transfer matrix: `G(e^{jw})`, `w` in rad/sample.
pub trait TransferMatrix {
    fn response(&mut self, w: f64) -> Option<DMatrix<Complex<f64>>>;
}

/// An ARX model's response from its polynomials: `A(z)^-1 B(z)`, an `ny x ny`
/// solve per frequency however high the orders.
pub struct ArxResponse<'a>(pub &'a ArxModel);

impl TransferMatrix for ArxResponse<'_> {
    fn response(&mut self, w: f64) -> Option<DMatrix<Complex<f64>>> {
        self.0.frequency_response(w)
    }
}

/// `G(z) = C (zI - A)^-1 B + D` evaluated at many frequencies: `A` is reduced
/// once to Hessenberg form `A = Q H Q^T`, after which each frequency costs one
/// O(n^2) elimination on `zI - H` instead of an O(n^3) factorisation.
pub struct StateSpaceResponse {
    h: DMatrix<f64>,
    qtb: DMatrix<Complex<f64>>,
    cq: DMatrix<Complex<f64>>,
    d: DMatrix<Complex<f64>>,
    m: DMatrix<Complex<f64>>,
    x: DMatrix<Complex<f64>>,
}

impl StateSpaceResponse {
    pub fn new(model: &StateSpace) -> StateSpaceResponse {
        let n = model.n();
        let (q, h) = if n > 0 {
            model.a.clone().hessenberg().unpack()
        } else {
            (DMatrix::zeros(0, 0), DMatrix::zeros(0, 0))
        };
        let cplx = |m: &DMatrix<f64>| m.map(|x| Complex::new(x, 0.0));
        StateSpaceResponse {
            qtb: cplx(&(q.transpose() * &model.b)),
            cq: cplx(&(&model.c * &q)),
            d: cplx(&model.d),
            m: DMatrix::zeros(n, n),
            x: DMatrix::zeros(n, model.nu()),
            h,
        }
    }
}

impl TransferMatrix for StateSpaceResponse {
    fn response(&mut self, w: f64) -> Option<DMatrix<Complex<f64>>> {
        let n = self.h.nrows();
        let nu = self.qtb.ncols();
        let z = Complex::from_polar(1.0, w);
        for j in 0..n {
            for i in 0..n {
                let hij = if i <= j + 1 { self.h[(i, j)] } else { 0.0 };
                self.m[(i, j)] =
                    Complex::new(-hij, 0.0) + if i == j { z } else { Complex::new(0.0, 0.0) };
            }
        }
        self.x.copy_from(&self.qtb);
        // Gaussian elimination on an upper Hessenberg matrix: one row below the
        // diagonal per column, partial pivoting between the two candidate rows.
        for k in 0..n.saturating_sub(1) {
            if self.m[(k + 1, k)].norm() > self.m[(k, k)].norm() {
                self.m.swap_rows(k, k + 1);
                self.x.swap_rows(k, k + 1);
            }
            let piv = self.m[(k, k)];
            if piv.norm() == 0.0 {
                return None;
            }
            let l = self.m[(k + 1, k)] / piv;
            if l.norm() != 0.0 {
                for j in k..n {
                    let v = self.m[(k, j)];
                    self.m[(k + 1, j)] -= l * v;
                }
                for j in 0..nu {
                    let v = self.x[(k, j)];
                    self.x[(k + 1, j)] -= l * v;
                }
            }
        }
        for i in (0..n).rev() {
            let piv = self.m[(i, i)];
            if piv.norm() == 0.0 {
                return None;
            }
            for j in 0..nu {
                let mut s = self.x[(i, j)];
                for k in i + 1..n {
                    s -= self.m[(i, k)] * self.x[(k, j)];
                }
                self.x[(i, j)] = s / piv;
            }
        }
        Some(&self.cq * &self.x + &self.d)
    }
}

/// Singular values of `G`, largest first.
pub fn singular_values(g: &DMatrix<Complex<f64>>) -> Vec<f64> {
    if g.is_empty() {
        return Vec::new();
    }
    match SVD::try_new(g.clone(), false, false, f64::EPSILON, 10_000) {
        Some(s) => {
            let mut v: Vec<f64> = s.singular_values.iter().copied().collect();
            v.sort_by(|a, b| b.total_cmp(a));
            v
        }
        None => vec![f64::NAN; g.nrows().min(g.ncols())],
    }
}

/// The singular-value plot of a model and what it says.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SigmaResponse {
    /// `"rad/s"` when the sample time is known, else `"rad/sample"`.
    pub frequency_unit: String,
    /// Frequencies, log-spaced from 1/1000 of the Nyquist frequency to it.
    pub frequency: Vec<f64>,
    /// Per frequency, the singular values of `G` in dB, largest first.
    pub sigma_db: Vec<Vec<f64>>,
    /// Largest gain over frequency (largest singular value), dB.
    pub peak_gain_db: f64,
    /// Where it occurs.
    pub peak_frequency: f64,
    /// Largest singular value at zero frequency, dB (`None` for a pole at z = 1).
    pub dc_gain_db: Option<f64>,
    /// First frequency where the largest singular value falls 3 dB below its
    /// zero-frequency value (MATLAB's `bandwidth` definition, on the largest
    /// singular value); `None` when the gain never falls that far below Nyquist or
    /// the zero-frequency gain is not finite.
    pub bandwidth: Option<f64>,
}

fn db(x: f64) -> f64 {
    20.0 * x.log10()
}

/// Singular values of the frequency response on `points` log-spaced frequencies
/// (seed 003, Figs 52 and 55: "singular values of the model transfer matrix ...
/// bandwidth ... maximal gain"), the peak refined by golden-section search and the
/// bandwidth by bisection between grid points.
pub fn sigma_response(
    g: &mut dyn TransferMatrix,
    sample_time: Option<f64>,
    points: usize,
) -> SigmaResponse {
    let points = points.max(2);
    let scale = sample_time.map_or(1.0, |ts| 1.0 / ts);
    let (lo, hi) = (
        (std::f64::consts::PI * 1e-3).ln(),
        std::f64::consts::PI.ln(),
    );
    let sigma1 = |w: f64, g: &mut dyn TransferMatrix| -> f64 {
        g.response(w)
            .map(|m| singular_values(&m).first().copied().unwrap_or(0.0))
            .unwrap_or(f64::INFINITY)
    };
    let mut freq = Vec::with_capacity(points);
    let mut sig = Vec::with_capacity(points);
    let mut s1 = Vec::with_capacity(points);
    for i in 0..points {
        let w = (lo + (hi - lo) * i as f64 / (points - 1) as f64).exp();
        let sv = g
            .response(w)
            .map(|m| singular_values(&m))
            .unwrap_or_default();
        s1.push(sv.first().copied().unwrap_or(f64::INFINITY));
        sig.push(sv.iter().map(|&s| db(s)).collect::<Vec<f64>>());
        freq.push(w);
    }
    // Peak: best grid point, then golden-section search between its neighbours.
    let ip = (0..points)
        .max_by(|&a, &b| s1[a].total_cmp(&s1[b]))
        .unwrap_or(0);
    let (mut a, mut b) = (freq[ip.saturating_sub(1)], freq[(ip + 1).min(points - 1)]);
    let (mut wp, mut sp) = (freq[ip], s1[ip]);
    if sp.is_finite() {
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..60 {
            let c = b - gr * (b - a);
            let d = a + gr * (b - a);
            let (sc, sd) = (sigma1(c, g), sigma1(d, g));
            if sc > sp {
                (wp, sp) = (c, sc);
            }
            if sd > sp {
                (wp, sp) = (d, sd);
            }
            if sc >= sd {
                b = d;
            } else {
                a = c;
            }
        }
    }
    let dc = g
        .response(0.0)
        .map(|m| singular_values(&m).first().copied().unwrap_or(0.0))
        .filter(|x| x.is_finite() && *x > 0.0);
    let bandwidth = dc.and_then(|dc| {
        let level = dc / 2f64.sqrt();
        let i = (0..points).find(|&i| s1[i] < level)?;
        if i == 0 {
            // Already below at the first grid point: search between 0 and it.
            let (mut a, mut b) = (0.0, freq[0]);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if sigma1(m, g) < level {
                    b = m;
                } else {
                    a = m;
                }
            }
            return Some(0.5 * (a + b));
        }
        let (mut a, mut b) = (freq[i - 1], freq[i]);
        for _ in 0..60 {
            let m = (a * b).sqrt();
            if sigma1(m, g) < level {
                b = m;
            } else {
                a = m;
            }
        }
        Some((a * b).sqrt())
    });
    SigmaResponse {
        frequency_unit: if sample_time.is_some() {
            "rad/s"
        } else {
            "rad/sample"
        }
        .to_string(),
        frequency: freq.iter().map(|w| w * scale).collect(),
        sigma_db: sig,
        peak_gain_db: db(sp),
        peak_frequency: wp * scale,
        dc_gain_db: dc.map(db),
        bandwidth: bandwidth.map(|w| w * scale),
    }
}
