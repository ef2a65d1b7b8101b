//! Gramians, Hankel singular values and balanced truncation (seed 003, Figs 51
//! and 54: "Hankel singular values ... determined from the controllability and
//! observability Gramians").
//!
//! The Gramians of a stable discrete system solve the discrete Lyapunov (Stein)
//! equations `A P A^T - P + B B^T = 0` and `A^T Q A - Q + C^T C = 0`. They are
//! solved here by the Bartels-Stewart method in Kitagawa's form for the discrete
//! equation: `A = U T U^T` (real Schur form, `T` quasi-triangular with 1x1 and
//! 2x2 diagonal blocks), the transformed equation `T X T^T - X + U^T Q U = 0` is
//! solved block column by block column from the last one, each block by a
//! Kronecker system of order at most 4, and `X = U X~ U^T`: O(n^3) work.

// The block solves index small fixed arrays by position, as the formulas do.
#![allow(clippy::needless_range_loop)]

use crate::error::{Result, SysidError};
use crate::linalg::psd_sqrt;
use crate::ss::StateSpace;
use nalgebra::{DMatrix, Schur};

/// The diagonal blocks `(start, size)` of a quasi-triangular `T` (sizes 1 or 2),
/// after setting the entries below the subdiagonal and negligible subdiagonal
/// entries to zero.
fn schur_blocks(t: &mut DMatrix<f64>) -> Vec<(usize, usize)> {
    let n = t.nrows();
    for j in 0..n {
        for i in j + 2..n {
            t[(i, j)] = 0.0;
        }
    }
    for i in 0..n.saturating_sub(1) {
        let s = t[(i + 1, i)].abs();
        if s != 0.0 && s <= f64::EPSILON * (t[(i, i)].abs() + t[(i + 1, i + 1)].abs()) {
            t[(i + 1, i)] = 0.0;
        }
    }
    let mut blocks = Vec::new();
    let mut i = 0;
    while i < n {
        if i + 1 < n && t[(i + 1, i)] != 0.0 {
            blocks.push((i, 2));
            i += 2;
        } else {
            blocks.push((i, 1));
            i += 1;
        }
    }
    blocks
}

/// Solve `(Tj kron Ti - I) vec(Y) = vec(R)` for `Y` (`si x sj`, at most 2 x 2)
/// by Gaussian elimination with partial pivoting. `None` when singular, i.e. when
/// an eigenvalue of `Ti` times one of `Tj` is 1.
fn small_stein(
    ti: &[[f64; 2]; 2],
    si: usize,
    tj: &[[f64; 2]; 2],
    sj: usize,
    r: &mut [f64; 4],
) -> Option<()> {
    let m = si * sj;
    let mut k = [[0.0f64; 4]; 4];
    // vec index p = a + si * b for Y[a][b]; (Tj kron Ti)[(a + si b), (c + si d)] = Tj[b][d] Ti[a][c]
    for b in 0..sj {
        for a in 0..si {
            let p = a + si * b;
            for d in 0..sj {
                for c in 0..si {
                    let q = c + si * d;
                    k[p][q] = tj[b][d] * ti[a][c] - if p == q { 1.0 } else { 0.0 };
                }
            }
        }
    }
    let scale = k
        .iter()
        .take(m)
        .flat_map(|row| row.iter().take(m))
        .fold(0.0f64, |a, x| a.max(x.abs()));
    for col in 0..m {
        let piv = (col..m).max_by(|&x, &y| k[x][col].abs().total_cmp(&k[y][col].abs()))?;
        if k[piv][col].abs() <= 1e3 * f64::EPSILON * scale.max(f64::MIN_POSITIVE) {
            return None;
        }
        k.swap(col, piv);
        r.swap(col, piv);
        for row in col + 1..m {
            let f = k[row][col] / k[col][col];
            for c in col..m {
                k[row][c] -= f * k[col][c];
            }
            r[row] -= f * r[col];
        }
    }
    for col in (0..m).rev() {
        let mut s = r[col];
        for c in col + 1..m {
            s -= k[col][c] * r[c];
        }
        r[col] = s / k[col][col];
    }
    Some(())
}

fn block(t: &DMatrix<f64>, (s, n): (usize, usize)) -> [[f64; 2]; 2] {
    let mut b = [[0.0; 2]; 2];
    for i in 0..n {
        for j in 0..n {
            b[i][j] = t[(s + i, s + j)];
        }
    }
    b
}

