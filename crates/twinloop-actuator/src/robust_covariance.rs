//! The cluster-robust covariance of a least-squares fit whose residuals are
//! correlated in time (quantisation and timing errors persist over a step).

/// Length of the blocks of the robust covariance, s: longer than the time over
/// which the residuals stay correlated (a step response, a sine period).
pub const BLOCK_SECONDS: f64 = 1.0;

/// Covariance of the log-parameters robust to residuals correlated in time: the
/// sandwich `A+ S A+`, `A = J^T J`, `S = sum_b g_b g_b^T` with `g_b = J_b^T r_b`
/// summed over the rows of time block `b` (the cluster-robust form of Newey and
/// West's estimator, blocks as clusters), times `B/(B-1)` for `B` blocks. The
/// Jacobian's own `s^2 A^-1` takes the residuals as independent; on these logs it
/// is several times too small (quantisation and timing errors persist over a
/// step), which the test of "do the servos differ" cannot afford.
pub(crate) fn robust_covariance(
    j: &nalgebra::DMatrix<f64>,
    r: &nalgebra::DVector<f64>,
    block: &[usize],
) -> nalgebra::DMatrix<f64> {
    let n = j.ncols();
    let blocks = block.iter().copied().max().map_or(0, |b| b + 1);
    let mut g = nalgebra::DMatrix::<f64>::zeros(n, blocks);
    for (row, &b) in block.iter().enumerate() {
        let e = r[row];
        if e != 0.0 {
            for k in 0..n {
                g[(k, b)] += j[(row, k)] * e;
            }
        }
    }
    let s = &g * g.transpose() * (blocks as f64 / (blocks.max(2) - 1) as f64);
    let a = j.transpose() * j;
    let eig = a.symmetric_eigen();
    let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut a_inv = nalgebra::DMatrix::<f64>::zeros(n, n);
    for k in 0..n {
        let l = eig.eigenvalues[k];
        let inv = if l > 1e-20 * top {
            1.0 / l
        } else {
            f64::INFINITY
        };
        let v = eig.eigenvectors.column(k);
        for x in 0..n {
            for y in 0..n {
                let w = v[x] * v[y];
                if w != 0.0 {
                    a_inv[(x, y)] += w * inv;
                }
            }
        }
    }
    &a_inv * s * &a_inv
}
