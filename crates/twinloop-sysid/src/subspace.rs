//! Subspace identification (N4SID family): a state-space model in innovations
//! form straight from the data, without iterations, used as the initial
//! estimate of the prediction-error method (as MATLAB's `ssest` does).
//!
//! Steps, with `i` block rows of past and future and `j = N - 2i + 1` columns:
//!
//! 1. Oblique projection `O_i = Y_f /_{U_f} W_p` of the future outputs along the
//!    future inputs onto the past data `W_p = [U_p; Y_p]`: the least-squares fit of
//!    `Y_f` on `[W_p; U_f]`, keeping the `W_p` part. Same for the shifted split
//!    (`O_{i-1}`, past one block longer).
//! 2. SVD of `O_i` with the future inputs projected out (MOESP-style column
//!    weighting); the order is the number of singular values kept (given, or the
//!    largest gap), the extended observability matrix `Gamma_i = U_1 S_1^1/2`.
//! 3. State sequences `X_i = Gamma_i^+ O_i`, `X_{i+1} = Gamma_{i-1}^+ O_{i-1}` and
//!    `A`, `C` from `[X_{i+1}; Y_i] = [A B; C D] [X_i; U_i]` by least squares.
//! 4. `B`, `D` and the initial state again by least squares on the simulated
//!    output, linear in them once `A`, `C` are fixed (unbiased for any noise
//!    colour in open loop).
//! 5. `K` from the residual covariances of step 3 through the Kalman filter
//!    Riccati equation, so the predictor `A - K C` is stable.

