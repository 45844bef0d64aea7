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

use super::block_lanes::LaneGroups;

/// Pivots below this fraction of the largest diagonal entry mean a singular matrix.
const SINGULAR: f64 = 1e-12;

/// A symmetric 3 × 3 block by its lower triangle, column by column: (0, 0), (1, 0),
/// (2, 0), (1, 1), (2, 1), (2, 2).
pub type Symmetric = [f64; 6];
/// Where each entry of a [`Symmetric`] is in a column-major 3 × 3 block.
pub(super) const LOWER: [usize; 6] = [0, 1, 2, 4, 5, 8];
/// Which entry of a [`Symmetric`] each entry of a column-major 3 × 3 block is.
pub(super) const SYMMETRIC: [usize; 9] = [0, 1, 2, 1, 3, 4, 2, 4, 5];

/// A block-sparse symmetric positive-definite matrix and its factor.
#[derive(Debug, Clone)]
pub struct BlockLdl {
    n: usize,
    /// K's lower blocks in L's layout (fill slots zero), set by the caller through
    /// [`Self::put_symmetric`] at [`Self::k_index`]; the scalar factorization overwrites them with
    /// the Schur complement's blocks `L_ik D_k` below the diagonal, for the updates of
    /// later columns (`D_k` itself is not stored, only its inverse). One array, so an evaluation streams K once (it
    /// matters for large structures). L itself is not kept: `L_ik = (L_ik D_k) D_k⁻¹` is
    /// multiplied out where it is used, the same product as when it was stored, so the
    /// same bits, and 144 B less memory traffic per block column. Empty when the lanes
    /// hold K.
    k_values: Vec<Matrix3<f64>>,
    pattern: Pattern,
    /// `D_k⁻¹`, symmetric.
    d_inv: Vec<Matrix3<f64>>,
    /// Identical independent chains factored side by side, when K is made of them.
    lanes: Option<Box<LaneGroups>>,
}

/// The symbolic factor: where L's blocks are and which updates make each column.
#[derive(Debug, Clone)]
pub(super) struct Pattern {
    /// Strictly lower blocks `L_ik` by column (with fill); each column's first slot, the
    /// identity, is unused.
    pub l_start: Vec<usize>,
    pub l_rows: Vec<usize>,
    /// The updates `S[target] −= L[source] (LD[with])ᵀ` of each column, `update_start[k]..`,
    /// `source` and `with` in the earlier column `column`.
    pub update_start: Vec<usize>,
    pub updates: Vec<Update>,
}

/// One block update of the factorization, as slots in L's layout.
#[derive(Debug, Clone, Copy)]
pub(super) struct Update {
    pub target: usize,
    pub source: usize,
    pub with: usize,
    pub column: usize,
}

/// The scalar factor's K and D⁻¹ as raw pointers, so that two threads can factor and
/// solve different components of K at once: columns of different components share no
/// slot, pivot or entry of `b` (see [`BlockLdl::components`]), and a component's columns
/// read only their own. It borrows the factor exclusively while it lives.
pub(crate) struct SharedFactor<'a> {
    k: *mut Matrix3<f64>,
    d_inv: *mut Matrix3<f64>,
    pattern: &'a Pattern,
    _exclusive: std::marker::PhantomData<&'a mut BlockLdl>,
}

// SAFETY: the callers of its unsafe methods keep their writes disjoint.
unsafe impl Send for SharedFactor<'_> {}
unsafe impl Sync for SharedFactor<'_> {}

