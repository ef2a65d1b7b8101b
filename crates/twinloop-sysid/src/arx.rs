//! MIMO ARX models (seed 003, section 7.1, eq 8), estimated by least squares
//! with MATLAB's `arx` structure:
//!
//! ```text
//! y(k) + A1 y(k-1) + ... + A_na y(k-na) = B1 u(k-nk) + ... + B_nb u(k-nk-nb+1) + e(k)
//! ```
//!
//! Every `A_i` is a full `ny x ny` matrix, so the outputs influence each other
//! (the seed's `W_yy`), every `B_j` is `ny x nu`. All outputs share one regressor,
//! solved once by Householder QR for all of them.

use crate::data::IoData;
use crate::error::{Result, SysidError};
use crate::linalg::HouseholderQr;
use crate::ss::StateSpace;
use nalgebra::{DMatrix, DVector};

/// Orders of an ARX model: `na` output lags, `nb` input lags, `nk` input delay.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ArxOrders {
    pub na: usize,
    pub nb: usize,
    pub nk: usize,
}

impl ArxOrders {
    /// The first sample that has a full regressor: `max(na, nb + nk - 1)` (0-based),
    /// as MATLAB's `arx` uses.
    pub fn first_row(&self) -> usize {
        self.na.max((self.nb + self.nk).saturating_sub(1))
    }

    /// Parameters per output: `na ny + nb nu`.
    pub fn parameters_per_output(&self, ny: usize, nu: usize) -> usize {
        self.na * ny + self.nb * nu
    }
}

/// An estimated ARX model.
#[derive(Debug, Clone, PartialEq)]
pub struct ArxModel {
    /// `A1 .. A_na`, each `ny x ny`.
    pub a: Vec<DMatrix<f64>>,
    /// `B1 .. B_nb`, each `ny x nu`; `B_j` multiplies `u(k - nk - j + 1)`.
    pub b: Vec<DMatrix<f64>>,
    pub nk: usize,
    /// Covariance of the equation errors `e(k)` over the fitted rows.
    pub noise_covariance: DMatrix<f64>,
    pub sample_time: Option<f64>,
}

/// The least-squares regressor of the ARX structure: row `r` is sample
/// `k = first_row + r`, `phi(k) = [-y(k-1)^T .. -y(k-na)^T, u(k-nk)^T .. u(k-nk-nb+1)^T]`,
/// the target row is `y(k)^T`. Returns `(Phi, Y, first_row)`.
pub fn arx_regressor(
    data: &IoData,
    orders: ArxOrders,
) -> Result<(DMatrix<f64>, DMatrix<f64>, usize)> {
    let (ny, nu, n) = (data.ny(), data.nu(), data.len());
    let ArxOrders { na, nb, nk } = orders;
    if na == 0 && nb == 0 {
        return Err(SysidError::order(
            "na = nb = 0: the model would have no parameters",
        ));
    }
    if nb > 0 && nu == 0 {
        return Err(SysidError::order(
            "nb > 0 but the record has no input channel",
        ));
    }
    if nb == 0 && nu > 0 {
        return Err(SysidError::order(format!(
            "nb = 0 would ignore all {nu} inputs: use nb >= 1 (a model without inputs is a \
             time-series model, which this command does not fit)"
        )));
    }
    let k0 = orders.first_row();
    let d = orders.parameters_per_output(ny, nu);
    let rows = n.saturating_sub(k0);
    if rows < d {
        return Err(SysidError::data(format!(
            "ARX na={na} nb={nb} nk={nk} has {d} parameters per output, but {n} samples give only \
             {rows} usable rows (samples {k0}..{n} have a full regressor): lower the orders or \
             record at least {} samples",
            k0 + d
        )));
    }
    let mut phi = DMatrix::zeros(rows, d);
    let mut target = DMatrix::zeros(rows, ny);
    for r in 0..rows {
        let k = k0 + r;
        for i in 0..na {
            for o in 0..ny {
                phi[(r, i * ny + o)] = -data.y[(o, k - 1 - i)];
            }
        }
        for j in 0..nb {
            for c in 0..nu {
                phi[(r, na * ny + j * nu + c)] = data.u[(c, k - nk - j)];
            }
        }
        for o in 0..ny {
            target[(r, o)] = data.y[(o, k)];
        }
    }
    Ok((phi, target, k0))
}

/// The regressor column `c` as words, for error messages.
fn describe_column(data: &IoData, orders: ArxOrders, c: usize) -> String {
    let ny = data.ny();
    let nu = data.nu();
    if c < orders.na * ny {
        format!(
            "output \"{}\" at lag {}",
            data.output_names[c % ny],
            c / ny + 1
        )
    } else {
        let c = c - orders.na * ny;
        format!(
            "input \"{}\" at lag {}",
            data.input_names[c % nu],
            orders.nk + c / nu
        )
    }
}

