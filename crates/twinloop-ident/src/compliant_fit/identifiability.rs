//! What the data determine: output sensitivities, the Fisher information and its
//! Cramer-Rao bounds, and the parameter correlations, at a parameter point.
//!
//! For residuals r = model(p) - data with white Gaussian noise of standard deviation
//! sigma on every x and z sample, the Fisher information is F = J^T J / sigma^2 and any
//! unbiased estimate has covariance at least F^-1 (Cramer-Rao). sigma is the one given
//! or, at a least-squares optimum, the estimate sigma^2 = r^T r / (2N - n). The
//! correlation matrix of F^-1 shows which parameters trade off against each other.

use super::sensitivity::normal_equations;
use super::{FitProblem, PARAMETER_NAMES};
use crate::error::{IdentError, err};
use nalgebra::{DMatrix, DVector};

/// A parameter counts as poorly determined above this relative standard deviation: the
/// data cannot place it within +-3 % (3 sigma) of its value.
pub const POOR_RELATIVE_STD: f64 = 0.01;
/// Pairs with a larger absolute correlation are flagged.
pub const HIGH_CORRELATION: f64 = 0.95;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Identifiability {
    /// The free parameters, in order.
    pub names: Vec<String>,
    pub values: Vec<f64>,
    /// sqrt(r^T r / (2N - n)): the noise estimated from the residuals, m.
    pub noise_std_estimated: f64,
    /// The noise level the bounds use, m.
    pub noise_std: f64,
    /// Cramer-Rao standard deviation of the noise variance estimate itself,
    /// sqrt(2 / (2N - n)) sigma^2 (m^2): how well the residuals pin the noise down.
    pub noise_variance_std: f64,
    /// RMS over the trajectory of d(CoM)/d(parameter), m per unit parameter.
    pub sensitivity_rms: Vec<f64>,
    /// Cramer-Rao standard deviations sqrt(diag F^-1).
    pub std: Vec<f64>,
    /// std / |value|.
    pub relative_std: Vec<f64>,
    /// Correlation matrix of F^-1.
    pub correlation: Vec<Vec<f64>>,
    /// Condition number of the correlation-scaled Fisher matrix.
    pub condition: f64,
    /// Unit direction (in relative parameter changes) the data determine least.
    pub weakest_direction: Vec<f64>,
    /// Parameters with relative std above [`POOR_RELATIVE_STD`].
    pub poorly_determined: Vec<String>,
    /// Pairs with |correlation| above [`HIGH_CORRELATION`].
    pub correlated: Vec<(String, String, f64)>,
}

/// The identifiability of `problem`'s free parameters at `p`; `noise_std` None uses
/// the noise estimated from the residuals at `p`.
pub fn identifiability(
    problem: &FitProblem,
    p: &[f64],
    noise_std: Option<f64>,
) -> Result<Identifiability, IdentError> {
    let n = problem.dim();
    let full = problem.full(p);
    let ne = normal_equations(&problem.model(&full), problem.data);
    if !ne.sse.is_finite() {
        return err("the model diverges at these parameters");
    }
    let dof = ne.residuals.saturating_sub(n).max(1);
    let noise_std_estimated = (ne.sse / dof as f64).sqrt();
    let sigma = noise_sigma(noise_std, noise_std_estimated)?;
    let jtj = DMatrix::from_fn(n, n, |r, c| ne.jtj[problem.free[r]][problem.free[c]]);
    let names: Vec<String> = problem
        .free
        .iter()
        .map(|&i| PARAMETER_NAMES[i].to_string())
        .collect();
    check_informative(&jtj, &names)?;
    // Scale to unit diagonal so the inverse and the condition number are meaningful
    // whatever the parameters' effect sizes.
    let d: Vec<f64> = (0..n).map(|i| jtj[(i, i)].sqrt()).collect();
    let scaled = DMatrix::from_fn(n, n, |r, c| jtj[(r, c)] / (d[r] * d[c]));
    let eig = scaled.clone().symmetric_eigen();
    let (lo, hi) = extreme_indices(&eig.eigenvalues);
    let condition = eig.eigenvalues[hi] / eig.eigenvalues[lo];
    let Some(inv_scaled) = scaled
        .try_inverse()
        .filter(|_| condition.is_finite() && condition < 1e15)
    else {
        return err(format!(
            "the Fisher information is singular (condition {condition:e}): the parameters {} cannot be told apart by these data",
            names.join(", ")
        ));
    };
    let cov = DMatrix::from_fn(n, n, |r, c| {
        sigma * sigma * inv_scaled[(r, c)] / (d[r] * d[c])
    });
    let std: Vec<f64> = (0..n).map(|i| cov[(i, i)].sqrt()).collect();
    let correlation: Vec<Vec<f64>> = (0..n)
        .map(|r| (0..n).map(|c| cov[(r, c)] / (std[r] * std[c])).collect())
        .collect();
    let relative_std: Vec<f64> = (0..n).map(|i| std[i] / p[i].abs()).collect();
    let weakest = weakest_direction(&eig.eigenvectors, lo, &d, p);
    let correlated = correlated_pairs(&correlation, &names);
    Ok(Identifiability {
        poorly_determined: (0..n)
            .filter(|&i| relative_std[i] > POOR_RELATIVE_STD)
            .map(|i| names[i].clone())
            .collect(),
        sensitivity_rms: (0..n)
            .map(|i| (jtj[(i, i)] / ne.residuals as f64).sqrt())
            .collect(),
        values: p.to_vec(),
        names,
        noise_std_estimated,
        noise_std: sigma,
        noise_variance_std: (2.0 / dof as f64).sqrt() * sigma * sigma,
        std,
        relative_std,
        correlation,
        condition,
        weakest_direction: weakest,
        correlated,
    })
}

