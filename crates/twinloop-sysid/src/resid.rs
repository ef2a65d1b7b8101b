//! Residual tests (seed 003, section 8.1, eqs 11-12): the one-step prediction
//! errors of a good model are white (eq 11: every autocorrelation is zero away
//! from lag 0), uncorrelated with each other away from lag 0 (eq 12), and
//! uncorrelated with past inputs. Correlations are normalised sample
//! correlations of the mean-removed sequences; the 99 % band is
//! `+-2.5758/sqrt(N)`. Each function also gets a test statistic and p-value:
//!
//! * autocorrelation: the Ljung-Box statistic `N(N+2) sum_{t=1..M} r(t)^2/(N-t)`,
//!   chi-square with `M` degrees of freedom;
//! * residual-residual cross-correlation at lags `+-1..+-M`: `r(t)` and `r(-t)` of
//!   white sequences are each `N(0, 1/N)` with covariance `c^2/N` (`c` the lag-0
//!   correlation), so `N (a^2 + b^2 - 2 c^2 a b) / (1 - c^4)` per lag pair, summed:
//!   chi-square with `2M` degrees of freedom;
//! * residual-input cross-correlation at lags `0..M` (residual after the input):
//!   for white residuals the lags have covariance `R_u / N` with `R_u` the input's
//!   autocorrelation (Toeplitz), so `N r^T R_u^+ r`, chi-square with `rank(R_u)`
//!   degrees of freedom (a pseudo-inverse: periodic gait inputs make `R_u` singular).
//!
//! A family passes when no p-value is below `0.01 / (number of tests)`
//! (Bonferroni: at most a 1 % chance that a correct model fails the family).

use crate::stats::{NORMAL_99_TWO_SIDED, chi2_sf};
use nalgebra::{DMatrix, SymmetricEigen};

/// One correlation function and its test.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CorrelationTest {
    /// The residual (an output's name).
    pub residual: String,
    /// The other sequence: the same residual, another output's residual, or an input.
    pub with: String,
    /// Lags of `correlation`: `r(t) = corr(a(k + t), b(k))`.
    pub lags: Vec<i64>,
    pub correlation: Vec<f64>,
    /// Lags outside the 99 % band among those tested.
    pub outside_band: usize,
    pub statistic: f64,
    pub degrees_of_freedom: f64,
    pub p_value: f64,
    /// `p_value` above the family's Bonferroni threshold.
    pub pass: bool,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ResidualTests {
    pub samples: usize,
    pub max_lag: usize,
    /// Half-width of the 99 % band for one correlation value, `2.5758/sqrt(N)`.
    pub band_99: f64,
    /// Autocorrelation per output, lags 0..M (seed eq 11).
    pub autocorrelation: Vec<CorrelationTest>,
    /// Cross-correlation per pair of outputs, lags -M..M (seed eq 12); lag 0 is
    /// shown but not tested (innovations may be correlated at the same instant).
    pub cross_correlation: Vec<CorrelationTest>,
    /// Residual-input cross-correlation per output and input, lags -M..M; lags
    /// 0..M are tested (negative lags reveal feedback, not a model error).
    pub input_correlation: Vec<CorrelationTest>,
    /// Autocorrelation and residual-residual tests all pass.
    pub whiteness_pass: bool,
    /// Residual-input tests all pass.
    pub independence_pass: bool,
    pub pass: bool,
    pub summary: String,
}

/// `r(t) = sum_k a(k+t) b(k) / sqrt(sum a^2 sum b^2)` for `t = -m..=m`, of the
/// mean-removed sequences.
pub fn cross_correlation(a: &[f64], b: &[f64], max_lag: usize) -> Vec<f64> {
    let n = a.len().min(b.len());
    let mean = |v: &[f64]| v[..n].iter().sum::<f64>() / n.max(1) as f64;
    let (ma, mb) = (mean(a), mean(b));
    let a: Vec<f64> = a[..n].iter().map(|x| x - ma).collect();
    let b: Vec<f64> = b[..n].iter().map(|x| x - mb).collect();
    let den = (a.iter().map(|x| x * x).sum::<f64>() * b.iter().map(|x| x * x).sum::<f64>()).sqrt();
    let mut out = Vec::with_capacity(2 * max_lag + 1);
    for t in -(max_lag as i64)..=(max_lag as i64) {
        let mut s = 0.0;
        if t >= 0 {
            let t = t as usize;
            for k in 0..n.saturating_sub(t) {
                s += a[k + t] * b[k];
            }
        } else {
            let t = (-t) as usize;
            for k in 0..n.saturating_sub(t) {
                s += a[k] * b[k + t];
            }
        }
        out.push(if den > 0.0 { s / den } else { 0.0 });
    }
    out
}

