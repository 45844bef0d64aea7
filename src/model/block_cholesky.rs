//! Sparse Cholesky `K = L Lᵀ` over 3 × 3 blocks with a pattern fixed once.
//!
//! The reaction matrix is made of dense 3 × 3 blocks (one per pair of constraint columns
//! sharing a bar). A scalar sparse factorisation spends its time on index bookkeeping for
//! every scalar; working on `Matrix3` blocks keeps the same fill but does the arithmetic on
//! stack-allocated 3 × 3 matrices. The symbolic analysis (elimination tree and fill) runs
//! once; `factor` and `solve` allocate nothing.

use nalgebra::{DVector, Matrix3, Vector3};

/// Pivots below this fraction of the largest diagonal entry mean a singular matrix.
const SINGULAR: f64 = 1e-12;

/// A block-sparse symmetric positive-definite matrix and its factor.
#[derive(Debug, Clone)]
pub struct BlockCholesky {
    n: usize,
    /// Lower blocks of K by column; each column's first entry is its diagonal.
    k_start: Vec<usize>,
    k_rows: Vec<usize>,
    /// Values of the lower blocks of K, filled by the caller.
    pub k_values: Vec<Matrix3<f64>>,
    /// Blocks of L by column, same layout (with fill).
    l_start: Vec<usize>,
    l_rows: Vec<usize>,
    l_values: Vec<Matrix3<f64>>,
    /// Inverse of each diagonal block of L.
    l_diag_inv: Vec<Matrix3<f64>>,
    /// Row structure of L: for row k, the `l_values` indices of `L_kj`, j < k.
    row_start: Vec<usize>,
    row_entries: Vec<(usize, usize)>,
    work: Vec<Matrix3<f64>>,
}

