//! The node-constraint reactions Ω from `N̈ P = 0` (the paper's eq. 10–11).
//!
//! Each bar's end accelerations respond to its end forces through a symmetric 6 × 6
//! compliance (its mass block with λ eliminated), so the system for Ω is
//! `K = Pᵀ 𝒜 P`, symmetric positive semi-definite, with 3 × 3 blocks wherever two
//! constraint columns share a bar. Its pattern is fixed by the topology: the sparse
//! solver factors it symbolically once and numerically every evaluation.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

mod lanes;
mod shared;

use super::coords::Coordinates;
use super::inertia::BarInertia;
use crate::linalg::block_cholesky::BlockLdl;
use crate::linalg::block_lanes::LaneGroups;
use crate::linalg::pattern::components;
use crate::linalg::symmetric::{Symmetric, SYMMETRIC};
use lanes::LaneAssembly;

/// A constraint column touching a bar: (column, coefficient, end side 0/1).
type Term = (usize, f64, usize);

/// One bar's contribution to a 3 × 3 block of K: `coef (W_ij I − c_ij u uᵀ)`, with the
/// constant scalars multiplied out once.
#[derive(Debug, Clone)]
struct Contribution {
    /// Sparse: index into the block values; dense: offset of the block's (0, 0) entry.
    slot: usize,
    /// `coef · W_ij`, added to the diagonal (`coef` the product of the two constraint
    /// coefficients, ±1 for joints and pins, so the products are exact).
    diagonal: f64,
    /// `coef · c_ij`, the factor of `−u uᵀ`.
    along: f64,
    /// The first contribution to its sparse slot in assembly order: it sets the block
    /// instead of adding to it, so K needs no zeroing pass.
    first: bool,
    /// The last contribution to a pivot block in assembly order: the block is then as
    /// assembled, and its diagonal enters the singularity threshold's scale.
    closes_pivot: bool,
}

impl Contribution {
    /// This contribution's block for a bar with `b bᵀ` (lower triangle) and `1/|b|²`. A
    /// uniform rod: same end (4I − 3uuᵀ)/m, opposite ends (−2I + 3uuᵀ)/m.
    #[inline(always)]
    fn block(&self, bb: &Symmetric, inv_l2: f64) -> Symmetric {
        let s = -self.along * inv_l2;
        let mut block = bb.map(|x| x * s);
        for k in [0, 3, 5] {
            block[k] += self.diagonal;
        }
        block
    }
}

/// `b bᵀ`'s lower triangle (its upper one is the same products).
#[inline(always)]
fn outer_lower(b: &Vector3<f64>) -> Symmetric {
    [
        b.x * b.x,
        b.y * b.x,
        b.z * b.x,
        b.y * b.y,
        b.z * b.y,
        b.z * b.z,
    ]
}

/// How K is stored and solved.
#[derive(Debug, Clone)]
enum Solver {
    /// Block-sparse Cholesky with a fixed pattern: linear cost for banded structures.
    Sparse(Box<BlockLdl>),
    /// Dense SVD with a rank cut: any P, including redundant or indeterminate ones.
    Dense(Vec<f64>),
}

/// The assembled reaction system and its scratch space.
#[derive(Debug, Clone)]
pub struct Reactions {
    n: usize,
    /// Bar i's contributions, flat: `contributions[bar_start[i]..bar_start[i + 1]]`.
    bar_start: Vec<usize>,
    contributions: Vec<Contribution>,
    solver: Solver,
    /// Right-hand side, then solution Ω (3 per constraint column, in the system's
    /// numbering: see [`Self::solution`]).
    pub rhs: DVector<f64>,
    /// The constraint columns' `(end, coefficient)` terms, flat, column c (in the system's
    /// numbering) at `term_start[c]..term_start[c + 1]`.
    term_start: Vec<usize>,
    terms: Vec<(usize, f64)>,
    /// Sparse slots no contribution sets (see [`Contribution::first`]).
    unassigned: Vec<usize>,
    /// Per constraint column of the coordinates, its number in the system.
    internal: Vec<usize>,
    /// Bars assembled several at a time into the side-by-side chains, where K lives in them
    /// and bars make bundles.
    lane_assembly: Option<LaneAssembly>,
}