use crate::data::IoData;
use crate::error::{Result, SysidError};
use crate::linalg::HouseholderQr;
use crate::ss::{StateSpace, spectral_radius};
use nalgebra::{DMatrix, DVector, SVD};

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SubspaceOptions {
    /// Model order; `None` picks the largest gap in the singular values.
    pub order: Option<usize>,
    /// Block rows of past and future (`i`); `None` chooses `max(10, order/ny + 2)`
    /// within what the record allows.
    pub horizon: Option<usize>,
    /// Estimate a direct feedthrough `D` (MATLAB `ssest`'s default is none).
    pub feedthrough: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct SubspaceResult {
    pub model: StateSpace,
    /// Singular values of the weighted projection, for choosing the order.
    pub singular_values: Vec<f64>,
    pub horizon: usize,
    /// Estimated initial state of the record.
    pub x0: DVector<f64>,
    /// Things the user should know (e.g. the Riccati equation failed and a
    /// least-squares `K` was used).
    pub warnings: Vec<String>,
}

/// Rows `t = 0..j` of block-Hankel data: for every `t`, the samples
/// `t + first .. t + first + blocks` of each channel matrix (`ch x N`) side by side.
fn hankel_rows(parts: &[(&DMatrix<f64>, usize, usize)], j: usize) -> DMatrix<f64> {
    let width: usize = parts.iter().map(|(m, _, b)| m.nrows() * b).sum();
    let mut h = DMatrix::zeros(j, width);
    for t in 0..j {
        let mut c = 0;
        for &(m, first, blocks) in parts {
            for s in 0..blocks {
                for ch in 0..m.nrows() {
                    h[(t, c)] = m[(ch, t + first + s)];
                    c += 1;
                }
            }
        }
    }
    h
}

/// Least squares of `target` on `[keep, other]`: returns the fitted part that
/// comes from `keep` (the oblique projection along `other`).
fn oblique(
    keep: &DMatrix<f64>,
    other: &DMatrix<f64>,
    target: &DMatrix<f64>,
) -> Result<DMatrix<f64>> {
    let (j, nk, no) = (keep.nrows(), keep.ncols(), other.ncols());
    let mut reg = DMatrix::zeros(j, nk + no);
    reg.view_mut((0, 0), (j, nk)).copy_from(keep);
    reg.view_mut((0, nk), (j, no)).copy_from(other);
    let theta = HouseholderQr::new(reg).solve(target).map_err(|_| {
        SysidError::numerical(
            "the subspace regressor (past inputs and outputs, future inputs) is rank-deficient: \
             the inputs do not excite the system over this many block rows of past and \
             future (the horizon; piecewise-constant or periodic inputs, or inputs that copy \
             others); use a shorter horizon, drop the copies, use richer inputs, or start \
             from an ARX model (method arx-reduce-pem)",
        )
    })?;
    Ok(keep * theta.rows(0, nk))
}

/// Subspace identification, see the module notes. Errors when the record is too
/// short for the horizon, the inputs are not exciting, or the order is impossible.
pub fn n4sid(data: &IoData, opts: &SubspaceOptions) -> Result<SubspaceResult> {
    data.check_excitation()?;
    let (n_samples, nu, ny) = (data.len(), data.nu(), data.ny());
    if nu == 0 {
        return Err(SysidError::order(
            "subspace identification here needs at least one input channel",
        ));
    }
    let i = horizon(n_samples, nu, ny, opts)?;
    let j = n_samples + 1 - 2 * i;
    let (u, y) = (&data.u, &data.y);
    // Step 1: oblique projections.
    let wp = hankel_rows(&[(u, 0, i), (y, 0, i)], j);
    let uf = hankel_rows(&[(u, i, i)], j);
    let yf = hankel_rows(&[(y, i, i)], j);
    let oi = oblique(&wp, &uf, &yf)?; // j x i ny  (= O_i^T)
    let wp1 = hankel_rows(&[(u, 0, i + 1), (y, 0, i + 1)], j);
    let uf1 = hankel_rows(&[(u, i + 1, i - 1)], j);
    let yf1 = hankel_rows(&[(y, i + 1, i - 1)], j);
    let oi1 = oblique(&wp1, &uf1, &yf1)?; // j x (i-1) ny
    // Step 2: weighted SVD. O_i with U_f projected out; its left singular vectors
    // (as an i ny x j matrix) are those of R^T from the QR of its transpose.
    let uf_qr = HouseholderQr::new(uf.clone());
    let proj = {
        let coef = uf_qr.solve(&oi)?;
        &oi - &uf * coef
    };
    let r = HouseholderQr::new(proj).r(); // (i ny) x (i ny)
    let svd = SVD::try_new(r.transpose(), true, false, f64::EPSILON, 10_000)
        .ok_or_else(|| SysidError::numerical("SVD of the subspace projection did not converge"))?;
    let mut idx: Vec<usize> = (0..svd.singular_values.len()).collect();
    idx.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let sv: Vec<f64> = idx.iter().map(|&k| svd.singular_values[k]).collect();
    let n = choose_order(opts, &sv, (i - 1) * ny)?;
    let Some(su) = svd.u else {
        return Err(SysidError::numerical("SVD gave no singular vectors"));
    };
    let mut gamma = DMatrix::zeros(i * ny, n);
    for c in 0..n {
        gamma.set_column(c, &(su.column(idx[c]) * sv[c].sqrt()));
    }
    let gamma1 = gamma.rows(0, (i - 1) * ny).into_owned();
    // Step 3: states and A, C.
    let xi = HouseholderQr::new(gamma.clone()).solve(&oi.transpose())?; // n x j
    let xi1 = HouseholderQr::new(gamma1).solve(&oi1.transpose())?; // n x j
    let ui = hankel_rows(&[(u, i, 1)], j); // j x nu
    let yi = hankel_rows(&[(y, i, 1)], j); // j x ny
    let mut reg = DMatrix::zeros(j, n + nu);
    reg.view_mut((0, 0), (j, n)).copy_from(&xi.transpose());
    reg.view_mut((0, n), (j, nu)).copy_from(&ui);
    let ab = HouseholderQr::new(reg.clone()).solve(&xi1.transpose())?; // (n+nu) x n
    let a = ab.rows(0, n).transpose();
    let c = if opts.feedthrough {
        HouseholderQr::new(reg.clone())
            .solve(&yi)?
            .rows(0, n)
            .transpose()
    } else {
        HouseholderQr::new(xi.transpose()).solve(&yi)?.transpose()
    };
    // Step 4: B, D, x0 on the simulated output.
    let (b, d, x0) = fit_b_d_x0(data, &a, &c, opts.feedthrough)?;
    // Step 5: K from the state and output residual covariances.
    let xt = xi.transpose();
    let rho_w = xi1.transpose() - &xt * a.transpose() - &ui * b.transpose(); // j x n
    let rho_v = &yi - &xt * c.transpose() - &ui * d.transpose(); // j x ny
    let jf = j as f64;
    let qn = rho_w.transpose() * &rho_w / jf;
    let sn = rho_w.transpose() * &rho_v / jf;
    let rn = rho_v.transpose() * &rho_v / jf;
    let (k, warnings) = noise_gain(&a, &c, &rho_w, &rho_v, &qn, &sn, &rn)?;
    let mut model = StateSpace {
        a,
        b,
        c,
        d,
        k,
        noise_covariance: rn,
        sample_time: data.sample_time,
    };
    let (_, e) = model.predictor_states(data, Some(&x0))?;
    model.noise_covariance = &e * e.transpose() / n_samples as f64;
    Ok(SubspaceResult {
        model,
        singular_values: sv,
        horizon: i,
        x0,
        warnings,
    })
}

/// The block rows `i` of past and future: the asked horizon, else
/// `max(10, order/ny + 2)`, within the largest the record supports (j rows for
/// i (2 nu + ny) + nu unknowns, with at least twice as many rows as unknowns).
/// Errors when the record allows less than 2 or less than the order needs.
fn horizon(n_samples: usize, nu: usize, ny: usize, opts: &SubspaceOptions) -> Result<usize> {
    // The largest horizon the record supports: j rows for i (2 nu + ny) + nu unknowns,
    // with at least twice as many rows as unknowns.
    let max_i = (1..=n_samples / 2)
        .take_while(|&i| {
            n_samples + 1 >= 2 * i && (n_samples + 1 - 2 * i) >= 2 * ((i + 1) * (2 * nu + ny))
        })
        .last()
        .unwrap_or(0);
    let want = opts.horizon.unwrap_or_else(|| {
        let need = opts.order.map_or(0, |n| n.div_ceil(ny) + 2);
        need.max(10)
    });
    let i = want.min(max_i);
    if i < 2 {
        return Err(SysidError::data(format!(
            "{n_samples} samples are too few for subspace identification with {nu} inputs and {ny} outputs"
        )));
    }
    if let Some(n) = opts.order
        && n > (i - 1) * ny
    {
        return Err(SysidError::order(format!(
            "order {n} needs a horizon of at least {} block rows, but {} samples allow only {i}{}",
            n.div_ceil(ny) + 1,
            n_samples,
            if opts.horizon.is_some() {
                " (or the horizon option is set too low)"
            } else {
                ""
            }
        )));
    }
    Ok(i)
}

/// The model order: the asked one, else the largest gap among the first `nmax + 1`
/// singular values `sv` (sorted, decreasing); it must be positive and supported by a
/// non-zero singular value.
fn choose_order(opts: &SubspaceOptions, sv: &[f64], nmax: usize) -> Result<usize> {
    let n = match opts.order {
        Some(n) => n,
        None => {
            let lim = nmax.min(sv.len() - 1);
            let floor = sv[0] * 1e-12;
            (1..=lim)
                .max_by(|&a, &b| {
                    let ga = sv[a - 1] / sv[a].max(floor);
                    let gb = sv[b - 1] / sv[b].max(floor);
                    ga.total_cmp(&gb)
                })
                .unwrap_or(1)
        }
    };
    if n == 0 {
        return Err(SysidError::order(
            "order 0: a state-space model needs at least one state",
        ));
    }
    if sv[n - 1] <= sv[0] * 1e-12 {
        return Err(SysidError::order(format!(
            "order {n} is more than the data support: only {} singular values of the projection are \
             non-zero; choose a lower order",
            sv.iter().filter(|&&s| s > sv[0] * 1e-12).count()
        )));
    }
    Ok(n)
}

/// The Kalman gain from the state and output residuals' covariances (`qn`, `sn`,
/// `rn`); if the Riccati equation does not converge, the least-squares regression of
/// the state residuals `rho_w` on the output residuals `rho_v`, or zero when that
/// gives an unstable predictor. Returns the warnings those fallbacks raise.
fn noise_gain(
    a: &DMatrix<f64>,
    c: &DMatrix<f64>,
    rho_w: &DMatrix<f64>,
    rho_v: &DMatrix<f64>,
    qn: &DMatrix<f64>,
    sn: &DMatrix<f64>,
    rn: &DMatrix<f64>,
) -> Result<(DMatrix<f64>, Vec<String>)> {
    let n = a.nrows();
    let ny = c.nrows();
    let mut warnings = Vec::new();
    let k = match kalman_gain(a, c, qn, sn, rn) {
        Some(k) => k,
        None => {
            warnings.push(
                "the Kalman filter Riccati equation did not converge; K is the least-squares \
                 regression of the state residuals on the output residuals"
                    .to_string(),
            );
            let ls = HouseholderQr::new(rho_v.clone()).solve(rho_w)?; // ny x n
            let k = ls.transpose();
            if spectral_radius(&(a - &k * c)).is_some_and(|r| r < 1.0) {
                k
            } else {
                warnings.push("that K gave an unstable predictor; K set to zero".to_string());
                DMatrix::zeros(n, ny)
            }
        }
    };
    Ok((k, warnings))
}

/// `B`, `D` (when `feedthrough`) and `x(0)` minimising `sum |y(k) - yhat(k)|^2` of the
/// simulated output `yhat(k) = C A^k x0 + sum_{t<k} C A^{k-1-t} B u(t) + D u(k)`, which
/// is linear in them: one regressor column per unknown, built by simulating the
/// matrix recursions once per input.
pub fn fit_b_d_x0(
    data: &IoData,
    a: &DMatrix<f64>,
    c: &DMatrix<f64>,
    feedthrough: bool,
) -> Result<(DMatrix<f64>, DMatrix<f64>, DVector<f64>)> {
    let (n_samples, nu, ny, n) = (data.len(), data.nu(), data.ny(), a.nrows());
    let nd = if feedthrough { ny * nu } else { 0 };
    let p = n * nu + nd + n;
    if n_samples * ny < 2 * p {
        return Err(SysidError::data(format!(
            "{n_samples} samples of {ny} outputs are too few to fit B, D and x0 ({p} unknowns)"
        )));
    }
    let mut phi = DMatrix::zeros(n_samples * ny, p);
    // Column of B entry (row r, input b): state recursion X_b(k+1) = A X_b(k) + I u_b(k).
    let mut xb = DMatrix::zeros(n, n);
    let mut xn = DMatrix::zeros(n, n);
    let mut cy = DMatrix::zeros(ny, n);
    for bi in 0..nu {
        xb.fill(0.0);
        for k in 0..n_samples {
            cy.gemm(1.0, c, &xb, 0.0);
            for r in 0..n {
                for o in 0..ny {
                    phi[(k * ny + o, bi * n + r)] = cy[(o, r)];
                }
            }
            xn.gemm(1.0, a, &xb, 0.0);
            let ub = data.u[(bi, k)];
            for r in 0..n {
                xn[(r, r)] += ub;
            }
            std::mem::swap(&mut xb, &mut xn);
        }
    }
    if feedthrough {
        for k in 0..n_samples {
            for bi in 0..nu {
                for o in 0..ny {
                    phi[(k * ny + o, n * nu + bi * ny + o)] = data.u[(bi, k)];
                }
            }
        }
    }
    // x0 columns: C A^k.
    let mut ak = DMatrix::<f64>::identity(n, n);
    for k in 0..n_samples {
        cy.gemm(1.0, c, &ak, 0.0);
        for r in 0..n {
            for o in 0..ny {
                phi[(k * ny + o, n * nu + nd + r)] = cy[(o, r)];
            }
        }
        xn.gemm(1.0, a, &ak, 0.0);
        std::mem::swap(&mut ak, &mut xn);
        if ak.amax() > 1e150 {
            // An unstable A: the initial-state columns would overflow; the later
            // samples carry no usable information about x0 anyway.
            for kk in k + 1..n_samples {
                for r in 0..n {
                    for o in 0..ny {
                        phi[(kk * ny + o, n * nu + nd + r)] = 0.0;
                    }
                }
            }
            break;
        }
    }
    let mut target = DMatrix::zeros(n_samples * ny, 1);
    for k in 0..n_samples {
        for o in 0..ny {
            target[(k * ny + o, 0)] = data.y[(o, k)];
        }
    }
    let theta = HouseholderQr::new(phi).solve(&target).map_err(|_| {
        SysidError::numerical(
            "B, D and x0 are not determined by the data (the model is not controllable from the \
             inputs or the inputs are not exciting); try a lower order",
        )
    })?;
    let b = DMatrix::from_fn(n, nu, |r, bi| theta[(bi * n + r, 0)]);
    let d = if feedthrough {
        DMatrix::from_fn(ny, nu, |o, bi| theta[(n * nu + bi * ny + o, 0)])
    } else {
        DMatrix::zeros(ny, nu)
    };
    let x0 = DVector::from_fn(n, |r, _| theta[(n * nu + nd + r, 0)]);
    Ok((b, d, x0))
}

/// Steady-state Kalman predictor gain for `x(k+1) = A x + w`, `y = C x + v` with
/// `cov(w) = Q`, `cov(w, v) = S`, `cov(v) = R`: iterate the Riccati recursion
/// `P <- A P A^T + Q - (A P C^T + S)(C P C^T + R)^-1 (A P C^T + S)^T` to its fixed point,
/// `K = (A P C^T + S)(C P C^T + R)^-1`. `None` if it does not converge or the
/// predictor `A - K C` is not stable.
pub fn kalman_gain(
    a: &DMatrix<f64>,
    c: &DMatrix<f64>,
    q: &DMatrix<f64>,
    s: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Option<DMatrix<f64>> {
    let (n, ny) = (a.nrows(), c.nrows());
    let (at, ct) = (a.transpose(), c.transpose());
    // Work space for the recursion, allocated once.
    let mut p = q.clone();
    let mut pn = DMatrix::zeros(n, n);
    let mut ap = DMatrix::zeros(n, n);
    let mut apc = DMatrix::zeros(n, ny);
    let mut cp = DMatrix::zeros(ny, n);
    let mut cpc = DMatrix::zeros(ny, ny);
    let mut kt = DMatrix::zeros(ny, n);
    for _ in 0..20_000 {
        ap.gemm(1.0, a, &p, 0.0);
        apc.copy_from(s);
        apc.gemm(1.0, &ap, &ct, 1.0);
        cp.gemm(1.0, c, &p, 0.0);
        cpc.copy_from(r);
        cpc.gemm(1.0, &cp, &ct, 1.0);
        let chol = nalgebra::Cholesky::new(std::mem::replace(&mut cpc, DMatrix::zeros(0, 0)))?;
        apc.transpose_to(&mut kt);
        chol.solve_mut(&mut kt); // kt = (C P C^T + R)^-1 (A P C^T + S)^T = K^T
        cpc = chol.unpack_dirty();
        // P' = A P A^T + Q - (A P C^T + S) K^T
        pn.copy_from(q);
        pn.gemm(1.0, &ap, &at, 1.0);
        pn.gemm(-1.0, &apc, &kt, 1.0);
        let mut change = 0.0f64;
        for j in 0..n {
            for i in 0..=j {
                let v = 0.5 * (pn[(i, j)] + pn[(j, i)]);
                change = change.max((v - p[(i, j)]).abs());
                p[(i, j)] = v;
                p[(j, i)] = v;
            }
        }
        if !p.iter().all(|x| x.is_finite()) {
            return None;
        }
        if change <= 1e-13 * p.amax().max(f64::MIN_POSITIVE) {
            let k = kt.transpose();
            return spectral_radius(&(a - &k * c))
                .is_some_and(|rho| rho < 1.0)
                .then_some(k);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gain makes the predictor stable and its error covariance a fixed point
    /// of the Riccati recursion.
    #[test]
    fn kalman_gain_is_the_riccati_fixed_point() {
        let a = DMatrix::from_row_slice(3, 3, &[0.9, 0.2, 0.0, -0.2, 0.9, 0.1, 0.0, 0.0, 0.5]);
        let c = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.5, 0.0, 1.0, -1.0]);
        let g = DMatrix::from_row_slice(3, 2, &[0.3, 0.1, 0.0, 0.4, 0.2, 0.0]);
        let q = &g * g.transpose();
        let s = DMatrix::from_row_slice(3, 2, &[0.01, 0.0, 0.0, 0.02, 0.0, 0.0]);
        let r = DMatrix::from_row_slice(2, 2, &[0.5, 0.1, 0.1, 0.4]);
        let k = kalman_gain(&a, &c, &q, &s, &r).unwrap();
        assert!(spectral_radius(&(&a - &k * &c)).unwrap() < 1.0);
        // Iterate once more from a long run's P: recover P from the closed form.
        let mut p = q.clone();
        for _ in 0..5000 {
            let apc = &a * &p * c.transpose() + &s;
            let cpc = &c * &p * c.transpose() + &r;
            let kk = &apc * cpc.clone().try_inverse().unwrap();
            p = &a * &p * a.transpose() + &q - &kk * apc.transpose();
        }
        let apc = &a * &p * c.transpose() + &s;
        let cpc = &c * &p * c.transpose() + &r;
        let k_ref = &apc * cpc.try_inverse().unwrap();
        assert!((k - k_ref).amax() < 1e-10);
    }
}
