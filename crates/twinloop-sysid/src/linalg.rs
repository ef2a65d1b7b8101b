//! Dense linear algebra the estimators share: a blocked Householder QR for tall
//! least-squares problems, strided transposed views for products such as `J^T J`
//! without copying, and square-root factors of symmetric semi-definite matrices.
//!
//! nalgebra's own QR applies one reflector at a time to the whole trailing
//! matrix; for the tall regressors of identification (1000 x 400) that streams
//! the matrix through the cache hundreds of times. Here reflectors are grouped
//! in panels of [`QR_BLOCK`] columns in the compact WY form `I - V T V^T`
//! (Schreiber and Van Loan), so the trailing update is two matrix products
//! that run at the speed of nalgebra's `gemm`.

use crate::error::{Result, SysidError};
use nalgebra::{DMatrix, Dyn, MatrixView, SymmetricEigen};

/// Columns per Householder panel.
pub const QR_BLOCK: usize = 32;

/// A read-only strided view (any row and column stride).
pub type StridedView<'a> = MatrixView<'a, f64, Dyn, Dyn, Dyn, Dyn>;

/// Below this size nalgebra's `gemm` falls back to column loops that mishandle
/// views with a row stride; [`gemm_tn`] then does its own loops.
const SMALL_DIM: usize = 5;

/// `C <- alpha A^T B + beta C`, where `A` is the block of `a` at `(r0, c0)` of size
/// `rows x cols` and `B` has `rows` rows. The transpose is a strided view over
/// `a`'s storage, so nothing is copied and the product runs in nalgebra's `gemm`.
pub fn gemm_tn(
    c: &mut nalgebra::DMatrixViewMut<f64>,
    alpha: f64,
    a: &DMatrix<f64>,
    (r0, c0): (usize, usize),
    (rows, cols): (usize, usize),
    b: &nalgebra::DMatrixView<f64>,
    beta: f64,
) {
    assert!(
        r0 + rows <= a.nrows() && c0 + cols <= a.ncols(),
        "gemm_tn: block outside A"
    );
    assert_eq!(
        b.nrows(),
        rows,
        "gemm_tn: B must have as many rows as the block of A"
    );
    assert_eq!(
        c.shape(),
        (cols, b.ncols()),
        "gemm_tn: C has the wrong shape"
    );
    if cols == 0 || b.ncols() == 0 {
        return;
    }
    let ld = a.nrows();
    if rows > SMALL_DIM && cols > SMALL_DIM && b.ncols() > SMALL_DIM {
        let start = r0 + c0 * ld;
        let at = StridedView::from_slice_with_strides_generic(
            &a.as_slice()[start..],
            Dyn(cols),
            Dyn(rows),
            Dyn(ld),
            Dyn(1),
        );
        c.gemm(alpha, &at, b, beta);
    } else {
        let data = a.as_slice();
        for j in 0..b.ncols() {
            let bj = b.column(j);
            for i in 0..cols {
                let col = &data[r0 + (c0 + i) * ld..r0 + (c0 + i) * ld + rows];
                let mut s = 0.0;
                for (x, y) in col.iter().zip(bj.iter()) {
                    s += x * y;
                }
                let old = if beta == 0.0 { 0.0 } else { beta * c[(i, j)] };
                c[(i, j)] = alpha * s + old;
            }
        }
    }
}

/// `Q R` factorisation of an `m x n` matrix, `m >= n`, by Householder reflections.
/// `R` is in the upper triangle of `qr`; the reflector vectors (unit first entry
/// implied) are below the diagonal; `t_blocks[b]` is the triangular factor of panel `b`.
pub struct HouseholderQr {
    qr: DMatrix<f64>,
    tau: Vec<f64>,
    t_blocks: Vec<DMatrix<f64>>,
}