impl SharedFactor<'_> {
    /// Sets (`first`) or adds to K's symmetric block at `slot`.
    ///
    /// # Safety
    /// No other thread reads or writes `slot` meanwhile.
    #[inline(always)]
    pub unsafe fn put_symmetric(&self, slot: usize, lower: &Symmetric, first: bool) {
        let k = (*self.k.add(slot)).as_mut_slice();
        k.copy_from_slice(&summed(lower, first, |e| k[e]));
    }

    /// The largest magnitude on the diagonal of K's block at `slot`.
    ///
    /// # Safety
    /// No other thread writes `slot` meanwhile.
    #[inline(always)]
    pub unsafe fn diagonal_amax_at(&self, slot: usize) -> f64 {
        diagonal_amax(&*self.k.add(slot))
    }

    /// Factors `columns` (in order, whole components, after every earlier column of their
    /// components) and runs the forward substitution of `b` with them, pivots tested
    /// against `tiny`; false if one fails.
    ///
    /// # Safety
    /// `b` holds K's block columns; no other thread touches these columns' components.
    #[inline(always)]
    pub unsafe fn factor_columns(
        &self,
        columns: impl Iterator<Item = usize>,
        tiny: f64,
        b: *mut [f64; 3],
    ) -> bool {
        let pattern = self.pattern;
        for k in columns {
            let diagonal = pattern.l_start[k];
            // The pivot block is updated here and never stored: only its inverse is used
            // later, so K's lines of a chain without fill are read and not written back
            // (at 60,000 bars the factor is bound by memory).
            let mut pivot = *self.k.add(diagonal);
            for u in &pattern.updates[pattern.update_start[k]..pattern.update_start[k + 1]] {
                let l = self.l(u.source, u.column);
                let ld = *self.k.add(u.with);
                if u.target == diagonal {
                    // Only the lower triangle of a pivot block is read.
                    subtract_lower_abt(&mut pivot, &l, &ld);
                } else {
                    subtract_abt(&mut *self.k.add(u.target), &l, &ld);
                }
            }
            let Some(d_inv) = inverse3(&pivot, tiny) else {
                return false;
            };
            *self.d_inv.add(k) = d_inv;
            // b[k] has had every earlier column's update: it is y_k.
            let y = Vector3::from(*b.add(k));
            for p in diagonal + 1..pattern.l_start[k + 1] {
                let l = mul_symmetric(&*self.k.add(p), &d_inv);
                let bi = &mut *b.add(pattern.l_rows[p]);
                *bi = (Vector3::from(*bi) - l * y).into();
            }
        }
        true
    }

    /// The backward substitution of `b` over `columns` (in reverse order), after
    /// [`Self::factor_columns`] succeeded on them.
    ///
    /// # Safety
    /// As for [`Self::factor_columns`].
    #[inline(always)]
    pub unsafe fn solve_back(
        &self,
        columns: impl DoubleEndedIterator<Item = usize>,
        b: *mut [f64; 3],
    ) {
        let pattern = self.pattern;
        for k in columns.rev() {
            let mut x = *self.d_inv.add(k) * Vector3::from(*b.add(k));
            for p in pattern.l_start[k] + 1..pattern.l_start[k + 1] {
                let l = self.l(p, k);
                x -= l.tr_mul(&Vector3::from(*b.add(pattern.l_rows[p])));
            }
            *b.add(k) = x.into();
        }
    }

    /// `L` at `slot` of the factored column `column`: `(L D) D⁻¹`, multiplied out as when
    /// the column was factored.
    ///
    /// # Safety
    /// `column` is factored and no other thread writes it.
    #[inline(always)]
    unsafe fn l(&self, slot: usize, column: usize) -> Matrix3<f64> {
        mul_symmetric(&*self.k.add(slot), &*self.d_inv.add(column))
    }
}

impl BlockLdl {
    /// Analyses the pattern of `n` block columns with the given lower blocks `(row, col)`,
    /// `row ≥ col`; every diagonal block is added.
    pub fn new(n: usize, lower_blocks: &[(usize, usize)]) -> Self {
        let pattern = Pattern::new(n, lower_blocks);
        let slots = pattern.l_rows.len();
        let mut chol = Self {
            n,
            k_values: vec![Matrix3::zeros(); slots],
            d_inv: vec![Matrix3::zeros(); n],
            pattern,
            lanes: None,
        };
        chol.lanes = LaneGroups::find(&chol, lower_blocks).map(Box::new);
        if chol.lanes.is_some() {
            // The lanes keep their own K and factor.
            chol.k_values = Vec::new();
            chol.d_inv = Vec::new();
        }
        chol
    }