impl BlockCholesky {
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
        let (k_start, k_rows) = flatten(&k_cols);
        let (l_start, l_rows) = flatten(&l_cols);
        let mut rows_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
        for j in 0..n {
            for p in l_start[j] + 1..l_start[j + 1] {
                rows_of[l_rows[p]].push((j, p));
            }
        }
        let (row_start, row_entries) = flatten(&rows_of);
        Self {
            n,
            k_values: vec![Matrix3::zeros(); k_rows.len()],
            k_start,
            k_rows,
            l_values: vec![Matrix3::zeros(); l_rows.len()],
            l_start,
            l_rows,
            l_diag_inv: vec![Matrix3::zeros(); n],
            row_start,
            row_entries,
            work: vec![Matrix3::zeros(); n],
        }
    }

    /// Index into `k_values` of the lower block `(row, col)`, `row ≥ col`.
    pub fn k_index(&self, row: usize, col: usize) -> Option<usize> {
        let range = self.k_start[col]..self.k_start[col + 1];
        if row == col {
            return Some(range.start);
        }
        let rows = &self.k_rows[range.start + 1..range.end];
        rows.binary_search(&row).ok().map(|p| range.start + 1 + p)
    }

    /// Factors the current `k_values`; false if K is not (numerically) positive definite.
    pub fn factor(&mut self) -> bool {
        let scale = (0..self.n)
            .map(|k| self.k_values[self.k_start[k]].diagonal().amax())
            .fold(0.0, f64::max);
        for k in 0..self.n {
            for p in self.l_start[k]..self.l_start[k + 1] {
                self.work[self.l_rows[p]] = Matrix3::zeros();
            }
            for p in self.k_start[k]..self.k_start[k + 1] {
                self.work[self.k_rows[p]] = self.k_values[p];
            }
            for &(j, at) in &self.row_entries[self.row_start[k]..self.row_start[k + 1]] {
                let l_kj_t = self.l_values[at].transpose();
                for p in at..self.l_start[j + 1] {
                    self.work[self.l_rows[p]] -= self.l_values[p] * l_kj_t;
                }
            }
            let Some((l_kk, inv)) = cholesky3(&self.work[k], SINGULAR * scale) else {
                return false;
            };
            self.l_values[self.l_start[k]] = l_kk;
            self.l_diag_inv[k] = inv;
            let inv_t = inv.transpose();
            for p in self.l_start[k] + 1..self.l_start[k + 1] {
                self.l_values[p] = self.work[self.l_rows[p]] * inv_t;
            }
        }
        true
    }

    /// Solves `K x = b` in place with the last successful factor.
    pub fn solve(&self, b: &mut DVector<f64>) {
        let get = |b: &DVector<f64>, k: usize| Vector3::new(b[3 * k], b[3 * k + 1], b[3 * k + 2]);
        let set = |b: &mut DVector<f64>, k: usize, v: Vector3<f64>| {
            b[3 * k] = v.x;
            b[3 * k + 1] = v.y;
            b[3 * k + 2] = v.z;
        };
        for k in 0..self.n {
            let y = self.l_diag_inv[k] * get(b, k);
            set(b, k, y);
            for p in self.l_start[k] + 1..self.l_start[k + 1] {
                let i = self.l_rows[p];
                let bi = get(b, i) - self.l_values[p] * y;
                set(b, i, bi);
            }
        }
        for k in (0..self.n).rev() {
            let mut x = get(b, k);
            for p in self.l_start[k] + 1..self.l_start[k + 1] {
                x -= self.l_values[p].tr_mul(&get(b, self.l_rows[p]));
            }
            set(b, k, self.l_diag_inv[k].tr_mul(&x));
        }
    }

    /// K as a dense symmetric matrix (for the indeterminate fallback).
    pub fn dense(&self) -> nalgebra::DMatrix<f64> {
        let mut m = nalgebra::DMatrix::zeros(3 * self.n, 3 * self.n);
        for c in 0..self.n {
            for p in self.k_start[c]..self.k_start[c + 1] {
                let r = self.k_rows[p];
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

/// `L` and `L⁻¹` of a symmetric 3 × 3 matrix, unrolled: nalgebra's generic routine was a
/// seventh of a tower's step. `None` if a squared pivot is ≤ `tiny`.
#[inline]
fn cholesky3(a: &Matrix3<f64>, tiny: f64) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
    let pivot = |d: f64| (d > tiny).then(|| d.sqrt());
    let l00 = pivot(a[(0, 0)])?;
    let l10 = a[(1, 0)] / l00;
    let l20 = a[(2, 0)] / l00;
    let l11 = pivot(a[(1, 1)] - l10 * l10)?;
    let l21 = (a[(2, 1)] - l20 * l10) / l11;
    let l22 = pivot(a[(2, 2)] - l20 * l20 - l21 * l21)?;
    let (m00, m11, m22) = (1.0 / l00, 1.0 / l11, 1.0 / l22);
    let m10 = -l10 * m00 * m11;
    let m21 = -l21 * m11 * m22;
    let m20 = -(l20 * m00 + l21 * m10) * m22;
    #[rustfmt::skip]
    let l = Matrix3::new(
        l00, 0.0, 0.0,
        l10, l11, 0.0,
        l20, l21, l22,
    );
    #[rustfmt::skip]
    let inv = Matrix3::new(
        m00, 0.0, 0.0,
        m10, m11, 0.0,
        m20, m21, m22,
    );
    Some((l, inv))
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
        let mut chol = BlockCholesky::new(n, &pattern);
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
        let mut chol = BlockCholesky::new(2, &[(1, 0)]);
        let u = Vector3::new(1.0, 2.0, 2.0) / 3.0;
        let a = Matrix3::identity() * 4.0 - u * u.transpose() * 3.0;
        for (r, c, m) in [(0, 0, a), (1, 1, a), (1, 0, -a)] {
            let idx = chol.k_index(r, c).unwrap();
            chol.k_values[idx] = m;
        }
        assert!(!chol.factor());
    }
}
