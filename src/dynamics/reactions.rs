//! The node-constraint reactions Ω from `N̈ P = 0` (the paper's eq. 10–11).
//!
//! Each bar's end accelerations respond to its end forces through a symmetric 6 × 6
//! compliance (its mass block with λ eliminated), so the system for Ω is
//! `K = Pᵀ 𝒜 P`, symmetric positive semi-definite, with 3 × 3 blocks wherever two
//! constraint columns share a bar. Its pattern is fixed by the topology: the sparse
//! solver factors it symbolically once and numerically every evaluation.

use nalgebra::{DMatrix, DVector, Vector3};
use nalgebra_sparse::factorization::CscCholesky;
use nalgebra_sparse::pattern::SparsityPattern;
use nalgebra_sparse::CscMatrix;

use crate::model::coords::Coordinates;

/// One bar's contribution to a 3 × 3 block of K.
#[derive(Debug, Clone)]
struct Contribution {
    /// Storage index of block entry (0, j) for j = 0..3; entry (i, j) is `slot[j] + i`.
    slot: [usize; 3],
    /// Product of the two constraint coefficients.
    coef: f64,
    /// Both terms at the same end of the bar.
    same_end: bool,
}

/// How K is stored and solved.
#[derive(Debug, Clone)]
enum Solver {
    /// Sparse Cholesky with a fixed pattern: linear cost for banded structures.
    Sparse {
        pattern: SparsityPattern,
        cholesky: Option<Box<CscCholesky<f64>>>,
    },
    /// Dense SVD with a rank cut: any P, including redundant or indeterminate ones.
    Dense,
}

/// The assembled reaction system and its scratch space.
#[derive(Debug, Clone)]
pub struct Reactions {
    n: usize,
    per_bar: Vec<Vec<Contribution>>,
    values: Vec<f64>,
    solver: Solver,
    /// Right-hand side, then solution Ω (3 per constraint column).
    pub rhs: DVector<f64>,
}

impl Reactions {
    /// Lays out K for the constraint columns of `coords`.
    pub fn new(coords: &Coordinates, n_bars: usize, dense: bool) -> Self {
        let nc = coords.constraints.len();
        let n = 3 * nc;
        // Per bar: the (column, coefficient, end side) terms that touch it.
        let mut touching: Vec<Vec<(usize, f64, usize)>> = vec![Vec::new(); n_bars];
        for (c, col) in coords.constraints.iter().enumerate() {
            for &(e, coef) in &col.terms {
                if !coords.static_bar[e / 2] {
                    touching[e / 2].push((c, coef, e % 2));
                }
            }
        }
        let mut blocks: Vec<(usize, usize)> = touching
            .iter()
            .flat_map(|t| t.iter().flat_map(|a| t.iter().map(|b| (a.0, b.0))))
            .collect();
        blocks.sort_unstable_by_key(|&(row, col)| (col, row));
        blocks.dedup();
        let (solver, slots) = if dense {
            let slots = blocks
                .iter()
                .map(|&(row, col)| block_slot_dense(n, row, col))
                .collect();
            (Solver::Dense, slots)
        } else {
            let (pattern, slots) = block_pattern(nc, &blocks);
            let solver = Solver::Sparse {
                pattern,
                cholesky: None,
            };
            (solver, slots)
        };
        let slot_of = |row: usize, col: usize| {
            let k = blocks
                .binary_search_by_key(&(col, row), |&(r, c)| (c, r))
                .expect("block is in the pattern");
            slots[k]
        };
        let per_bar = touching
            .iter()
            .map(|t| {
                t.iter()
                    .flat_map(|a| t.iter().map(move |b| (a, b)))
                    .map(|(a, b)| Contribution {
                        slot: slot_of(a.0, b.0),
                        coef: a.1 * b.1,
                        same_end: a.2 == b.2,
                    })
                    .collect()
            })
            .collect();
        let len = match &solver {
            Solver::Sparse { pattern, .. } => pattern.nnz(),
            Solver::Dense => n * n,
        };
        Self {
            n,
            per_bar,
            values: vec![0.0; len],
            solver,
            rhs: DVector::zeros(n),
        }
    }

    /// Number of unknowns (3 per constraint column).
    pub fn size(&self) -> usize {
        self.n
    }