impl Reactions {
    /// Lays out K for the constraint columns of `coords` and the bars' `inertia`.
    pub fn new(coords: &Coordinates, inertia: &[BarInertia], dense: bool) -> Self {
        let n_bars = inertia.len();
        let nc = coords.constraints.len();
        let n = 3 * nc;
        // Per bar: the (column, coefficient, end side) terms that touch it.
        let mut touching: Vec<Vec<Term>> = vec![Vec::new(); n_bars];
        for (c, col) in coords.constraints.iter().enumerate() {
            for &(e, coef) in &col.terms {
                if !coords.static_bar[e / 2] {
                    touching[e / 2].push((c, coef, e % 2));
                }
            }
        }
        // The sparse system numbers its columns component by component (each in its own
        // order), so that K's components, which factor independently, lie apart in memory:
        // two threads factor different ones without sharing a cache line (a tower's three
        // chains are otherwise interleaved). Each component's arithmetic is unchanged.
        let order: Vec<usize> = if dense {
            (0..nc).collect()
        } else {
            let coupled: Vec<(usize, usize)> = touching
                .iter()
                .flat_map(|t| t.windows(2).map(|w| (w[1].0, w[0].0)))
                .collect();
            components(nc, &coupled).concat()
        };
        let mut internal = vec![0; nc];
        for (p, &c) in order.iter().enumerate() {
            internal[c] = p;
        }
        for term in touching.iter_mut().flatten() {
            term.0 = internal[term.0];
        }
        // The 3 × 3 blocks are symmetric, so the sparse path keeps the lower ones only.
        let pairs = |t: &Vec<Term>| -> Vec<(Term, Term)> {
            t.iter()
                .flat_map(|&a| t.iter().map(move |&b| (a, b)))
                .filter(|(a, b)| dense || a.0 >= b.0)
                .collect()
        };
        let solver = if dense {
            Solver::Dense(vec![0.0; n * n])
        } else {
            let lower: Vec<(usize, usize)> = touching
                .iter()
                .flat_map(&pairs)
                .map(|(a, b)| (a.0, b.0))
                .collect();
            Solver::Sparse(Box::new(BlockLdl::new(nc, &lower)))
        };
        let slot = |row: usize, col: usize| match &solver {
            Solver::Sparse(chol) => chol.k_index(row, col).expect("block is in the pattern"),
            Solver::Dense(_) => 3 * col * n + 3 * row,
        };
        let slots = match &solver {
            Solver::Sparse(chol) => chol.slots(),
            Solver::Dense(_) => 0,
        };
        let mut assigned = vec![false; slots];
        let mut closing = vec![None; slots];
        let mut bar_start = vec![0];
        let mut contributions = Vec::new();
        for (bar, t) in touching.iter().enumerate() {
            for (a, b) in pairs(t) {
                let coef = a.1 * b.1;
                let (w, c) = inertia[bar].compliance_scalars(a.2, b.2);
                let slot = slot(a.0, b.0);
                let first = !dense && !std::mem::replace(&mut assigned[slot], true);
                if !dense && a.0 == b.0 {
                    closing[slot] = Some(contributions.len());
                }
                contributions.push(Contribution {
                    slot,
                    diagonal: w * coef,
                    along: c * coef,
                    first,
                    closes_pivot: false,
                });
            }
            bar_start.push(contributions.len());
        }
        for &i in closing.iter().flatten() {
            contributions[i].closes_pivot = true;
        }
        // Fill-in, and blocks of columns no moving bar touches: zeroed before each assembly.
        let unassigned = (0..slots).filter(|&p| !assigned[p]).collect();
        let mut term_start = vec![0];
        let mut terms = Vec::new();
        for &c in &order {
            terms.extend_from_slice(&coords.constraints[c].terms);
            term_start.push(terms.len());
        }
        let lane_assembly = match &solver {
            Solver::Sparse(chol) => chol.lanes().and_then(|lanes| {
                let of = |bar: usize| &contributions[bar_start[bar]..bar_start[bar + 1]];
                let position = |slot| lanes.position(slot);
                LaneAssembly::new(n_bars, of, position, |block| lanes.used_lanes(block))
            }),
            Solver::Dense(_) => None,
        };
        Self {
            n,
            bar_start,
            contributions,
            solver,
            rhs: DVector::zeros(n),
            term_start,
            terms,
            unassigned,
            internal,
            lane_assembly,
        }
    }