/// A real Schur form `A = U T U^T` kept for solving several Lyapunov equations
/// with the same `A` (both Gramians need `A` and `A^T`).
pub struct LyapunovSolver {
    u: DMatrix<f64>,
    t: DMatrix<f64>,
    blocks: Vec<(usize, usize)>,
    /// `J T^T J` (`J` reverses the index order): upper quasi-triangular again, for `A^T`.
    t_rev: DMatrix<f64>,
    blocks_rev: Vec<(usize, usize)>,
}

impl LyapunovSolver {
    pub fn new(a: &DMatrix<f64>) -> Result<LyapunovSolver> {
        let n = a.nrows();
        if a.ncols() != n {
            return Err(SysidError::order("Lyapunov equation: A must be square"));
        }
        if !a.iter().all(|x| x.is_finite()) {
            return Err(SysidError::numerical(
                "Lyapunov equation: A holds a non-finite number",
            ));
        }
        let (u, mut t) = if n == 0 {
            (DMatrix::zeros(0, 0), DMatrix::zeros(0, 0))
        } else {
            Schur::try_new(a.clone(), f64::EPSILON, 10_000 * n)
                .ok_or_else(|| SysidError::numerical("real Schur decomposition did not converge"))?
                .unpack()
        };
        let blocks = schur_blocks(&mut t);
        let t_rev = DMatrix::from_fn(n, n, |i, j| t[(n - 1 - j, n - 1 - i)]);
        let blocks_rev = blocks.iter().rev().map(|&(s, k)| (n - s - k, k)).collect();
        Ok(LyapunovSolver {
            u,
            t,
            blocks,
            t_rev,
            blocks_rev,
        })
    }

    /// `X` with `A X A^T - X + Q = 0`.
    pub fn solve(&self, q: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        let n = self.t.nrows();
        check_q(q, n)?;
        let qt = self.u.transpose() * q * &self.u;
        let x = solve_quasi_triangular(&self.t, &self.blocks, &qt)?;
        let full = &self.u * x * self.u.transpose();
        Ok((&full + full.transpose()) * 0.5)
    }

    /// `X` with `A^T X A - X + Q = 0`: with `A^T = U T^T U^T` and the index order
    /// reversed, `T^T` is upper quasi-triangular, so the same block solver applies.
    pub fn solve_transposed(&self, q: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        let n = self.t.nrows();
        check_q(q, n)?;
        let qt = self.u.transpose() * q * &self.u;
        let qr = DMatrix::from_fn(n, n, |i, j| qt[(n - 1 - i, n - 1 - j)]);
        let xr = solve_quasi_triangular(&self.t_rev, &self.blocks_rev, &qr)?;
        let x = DMatrix::from_fn(n, n, |i, j| xr[(n - 1 - i, n - 1 - j)]);
        let full = &self.u * x * self.u.transpose();
        Ok((&full + full.transpose()) * 0.5)
    }
}

fn check_q(q: &DMatrix<f64>, n: usize) -> Result<()> {
    if q.shape() != (n, n) {
        return Err(SysidError::order(
            "Lyapunov equation: A and Q must be square and of equal size",
        ));
    }
    if !q.iter().all(|x| x.is_finite()) {
        return Err(SysidError::numerical(
            "Lyapunov equation: Q holds a non-finite number",
        ));
    }
    Ok(())
}

