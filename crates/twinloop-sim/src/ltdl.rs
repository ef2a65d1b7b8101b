//! Sparse L^T D L factorisation of a joint-space matrix with the kinematic tree's
//! sparsity (Featherstone, RBDA section 6.5, tables 6.3 and 6.4).
//!
//! The mass matrix of a tree has H[i][j] = 0 unless i and j lie on one branch; so does
//! `M + dt D + dt^2 K` when D and K come from joint terms and from contacts (a contact
//! Jacobian is non-zero only on its body's branch). Factorising along the parent array
//! costs O(n d^2) for depth d instead of O(n^3), and creates no fill-in.

use nalgebra::DMatrix;

/// No parent (root of the DOF tree).
pub const NONE: usize = usize::MAX;

/// Factorise `h = L^T D L` in place, using and overwriting the lower triangle: D on the
/// diagonal, L's strictly lower entries below it. `parent[k] < k` for every DOF
/// (or `NONE`). Returns the index of a non-positive pivot if `h` is not positive definite.
pub fn factor(h: &mut DMatrix<f64>, parent: &[usize]) -> Result<(), usize> {
    let n = h.nrows();
    for k in (0..n).rev() {
        let hkk = h[(k, k)];
        if hkk.is_nan() || hkk <= 0.0 {
            return Err(k);
        }
        let mut i = parent[k];
        while i != NONE {
            let a = h[(k, i)] / hkk;
            let mut j = i;
            while j != NONE {
                let hkj = h[(k, j)];
                h[(i, j)] -= a * hkj;
                j = parent[j];
            }
            h[(k, i)] = a;
            i = parent[i];
        }
    }
    Ok(())
}

/// Solve `h x = b` in place (`b` becomes `x`) with the factors from [`factor`].
pub fn solve(h: &DMatrix<f64>, parent: &[usize], b: &mut [f64]) {
    let n = h.nrows();
    // L^T y = b
    for i in (0..n).rev() {
        let bi = b[i];
        let mut j = parent[i];
        while j != NONE {
            b[j] -= h[(i, j)] * bi;
            j = parent[j];
        }
    }
    for (i, x) in b.iter_mut().enumerate() {
        *x /= h[(i, i)];
    }
    // L x = y
    for i in 0..n {
        let mut j = parent[i];
        let mut s = b[i];
        while j != NONE {
            s -= h[(i, j)] * b[j];
            j = parent[j];
        }
        b[i] = s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_dense_solve_on_a_tree_patterned_matrix() {
        // A small tree: 0 <- 1 <- 2, 1 <- 3, 0 <- 4.
        let parent = [NONE, 0, 1, 1, 0];
        let n = parent.len();
        let on_branch = |i: usize, j: usize| {
            let anc = |mut a: usize, b: usize| {
                while a != NONE {
                    if a == b {
                        return true;
                    }
                    a = parent[a];
                }
                false
            };
            anc(i, j) || anc(j, i)
        };
        // Build a random SPD matrix with the pattern: A = L^T D L from a random L.
        let mut l = DMatrix::<f64>::identity(n, n);
        let mut seed = 3u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for i in 0..n {
            let mut j = parent[i];
            while j != NONE {
                l[(i, j)] = rnd();
                j = parent[j];
            }
        }
        let d = DMatrix::from_diagonal(&nalgebra::DVector::from_fn(n, |i, _| 1.0 + i as f64));
        let a = l.transpose() * d * &l;
        for i in 0..n {
            for j in 0..n {
                if !on_branch(i, j) {
                    assert!(a[(i, j)].abs() < 1e-15, "pattern");
                }
            }
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin() + 0.3).collect();
        let mut h = a.clone();
        factor(&mut h, &parent).unwrap();
        let mut x = b.clone();
        solve(&h, &parent, &mut x);
        let x_dense = a
            .clone()
            .cholesky()
            .unwrap()
            .solve(&nalgebra::DVector::from_vec(b));
        for i in 0..n {
            assert!((x[i] - x_dense[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn reports_a_non_positive_pivot() {
        let mut h = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
        assert_eq!(factor(&mut h, &[NONE, 0]), Err(1));
    }
}
