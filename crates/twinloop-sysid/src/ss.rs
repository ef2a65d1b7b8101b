//! State-space models in innovations form (seed 003, eq 9, with a feedthrough `D`
//! that is zero unless asked for):
//!
//! ```text
//! x(k+1) = A x(k) + B u(k) + K e(k)
//! y(k)   = C x(k) + D u(k) + e(k)
//! ```

use crate::data::IoData;
use crate::error::{Result, SysidError};
use nalgebra::{Complex, DMatrix, DVector, Schur};

/// A discrete state-space model in innovations form (seed 003, eq 9, with `G = K`).
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpace {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub d: DMatrix<f64>,
    pub k: DMatrix<f64>,
    /// Covariance of the innovations `e(k)` (`ny x ny`).
    pub noise_covariance: DMatrix<f64>,
    pub sample_time: Option<f64>,
}

impl StateSpace {
    pub fn n(&self) -> usize {
        self.a.nrows()
    }

    pub fn nu(&self) -> usize {
        self.b.ncols()
    }

    pub fn ny(&self) -> usize {
        self.c.nrows()
    }

    /// Error unless `u` has `nu` rows, `y` (when given) `ny` rows and `x0` `n` entries.
    pub fn check_shapes(
        &self,
        u: &DMatrix<f64>,
        y: Option<&DMatrix<f64>>,
        x0: Option<&DVector<f64>>,
    ) -> Result<()> {
        let yrows = y.map_or(self.ny(), |y| y.nrows());
        if u.nrows() != self.nu() || yrows != self.ny() {
            return Err(SysidError::data(format!(
                "the model has {} inputs and {} outputs, the data {} and {}",
                self.nu(),
                self.ny(),
                u.nrows(),
                yrows
            )));
        }
        if let Some(y) = y
            && y.ncols() != u.ncols()
        {
            return Err(SysidError::data(
                "inputs and outputs have different lengths",
            ));
        }
        if let Some(x0) = x0
            && x0.len() != self.n()
        {
            return Err(SysidError::data(format!(
                "initial state of length {} for a model with {} states",
                x0.len(),
                self.n()
            )));
        }
        Ok(())
    }

    /// Simulated outputs (`ny x N`) for inputs `u` (`nu x N`) from `x(0) = x0`
    /// (zero when `None`), innovations set to zero. An unstable model's outputs may
    /// overflow to infinity; they are returned as computed.
    pub fn simulate(&self, u: &DMatrix<f64>, x0: Option<&DVector<f64>>) -> Result<DMatrix<f64>> {
        self.check_shapes(u, None, x0)?;
        let n = u.ncols();
        let mut y = DMatrix::zeros(self.ny(), n);
        let mut x = x0.cloned().unwrap_or_else(|| DVector::zeros(self.n()));
        let mut xn = DVector::zeros(self.n());
        for k in 0..n {
            let uk = u.column(k);
            let mut yk = y.column_mut(k);
            yk.gemv(1.0, &self.c, &x, 0.0);
            yk.gemv(1.0, &self.d, &uk, 1.0);
            xn.gemv(1.0, &self.a, &x, 0.0);
            xn.gemv(1.0, &self.b, &uk, 1.0);
            std::mem::swap(&mut x, &mut xn);
        }
        Ok(y)
    }

    /// Predicted states `x(k | k-1)` for `k = 0..=N` (`n x (N+1)`) of the Kalman
    /// predictor `x(k+1) = A x + B u + K (y - C x - D u)` started at `x0` (zero when
    /// `None`), and the one-step prediction errors (`ny x N`).
    pub fn predictor_states(
        &self,
        data: &IoData,
        x0: Option<&DVector<f64>>,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
        self.check_shapes(&data.u, Some(&data.y), x0)?;
        let n = data.len();
        let mut xs = DMatrix::zeros(self.n(), n + 1);
        let mut err = DMatrix::zeros(self.ny(), n);
        if let Some(x0) = x0 {
            xs.set_column(0, x0);
        }
        let mut xn = DVector::zeros(self.n());
        let mut e = DVector::zeros(self.ny());
        for k in 0..n {
            let uk = data.u.column(k);
            let x = xs.column(k);
            e.copy_from(&data.y.column(k));
            e.gemv(-1.0, &self.c, &x, 1.0);
            e.gemv(-1.0, &self.d, &uk, 1.0);
            xn.gemv(1.0, &self.a, &x, 0.0);
            xn.gemv(1.0, &self.b, &uk, 1.0);
            xn.gemv(1.0, &self.k, &e, 1.0);
            xs.set_column(k + 1, &xn);
            err.set_column(k, &e);
        }
        Ok((xs, err))
    }

