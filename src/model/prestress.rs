//! Equilibrium prestress: a self-stress of the start geometry, every cable in tension and
//! every bar in compression, from the null space of the equilibrium matrix at the free
//! nodes. Pinned nodes take reactions, so they add no equation.

use microlp::{ComparisonOp, OptimizationDirection, Problem};
use nalgebra::{DMatrix, DVector, Vector3};

use crate::error::SceneError;

/// Force densities (N/m) of a self-stress: cables (tension) then bars (compression).
#[derive(Debug, Clone, PartialEq)]
pub struct SelfStress {
    /// γ per cable, > 0.
    pub cables: Vec<f64>,
    /// λ per bar, > 0.
    pub bars: Vec<f64>,
}

/// Finds a self-stress whose smallest cable tension is `min_tension` (N).
///
/// The free-standing structure (equilibrium at every node) is tried first, so that
/// elements between pinned nodes share the structure's own self-stress; only if it has
/// none are the pinned nodes' equations dropped.
pub fn self_stress(
    positions: &[Vector3<f64>],
    pinned: &[bool],
    bars: &[[usize; 2]],
    cables: &[[usize; 2]],
    min_tension: f64,
) -> Result<SelfStress, SceneError> {
    let unpinned = vec![false; pinned.len()];
    let mut x = match positive_null_vector(positions, &unpinned, bars, cables) {
        Ok(x) => x,
        Err(_) => positive_null_vector(positions, pinned, bars, cables)?,
    };
    let min_t = cables
        .iter()
        .enumerate()
        .map(|(j, &[p, q])| x[j] * (positions[q] - positions[p]).norm())
        .fold(f64::INFINITY, f64::min);
    let scale = if min_t.is_finite() {
        min_tension / min_t
    } else {
        1.0
    };
    x *= scale;
    Ok(SelfStress {
        cables: x.rows(0, cables.len()).iter().copied().collect(),
        bars: x.rows(cables.len(), bars.len()).iter().copied().collect(),
    })
}

/// A null vector of the equilibrium matrix at the unpinned nodes with every entry > 0.
fn positive_null_vector(
    positions: &[Vector3<f64>],
    pinned: &[bool],
    bars: &[[usize; 2]],
    cables: &[[usize; 2]],
) -> Result<DVector<f64>, SceneError> {
    let free: Vec<Option<usize>> = {
        let mut k = 0;
        pinned
            .iter()
            .map(|&p| {
                (!p).then(|| {
                    k += 1;
                    k - 1
                })
            })
            .collect()
    };
    let n_free = free.iter().flatten().count();
    let elements: Vec<([usize; 2], f64)> = cables
        .iter()
        .map(|&c| (c, 1.0))
        .chain(bars.iter().map(|&b| (b, -1.0)))
        .collect();
    let n_el = elements.len();
    // Equilibrium at a free node: Σ γ (x_other − x) − Σ λ (x_other − x) = 0.
    let mut a = DMatrix::<f64>::zeros((3 * n_free).max(n_el), n_el);
    for (col, &([p, q], sign)) in elements.iter().enumerate() {
        for (here, there) in [(p, q), (q, p)] {
            if let Some(f) = free[here] {
                let d = (positions[there] - positions[here]) * sign;
                for k in 0..3 {
                    a[(3 * f + k, col)] += d[k];
                }
            }
        }
    }
    let svd = a.svd(false, true);
    let v_t = svd.v_t.as_ref().expect("requested V");
    let s_max = svd.singular_values.max().max(1e-300);
    let null: Vec<usize> = (0..n_el)
        .filter(|&k| svd.singular_values[k] <= 1e-10 * s_max)
        .collect();
    let no_self_stress = |why: &str| {
        SceneError::invalid(
            "prestress",
            format!(
                "the start geometry admits no self-stress with every cable in tension and \
                 every bar in compression ({why}); give explicit rest lengths or force \
                 densities, or fix the geometry"
            ),
        )
    };
    if null.is_empty() {
        return Err(no_self_stress("the equilibrium matrix has no null space"));
    }
    let z = DMatrix::from_fn(n_el, null.len(), |i, j| v_t[(null[j], i)]);
    let ones = DVector::from_element(n_el, 1.0);
    let mut x = &z * (z.transpose() * &ones);
    let positive = |x: &DVector<f64>| x.min() > 1e-9 * x.amax();
    if !positive(&x) {
        let w = max_min_combination(&z).ok_or_else(|| {
            no_self_stress(&format!(
                "no positive combination of its {} self-stress modes",
                null.len()
            ))
        })?;
        x = &z * w;
        if !positive(&x) {
            return Err(no_self_stress(&format!(
                "no positive combination of its {} self-stress modes",
                null.len()
            )));
        }
    }
    Ok(x)
}

/// Maximises `min(Z w)` over `|w|∞ ≤ 1`; `None` when the best minimum is not positive.
fn max_min_combination(z: &DMatrix<f64>) -> Option<DVector<f64>> {
    let mut lp = Problem::new(OptimizationDirection::Maximize);
    let t = lp.add_var(1.0, (f64::NEG_INFINITY, 1.0));
    let w: Vec<_> = (0..z.ncols())
        .map(|_| lp.add_var(0.0, (-1.0, 1.0)))
        .collect();
    for i in 0..z.nrows() {
        let mut terms: Vec<_> = w.iter().enumerate().map(|(k, &v)| (v, z[(i, k)])).collect();
        terms.push((t, -1.0));
        lp.add_constraint(&terms, ComparisonOp::Ge, 0.0);
    }
    let solution = lp.solve().ok()?.into_solution().ok()?;
    (solution.var_value(t) > 1e-9)
        .then(|| DVector::from_iterator(w.len(), w.iter().map(|&v| solution.var_value(v))))
}