/// Solve `T X T^T - X + Q = 0` for upper quasi-triangular `T` with diagonal blocks `blocks`.
fn solve_quasi_triangular(
    t: &DMatrix<f64>,
    blocks: &[(usize, usize)],
    qt: &DMatrix<f64>,
) -> Result<DMatrix<f64>> {
    let n = t.nrows();
    let mut x = DMatrix::<f64>::zeros(n, n);
    let mut rhs = DMatrix::<f64>::zeros(n, 2);
    let mut z = DMatrix::<f64>::zeros(n, 2);
    for &(cj, sj) in blocks.iter().rev() {
        let tail = cj + sj;
        let tjj = block(t, (cj, sj));
        // Z = sum_{l > j} X[:, l] T[j, l]^T over the columns already solved.
        let mut zv = z.view_mut((0, 0), (n, sj));
        if tail < n {
            zv.gemm(
                1.0,
                &x.view((0, tail), (n, n - tail)),
                &t.view((cj, tail), (sj, n - tail)).transpose(),
                0.0,
            );
        } else {
            zv.fill(0.0);
        }
        // RHS = -Q~[:, j] - T Z.
        let mut rv = rhs.view_mut((0, 0), (n, sj));
        rv.copy_from(&(-qt.view((0, cj), (n, sj))));
        rv.gemm(-1.0, t, &z.view((0, 0), (n, sj)), 1.0);
        // Row blocks from the last: T_ii Y T_jj^T - Y = RHS_i - (sum_{k>i} T_ik X_kj) T_jj^T.
        for &(ci, si) in blocks.iter().rev() {
            let itail = ci + si;
            let mut s = [[0.0f64; 2]; 2];
            for a_ in 0..si {
                for b_ in 0..sj {
                    let mut acc = 0.0;
                    for kk in itail..n {
                        acc += t[(ci + a_, kk)] * x[(kk, cj + b_)];
                    }
                    s[a_][b_] = acc;
                }
            }
            let mut r = [0.0f64; 4];
            for b_ in 0..sj {
                for a_ in 0..si {
                    let mut st = 0.0;
                    for d in 0..sj {
                        st += s[a_][d] * tjj[b_][d];
                    }
                    r[a_ + si * b_] = rhs[(ci + a_, b_)] - st;
                }
            }
            let tii = block(t, (ci, si));
            if small_stein(&tii, si, &tjj, sj, &mut r).is_none() {
                let ev = |bl: &[[f64; 2]; 2], sz: usize| {
                    if sz == 1 {
                        format!("{:.6}", bl[0][0])
                    } else {
                        let tr = bl[0][0] + bl[1][1];
                        let det = bl[0][0] * bl[1][1] - bl[0][1] * bl[1][0];
                        format!(
                            "a complex pair of modulus {:.6}",
                            det.abs().sqrt().max(tr.abs() / 2.0)
                        )
                    }
                };
                return Err(SysidError::numerical(format!(
                    "Lyapunov equation has no unique solution: eigenvalues {} and {} of A multiply to 1 \
                     (the system is not stable)",
                    ev(&tii, si),
                    ev(&tjj, sj)
                )));
            }
            for b_ in 0..sj {
                for a_ in 0..si {
                    x[(ci + a_, cj + b_)] = r[a_ + si * b_];
                }
            }
        }
    }
    Ok(x)
}

/// Solve the discrete Lyapunov equation `A X A^T - X + Q = 0` (Bartels-Stewart,
/// see the module notes). Requires that no two eigenvalues of `A` multiply to 1,
/// which holds for every stable `A`; the error says which pair fails otherwise.
pub fn solve_discrete_lyapunov(a: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    if q.shape() != a.shape() {
        return Err(SysidError::order(
            "Lyapunov equation: A and Q must be square and of equal size",
        ));
    }
    LyapunovSolver::new(a)?.solve(q)
}

/// Stability check with a message fit for a user: the spectral radius and how
/// many poles lie on or outside the unit circle.
pub fn check_stable(model: &StateSpace, what: &str) -> Result<()> {
    let poles = model.poles().ok_or_else(|| {
        SysidError::numerical(format!(
            "{what}: the eigenvalues of A could not be computed"
        ))
    })?;
    let outside: Vec<f64> = poles
        .iter()
        .map(|p| p.norm())
        .filter(|&r| r >= 1.0)
        .collect();
    if !outside.is_empty() {
        let rho = outside.iter().fold(0.0f64, |a, &b| a.max(b));
        return Err(SysidError::numerical(format!(
            "{what} is unstable: {} of its {} poles lie on or outside the unit circle (largest |pole| = {rho:.6})",
            outside.len(),
            poles.len()
        )));
    }
    Ok(())
}

/// Controllability Gramian `P`: `A P A^T - P + B B^T = 0`.
pub fn controllability_gramian(a: &DMatrix<f64>, b: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    solve_discrete_lyapunov(a, &(b * b.transpose()))
}

/// Observability Gramian `Q`: `A^T Q A - Q + C^T C = 0`.
pub fn observability_gramian(a: &DMatrix<f64>, c: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    LyapunovSolver::new(a)?.solve_transposed(&(c.transpose() * c))
}