fn centred(row: nalgebra::RowDVector<f64>) -> Vec<f64> {
    let m = row.mean();
    row.iter().map(|x| x - m).collect()
}

/// Run all tests on residuals `e` (`ny x N`) and inputs `u` (`nu x N`), lags up to
/// `max_lag` (MATLAB's `resid` uses 25).
pub fn residual_tests(
    e: &DMatrix<f64>,
    u: &DMatrix<f64>,
    output_names: &[String],
    input_names: &[String],
    max_lag: usize,
) -> ResidualTests {
    let n = e.ncols();
    let m = max_lag.min(n.saturating_sub(2)).max(1);
    let nf = n as f64;
    let lagging = Lagging {
        m,
        nf,
        band: NORMAL_99_TWO_SIDED / nf.sqrt(),
        lags: (-(m as i64)..=(m as i64)).collect(),
    };
    let es: Vec<Vec<f64>> = (0..e.nrows())
        .map(|i| centred(e.row(i).into_owned()))
        .collect();
    let us: Vec<Vec<f64>> = (0..u.nrows())
        .map(|i| centred(u.row(i).into_owned()))
        .collect();

    let mut auto = autocorrelation_tests(&es, output_names, &lagging);
    let mut cross = output_cross_tests(&es, output_names, &lagging);
    let mut input_tests = input_cross_tests(&es, &us, output_names, input_names, &lagging);
    set_verdicts(&mut auto, &mut cross, &mut input_tests);
    let whiteness_pass = auto.iter().chain(cross.iter()).all(|t| t.pass);
    let independence_pass = input_tests.iter().all(|t| t.pass);
    let summary = summary(
        &auto,
        &cross,
        &input_tests,
        whiteness_pass && independence_pass,
    );
    ResidualTests {
        samples: n,
        max_lag: m,
        band_99: lagging.band,
        autocorrelation: auto,
        cross_correlation: cross,
        input_correlation: input_tests,
        whiteness_pass,
        independence_pass,
        pass: whiteness_pass && independence_pass,
        summary,
    }
}

/// What every test shares: the lag range and the sample count it depends on.
struct Lagging {
    /// Largest lag tested; also the index of lag 0 in a correlation vector.
    m: usize,
    /// Number of samples, as a float.
    nf: f64,
    /// Half-width of the 99 % band.
    band: f64,
    /// `-m..=m`.
    lags: Vec<i64>,
}

/// Ljung-Box test per residual (seed eq 11).
fn autocorrelation_tests(
    es: &[Vec<f64>],
    output_names: &[String],
    l: &Lagging,
) -> Vec<CorrelationTest> {
    let (m, mid, nf, band) = (l.m, l.m, l.nf, l.band);
    let mut auto = Vec::new();
    for (i, ei) in es.iter().enumerate() {
        let r = cross_correlation(ei, ei, m);
        let mut q = 0.0;
        for t in 1..=m {
            q += r[mid + t] * r[mid + t] / (nf - t as f64);
        }
        q *= nf * (nf + 2.0);
        let outside = (1..=m).filter(|&t| r[mid + t].abs() > band).count();
        auto.push(CorrelationTest {
            residual: output_names[i].clone(),
            with: output_names[i].clone(),
            lags: l.lags[mid..].to_vec(),
            correlation: r[mid..].to_vec(),
            outside_band: outside,
            statistic: q,
            degrees_of_freedom: m as f64,
            p_value: chi2_sf(q, m as f64),
            pass: true,
        });
    }
    auto
}

/// One test per pair of residuals at lags `+-1..+-M` (seed eq 12).
fn output_cross_tests(
    es: &[Vec<f64>],
    output_names: &[String],
    l: &Lagging,
) -> Vec<CorrelationTest> {
    let (m, mid, nf, band) = (l.m, l.m, l.nf, l.band);
    let mut cross = Vec::new();
    for i in 0..es.len() {
        for j in i + 1..es.len() {
            let r = cross_correlation(&es[i], &es[j], m);
            let c2 = r[mid] * r[mid];
            let mut s = 0.0;
            for t in 1..=m {
                let (a, b) = (r[mid + t], r[mid - t]);
                s += (a * a + b * b - 2.0 * c2 * a * b) / (1.0 - c2 * c2).max(1e-12);
            }
            s *= nf;
            let outside = (1..=m)
                .map(|t| (r[mid + t].abs() > band) as usize + (r[mid - t].abs() > band) as usize)
                .sum();
            cross.push(CorrelationTest {
                residual: output_names[i].clone(),
                with: output_names[j].clone(),
                lags: l.lags.clone(),
                correlation: r,
                outside_band: outside,
                statistic: s,
                degrees_of_freedom: 2.0 * m as f64,
                p_value: chi2_sf(s, 2.0 * m as f64),
                pass: true,
            });
        }
    }
    cross
}