    /// The same without side-by-side chains (the reference the lanes are tested against).
    #[cfg(test)]
    pub fn without_lanes(mut self) -> Self {
        self.k_values = (0..self.slots()).map(|p| self.block(p)).collect();
        self.lanes = None;
        self.d_inv = vec![Matrix3::zeros(); self.n];
        self
    }

    /// Number of block columns.
    pub fn size(&self) -> usize {
        self.n
    }

    /// Number of lower blocks of K with fill (the slots [`Self::k_index`] returns).
    pub fn slots(&self) -> usize {
        self.pattern.l_rows.len()
    }

    /// Sets K's block at `slot`.
    pub fn set(&mut self, slot: usize, block: &Matrix3<f64>) {
        match &mut self.lanes {
            Some(lanes) => lanes.set(slot, block),
            None => self.k_values[slot] = *block,
        }
    }

    /// Sets (`first`) or adds to K's block at `slot`, a symmetric one given by its lower
    /// triangle (six sums, not nine).
    #[inline(always)]
    pub fn put_symmetric(&mut self, slot: usize, lower: &Symmetric, first: bool) {
        match &mut self.lanes {
            Some(lanes) => lanes.put_symmetric(slot, lower, first),
            None => {
                let k = self.k_values[slot].as_mut_slice();
                k.copy_from_slice(&summed(lower, first, |e| k[e]));
            }
        }
    }

    /// K's block at `slot` as last set (until a factorization overwrites it).
    pub fn block(&self, slot: usize) -> Matrix3<f64> {
        match &self.lanes {
            Some(lanes) => lanes.block(slot),
            None => self.k_values[slot],
        }
    }

    /// Factors and solves with the side-by-side chains' portable (SSE2) code.
    #[cfg(test)]
    pub fn factor_and_solve_portable(&mut self, b: &mut DVector<f64>) -> bool {
        let lanes = self.lanes.as_mut().expect("side by side");
        let (b, _) = b.as_mut_slice().as_chunks_mut::<3>();
        lanes.factor_and_solve_portable(SINGULAR, b)
    }
}

impl Pattern {
    /// The symbolic factorisation of `n` block columns with lower blocks `lower_blocks`.
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
        // The pattern of column k of L is K's plus its children's.
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
        let (l_start, l_rows) = super::flatten(&l_cols);
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
                        column: j,
                    });
                }
            }
            update_start.push(updates.len());
        }
        Self {
            l_start,
            l_rows,
            update_start,
            updates,
        }
    }

    /// Slot of the lower block `(row, col)`, if it is in the pattern.
    pub fn slot(&self, row: usize, col: usize) -> Option<usize> {
        let start = self.l_start[col];
        let rows = &self.l_rows[start..self.l_start[col + 1]];
        rows.binary_search(&row).ok().map(|p| start + p)
    }
}

impl BlockLdl {
    /// The slot of the lower block `(row, col)`, `row ≥ col`.
    pub fn k_index(&self, row: usize, col: usize) -> Option<usize> {
        self.pattern.slot(row, col)
    }

    /// Factors K as put (overwriting its blocks below the diagonal that take updates;
    /// pivot blocks stay as put) and solves `K x = b` in place. The forward
    /// substitution runs inside the factor's sweep, column by column as it is factored, so
    /// L is streamed twice per solve, not three times (the same operations in the same
    /// order as a separate forward pass). False if K is not (numerically) positive
    /// definite, which includes any NaN in it (a NaN reaches a pivot, and fails its test);
    /// `b` is then overwritten too.
    #[inline(always)]
    pub fn factor_and_solve(&mut self, b: &mut DVector<f64>) -> bool {
        let (b, _) = b.as_mut_slice().as_chunks_mut::<3>();
        let b = &mut b[..self.n];
        if let Some(lanes) = &mut self.lanes {
            return lanes.factor_and_solve(SINGULAR, b);
        }
        let tiny = Self::singular_below(self.diagonal_scale());
        let n = self.n;
        let shared = self.shared();
        // SAFETY: one caller, holding `self` and `b` exclusively.
        unsafe {
            if !shared.factor_columns(0..n, tiny, b.as_mut_ptr()) {
                return false;
            }
            shared.solve_back(0..n, b.as_mut_ptr());
        }
        true
    }

