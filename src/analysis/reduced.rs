//! The dynamics restricted to the tangent space of the bar constraints at a state.

use nalgebra::{DMatrix, DVector, Dyn, SymmetricEigen};

use super::Tangent;

/// Minimal coordinates ξ at a state: `δη₂ = Z ξ`, with mass, stiffness and damping in ξ.
#[derive(Debug, Clone)]
pub struct Reduced {
    /// `Z` (3r × m), orthonormal columns spanning null(G).
    pub basis: DMatrix<f64>,
    /// `Zᵀ M̄ Z`.
    pub mass: DMatrix<f64>,
    /// `Zᵀ K Z` with K the tangent stiffness at fixed multipliers (symmetric).
    pub stiffness: DMatrix<f64>,
    /// `−Zᵀ (∂f/∂q̇) Z`.
    pub damping: DMatrix<f64>,
}

impl Reduced {
    /// Restricts a tangent to its constraint tangent space.
    pub fn new(tangent: &Tangent) -> Self {
        let basis = null_basis(&tangent.constraints, tangent.mass.nrows());
        let restrict = |m: &DMatrix<f64>| basis.tr_mul(&(m * &basis));
        let k = restrict(&tangent.tangent_stiffness());
        Self {
            mass: restrict(&tangent.mass),
            stiffness: (&k + k.transpose()) * 0.5,
            damping: -restrict(&tangent.damping),
            basis,
        }
    }

    /// Number of minimal coordinates.
    pub fn dim(&self) -> usize {
        self.basis.ncols()
    }
}

/// An orthonormal basis of the null space of `g` (rows × n), from the eigenvectors of
/// `gᵀ g` whose eigenvalues vanish relative to the largest.
pub fn null_basis(g: &DMatrix<f64>, n: usize) -> DMatrix<f64> {
    if g.nrows() == 0 {
        return DMatrix::identity(n, n);
    }
    let eigen = symmetric_eigen(g.tr_mul(g));
    let largest = eigen.eigenvalues.amax();
    let keep: Vec<usize> = (0..n)
        .filter(|&k| eigen.eigenvalues[k] <= 1e-12 * largest)
        .collect();
    DMatrix::from_fn(n, keep.len(), |r, c| eigen.eigenvectors[(r, keep[c])])
}

/// The eigen-decomposition of a symmetric matrix; a 0 × 0 one (a structure with nothing
/// free to move, or nothing left after the rigid motions) has no eigenpairs, where
/// nalgebra would panic.
pub fn symmetric_eigen(a: DMatrix<f64>) -> SymmetricEigen<f64, Dyn> {
    if a.is_empty() {
        return SymmetricEigen {
            eigenvectors: a,
            eigenvalues: DVector::zeros(0),
        };
    }
    SymmetricEigen::new(a)
}
