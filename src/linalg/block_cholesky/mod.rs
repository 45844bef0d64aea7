//! Sparse `K = L D Lᵀ` over 3 × 3 blocks with a pattern fixed once.
//!
//! The reaction matrix is made of dense 3 × 3 blocks (one per pair of constraint columns
//! sharing a bar). A scalar sparse factorisation spends its time on index bookkeeping for
//! every scalar; working on `Matrix3` blocks keeps the same fill but does the arithmetic on
//! stack-allocated 3 × 3 matrices. The factor is square-root free: `L` has identity
//! diagonal blocks and `D` is block diagonal, kept as its inverse, whose three pivots cost
//! one reciprocal each (no `sqrt → div` chain). The symbolic analysis (elimination tree
//! and fill) runs once; `factor` and `solve` allocate nothing.

mod kernels;
mod shared;

use nalgebra::{DVector, Matrix3};

use super::block_lanes::LaneGroups;
use super::pattern::{components, Pattern};
use super::symmetric::{summed, Symmetric};
use kernels::diagonal_amax;
pub(crate) use shared::SharedFactor;

/// Pivots below this fraction of the largest diagonal entry mean a singular matrix.
const SINGULAR: f64 = 1e-12;

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
        chol.lanes = LaneGroups::find(&chol.pattern, lower_blocks).map(Box::new);
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
        components(self.n, &blocks)
    }

    /// The side-by-side chains, when K lives in them.
    pub(crate) fn lanes_mut(&mut self) -> Option<&mut LaneGroups> {
        self.lanes.as_deref_mut()
    }

    /// The side-by-side chains, when K lives in them (for their layout).
    pub(crate) fn lanes(&self) -> Option<&LaneGroups> {
        self.lanes.as_deref()
    }

    /// Whether identical chains are factored side by side (then K lives in the lanes).
    pub fn has_lanes(&self) -> bool {
        self.lanes.is_some()
    }

    /// The scalar factor's arrays for writers on two threads (see [`SharedFactor`]).
    pub(crate) fn shared(&mut self) -> SharedFactor<'_> {
        assert!(self.lanes.is_none(), "K is in the lanes");
        SharedFactor::new(&mut self.k_values, &mut self.d_inv, &self.pattern)
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

#[cfg(test)]
mod tests;