/// One test per residual and input at lags `0..M`, weighted by the input's own
/// autocorrelation.
fn input_cross_tests(
    es: &[Vec<f64>],
    us: &[Vec<f64>],
    output_names: &[String],
    input_names: &[String],
    l: &Lagging,
) -> Vec<CorrelationTest> {
    let (m, mid, nf, band) = (l.m, l.m, l.nf, l.band);
    // Input autocorrelations (Toeplitz R_u), one pseudo-inverse per input.
    let mut input_tests = Vec::new();
    let ru_pinv: Vec<(DMatrix<f64>, f64)> = us
        .iter()
        .map(|uj| {
            let ra = cross_correlation(uj, uj, m);
            let t = DMatrix::from_fn(m + 1, m + 1, |a, b| ra[mid + a.abs_diff(b)]);
            pseudo_inverse_sym(&t)
        })
        .collect();
    for (i, ei) in es.iter().enumerate() {
        for (j, uj) in us.iter().enumerate() {
            let r = cross_correlation(ei, uj, m);
            let rv = nalgebra::DVector::from_fn(m + 1, |t, _| r[mid + t]);
            let (pinv, rank) = &ru_pinv[j];
            let s = nf * rv.dot(&(pinv * &rv));
            let outside = (0..=m).filter(|&t| r[mid + t].abs() > band).count();
            input_tests.push(CorrelationTest {
                residual: output_names[i].clone(),
                with: input_names[j].clone(),
                lags: l.lags.clone(),
                correlation: r,
                outside_band: outside,
                statistic: s,
                degrees_of_freedom: *rank,
                p_value: if *rank > 0.0 { chi2_sf(s, *rank) } else { 1.0 },
                pass: true,
            });
        }
    }
    input_tests
}

/// Bonferroni per family: whiteness (auto and cross) and independence (inputs).
fn set_verdicts(
    auto: &mut [CorrelationTest],
    cross: &mut [CorrelationTest],
    input_tests: &mut [CorrelationTest],
) {
    let white_count = auto.len() + cross.len();
    let white_thr = 0.01 / white_count.max(1) as f64;
    for t in auto.iter_mut().chain(cross.iter_mut()) {
        t.pass = t.p_value > white_thr;
    }
    let indep_thr = 0.01 / input_tests.len().max(1) as f64;
    for t in input_tests.iter_mut() {
        t.pass = t.p_value > indep_thr;
    }
}

/// One line naming the failed tests (at most 6 of the input ones, as there can be
/// many).
fn summary(
    auto: &[CorrelationTest],
    cross: &[CorrelationTest],
    input_tests: &[CorrelationTest],
    pass: bool,
) -> String {
    let failed = |ts: &[CorrelationTest]| -> Vec<String> {
        ts.iter()
            .filter(|t| !t.pass)
            .map(|t| {
                if t.residual == t.with {
                    format!("{} (p={:.1e})", t.residual, t.p_value)
                } else {
                    format!("{}~{} (p={:.1e})", t.residual, t.with, t.p_value)
                }
            })
            .collect()
    };
    if pass {
        return "pass: residuals are white and uncorrelated with the inputs (family-wise 99 %)"
            .to_string();
    }
    let mut parts = Vec::new();
    let (fa, fc, fi) = (failed(auto), failed(cross), failed(input_tests));
    if !fa.is_empty() {
        parts.push(format!("residuals not white: {}", fa.join(", ")));
    }
    if !fc.is_empty() {
        parts.push(format!(
            "residuals correlated across outputs: {}",
            fc.join(", ")
        ));
    }
    if !fi.is_empty() {
        let shown: Vec<String> = fi.iter().take(6).cloned().collect();
        let more = if fi.len() > 6 {
            format!(" and {} more", fi.len() - 6)
        } else {
            String::new()
        };
        parts.push(format!(
            "residuals correlated with inputs: {}{more}",
            shown.join(", ")
        ));
    }
    format!("fail: {}", parts.join("; "))
}

/// Pseudo-inverse of a symmetric positive semi-definite matrix and its rank
/// (eigenvalues below 1e-8 of the largest are dropped).
fn pseudo_inverse_sym(t: &DMatrix<f64>) -> (DMatrix<f64>, f64) {
    let n = t.nrows();
    let Some(eig) = SymmetricEigen::try_new(t.clone(), f64::EPSILON, 1000 * n.max(1)) else {
        return (DMatrix::zeros(n, n), 0.0);
    };
    let big = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut pinv = DMatrix::zeros(n, n);
    let mut rank = 0.0;
    for (k, &lam) in eig.eigenvalues.iter().enumerate() {
        if lam > 1e-8 * big && lam > 0.0 {
            let v = eig.eigenvectors.column(k);
            pinv += v * v.transpose() / lam;
            rank += 1.0;
        }
    }
    (pinv, rank)
}