/// A square-root factor `L L^T = S` of a Gramian: Cholesky when `S` is positive
/// definite (cheap), else the eigendecomposition (semi-definite: uncontrollable or
/// unobservable parts).
fn gramian_factor(s: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    match s.clone().cholesky() {
        Some(c) => Ok(c.unpack()),
        None => psd_sqrt(s),
    }
}

/// Square-root factors of both Gramians and the SVD of `Lo^T Lc`, shared by the
/// Hankel singular values and balanced truncation.
struct Balancing {
    lc: DMatrix<f64>,
    lo: DMatrix<f64>,
    u: DMatrix<f64>,
    sigma: Vec<f64>,
    v: DMatrix<f64>,
}

fn balancing(a: &DMatrix<f64>, b: &DMatrix<f64>, c: &DMatrix<f64>) -> Result<Balancing> {
    let n = a.nrows();
    if n == 0 || b.ncols() == 0 || c.nrows() == 0 {
        return Ok(Balancing {
            lc: DMatrix::zeros(n, 0),
            lo: DMatrix::zeros(n, 0),
            u: DMatrix::zeros(n, 0),
            sigma: vec![0.0; n],
            v: DMatrix::zeros(n, 0),
        });
    }
    let solver = LyapunovSolver::new(a)?;
    let p = solver.solve(&(b * b.transpose()))?;
    let q = solver.solve_transposed(&(c.transpose() * c))?;
    let lc = gramian_factor(&p)?;
    let lo = gramian_factor(&q)?;
    let m = lo.transpose() * &lc;
    let svd = nalgebra::SVD::try_new(m, true, true, f64::EPSILON, 10_000)
        .ok_or_else(|| SysidError::numerical("SVD of the Gramian factors did not converge"))?;
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&i, &j| svd.singular_values[j].total_cmp(&svd.singular_values[i]));
    let (Some(su), Some(svt)) = (svd.u, svd.v_t) else {
        return Err(SysidError::numerical(
            "SVD of the Gramian factors gave no vectors",
        ));
    };
    let mut u = DMatrix::zeros(n, n);
    let mut v = DMatrix::zeros(n, n);
    let mut sigma = Vec::with_capacity(n);
    for (dst, &src) in order.iter().enumerate() {
        u.set_column(dst, &su.column(src));
        v.set_column(dst, &svt.row(src).transpose());
        sigma.push(svd.singular_values[src]);
    }
    Ok(Balancing {
        lc,
        lo,
        u,
        sigma,
        v,
    })
}

/// Hankel singular values of the input-to-output part `(A, B, C)` in decreasing
/// order: square roots of the eigenvalues of `P Q`, computed as the singular
/// values of `Lo^T Lc` with `P = Lc Lc^T`, `Q = Lo Lo^T` (seed 003, Figs 51, 54).
/// An unstable model has no Gramians: the error says so.
pub fn hankel_singular_values(model: &StateSpace) -> Result<Vec<f64>> {
    check_stable(model, "the model")?;
    hankel_singular_values_of_stable(model)
}

/// [`hankel_singular_values`] for a model already known to be stable (no second
/// eigenvalue computation); an unstable one gives an error from the Lyapunov solver.
pub fn hankel_singular_values_of_stable(model: &StateSpace) -> Result<Vec<f64>> {
    Ok(balancing(&model.a, &model.b, &model.c)?.sigma)
}