    /// Ω of constraint column `c` (in the coordinates' numbering) from the last solve, N.
    pub fn solution(&self, c: usize) -> Vector3<f64> {
        let i = 3 * self.internal[c];
        Vector3::new(self.rhs[i], self.rhs[i + 1], self.rhs[i + 2])
    }

    /// The same system with the chains factored one after the other (the reference the
    /// side-by-side factor is tested against).
    #[cfg(test)]
    pub(crate) fn without_lanes(mut self) -> Self {
        if let Solver::Sparse(chol) = self.solver {
            self.solver = Solver::Sparse(Box::new(chol.without_lanes()));
        }
        self.lane_assembly = None;
        self
    }

    /// Whether the sparse factor runs identical chains side by side.
    #[cfg(test)]
    pub(crate) fn side_by_side(&self) -> bool {
        matches!(&self.solver, Solver::Sparse(chol) if chol.has_lanes())
    }

    /// Number of unknowns (3 per constraint column).
    pub fn size(&self) -> usize {
        self.n
    }

    /// Assembles K for the current bar directions `u_i = b_i/|b_i|` (the inertias were
    /// folded into the contributions when K was laid out).
    pub fn assemble(&mut self, units: &[Vector3<f64>]) {
        self.clear();
        for (bar, u) in units.iter().enumerate() {
            self.add_bar(bar, u, 1.0);
        }
    }

