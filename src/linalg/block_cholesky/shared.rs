//! The scalar factor shared by two threads that factor and solve different components.

use nalgebra::{Matrix3, Vector3};

use super::kernels::{diagonal_amax, inverse3, mul_symmetric, subtract_abt, subtract_lower_abt};
use crate::linalg::pattern::Pattern;
use crate::linalg::symmetric::{summed, Symmetric};

/// The scalar factor's K and D⁻¹ as raw pointers, so that two threads can factor and
/// solve different components of K at once: columns of different components share no
/// slot, pivot or entry of `b` (see [`super::BlockLdl::components`]), and a component's columns
/// read only their own. It borrows the factor exclusively while it lives.
pub(crate) struct SharedFactor<'a> {
    k: *mut Matrix3<f64>,
    d_inv: *mut Matrix3<f64>,
    pattern: &'a Pattern,
    _exclusive: std::marker::PhantomData<&'a mut [Matrix3<f64>]>,
}

// SAFETY: the callers of its unsafe methods keep their writes disjoint.
unsafe impl Send for SharedFactor<'_> {}
unsafe impl Sync for SharedFactor<'_> {}

impl<'a> SharedFactor<'a> {
    /// K's blocks in `pattern`'s layout and the pivots' inverses, borrowed while it lives.
    pub(super) fn new(
        k: &'a mut [Matrix3<f64>],
        d_inv: &'a mut [Matrix3<f64>],
        pattern: &'a Pattern,
    ) -> Self {
        Self {
            k: k.as_mut_ptr(),
            d_inv: d_inv.as_mut_ptr(),
            pattern,
            _exclusive: std::marker::PhantomData,
        }
    }

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
