//! Sparse `K = L D Lᵀ` over 3 × 3 blocks with a pattern fixed once.
//!
//! The reaction matrix is made of dense 3 × 3 blocks (one per pair of constraint columns
//! sharing a bar). A scalar sparse factorisation spends its time on index bookkeeping for
//! every scalar; working on `Matrix3` blocks keeps the same fill but does the arithmetic on
//! stack-allocated 3 × 3 matrices. The factor is square-root free: `L` has identity
//! diagonal blocks and `D` is block diagonal, kept as its inverse, whose three pivots cost
//! one reciprocal each (no `sqrt → div` chain). The symbolic analysis (elimination tree
//! and fill) runs once; `factor` and `solve` allocate nothing.

use nalgebra::{DVector, Matrix3, Vector3};

/// Pivots below this fraction of the largest diagonal entry mean a singular matrix.
const SINGULAR: f64 = 1e-12;

/// A block-sparse symmetric positive-definite matrix and its factor.
#[derive(Debug, Clone)]
pub struct BlockLdl {
    n: usize,
    /// K's lower blocks in L's layout (fill slots zero), set by the caller through
    /// [`Self::k_index`]; the factorization overwrites them with the Schur complement's
    /// blocks: `L_ik D_k` below the diagonal, for the updates of later columns, and `D_k` on
    /// it. One array, so an evaluation streams K once (it matters for large structures).
    pub k_values: Vec<Matrix3<f64>>,
    /// Strictly lower blocks `L_ik` by column (with fill); each column's first slot, the
    /// identity, is unused.
    l_start: Vec<usize>,
    l_rows: Vec<usize>,
    l_values: Vec<Matrix3<f64>>,
    /// The updates `S[target] −= L[source] (LD[with])ᵀ` of each column, `update_start[k]..`.
    update_start: Vec<usize>,
    updates: Vec<Update>,
    /// `D_k⁻¹`, symmetric.
    d_inv: Vec<Matrix3<f64>>,
}

/// One block update of the factorization, as slots in L's layout.
#[derive(Debug, Clone, Copy)]
struct Update {
    target: usize,
    source: usize,
    with: usize,
}

impl BlockLdl {
    /// Analyses the pattern of `n` block columns with the given lower blocks `(row, col)`,
    /// `row ≥ col`; every diagonal block is added.
    pub fn new(n: usize, lower_blocks: &[(usize, usize)]) -> Self {
        let mut k_cols: Vec<Vec<usize>> = (0..n).map(|c| vec![c]).collect();
        for &(r, c) in lower_blocks {
            debug_assert!(r >= c, "lower blocks only");
            if r != c {
                k_cols[c].push(r);
            }
        }
        for col in &mut k_cols {
            col[1..].sort_unstable();
            col.dedup();
        }
        // Symbolic factorisation: the pattern of column k of L is K's plus its children's.
        let mut l_cols: Vec<Vec<usize>> = Vec::with_capacity(n);
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for k in 0..n {
            let mut rows: Vec<usize> = k_cols[k][1..].to_vec();
            for &j in &children[k] {
                rows.extend(l_cols[j].iter().skip(1).copied().filter(|&i| i > k));
            }
            rows.sort_unstable();
            rows.dedup();
            if let Some(&parent) = rows.first() {
                children[parent].push(k);
            }
            let mut col = vec![k];
            col.extend(rows);
            l_cols.push(col);
        }
        let (l_start, l_rows) = flatten(&l_cols);
        let mut rows_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
        for j in 0..n {
            for p in l_start[j] + 1..l_start[j + 1] {
                rows_of[l_rows[p]].push((j, p));
            }
        }
        // Column k of the Schur complement: K_ik − Σ_j L_ij (L_kj D_j)ᵀ over the j with
        // L_kj ≠ 0, each a fixed slot once the pattern is known.
        let l_slot = |row: usize, col: usize| {
            let rows = &l_rows[l_start[col]..l_start[col + 1]];
            l_start[col] + rows.binary_search(&row).expect("row is in L's pattern")
        };
        let mut update_start = vec![0];
        let mut updates = Vec::new();
        for (k, entries) in rows_of.iter().enumerate() {
            for &(j, at) in entries {
                for (p, &row) in l_rows.iter().enumerate().take(l_start[j + 1]).skip(at) {
                    updates.push(Update {
                        target: l_slot(row, k),
                        source: p,
                        with: at,
                    });
                }
            }
            update_start.push(updates.len());
        }
        Self {
            n,
            k_values: vec![Matrix3::zeros(); l_rows.len()],
            l_values: vec![Matrix3::zeros(); l_rows.len()],
            l_start,
            l_rows,
            update_start,
            updates,
            d_inv: vec![Matrix3::zeros(); n],
        }
    }