impl HouseholderQr {
    pub fn new(a: DMatrix<f64>) -> HouseholderQr {
        let (m, n) = a.shape();
        let mut qr = a;
        let kmax = m.min(n);
        let mut tau = vec![0.0; kmax];
        let mut t_blocks = Vec::with_capacity(kmax.div_ceil(QR_BLOCK));
        // Work space for the largest panel, reused by every panel.
        let mut v = DMatrix::<f64>::zeros(m, QR_BLOCK);
        let mut w = DMatrix::<f64>::zeros(QR_BLOCK, n);
        let mut w2 = DMatrix::<f64>::zeros(QR_BLOCK, n);
        let mut k = 0;
        while k < kmax {
            let nb = QR_BLOCK.min(kmax - k);
            // Factor the panel column by column, updating only the panel.
            for (j, tj) in tau.iter_mut().enumerate().skip(k).take(nb) {
                *tj = householder_column(&mut qr, j);
                let tj = *tj;
                if tj != 0.0 {
                    for c in j + 1..k + nb {
                        apply_reflector(&mut qr, j, tj, c);
                    }
                }
            }
            let t = triangular_factor(&qr, &tau, k, nb);
            let rows = m - k;
            let trailing = n - (k + nb);
            if trailing > 0 {
                // V: rows k..m of the panel's reflectors, explicit unit diagonal.
                let mut vv = v.view_mut((0, 0), (rows, nb));
                fill_v(&qr, k, nb, &mut vv);
                let vv = v.view((0, 0), (rows, nb));
                // C <- (I - V T V^T)^T C = C - V T^T (V^T C)
                let mut ww = w.view_mut((0, 0), (nb, trailing));
                gemm_tn(
                    &mut ww,
                    1.0,
                    &v,
                    (0, 0),
                    (rows, nb),
                    &qr.view((k, k + nb), (rows, trailing)),
                    0.0,
                );
                let mut ww2 = w2.view_mut((0, 0), (nb, trailing));
                ww2.gemm(1.0, &t.transpose(), &w.view((0, 0), (nb, trailing)), 0.0);
                qr.view_mut((k, k + nb), (rows, trailing)).gemm(
                    -1.0,
                    &vv,
                    &w2.view((0, 0), (nb, trailing)),
                    1.0,
                );
            }
            t_blocks.push(t);
            k += nb;
        }
        HouseholderQr { qr, tau, t_blocks }
    }

    pub fn nrows(&self) -> usize {
        self.qr.nrows()
    }

    pub fn ncols(&self) -> usize {
        self.qr.ncols()
    }

    /// The diagonal of `R`.
    pub fn r_diagonal(&self) -> Vec<f64> {
        (0..self.tau.len()).map(|i| self.qr[(i, i)]).collect()
    }

    /// `R` (`min(m, n) x n`, upper triangular).
    pub fn r(&self) -> DMatrix<f64> {
        let k = self.tau.len();
        DMatrix::from_fn(k, self.qr.ncols(), |i, j| {
            if i <= j { self.qr[(i, j)] } else { 0.0 }
        })
    }

    /// `b <- Q^T b` for `b` with `m` rows.
    pub fn apply_qt(&self, b: &mut DMatrix<f64>) {
        self.apply(b, true);
    }

    /// `b <- Q b` for `b` with `m` rows (Q is the full `m x m` orthogonal factor).
    pub fn apply_q(&self, b: &mut DMatrix<f64>) {
        self.apply(b, false);
    }

    fn apply(&self, b: &mut DMatrix<f64>, transpose: bool) {
        let m = self.qr.nrows();
        assert_eq!(
            b.nrows(),
            m,
            "apply: row count must match the factored matrix"
        );
        let r = b.ncols();
        if r == 0 {
            return;
        }
        let mut v = DMatrix::<f64>::zeros(m, QR_BLOCK);
        let mut w = DMatrix::<f64>::zeros(QR_BLOCK, r);
        let mut w2 = DMatrix::<f64>::zeros(QR_BLOCK, r);
        let nblocks = self.t_blocks.len();
        for step in 0..nblocks {
            let bi = if transpose { step } else { nblocks - 1 - step };
            let k = bi * QR_BLOCK;
            let t = &self.t_blocks[bi];
            let nb = t.nrows();
            let rows = m - k;
            let mut vv = v.view_mut((0, 0), (rows, nb));
            fill_v(&self.qr, k, nb, &mut vv);
            let mut ww = w.view_mut((0, 0), (nb, r));
            gemm_tn(
                &mut ww,
                1.0,
                &v,
                (0, 0),
                (rows, nb),
                &b.view((k, 0), (rows, r)),
                0.0,
            );
            let mut ww2 = w2.view_mut((0, 0), (nb, r));
            if transpose {
                ww2.gemm(1.0, &t.transpose(), &w.view((0, 0), (nb, r)), 0.0);
            } else {
                ww2.gemm(1.0, t, &w.view((0, 0), (nb, r)), 0.0);
            }
            b.view_mut((k, 0), (rows, r)).gemm(
                -1.0,
                &v.view((0, 0), (rows, nb)),
                &w2.view((0, 0), (nb, r)),
                1.0,
            );
        }
    }

    /// The orthonormal basis of the complement of the column space: the last
    /// `m - n` columns of the full `Q` (meaningful when the matrix has full column rank).
    pub fn complement_basis(&self) -> DMatrix<f64> {
        let (m, n) = self.qr.shape();
        let mut e = DMatrix::zeros(m, m - n.min(m));
        for j in 0..e.ncols() {
            e[(n + j, j)] = 1.0;
        }
        self.apply_q(&mut e);
        e
    }