    /// K's connected components (columns linked by no block, directly or through others),
    /// each its columns in order: they factor independently of each other.
    pub fn components(&self) -> Vec<Vec<usize>> {
        let pattern = &self.pattern;
        let blocks: Vec<(usize, usize)> = (0..self.n)
            .flat_map(|c| {
                let rows = &pattern.l_rows[pattern.l_start[c]..pattern.l_start[c + 1]];
                rows.iter().map(move |&r| (r, c))
            })
            .collect();
        super::block_lanes::components(self.n, &blocks)
    }

    /// The side-by-side chains, when K lives in them.
    pub(super) fn lanes_mut(&mut self) -> Option<&mut LaneGroups> {
        self.lanes.as_deref_mut()
    }

    /// The side-by-side chains, when K lives in them (for their layout).
    pub(super) fn lanes(&self) -> Option<&LaneGroups> {
        self.lanes.as_deref()
    }

    /// Whether identical chains are factored side by side (then K lives in the lanes).
    pub fn has_lanes(&self) -> bool {
        self.lanes.is_some()
    }

    /// The scalar factor's arrays for writers on two threads (see [`SharedFactor`]).
    pub(crate) fn shared(&mut self) -> SharedFactor<'_> {
        assert!(self.lanes.is_none(), "K is in the lanes");
        SharedFactor {
            k: self.k_values.as_mut_ptr(),
            d_inv: self.d_inv.as_mut_ptr(),
            pattern: &self.pattern,
            _exclusive: std::marker::PhantomData,
        }
    }

    /// Pivots at or below this mean a singular K, for a largest diagonal magnitude `amax`.
    pub(crate) fn singular_below(amax: f64) -> f64 {
        SINGULAR * amax
    }

    /// The largest magnitude on K's diagonal as assembled (the lanes find theirs the same
    /// way; two threads gather it as they assemble K).
    #[inline(always)]
    pub(crate) fn diagonal_scale(&self) -> f64 {
        self.pattern.l_start[..self.n]
            .iter()
            .map(|&d| diagonal_amax(&self.k_values[d]))
            .fold(0.0, f64::max)
    }

    /// K as a dense symmetric matrix (for the indeterminate fallback), as put, before a
    /// factorization overwrites it.
    pub fn dense(&self) -> nalgebra::DMatrix<f64> {
        let mut m = nalgebra::DMatrix::zeros(3 * self.n, 3 * self.n);
        for c in 0..self.n {
            for p in self.pattern.l_start[c]..self.pattern.l_start[c + 1] {
                let r = self.pattern.l_rows[p];
                let block = self.block(p);
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

/// The nine entries (column-major) of a block whose lower triangle is set to `lower`
/// (`first`) or has `lower` added to it, the block's entry `e` read by `at(e)`: six sums,
/// each stored twice off the diagonal.
#[inline(always)]
pub(super) fn summed(lower: &Symmetric, first: bool, at: impl Fn(usize) -> f64) -> [f64; 9] {
    let sum: Symmetric = std::array::from_fn(|i| {
        if first {
            lower[i]
        } else {
            at(LOWER[i]) + lower[i]
        }
    });
    std::array::from_fn(|e| sum[SYMMETRIC[e]])
}

/// The largest magnitude on a block's diagonal (a NaN there fails its pivot anyway).
#[inline(always)]
fn diagonal_amax(a: &Matrix3<f64>) -> f64 {
    a[(0, 0)].abs().max(a[(1, 1)].abs()).max(a[(2, 2)].abs())
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

#[cfg(test)]
mod tests;