    /// Assembles K for the current bar directions `u_i = b_i/|b_i|` and masses.
    pub fn assemble(&mut self, units: &[Vector3<f64>], masses: &[f64]) {
        self.values.iter_mut().for_each(|v| *v = 0.0);
        for (bar, contributions) in self.per_bar.iter().enumerate() {
            let u = units[bar];
            let inv_m = 1.0 / masses[bar];
            for c in contributions {
                // Same end: (4I − 3uuᵀ)/m; opposite ends: (−2I + 3uuᵀ)/m.
                let (alpha, beta) = if c.same_end { (4.0, -3.0) } else { (-2.0, 3.0) };
                let s = c.coef * inv_m;
                for j in 0..3 {
                    for i in 0..3 {
                        let diag = if i == j { alpha } else { 0.0 };
                        self.values[c.slot[j] + i] += s * (diag + beta * u[i] * u[j]);
                    }
                }
            }
        }
    }

    /// Solves `K Ω = rhs` in place; returns false when the sparse factor failed and the
    /// dense fallback was used (a statically indeterminate configuration).
    pub fn solve(&mut self) -> bool {
        if self.n == 0 {
            return true;
        }
        // Non-finite data would stall the factorisations; let the NaN reach the state
        // check, which restores the last good point.
        if !self
            .values
            .iter()
            .chain(self.rhs.iter())
            .all(|x| x.is_finite())
        {
            self.rhs.fill(f64::NAN);
            return true;
        }
        if let Solver::Sparse { pattern, cholesky } = &mut self.solver {
            let ok = match cholesky {
                Some(ch) => ch.refactor(&self.values).is_ok(),
                None => {
                    let m = CscMatrix::try_from_pattern_and_values(
                        pattern.clone(),
                        self.values.clone(),
                    )
                    .expect("values match the pattern");
                    *cholesky = CscCholesky::factor(&m).ok().map(Box::new);
                    cholesky.is_some()
                }
            };
            if ok {
                let ch = cholesky.as_ref().expect("factored");
                ch.solve_mut(&mut self.rhs);
                return true;
            }
            *cholesky = None;
            let dense = self.dense_from_sparse();
            solve_dense(dense, &mut self.rhs);
            return false;
        }
        let k = DMatrix::from_column_slice(self.n, self.n, &self.values);
        solve_dense(k, &mut self.rhs);
        true
    }

    fn dense_from_sparse(&self) -> DMatrix<f64> {
        let Solver::Sparse { pattern, .. } = &self.solver else {
            unreachable!("only called on the sparse path")
        };
        let mut k = DMatrix::zeros(self.n, self.n);
        for col in 0..self.n {
            let range = pattern.major_offsets()[col]..pattern.major_offsets()[col + 1];
            for p in range {
                k[(pattern.minor_indices()[p], col)] = self.values[p];
            }
        }
        k
    }

    /// True if K would use the sparse factor.
    pub fn is_sparse(&self) -> bool {
        matches!(self.solver, Solver::Sparse { .. })
    }
}

fn block_slot_dense(n: usize, row: usize, col: usize) -> [usize; 3] {
    [0, 1, 2].map(|j| (3 * col + j) * n + 3 * row)
}

/// Scalar CSC pattern of full 3 × 3 blocks, and each block's `slot` offsets.
fn block_pattern(nc: usize, blocks: &[(usize, usize)]) -> (SparsityPattern, Vec<[usize; 3]>) {
    let mut offsets = vec![0usize; 3 * nc + 1];
    let mut indices = Vec::new();
    let mut slots = vec![[0usize; 3]; blocks.len()];
    let mut k = 0;
    for col in 0..nc {
        let start = k;
        while k < blocks.len() && blocks[k].1 == col {
            k += 1;
        }
        for j in 0..3 {
            for (b, &(row, _)) in blocks[start..k].iter().enumerate() {
                slots[start + b][j] = indices.len();
                indices.extend([3 * row, 3 * row + 1, 3 * row + 2]);
            }
            offsets[3 * col + j + 1] = indices.len();
        }
    }
    let pattern = SparsityPattern::try_from_offsets_and_indices(3 * nc, 3 * nc, offsets, indices)
        .expect("blocks are sorted and unique");
    (pattern, slots)
}

/// Minimum-norm solve through the SVD, with the rank cut at round-off.
fn solve_dense(k: DMatrix<f64>, rhs: &mut DVector<f64>) {
    let Some(svd) = k.try_svd(true, true, f64::EPSILON, 10_000) else {
        rhs.fill(f64::NAN);
        return;
    };
    let tol = 1e-12 * svd.singular_values.max();
    let x = svd.solve(rhs, tol).expect("U and V were computed");
    rhs.copy_from(&x);
}