    /// Index of the first column whose `|R_ii|` is below `rel_tol` times the largest,
    /// i.e. a column that is (numerically) a combination of the ones before it.
    pub fn first_dependent_column(&self, rel_tol: f64) -> Option<usize> {
        let d = self.r_diagonal();
        let big = d.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        if big == 0.0 {
            return if d.is_empty() { None } else { Some(0) };
        }
        d.iter().position(|x| x.abs() <= rel_tol * big)
    }

    /// Least-squares solution of `A X = B` (`A` the factored `m x n` matrix, `m >= n`).
    /// Fails, naming the column, when `A` is rank-deficient.
    pub fn solve(&self, b: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        self.solve_with_residual(b).map(|(x, _)| x)
    }

    /// [`Self::solve`] and the residuals' cross-product `E^T E` (`E = B - A X`), read
    /// off the last `m - n` rows of `Q^T B` (no product with `A`, which need not be kept).
    pub fn solve_with_residual(&self, b: &DMatrix<f64>) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
        let (m, n) = self.qr.shape();
        if m < n {
            return Err(SysidError::data(format!(
                "{m} equations for {n} unknowns: a least-squares fit needs at least as many"
            )));
        }
        let tol = (m as f64) * f64::EPSILON;
        if let Some(c) = self.first_dependent_column(tol) {
            return Err(SysidError::numerical(format!(
                "regressor column {c} is a linear combination of the ones before it (rank-deficient)"
            )));
        }
        let mut qtb = b.clone();
        self.apply_qt(&mut qtb);
        let mut x = qtb.rows(0, n).into_owned();
        let r = self.qr.view((0, 0), (n, n));
        if !r.solve_upper_triangular_mut(&mut x) {
            return Err(SysidError::numerical("singular triangular factor"));
        }
        let tail = qtb.rows(n, m - n);
        let ete = tail.transpose() * tail;
        Ok((x, ete))
    }
}

/// Turn column `j` (rows `j..`) of `a` into a Householder reflector: on return
/// `a[j, j]` holds beta and rows `j+1..` the reflector's tail (head 1 implied).
fn householder_column(a: &mut DMatrix<f64>, j: usize) -> f64 {
    let m = a.nrows();
    let mut col = a.column_mut(j);
    let x = &mut col.as_mut_slice()[j..m];
    let alpha = x[0];
    let sigma = dot(&x[1..], &x[1..]);
    if sigma == 0.0 {
        return 0.0;
    }
    let norm = (alpha * alpha + sigma).sqrt();
    let beta = if alpha <= 0.0 { norm } else { -norm };
    let tau = (beta - alpha) / beta;
    let scale = 1.0 / (alpha - beta);
    for v in &mut x[1..] {
        *v *= scale;
    }
    x[0] = beta;
    tau
}