/// Estimate a MIMO ARX model by least squares (seed 003, eq 8 and section 7.1: the
/// initial model, "estimated with the standard least squares method").
///
/// The regressor rows are `k = max(na, nb + nk - 1) .. N - 1` (0-based), as MATLAB's
/// `arx` uses: no data before the record is invented. The problem is solved by
/// Householder QR (never the normal equations), one factorisation for all outputs.
pub fn estimate_arx(data: &IoData, orders: ArxOrders) -> Result<ArxModel> {
    data.check_excitation()?;
    let (ny, nu) = (data.ny(), data.nu());
    let (phi, target, _) = arx_regressor(data, orders)?;
    let rows = phi.nrows();
    let qr = HouseholderQr::new(phi);
    let (theta, ete) = qr.solve_with_residual(&target).map_err(|e| {
        let tol = (rows as f64) * f64::EPSILON;
        match qr.first_dependent_column(tol) {
            Some(c) => SysidError::numerical(format!(
                "the ARX regressor is rank-deficient: the column of {} is a linear combination \
                 of earlier columns (inputs that are copies or combinations of each other, or not \
                 exciting enough for nb={}); drop a channel or lower the orders",
                describe_column(data, orders, c),
                orders.nb
            )),
            None => e,
        }
    })?;
    let noise_covariance = ete / rows as f64;
    let a = (0..orders.na)
        .map(|i| theta.rows(i * ny, ny).transpose())
        .collect();
    let b = (0..orders.nb)
        .map(|j| theta.rows(orders.na * ny + j * nu, nu).transpose())
        .collect();
    Ok(ArxModel {
        a,
        b,
        nk: orders.nk,
        noise_covariance,
        sample_time: data.sample_time,
    })
}

impl ArxModel {
    pub fn ny(&self) -> usize {
        self.noise_covariance.nrows()
    }

    pub fn nu(&self) -> usize {
        self.b.first().map_or(0, |b| b.ncols())
    }

    pub fn orders(&self) -> ArxOrders {
        ArxOrders {
            na: self.a.len(),
            nb: self.b.len(),
            nk: self.nk,
        }
    }

    /// Error unless the data have this model's channel counts.
    fn check_shapes(&self, u: &DMatrix<f64>, y: Option<&DMatrix<f64>>) -> Result<()> {
        let yrows = y.map_or(self.ny(), |y| y.nrows());
        if (u.nrows() != self.nu() && !self.b.is_empty()) || yrows != self.ny() {
            return Err(SysidError::data(format!(
                "the model has {} inputs and {} outputs, the data {} and {}",
                self.nu(),
                self.ny(),
                u.nrows(),
                yrows
            )));
        }
        Ok(())
    }

    /// Simulated outputs (`ny x N`) for inputs `u` (`nu x N`), zero before the record:
    /// `y(k) = -sum A_i y(k-i) + sum B_j u(k-nk-j+1)`.
    pub fn simulate(&self, u: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        self.check_shapes(u, None)?;
        let n = u.ncols();
        let ny = self.ny();
        let mut y = DMatrix::zeros(ny, n);
        let mut acc = DVector::zeros(ny);
        for k in 0..n {
            self.input_part(u, k, &mut acc);
            for (i, ai) in self.a.iter().enumerate() {
                if k > i {
                    acc.gemv(-1.0, ai, &y.column(k - 1 - i), 1.0);
                }
            }
            y.set_column(k, &acc);
        }
        Ok(y)
    }

    /// `acc <- sum_j B_j u(k - nk - j + 1)` (terms before the record are zero).
    fn input_part(&self, u: &DMatrix<f64>, k: usize, acc: &mut DVector<f64>) {
        acc.fill(0.0);
        for (j, bj) in self.b.iter().enumerate() {
            if k >= self.nk + j {
                acc.gemv(1.0, bj, &u.column(k - self.nk - j), 1.0);
            }
        }
    }