    /// Index into `k_values` of the lower block `(row, col)`, `row ≥ col`.
    pub fn k_index(&self, row: usize, col: usize) -> Option<usize> {
        let start = self.l_start[col];
        let rows = &self.l_rows[start..self.l_start[col + 1]];
        rows.binary_search(&row).ok().map(|p| start + p)
    }

    /// Factors the current `k_values` (overwriting them); false if K is not (numerically)
    /// positive definite, which includes any NaN in it (a NaN reaches a pivot, and fails
    /// its test).
    pub fn factor(&mut self) -> bool {
        let scale = (0..self.n)
            .map(|k| self.k_values[self.l_start[k]].diagonal().amax())
            .fold(0.0, f64::max);
        let tiny = SINGULAR * scale;
        for k in 0..self.n {
            let diagonal = self.l_start[k];
            for u in &self.updates[self.update_start[k]..self.update_start[k + 1]] {
                let (l, ld) = (&self.l_values[u.source], self.k_values[u.with]);
                if u.target == diagonal {
                    // Only the lower triangle of a pivot block is read.
                    subtract_lower_abt(&mut self.k_values[u.target], l, &ld);
                } else {
                    subtract_abt(&mut self.k_values[u.target], l, &ld);
                }
            }
            let Some(d_inv) = inverse3(&self.k_values[diagonal], tiny) else {
                return false;
            };
            self.d_inv[k] = d_inv;
            for p in diagonal + 1..self.l_start[k + 1] {
                self.l_values[p] = mul_symmetric(&self.k_values[p], &d_inv);
            }
        }
        true
    }

    /// Solves `K x = b` in place with the last successful factor.
    pub fn solve(&self, b: &mut DVector<f64>) {
        let (b, _) = b.as_mut_slice().as_chunks_mut::<3>();
        let b = &mut b[..self.n];
        for k in 0..self.n {
            let y = Vector3::from(b[k]);
            for p in self.l_start[k] + 1..self.l_start[k + 1] {
                let i = self.l_rows[p];
                let bi = Vector3::from(b[i]) - self.l_values[p] * y;
                b[i] = bi.into();
            }
        }
        for k in (0..self.n).rev() {
            let mut x = self.d_inv[k] * Vector3::from(b[k]);
            for p in self.l_start[k] + 1..self.l_start[k + 1] {
                x -= self.l_values[p].tr_mul(&Vector3::from(b[self.l_rows[p]]));
            }
            b[k] = x.into();
        }
    }

    /// K as a dense symmetric matrix (for the indeterminate fallback), from `k_values` as
    /// set, before a factorization overwrites them.
    pub fn dense(&self) -> nalgebra::DMatrix<f64> {
        let mut m = nalgebra::DMatrix::zeros(3 * self.n, 3 * self.n);
        for c in 0..self.n {
            for p in self.l_start[c]..self.l_start[c + 1] {
                let r = self.l_rows[p];
                let block = self.k_values[p];
                m.fixed_view_mut::<3, 3>(3 * r, 3 * c).copy_from(&block);
                if r != c {
                    m.fixed_view_mut::<3, 3>(3 * c, 3 * r)
                        .copy_from(&block.transpose());
                }
            }
        }
        m
    }
}

/// `s −= a bᵀ`, written out so that each entry is three products and a sum.
#[inline(always)]
fn subtract_abt(s: &mut Matrix3<f64>, a: &Matrix3<f64>, b: &Matrix3<f64>) {
    for j in 0..3 {
        for i in 0..3 {
            s[(i, j)] -= a[(i, 0)] * b[(j, 0)] + a[(i, 1)] * b[(j, 1)] + a[(i, 2)] * b[(j, 2)];
        }
    }
}