    /// One-step prediction errors `e(k) = y(k) - yhat(k | k-1)` (`ny x N`), predictor
    /// started at zero.
    pub fn residuals(&self, data: &IoData) -> Result<DMatrix<f64>> {
        Ok(self.predictor_states(data, None)?.1)
    }

    /// Prediction cost `V = (1/N) sum_k |e(k)|^2` of the one-step predictor.
    pub fn prediction_cost(&self, data: &IoData) -> Result<f64> {
        let e = self.residuals(data)?;
        Ok(e.norm_squared() / data.len().max(1) as f64)
    }

    /// `horizon`-step-ahead predictions `yhat(k | k - horizon)` (`ny x N`): the Kalman
    /// predictor runs on measured data up to `k - horizon`, then the model runs
    /// `horizon - 1` steps on the inputs alone. `horizon = 1` is the one-step predictor.
    pub fn predict(&self, data: &IoData, horizon: usize) -> Result<DMatrix<f64>> {
        let horizon = horizon.max(1);
        let (xs, err) = self.predictor_states(data, None)?;
        if horizon == 1 {
            return Ok(&data.y - err);
        }
        let n = data.len();
        let mut out = DMatrix::zeros(self.ny(), n);
        let mut x = DVector::zeros(self.n());
        let mut xn = DVector::zeros(self.n());
        for k in 0..n {
            let s = k as isize - horizon as isize + 1;
            let s = if s < 0 {
                x.fill(0.0);
                0
            } else {
                x.copy_from(&xs.column(s as usize));
                s as usize
            };
            for tau in s..k {
                xn.gemv(1.0, &self.a, &x, 0.0);
                xn.gemv(1.0, &self.b, &data.u.column(tau), 1.0);
                std::mem::swap(&mut x, &mut xn);
            }
            let mut yk = out.column_mut(k);
            yk.gemv(1.0, &self.c, &x, 0.0);
            yk.gemv(1.0, &self.d, &data.u.column(k), 1.0);
        }
        Ok(out)
    }

    /// Eigenvalues of `A` (the model's poles), or `None` if the eigenvalue
    /// iteration did not converge or `A` holds non-finite numbers.
    pub fn poles(&self) -> Option<Vec<Complex<f64>>> {
        eigenvalues(&self.a)
    }

    /// Largest pole magnitude; the model is stable when it is below 1.
    pub fn spectral_radius(&self) -> Option<f64> {
        spectral_radius(&self.a)
    }

    /// Largest eigenvalue magnitude of the predictor's `A - K C`.
    pub fn predictor_spectral_radius(&self) -> Option<f64> {
        spectral_radius(&(&self.a - &self.k * &self.c))
    }

    /// `G(z) = C (zI - A)^-1 B + D` at `z = e^{j w}`, `w` in rad/sample.
    pub fn frequency_response(&self, w: f64) -> Option<DMatrix<Complex<f64>>> {
        let n = self.n();
        let z = Complex::from_polar(1.0, w);
        let mut m = self.a.map(|x| Complex::new(-x, 0.0));
        for i in 0..n {
            m[(i, i)] += z;
        }
        let b = self.b.map(|x| Complex::new(x, 0.0));
        let x = m.lu().solve(&b)?;
        let c = self.c.map(|x| Complex::new(x, 0.0));
        Some(c * x + self.d.map(|x| Complex::new(x, 0.0)))
    }
}

/// Eigenvalues of a real square matrix through its real Schur form.
pub fn eigenvalues(a: &DMatrix<f64>) -> Option<Vec<Complex<f64>>> {
    if a.nrows() == 0 {
        return Some(Vec::new());
    }
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let schur = Schur::try_new(a.clone(), f64::EPSILON, 10_000 * a.nrows())?;
    Some(schur.complex_eigenvalues().iter().copied().collect())
}

/// Largest eigenvalue magnitude of a real square matrix (0 for an empty one).
pub fn spectral_radius(a: &DMatrix<f64>) -> Option<f64> {
    eigenvalues(a).map(|ev| ev.iter().fold(0.0f64, |m, z| m.max(z.norm())))
}
