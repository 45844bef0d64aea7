//! A symmetric 3 × 3 block kept by its lower triangle, and how it is summed into a
//! column-major block (shared by the scalar factor and the side-by-side lanes).

/// A symmetric 3 × 3 block by its lower triangle, column by column: (0, 0), (1, 0),
/// (2, 0), (1, 1), (2, 1), (2, 2).
pub type Symmetric = [f64; 6];
/// Where each entry of a [`Symmetric`] is in a column-major 3 × 3 block.
pub(crate) const LOWER: [usize; 6] = [0, 1, 2, 4, 5, 8];
/// Which entry of a [`Symmetric`] each entry of a column-major 3 × 3 block is.
pub(crate) const SYMMETRIC: [usize; 9] = [0, 1, 2, 1, 3, 4, 2, 4, 5];

/// The nine entries (column-major) of a block whose lower triangle is set to `lower`
/// (`first`) or has `lower` added to it, the block's entry `e` read by `at(e)`: six sums,
/// each stored twice off the diagonal.
#[inline(always)]
pub(crate) fn summed(lower: &Symmetric, first: bool, at: impl Fn(usize) -> f64) -> [f64; 9] {
    let sum: Symmetric = std::array::from_fn(|i| {
        if first {
            lower[i]
        } else {
            at(LOWER[i]) + lower[i]
        }
    });
    std::array::from_fn(|e| sum[SYMMETRIC[e]])
}
