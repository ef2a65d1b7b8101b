//! Zero-phase low-pass filtering for smoothed differentiation: a digital Butterworth
//! design (analog prototype, pre-warped cut-off, bilinear transform) and forward-
//! backward filtering with odd-extension padding and steady-state initial
//! conditions, the same recipe as SciPy's `butter` + `filtfilt` (its default
//! `padtype="odd"`, `padlen = 3 max(len(a), len(b))`), so numbers agree with it.
//!
//! Seed 004 (section 3.1) filters marker and force data with a bi-directional
//! Butterworth filter at 10 Hz.

use crate::error::IdentError;
use nalgebra::{Complex, DMatrix, DVector};

/// A digital filter as a transfer function `b(z) / a(z)`, `a[0] = 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct TransferFunction {
    pub b: Vec<f64>,
    pub a: Vec<f64>,
}

/// Coefficients of the monic polynomial with the given roots, highest power first.
fn poly(roots: &[Complex<f64>]) -> Vec<Complex<f64>> {
    let mut c = vec![Complex::new(1.0, 0.0)];
    for r in roots {
        let mut next = vec![Complex::new(0.0, 0.0); c.len() + 1];
        for (i, ci) in c.iter().enumerate() {
            next[i] += ci;
            next[i + 1] -= ci * r;
        }
        c = next;
    }
    c
}

/// Low-pass Butterworth filter of `order` with cut-off `cutoff_hz` for data sampled at
/// `sample_hz`.
pub fn butter_lowpass(
    order: usize,
    cutoff_hz: f64,
    sample_hz: f64,
) -> Result<TransferFunction, IdentError> {
    if order == 0 || order > 8 {
        return Err(IdentError::new(format!(
            "Butterworth order {order}: use 1 to 8 (2 or 4 is usual)"
        ))
        .option("filter_order"));
    }
    let nyquist = 0.5 * sample_hz;
    if !(cutoff_hz > 0.0 && cutoff_hz < nyquist) {
        return Err(IdentError::new(format!(
            "cut-off {cutoff_hz} Hz must lie between 0 and the Nyquist frequency {nyquist} Hz \
             (sampling at {sample_hz} Hz)"
        ))
        .option("cutoff"));
    }
    let n = order as f64;
    // Analog prototype poles on the left half of the unit circle.
    let proto: Vec<Complex<f64>> = (0..order)
        .map(|k| {
            let m = -(n - 1.0) + 2.0 * k as f64;
            -Complex::from_polar(1.0, std::f64::consts::PI * m / (2.0 * n))
        })
        .collect();
    // Pre-warp the cut-off for the bilinear transform (sample rate 2 after normalising).
    let wn = cutoff_hz / nyquist;
    let fs = 2.0;
    let warped = 2.0 * fs * (std::f64::consts::PI * wn / fs).tan();
    let poles: Vec<Complex<f64>> = proto.iter().map(|p| p * warped).collect();
    let gain = warped.powi(order as i32);
    // Bilinear transform: z = (2 fs + s) / (2 fs - s); zeros at infinity go to z = -1.
    let fs2 = 2.0 * fs;
    let zpoles: Vec<Complex<f64>> = poles.iter().map(|p| (fs2 + p) / (fs2 - p)).collect();
    let zzeros = vec![Complex::new(-1.0, 0.0); order];
    let denom: Complex<f64> = poles.iter().map(|p| fs2 - p).product();
    let k = gain / denom.re;
    let b: Vec<f64> = poly(&zzeros).iter().map(|c| k * c.re).collect();
    let a: Vec<f64> = poly(&zpoles).iter().map(|c| c.re).collect();
    Ok(TransferFunction { b, a })
}

impl TransferFunction {
    fn order(&self) -> usize {
        self.a.len().max(self.b.len()) - 1
    }

    /// Direct form II transposed over `x` into `y`, starting from state `z` (updated).
    pub fn filter_with_state(&self, x: &[f64], z: &mut [f64], y: &mut [f64]) {
        let n = self.order();
        let (b, a) = (&self.b, &self.a);
        for (xi, yi) in x.iter().zip(y.iter_mut()) {
            let out = b[0] * xi + if n > 0 { z[0] } else { 0.0 };
            for i in 0..n.saturating_sub(1) {
                z[i] = b[i + 1] * xi + z[i + 1] - a[i + 1] * out;
            }
            if n > 0 {
                z[n - 1] = b[n] * xi - a[n] * out;
            }
            *yi = out;
        }
    }

    /// The state of a step response in steady state (input 1 forever): scaled by the
    /// first sample it starts a filter without a transient.
    pub fn steady_state(&self) -> Vec<f64> {
        let n = self.order();
        if n == 0 {
            return Vec::new();
        }
        // (I - A^T) zi = B with A the companion matrix of a.
        let mut m = DMatrix::<f64>::identity(n, n);
        for i in 0..n {
            m[(i, 0)] += self.a[i + 1];
            if i + 1 < n {
                m[(i, i + 1)] -= 1.0;
            }
        }
        let rhs = DVector::from_fn(n, |i, _| self.b[i + 1] - self.a[i + 1] * self.b[0]);
        m.lu()
            .solve(&rhs)
            .map(|v| v.iter().copied().collect())
            .unwrap_or_else(|| vec![0.0; n])
    }

    /// Padding length of the forward-backward filter (SciPy's default).
    pub fn pad_length(&self) -> usize {
        3 * self.a.len().max(self.b.len())
    }

    /// Zero-phase forward-backward filtering (SciPy `filtfilt` defaults): seed 004's
    /// bi-directional Butterworth (section 3.1). The signal
    /// must be longer than [`pad_length`](Self::pad_length).
    pub fn filtfilt(&self, x: &[f64]) -> Result<Vec<f64>, IdentError> {
        let pad = self.pad_length();
        if x.len() <= pad {
            return Err(IdentError::new(format!(
                "{} samples are too few to filter: more than {pad} are needed",
                x.len()
            )));
        }
        let n = x.len();
        let mut ext = Vec::with_capacity(n + 2 * pad);
        // Odd extension about the end points.
        for i in (1..=pad).rev() {
            ext.push(2.0 * x[0] - x[i]);
        }
        ext.extend_from_slice(x);
        for i in 1..=pad {
            ext.push(2.0 * x[n - 1] - x[n - 1 - i]);
        }
        let zi = self.steady_state();
        let mut z: Vec<f64> = zi.iter().map(|v| v * ext[0]).collect();
        let mut y = vec![0.0; ext.len()];
        self.filter_with_state(&ext, &mut z, &mut y);
        y.reverse();
        let mut z: Vec<f64> = zi.iter().map(|v| v * y[0]).collect();
        let mut out = vec![0.0; ext.len()];
        self.filter_with_state(&y, &mut z, &mut out);
        out.reverse();
        Ok(out[pad..pad + n].to_vec())
    }
}