/// The noise standard deviation to use: the given one (positive), else the estimate
/// from the residuals.
fn noise_sigma(noise_std: Option<f64>, estimated: f64) -> Result<f64, IdentError> {
    match noise_std {
        Some(s) if s.is_finite() && s > 0.0 => Ok(s),
        Some(s) => err(format!(
            "noise standard deviation must be positive, got {s}"
        )),
        None => Ok(estimated),
    }
}

/// Errors naming a parameter the CoM does not depend on (a zero diagonal of J^T J).
fn check_informative(jtj: &DMatrix<f64>, names: &[String]) -> Result<(), IdentError> {
    for i in 0..jtj.nrows() {
        if jtj[(i, i)].is_nan() || jtj[(i, i)] <= 0.0 {
            return err(format!(
                "the data carry no information on {}: the CoM does not depend on it (e.g. eta without double support)",
                names[i]
            ));
        }
    }
    Ok(())
}

/// Indices of the smallest and the largest value (the first of equals).
fn extreme_indices(values: &DVector<f64>) -> (usize, usize) {
    let (mut lo, mut hi) = (0, 0);
    for i in 0..values.len() {
        if values[i] < values[lo] {
            lo = i;
        }
        if values[i] > values[hi] {
            hi = i;
        }
    }
    (lo, hi)
}

/// The eigenvector `lo` of the unit-diagonal Fisher matrix back in relative parameter
/// changes (`/ d_i / |p_i|`), normalised, its largest entry positive.
fn weakest_direction(vectors: &DMatrix<f64>, lo: usize, d: &[f64], p: &[f64]) -> Vec<f64> {
    let mut weakest: Vec<f64> = (0..d.len())
        .map(|i| vectors[(i, lo)] / d[i] / p[i].abs())
        .collect();
    let norm = weakest.iter().map(|v| v * v).sum::<f64>().sqrt();
    let sign = if weakest
        .iter()
        .fold(0.0, |a: f64, v| if v.abs() > a.abs() { *v } else { a })
        < 0.0
    {
        -1.0
    } else {
        1.0
    };
    for v in &mut weakest {
        *v *= sign / norm;
    }
    weakest
}

/// Parameter pairs whose correlation exceeds [`HIGH_CORRELATION`] in magnitude.
fn correlated_pairs(correlation: &[Vec<f64>], names: &[String]) -> Vec<(String, String, f64)> {
    let mut correlated = Vec::new();
    for r in 0..correlation.len() {
        for c in 0..r {
            if correlation[r][c].abs() > HIGH_CORRELATION {
                correlated.push((names[c].clone(), names[r].clone(), correlation[r][c]));
            }
        }
    }
    correlated
}