    /// `horizon`-step-ahead predictions `yhat(k | k - horizon)` (`ny x N`): measured
    /// outputs up to `k - horizon`, predicted ones after, zero before the record.
    /// `horizon = 1` is the one-step predictor the model was fitted for.
    pub fn predict(&self, data: &IoData, horizon: usize) -> Result<DMatrix<f64>> {
        self.check_shapes(&data.u, Some(&data.y))?;
        let horizon = horizon.max(1);
        let (n, ny) = (data.len(), self.ny());
        let mut out = DMatrix::zeros(ny, n);
        // pred column j holds the prediction of sample (k - horizon + 1 + j).
        let mut pred = DMatrix::zeros(ny, horizon);
        let mut acc = DVector::zeros(ny);
        for k in 0..n {
            let base = k as isize - horizon as isize + 1;
            for j in 0..horizon {
                let s = base + j as isize;
                if s < 0 {
                    continue;
                }
                let s = s as usize;
                self.input_part(&data.u, s, &mut acc);
                for (i, ai) in self.a.iter().enumerate() {
                    let r = s as isize - 1 - i as isize;
                    if r < 0 {
                        continue;
                    }
                    if r < base {
                        acc.gemv(-1.0, ai, &data.y.column(r as usize), 1.0);
                    } else {
                        acc.gemv(-1.0, ai, &pred.column((r - base) as usize), 1.0);
                    }
                }
                pred.set_column(j, &acc);
            }
            out.set_column(k, &pred.column(horizon - 1));
        }
        Ok(out)
    }

    /// One-step prediction errors `e(k) = y(k) - yhat(k | k-1)` over the whole
    /// record (`ny x N`).
    pub fn residuals(&self, data: &IoData) -> Result<DMatrix<f64>> {
        Ok(&data.y - self.predict(data, 1)?)
    }

    /// The model in innovations state-space form (observer canonical blocks):
    /// `x(k+1) = A x + B u + K e`, `y = C x + D u + e` with `n = ny max(na, nk+nb-1)`
    /// states, `C = [I 0 .. 0]`, block row `i` of `A` = `[-A_{i+1}, 0 .., I, .. 0]`,
    /// `B_i = Bt_{i+1} - A_{i+1} Bt_0`, `K_i = -A_{i+1}`, `D = Bt_0`, where `Bt_l` is the
    /// coefficient of `u(k-l)`. Its one-step predictor equals the ARX predictor.
    pub fn to_state_space(&self) -> StateSpace {
        let (ny, nu) = (self.ny(), self.nu());
        let na = self.a.len();
        let m = (self.nk + self.b.len()).saturating_sub(1);
        let blocks = na.max(m);
        let n = blocks * ny;
        // Bt_l: coefficient of u(k - l), l = 0..=m.
        let bt = |l: usize| -> DMatrix<f64> {
            if l >= self.nk && l - self.nk < self.b.len() {
                self.b[l - self.nk].clone()
            } else {
                DMatrix::zeros(ny, nu)
            }
        };
        let ai = |i: usize| -> DMatrix<f64> {
            if i >= 1 && i <= na {
                self.a[i - 1].clone()
            } else {
                DMatrix::zeros(ny, ny)
            }
        };
        let d = bt(0);
        let mut a = DMatrix::zeros(n, n);
        let mut b = DMatrix::zeros(n, nu);
        let mut k = DMatrix::zeros(n, ny);
        let mut c = DMatrix::zeros(ny, n);
        if n > 0 {
            c.view_mut((0, 0), (ny, ny)).fill_with_identity();
        }
        for i in 0..blocks {
            let a_next = ai(i + 1);
            a.view_mut((i * ny, 0), (ny, ny)).copy_from(&(-&a_next));
            if i + 1 < blocks {
                a.view_mut((i * ny, (i + 1) * ny), (ny, ny))
                    .fill_with_identity();
            }
            b.view_mut((i * ny, 0), (ny, nu))
                .copy_from(&(bt(i + 1) - &a_next * &d));
            k.view_mut((i * ny, 0), (ny, ny)).copy_from(&(-a_next));
        }
        StateSpace {
            a,
            b,
            c,
            d,
            k,
            noise_covariance: self.noise_covariance.clone(),
            sample_time: self.sample_time,
        }
    }

    /// Frequency response `G(z) = A(z)^-1 B(z)` at `z = e^{j w}` (`w` in rad/sample),
    /// with `A(z) = I + sum A_i z^-i`, `B(z) = sum B_j z^-(nk+j-1)`.
    pub fn frequency_response(&self, w: f64) -> Option<DMatrix<nalgebra::Complex<f64>>> {
        use nalgebra::Complex;
        let (ny, nu) = (self.ny(), self.nu());
        let zinv = |p: usize| Complex::from_polar(1.0, -(w * p as f64));
        let mut ap = DMatrix::<Complex<f64>>::identity(ny, ny);
        for (i, ai) in self.a.iter().enumerate() {
            let f = zinv(i + 1);
            ap.zip_apply(ai, |x, r| *x += f * r);
        }
        let mut bp = DMatrix::<Complex<f64>>::zeros(ny, nu);
        for (j, bj) in self.b.iter().enumerate() {
            let f = zinv(self.nk + j);
            bp.zip_apply(bj, |x, r| *x += f * r);
        }
        ap.lu().solve(&bp)
    }
}
