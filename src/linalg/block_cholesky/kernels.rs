//! The scalar factor's 3 × 3 block kernels, written out so that each entry is summed in
//! a fixed order (the lanes repeat it lane by lane, for the same bits).

use nalgebra::Matrix3;

/// The largest magnitude on a block's diagonal (a NaN there fails its pivot anyway).
#[inline(always)]
pub(super) fn diagonal_amax(a: &Matrix3<f64>) -> f64 {
    a[(0, 0)].abs().max(a[(1, 1)].abs()).max(a[(2, 2)].abs())
}

/// `s −= a bᵀ`, written out so that each entry is three products and a sum.
#[inline(always)]
pub(super) fn subtract_abt(s: &mut Matrix3<f64>, a: &Matrix3<f64>, b: &Matrix3<f64>) {
    for j in 0..3 {
        for i in 0..3 {
            s[(i, j)] -= a[(i, 0)] * b[(j, 0)] + a[(i, 1)] * b[(j, 1)] + a[(i, 2)] * b[(j, 2)];
        }
    }
}

/// The lower triangle of `s −= a bᵀ` (the upper one is left stale).
#[inline(always)]
pub(super) fn subtract_lower_abt(s: &mut Matrix3<f64>, a: &Matrix3<f64>, b: &Matrix3<f64>) {
    for j in 0..3 {
        for i in j..3 {
            s[(i, j)] -= a[(i, 0)] * b[(j, 0)] + a[(i, 1)] * b[(j, 1)] + a[(i, 2)] * b[(j, 2)];
        }
    }
}

/// `a d` for a symmetric `d` given whole.
#[inline(always)]
pub(super) fn mul_symmetric(a: &Matrix3<f64>, d: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| a[(i, 0)] * d[(0, j)] + a[(i, 1)] * d[(1, j)] + a[(i, 2)] * d[(2, j)])
}

/// The inverse of a symmetric 3 × 3 matrix from its adjugate: one division, no square
/// root. The pivots of its `L D Lᵀ` are `a₀₀`, `m₂/a₀₀` and `det/m₂` (`m₂` the leading 2 × 2
/// minor), so they are tested against `tiny` without dividing. `None` if one is ≤ `tiny`
/// (or NaN).
#[inline]
pub(super) fn inverse3(a: &Matrix3<f64>, tiny: f64) -> Option<Matrix3<f64>> {
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
