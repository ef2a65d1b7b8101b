//! Sparse L^T D L factorisation of a joint-space matrix with the kinematic tree's
//! sparsity (Featherstone, RBDA section 6.5, tables 6.3 and 6.4).
//!
//! The mass matrix of a tree has H[i][j] = 0 unless i and j lie on one branch; so does
//! `M + dt D + dt^2 K` when D and K come from joint terms and from contacts (a contact
//! Jacobian is non-zero only on its body's branch). Factorising along the parent array
//! costs O(n d^2) for depth d instead of O(n^3), and creates no fill-in.
//!
//! [`TreeMatrix`] keeps only those entries, each row with its ancestors in one contiguous
//! run (MuJoCo keeps its sparse mass matrix the same way): row k holds H[k][k] then
//! H[k][j] for j = parent(k), parent(parent(k)), ..., so an ancestor's row is a suffix
//! of the pattern of k's row, and the factorisation's updates and the solves' sums are
//! runs over contiguous memory with no parent chasing.

use nalgebra::DMatrix;

/// No parent (root of the DOF tree).
pub const NONE: usize = usize::MAX;

/// A symmetric matrix with the sparsity of a DOF tree, its lower triangle stored by rows
/// (see the module notes); after [`TreeMatrix::factor`] it holds the factors.
#[derive(Debug, Clone)]
pub struct TreeMatrix {
    /// Start of each row in `val` and `anc`.
    adr: Vec<usize>,
    /// Per row: the DOF itself, then its ancestors, nearest first.
    anc: Vec<usize>,
    /// Per entry: where its value stands in a column-major n x n matrix's upper
    /// triangle (row k's entry for ancestor j at `k n + j`), for `set_from_upper`.
    upper: Vec<usize>,
    val: Vec<f64>,
}

impl TreeMatrix {
    /// A zero matrix over the tree `parent` (`parent[k] < k`, or `NONE`).
    pub fn new(parent: &[usize]) -> TreeMatrix {
        let mut adr = Vec::with_capacity(parent.len() + 1);
        let mut anc = Vec::new();
        for k in 0..parent.len() {
            adr.push(anc.len());
            let mut j = k;
            while j != NONE {
                anc.push(j);
                j = parent[j];
            }
        }
        adr.push(anc.len());
        let n = parent.len();
        let upper = (0..n)
            .flat_map(|k| anc[adr[k]..adr[k + 1]].iter().map(move |&j| k * n + j))
            .collect();
        let val = vec![0.0; anc.len()];
        TreeMatrix {
            adr,
            anc,
            upper,
            val,
        }
    }

    pub fn n(&self) -> usize {
        self.adr.len() - 1
    }

    /// Row k: H[k][k], then H[k][a] for each ancestor a of k, nearest first.
    #[inline]
    pub fn row(&self, k: usize) -> &[f64] {
        &self.val[self.adr[k]..self.adr[k + 1]]
    }

    #[inline]
    pub fn row_mut(&mut self, k: usize) -> &mut [f64] {
        &mut self.val[self.adr[k]..self.adr[k + 1]]
    }

    /// The DOFs of row k's entries: k, then its ancestors, nearest first.
    #[inline]
    pub fn pattern(&self, k: usize) -> &[usize] {
        &self.anc[self.adr[k]..self.adr[k + 1]]
    }

    /// Set the tree's entries from the upper triangle of the dense n x n `m` (row k's
    /// entry for ancestor j is `m[(j, k)]`): one gather through the precomputed
    /// positions (2.4 k instructions a step on OP3 row by row, callgrind).
    pub fn set_from_upper(&mut self, m: &DMatrix<f64>) {
        assert_eq!(m.shape(), (self.n(), self.n()), "set_from_upper: n x n");
        let m = m.as_slice();
        for (x, &at) in self.val.iter_mut().zip(&self.upper) {
            *x = m[at];
        }
    }

    /// Factorise `h = L^T D L` in place: D on the diagonal, L's strictly lower entries
    /// beside it. The operations and their order are those of the dense-indexed form
    /// (Featherstone's table 6.3), so the factors are the same to the bit. Returns the
    /// index of a non-positive pivot if `h` is not positive definite.
    pub fn factor(&mut self) -> Result<(), usize> {
        for k in (0..self.n()).rev() {
            let (ak, end) = (self.adr[k], self.adr[k + 1]);
            // Every ancestor's row lies before row k.
            let (lo, hi) = self.val.split_at_mut(ak);
            let rk = &mut hi[..end - ak];
            let hkk = rk[0];
            if hkk.is_nan() || hkk <= 0.0 {
                return Err(k);
            }
            let anc = &self.anc[ak..end];
            for m in 1..rk.len() {
                let a = rk[m] / hkk;
                let (tail, start) = (&rk[m..], self.adr[anc[m]]);
                let ri = &mut lo[start..start + tail.len()];
                // Rows are short (at most the tree's depth): a plain two-wide loop beats
                // the vectoriser's set-up for a zip (9 k against 14 k instructions per
                // factorisation of OP3, callgrind).
                let mut t = 0;
                while t + 2 <= tail.len() {
                    let (y0, y1) = (tail[t], tail[t + 1]);
                    ri[t] -= a * y0;
                    ri[t + 1] -= a * y1;
                    t += 2;
                }
                if t < tail.len() {
                    ri[t] -= a * tail[t];
                }
                rk[m] = a;
            }
        }
        Ok(())
    }

    /// Solve `h x = b` in place (`b` becomes `x`) with the factors from [`Self::factor`].
    pub fn solve(&self, b: &mut [f64]) {
        let n = self.n();
        // L^T y = b
        for i in (0..n).rev() {
            let (a0, a1) = (self.adr[i], self.adr[i + 1]);
            let bi = b[i];
            for (&l, &j) in self.val[a0 + 1..a1].iter().zip(&self.anc[a0 + 1..a1]) {
                b[j] -= l * bi;
            }
        }
        for (i, x) in b.iter_mut().enumerate() {
            *x /= self.val[self.adr[i]];
        }
        // L x = y
        for i in 0..n {
            let (a0, a1) = (self.adr[i], self.adr[i + 1]);
            let mut s = b[i];
            for (&l, &j) in self.val[a0 + 1..a1].iter().zip(&self.anc[a0 + 1..a1]) {
                s -= l * b[j];
            }
            b[i] = s;
        }
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
        let mut h = TreeMatrix::new(&parent);
        for k in 0..n {
            let pattern = h.pattern(k).to_vec();
            for (x, &j) in h.row_mut(k).iter_mut().zip(&pattern) {
                *x = a[(k, j)];
            }
        }
        h.factor().unwrap();
        let mut x = b.clone();
        h.solve(&mut x);
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
        let mut h = TreeMatrix::new(&[NONE, 0]);
        h.row_mut(0)[0] = 1.0;
        h.row_mut(1)[0] = -1.0;
        assert_eq!(h.factor(), Err(1));
    }
}