/// `sum x_i y_i` with four partial sums, so the loop vectorises.
#[inline]
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len());
    let (x, y) = (&x[..n], &y[..n]);
    let mut acc = [0.0f64; 4];
    let chunks = n / 4;
    for k in 0..chunks {
        for l in 0..4 {
            acc[l] += x[4 * k + l] * y[4 * k + l];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for k in 4 * chunks..n {
        s += x[k] * y[k];
    }
    s
}

/// Apply reflector `j` (stored in column `j`) to column `c > j`, rows `j..`.
fn apply_reflector(a: &mut DMatrix<f64>, j: usize, tau: f64, c: usize) {
    let m = a.nrows();
    let (left, right) = a.as_mut_slice().split_at_mut(c * m);
    let v = &left[j * m + j + 1..j * m + m];
    let col = &mut right[j..m];
    let s = tau * (col[0] + dot(v, &col[1..]));
    col[0] -= s;
    for (x, vi) in col[1..].iter_mut().zip(v) {
        *x -= s * vi;
    }
}

/// The upper-triangular `T` with `H_k ... H_{k+nb-1} = I - V T V^T` (forward, columnwise).
fn triangular_factor(qr: &DMatrix<f64>, tau: &[f64], k: usize, nb: usize) -> DMatrix<f64> {
    let m = qr.nrows();
    let data = qr.as_slice();
    let mut t = DMatrix::<f64>::zeros(nb, nb);
    let mut z = vec![0.0; nb];
    for i in 0..nb {
        let ti = tau[k + i];
        // z = V[:, 0..i]^T v_i, with v's unit head and zeros above it.
        let ci = k + i;
        let vi = &data[ci * m + ci + 1..ci * m + m];
        for (p, zp) in z.iter_mut().enumerate().take(i) {
            let cp = k + p;
            // v_p at row ci times v_i's head 1, then the tails.
            *zp = data[cp * m + ci] + dot(&data[cp * m + ci + 1..cp * m + m], vi);
        }
        for p in 0..i {
            let mut s = 0.0;
            for q in p..i {
                s += t[(p, q)] * z[q];
            }
            t[(p, i)] = -ti * s;
        }
        t[(i, i)] = ti;
    }
    t
}

/// Copy rows `k..` of panel `k..k+nb`'s reflectors into `v` with the unit
/// diagonal and zeros above it.
fn fill_v(qr: &DMatrix<f64>, k: usize, nb: usize, v: &mut nalgebra::DMatrixViewMut<f64>) {
    let m = qr.nrows();
    for j in 0..nb {
        for i in 0..m - k {
            let r = k + i;
            v[(i, j)] = if i < j {
                0.0
            } else if i == j {
                1.0
            } else {
                qr[(r, k + j)]
            };
        }
    }
}

/// Least squares `min ||A X - B||_F` by Householder QR.
pub fn lstsq(a: DMatrix<f64>, b: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    HouseholderQr::new(a).solve(b)
}

/// `L` with `L L^T = S` for a symmetric positive semi-definite `S`, by its
/// eigendecomposition (negative eigenvalues from rounding are taken as 0), so it
/// exists also when `S` is singular, where a Cholesky factor would fail.
pub fn psd_sqrt(s: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let sym = (s + s.transpose()) * 0.5;
    let n = sym.nrows();
    let eig = SymmetricEigen::try_new(sym, f64::EPSILON, 1000 * n.max(1))
        .ok_or_else(|| SysidError::numerical("symmetric eigendecomposition did not converge"))?;
    let mut l = eig.eigenvectors;
    for (j, &lam) in eig.eigenvalues.iter().enumerate() {
        let f = lam.max(0.0).sqrt();
        for x in l.column_mut(j).iter_mut() {
            *x *= f;
        }
    }
    Ok(l)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pseudo_random(m: usize, n: usize, seed: u64) -> DMatrix<f64> {
        let mut s = seed;
        DMatrix::from_fn(m, n, |_, _| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
    }

    #[test]
    fn qr_reconstructs_and_q_is_orthogonal() {
        for &(m, n) in &[(7, 3), (100, 70), (130, 65), (40, 40)] {
            let a = pseudo_random(m, n, (m * n) as u64);
            let qr = HouseholderQr::new(a.clone());
            let mut q = DMatrix::identity(m, m);
            qr.apply_q(&mut q);
            let mut rr = DMatrix::zeros(m, n);
            rr.view_mut((0, 0), (n, n)).copy_from(&qr.r());
            let err = (&q * rr - &a).amax();
            assert!(err < 1e-12, "{m}x{n}: |QR - A| = {err}");
            let orth = (q.transpose() * &q - DMatrix::identity(m, m)).amax();
            assert!(orth < 1e-13, "{m}x{n}: |Q^T Q - I| = {orth}");
            let mut qt = DMatrix::identity(m, m);
            qr.apply_qt(&mut qt);
            assert!((qt - q.transpose()).amax() < 1e-13);
        }
    }

    #[test]
    fn least_squares_matches_nalgebra_svd() {
        let a = pseudo_random(300, 90, 7);
        let b = pseudo_random(300, 4, 8);
        let x = lstsq(a.clone(), &b).unwrap();
        let svd = a.svd(true, true);
        let x2 = svd.solve(&b, 1e-14).unwrap();
        assert!((x - x2).amax() < 1e-11);
    }

    #[test]
    fn residual_cross_product_from_qtb() {
        let a = pseudo_random(120, 40, 21);
        let b = pseudo_random(120, 3, 22);
        let (x, ete) = HouseholderQr::new(a.clone())
            .solve_with_residual(&b)
            .unwrap();
        let e = &b - &a * &x;
        assert!((e.transpose() * e - ete).amax() < 1e-12);
    }

    #[test]
    fn dependent_column_is_found() {
        let mut a = pseudo_random(50, 6, 3);
        let c = a.column(1) * 2.0 - a.column(4);
        a.set_column(5, &c);
        let e = lstsq(a, &pseudo_random(50, 1, 4)).unwrap_err();
        assert!(e.message.contains("column 5"), "{e}");
    }

    #[test]
    fn complement_is_orthogonal_to_columns() {
        let a = pseudo_random(20, 6, 9);
        let qr = HouseholderQr::new(a.clone());
        let c = qr.complement_basis();
        assert_eq!(c.shape(), (20, 14));
        assert!((a.transpose() * &c).amax() < 1e-13);
        assert!((c.transpose() * &c - DMatrix::identity(14, 14)).amax() < 1e-13);
    }

    #[test]
    fn psd_square_root() {
        let g = pseudo_random(5, 3, 11);
        let s = &g * g.transpose();
        let l = psd_sqrt(&s).unwrap();
        assert!((&l * l.transpose() - s).amax() < 1e-13);
    }
}