/// Balanced truncation to `order` states by the square-root method: with
/// `Lo^T Lc = U S V^T`, `T_r = Lc V_r S_r^-1/2`, `T_l = S_r^-1/2 U_r^T Lo^T`, the
/// reduced model is `(T_l A T_r, T_l B, C T_r, D, T_l K)`. With `with_noise` the
/// balancing uses the inputs `[B K]` (the measured inputs and the innovations),
/// so the noise model is kept as well as the input-output dynamics. Returns the
/// reduced model and the Hankel singular values it was cut from.
pub fn balanced_truncation(
    model: &StateSpace,
    order: usize,
    with_noise: bool,
) -> Result<(StateSpace, Vec<f64>)> {
    check_stable(model, "the model to reduce")?;
    let n = model.n();
    if order == 0 || order > n {
        return Err(SysidError::order(format!(
            "cannot reduce a model of order {n} to order {order}: choose 1..={n}"
        )));
    }
    let bin = if with_noise {
        let mut m = DMatrix::zeros(n, model.nu() + model.ny());
        m.view_mut((0, 0), (n, model.nu())).copy_from(&model.b);
        m.view_mut((0, model.nu()), (n, model.ny()))
            .copy_from(&model.k);
        m
    } else {
        model.b.clone()
    };
    let bal = balancing(&model.a, &bin, &model.c)?;
    let s_r = bal.sigma[order - 1];
    let negligible = f64::EPSILON * bal.sigma[0].max(f64::MIN_POSITIVE) * n as f64;
    if s_r.is_nan() || s_r <= negligible {
        return Err(SysidError::order(format!(
            "the model has only {} numerically non-zero Hankel singular values; reduce to at most that order",
            bal.sigma
                .iter()
                .filter(|&&s| s > f64::EPSILON * bal.sigma[0] * n as f64)
                .count()
        )));
    }
    let mut tr = &bal.lc * bal.v.columns(0, order);
    let mut tl = bal.u.columns(0, order).transpose() * bal.lo.transpose();
    for i in 0..order {
        let f = 1.0 / bal.sigma[i].sqrt();
        tr.column_mut(i).scale_mut(f);
        tl.row_mut(i).scale_mut(f);
    }
    let reduced = StateSpace {
        a: &tl * &model.a * &tr,
        b: &tl * &model.b,
        c: &model.c * &tr,
        d: model.d.clone(),
        k: &tl * &model.k,
        noise_covariance: model.noise_covariance.clone(),
        sample_time: model.sample_time,
    };
    Ok((reduced, bal.sigma))
}

/// Model-order help from Hankel singular values (sorted, decreasing).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct OrderSuggestion {
    /// The order before the largest relative drop `sigma_r / sigma_{r+1}`.
    pub order: usize,
    /// That ratio: the larger, the clearer the cut.
    pub gap_ratio: f64,
    /// Per order `r = 1..n-1`: `2 (sigma_{r+1} + .. + sigma_n)`, the balanced-truncation
    /// bound on the largest gain error of the reduced model (H-infinity norm).
    pub truncation_error_bound: Vec<f64>,
}

/// Suggest an order from the largest gap in the Hankel singular values; `None`
/// with fewer than two values.
pub fn suggest_order(hsv: &[f64]) -> Option<OrderSuggestion> {
    if hsv.len() < 2 {
        return None;
    }
    let floor = hsv[0] * 1e-14;
    let mut best = (1usize, 0.0f64);
    for r in 1..hsv.len() {
        let ratio = hsv[r - 1] / hsv[r].max(floor);
        if ratio > best.1 {
            best = (r, ratio);
        }
    }
    let mut bound = Vec::with_capacity(hsv.len() - 1);
    for r in 1..hsv.len() {
        bound.push(2.0 * hsv[r..].iter().sum::<f64>());
    }
    Some(OrderSuggestion {
        order: best.0,
        gap_ratio: best.1,
        truncation_error_bound: bound,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lyapunov_residual_small_on_mixed_blocks() {
        // Complex pair, real poles, negative pole, nilpotent-like coupling.
        let a = DMatrix::from_row_slice(
            5,
            5,
            &[
                0.5, -0.6, 0.1, 0.0, 0.2, 0.6, 0.5, 0.0, 0.3, 0.0, 0.0, 0.0, -0.7, 0.4, 0.1, 0.1,
                0.0, 0.0, 0.2, 0.0, 0.0, 0.2, 0.0, 0.1, 0.9,
            ],
        );
        let g = DMatrix::from_fn(5, 2, |i, j| ((i + 2 * j) as f64 * 0.37).sin());
        let q = &g * g.transpose();
        let x = solve_discrete_lyapunov(&a, &q).unwrap();
        let res = &a * &x * a.transpose() - &x + &q;
        assert!(
            res.amax() < 1e-13 * x.amax().max(1.0),
            "residual {}",
            res.amax()
        );
    }

    #[test]
    fn unstable_pair_is_reported() {
        let a = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 0.5]);
        let e = solve_discrete_lyapunov(&a, &DMatrix::identity(2, 2)).unwrap_err();
        assert!(e.message.contains("multiply to 1"), "{e}");
    }

    #[test]
    fn gap_suggestion() {
        let s = suggest_order(&[10.0, 8.0, 5.0, 0.01, 0.005]).unwrap();
        assert_eq!(s.order, 3);
        assert!((s.gap_ratio - 500.0).abs() < 1e-9);
        assert!((s.truncation_error_bound[2] - 0.03).abs() < 1e-12);
    }
}
