//! K assembled, factored and solved by two threads at once, each on its own part of the
//! structure (the split is `dynamics::parallel`'s).

use nalgebra::Vector3;

use super::{outer_lower, Contribution, Reactions, Solver};
use crate::linalg::block_cholesky::{BlockLdl, SharedFactor};

/// The sparse system for two threads: K's blocks, its factor and the right-hand side as
/// raw pointers, each thread writing only what its part of the structure owns (the caller
/// checks the parts are disjoint when it splits the structure; see
/// `dynamics::parallel`). It borrows the system exclusively while it lives.
pub(crate) struct SharedReactions<'a> {
    factor: SharedFactor<'a>,
    contributions: &'a [Contribution],
    bar_start: &'a [usize],
    term_start: &'a [usize],
    terms: &'a [(usize, f64)],
    internal: &'a [usize],
    rhs: *mut [f64; 3],
}

// SAFETY: the callers of its unsafe methods keep their writes disjoint.
unsafe impl Send for SharedReactions<'_> {}
unsafe impl Sync for SharedReactions<'_> {}

impl Reactions {
    /// The system for two threads, when it is sparse with the scalar factor (not the lanes
    /// or the dense solve).
    pub(crate) fn shared(&mut self) -> Option<SharedReactions<'_>> {
        let Solver::Sparse(chol) = &mut self.solver else {
            return None;
        };
        if chol.has_lanes() {
            return None;
        }
        let (rhs, _) = self.rhs.as_mut_slice().as_chunks_mut::<3>();
        Some(SharedReactions {
            factor: chol.shared(),
            contributions: &self.contributions,
            bar_start: &self.bar_start,
            term_start: &self.term_start,
            terms: &self.terms,
            internal: &self.internal,
            rhs: rhs.as_mut_ptr(),
        })
    }

    /// The sparse factor, if any.
    pub(crate) fn sparse(&self) -> Option<&BlockLdl> {
        match &self.solver {
            Solver::Sparse(chol) => Some(chol),
            Solver::Dense(_) => None,
        }
    }

    /// Bar `bar`'s contributions to K: indices for [`Self::contribution_slot`].
    pub(crate) fn contributions_of(&self, bar: usize) -> std::ops::Range<usize> {
        self.bar_start[bar]..self.bar_start[bar + 1]
    }

    /// The sparse slot contribution `i` goes to.
    pub(crate) fn contribution_slot(&self, i: usize) -> usize {
        self.contributions[i].slot
    }

    /// Constraint column `c`'s `(end, coefficient)` terms (the coordinates' numbering).
    pub(crate) fn column_terms(&self, c: usize) -> &[(usize, f64)] {
        let i = self.internal[c];
        &self.terms[self.term_start[i]..self.term_start[i + 1]]
    }
}

impl SharedReactions<'_> {
    /// Adds bar `bar`'s contributions to K for its vector `b` and `1/|b|²`, those with
    /// `skip(i)` false (`i` the contribution's index), in order; returns the largest
    /// magnitude on the diagonals of the pivot blocks it closed (0 if none).
    ///
    /// # Safety
    /// No other thread touches the slots these contributions go to meanwhile.
    #[inline(always)]
    pub unsafe fn add_bar(
        &self,
        bar: usize,
        b: &Vector3<f64>,
        inv_l2: f64,
        skip: impl Fn(usize) -> bool,
    ) -> f64 {
        let (start, end) = (self.bar_start[bar], self.bar_start[bar + 1]);
        let bb = outer_lower(b);
        let mut amax: f64 = 0.0;
        for i in start..end {
            if !skip(i) {
                let c = &self.contributions[i];
                self.factor
                    .put_symmetric(c.slot, &c.block(&bb, inv_l2), c.first);
                if c.closes_pivot {
                    amax = amax.max(self.factor.diagonal_amax_at(c.slot));
                }
            }
        }
        amax
    }

    /// Sets the right-hand side of `columns` to `−N̈ P` for the end accelerations without
    /// reactions, as [`Reactions::set_rhs`] does.
    ///
    /// # Safety
    /// No other thread touches these entries of the right-hand side meanwhile.
    #[inline(always)]
    pub unsafe fn set_rhs(&self, columns: std::ops::Range<usize>, end_acc: &[Vector3<f64>]) {
        for c in columns {
            let i = self.internal[c];
            let mut sum = Vector3::zeros();
            for &(e, coef) in &self.terms[self.term_start[i]..self.term_start[i + 1]] {
                sum += end_acc[e] * coef;
            }
            *self.rhs.add(i) = [-sum.x, -sum.y, -sum.z];
        }
    }

    /// Factors `columns` (whole components, in order) and runs their forward
    /// substitution, pivots tested against `tiny`; false if one fails.
    ///
    /// # Safety
    /// No other thread touches these columns' components meanwhile.
    #[inline(always)]
    pub unsafe fn factor(&self, columns: &[usize], tiny: f64) -> bool {
        self.factor
            .factor_columns(columns.iter().copied(), tiny, self.rhs)
    }

    /// The backward substitution of `columns` after [`Self::factor`] succeeded on them:
    /// their Ω.
    ///
    /// # Safety
    /// As for [`Self::factor`]; the factor's writes to these columns happened before (on
    /// this thread, or published to it).
    #[inline(always)]
    pub unsafe fn solve_back(&self, columns: &[usize]) {
        self.factor.solve_back(columns.iter().copied(), self.rhs);
    }

    /// Adds the solved reactions of `columns` to the end forces, as [`Reactions::add_to`]
    /// does.
    ///
    /// # Safety
    /// No other thread touches these columns' ends meanwhile.
    #[inline(always)]
    pub unsafe fn add_to(&self, columns: std::ops::Range<usize>, end_force: *mut Vector3<f64>) {
        for c in columns {
            let i = self.internal[c];
            let o = Vector3::from(*self.rhs.add(i));
            for &(e, coef) in &self.terms[self.term_start[i]..self.term_start[i + 1]] {
                *end_force.add(e) += o * coef;
            }
        }
    }
}