/// The lower triangle of `s −= a bᵀ` (the upper one is left stale).
#[inline(always)]
fn subtract_lower_abt(s: &mut Matrix3<f64>, a: &Matrix3<f64>, b: &Matrix3<f64>) {
    for j in 0..3 {
        for i in j..3 {
            s[(i, j)] -= a[(i, 0)] * b[(j, 0)] + a[(i, 1)] * b[(j, 1)] + a[(i, 2)] * b[(j, 2)];
        }
    }
}

/// `a d` for a symmetric `d` given whole.
#[inline(always)]
fn mul_symmetric(a: &Matrix3<f64>, d: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| a[(i, 0)] * d[(0, j)] + a[(i, 1)] * d[(1, j)] + a[(i, 2)] * d[(2, j)])
}

/// The inverse of a symmetric 3 × 3 matrix from its adjugate: one division, no square
/// root. The pivots of its `L D Lᵀ` are `a₀₀`, `m₂/a₀₀` and `det/m₂` (`m₂` the leading 2 × 2
/// minor), so they are tested against `tiny` without dividing. `None` if one is ≤ `tiny`
/// (or NaN).
#[inline]
fn inverse3(a: &Matrix3<f64>, tiny: f64) -> Option<Matrix3<f64>> {
    let (a00, a10, a20, a11, a21, a22) = (
        a[(0, 0)],
        a[(1, 0)],
        a[(2, 0)],
        a[(1, 1)],
        a[(2, 1)],
        a[(2, 2)],
    );
    let c00 = a11 * a22 - a21 * a21;
    let c10 = a20 * a21 - a10 * a22;
    let c20 = a10 * a21 - a11 * a20;
    let m2 = a00 * a11 - a10 * a10;
    let det = a00 * c00 + a10 * c10 + a20 * c20;
    if !(a00 > tiny && m2 > tiny * a00 && det > tiny * m2) {
        return None;
    }
    let r = 1.0 / det;
    let c11 = a00 * a22 - a20 * a20;
    let c21 = a10 * a20 - a00 * a21;
    #[rustfmt::skip]
    let inv = Matrix3::new(
        c00 * r, c10 * r, c20 * r,
        c10 * r, c11 * r, c21 * r,
        c20 * r, c21 * r, m2 * r,
    );
    Some(inv)
}

fn flatten<T: Copy>(lists: &[Vec<T>]) -> (Vec<usize>, Vec<T>) {
    let mut start = Vec::with_capacity(lists.len() + 1);
    let mut items = Vec::new();
    start.push(0);
    for list in lists {
        items.extend_from_slice(list);
        start.push(items.len());
    }
    (start, items)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// A random SPD block matrix with a given block pattern agrees with a dense solve.
    #[test]
    fn solves_like_dense_cholesky() {
        let n = 7;
        let pattern = [
            (1, 0),
            (3, 0),
            (2, 1),
            (4, 2),
            (6, 3),
            (5, 4),
            (6, 5),
            (6, 0),
        ];
        let mut seed = 12345u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut chol = BlockLdl::new(n, &pattern);
        for &(r, c) in pattern.iter() {
            let idx = chol.k_index(r, c).unwrap();
            chol.k_values[idx] = Matrix3::from_fn(|_, _| rand());
        }
        for k in 0..n {
            let a = Matrix3::from_fn(|_, _| rand());
            let idx = chol.k_index(k, k).unwrap();
            chol.k_values[idx] = a * a.transpose() + Matrix3::identity() * 8.0;
        }
        let dense: DMatrix<f64> = chol.dense();
        assert!(chol.factor());
        let b = DVector::from_fn(3 * n, |i, _| (i as f64).sin());
        let mut x = b.clone();
        chol.solve(&mut x);
        let expected = dense.cholesky().unwrap().solve(&b);
        assert!((x - expected).amax() < 1e-12);
    }

    #[test]
    fn singular_matrix_is_reported() {
        let mut chol = BlockLdl::new(2, &[(1, 0)]);
        let u = Vector3::new(1.0, 2.0, 2.0) / 3.0;
        let a = Matrix3::identity() * 4.0 - u * u.transpose() * 3.0;
        for (r, c, m) in [(0, 0, a), (1, 1, a), (1, 0, -a)] {
            let idx = chol.k_index(r, c).unwrap();
            chol.k_values[idx] = m;
        }
        assert!(!chol.factor());
    }
}