    /// Assembles K for the bar vectors and their `1/|b|²`, `b(bar)`, as [`Self::add_bar`] of
    /// every bar in order would (the same bits), several bars at a time where they make
    /// bundles in the side-by-side chains.
    #[inline(always)]
    pub fn assemble_bars<'a>(&mut self, b: impl Fn(usize) -> (&'a Vector3<f64>, &'a f64)) {
        self.assemble_bars_with(b, crate::simd::has_avx2());
    }

    /// [`Self::assemble_bars`], the bundles in AVX2 if `avx2` (the processor has it).
    #[inline(always)]
    fn assemble_bars_with<'a>(
        &mut self,
        b: impl Fn(usize) -> (&'a Vector3<f64>, &'a f64),
        avx2: bool,
    ) {
        self.clear();
        let bars = self.bar_start.len() - 1;
        let Self {
            solver,
            contributions,
            bar_start,
            lane_assembly,
            ..
        } = self;
        if let (Some(assembly), Solver::Sparse(chol)) = (lane_assembly, solver) {
            let lanes_k = chol
                .lanes_mut()
                .expect("bundles only where K is in the lanes");
            let of = |bar: usize| &contributions[bar_start[bar]..bar_start[bar + 1]];
            let add_bar = |lanes_k: &mut LaneGroups, bar, bv: &Vector3<f64>, inv_l2| {
                let bb = outer_lower(bv);
                for c in of(bar) {
                    lanes_k.put_symmetric(c.slot, &c.block(&bb, inv_l2), c.first);
                }
            };
            assembly.assemble(lanes_k, b, add_bar, avx2);
            return;
        }
        for bar in 0..bars {
            let (bv, inv_l2) = b(bar);
            self.add_bar(bar, bv, *inv_l2);
        }
    }

    /// Whether [`Self::assemble_bars`] takes bars several at a time (then the first λ pass
    /// leaves K to it).
    pub fn assembles_in_bundles(&self) -> bool {
        self.lane_assembly.is_some()
    }

    /// Sets the right-hand side to `−N̈ P` for the end accelerations without reactions.
    #[inline(always)]
    pub fn set_rhs(&mut self, end_acc: &[Vector3<f64>]) {
        let (rhs, _) = self.rhs.as_mut_slice().as_chunks_mut::<3>();
        for (r, span) in rhs.iter_mut().zip(self.term_start.windows(2)) {
            let mut sum = Vector3::zeros();
            for &(e, coef) in &self.terms[span[0]..span[1]] {
                sum += end_acc[e] * coef;
            }
            *r = [-sum.x, -sum.y, -sum.z];
        }
    }

    /// Adds the solved reactions `Ω P` to the end forces.
    #[inline(always)]
    pub fn add_to(&self, end_force: &mut [Vector3<f64>]) {
        let (omega, _) = self.rhs.as_slice().as_chunks::<3>();
        for (o, span) in omega.iter().zip(self.term_start.windows(2)) {
            let o = Vector3::from(*o);
            for &(e, coef) in &self.terms[span[0]..span[1]] {
                end_force[e] += o * coef;
            }
        }
    }

    /// Readies K for [`Self::add_bar`] of every bar in order (sparse: zeroes only the slots
    /// no bar sets).
    #[inline(always)]
    pub fn clear(&mut self) {
        match &mut self.solver {
            Solver::Sparse(chol) => {
                for &p in &self.unassigned {
                    chol.set(p, &Matrix3::zeros());
                }
            }
            Solver::Dense(values) => values.fill(0.0),
        }
    }

    /// Adds bar `bar`'s blocks to K for its vector `b`, given `1/|b|²` (so that
    /// `u uᵀ = b bᵀ/|b|²` needs neither a square root nor a division per entry).
    #[inline(always)]
    pub fn add_bar(&mut self, bar: usize, b: &Vector3<f64>, inv_l2: f64) {
        let (start, end) = (self.bar_start[bar], self.bar_start[bar + 1]);
        if start == end {
            return;
        }
        let bb = outer_lower(b);
        let block = |c: &Contribution| c.block(&bb, inv_l2);
        let contributions = &self.contributions[start..end];
        match &mut self.solver {
            Solver::Sparse(chol) => {
                for c in contributions {
                    chol.put_symmetric(c.slot, &block(c), c.first);
                }
            }
            Solver::Dense(values) => {
                for c in contributions {
                    let block = block(c);
                    for j in 0..3 {
                        for i in 0..3 {
                            let k = SYMMETRIC[3 * j + i];
                            values[c.slot + j * self.n + i] += block[k];
                        }
                    }
                }
            }
        }
    }

    /// Solves `K Ω = rhs` in place; returns false when the sparse factor failed and the
    /// dense fallback was used (a statically indeterminate configuration). The factor
    /// may overwrite K (its updated blocks) and, as it solves in the same sweep, the right-hand side, so the
    /// fallback calls `assemble_again` to assemble the same K and right-hand side again
    /// (the caller still has what they came from; keeping copies here would cost every
    /// evaluation).
    #[inline(always)]
    pub fn solve(&mut self, assemble_again: impl FnOnce(&mut Self)) -> bool {
        if self.n == 0 {
            return true;
        }
        if let Solver::Sparse(chol) = &mut self.solver {
            if chol.factor_and_solve(&mut self.rhs) {
                return true;
            }
            assemble_again(self);
        }
        // A NaN fails a pivot, so only a failed or dense solve scans: non-finite data would
        // stall the SVD; let the NaN reach the state check, which restores the last good
        // point.
        if !self.finite() {
            self.rhs.fill(f64::NAN);
            return true;
        }
        match &self.solver {
            Solver::Sparse(chol) => {
                solve_dense(chol.dense(), &mut self.rhs);
                false
            }
            Solver::Dense(values) => {
                solve_dense(
                    DMatrix::from_column_slice(self.n, self.n, values),
                    &mut self.rhs,
                );
                true
            }
        }
    }

    /// Whether K and the right-hand side are finite.
    fn finite(&self) -> bool {
        let k = match &self.solver {
            Solver::Sparse(chol) => {
                (0..chol.slots()).all(|p| chol.block(p).iter().all(|x| x.is_finite()))
            }
            Solver::Dense(values) => values.iter().all(|x| x.is_finite()),
        };
        k && self.rhs.iter().all(|x| x.is_finite())
    }
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

#[cfg(test)]
mod tests;
