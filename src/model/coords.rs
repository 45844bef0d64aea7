//! Non-minimal coordinates: each bar owns two end columns of `N` (3 × 2β), and the node
//! constraints `N P = D` are eliminated by `N = N₀ + η₂ U₂ᵀ`, with `U₂` an orthonormal
//! basis of null(Pᵀ) and `N₀ = D P⁺` constant. `U₂` is stored by rows (one row per end),
//! so the sparse joint/pin basis and a dense SVD basis share every loop.

use nalgebra::{DMatrix, Vector3};

use crate::error::SceneError;

/// End `e` of the non-minimal coordinates: bar `e / 2`, start if even, end if odd.
pub type End = usize;

/// One column of `P`: `Σ coef · n_end` is held at the matching column of `D`.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstraintColumn {
    /// `(end, coefficient)` pairs.
    pub terms: Vec<(End, f64)>,
}

/// Which orthonormal basis of null(Pᵀ) to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BasisKind {
    /// Merged-node columns of 1/√k: valid for joints and pins, linear cost.
    #[default]
    Sparse,
    /// SVD of the paper's full `P` (with its redundant columns): general, quadratic cost.
    Dense,
}

/// The map between the reduced coordinates η₂ (3 × r, stored flat, column `g` at
/// `3g..3g+3`) and the bar-end positions.
#[derive(Debug, Clone)]
pub struct Coordinates {
    /// Number of reduced columns r.
    pub r: usize,
    /// Physical node of each end (0-based).
    pub end_node: Vec<usize>,
    /// One end standing for each physical node; `None` for a bar-less (pinned) node.
    pub node_end: Vec<Option<End>>,
    /// Columns of `N₀ = D P⁺` per end, in m.
    pub fixed: Vec<Vector3<f64>>,
    /// Row offsets of `U₂` (CSR, length 2β + 1).
    pub row_start: Vec<usize>,
    /// `(g, U₂[e, g])` entries, row by row.
    pub entries: Vec<(usize, f64)>,
    /// The sparse basis's rows, each at most one entry (`None`: a pinned end), so the
    /// hot loops read an end's term directly instead of through `row_start`.
    pub single: Option<Vec<Option<(usize, f64)>>>,
    /// Constraint columns used for the reactions Ω.
    pub constraints: Vec<ConstraintColumn>,
    /// True for a bar whose ends are both pinned: it never moves.
    pub static_bar: Vec<bool>,
}

impl Coordinates {
    /// Builds the coordinates for bars `(start, end)` over `positions`, with `pinned` nodes.
    pub fn new(
        bars: &[(usize, usize)],
        positions: &[Vector3<f64>],
        pinned: &[bool],
        kind: BasisKind,
    ) -> Result<Self, SceneError> {
        let mut coords = Self::skeleton(bars, positions.len(), pinned);
        let node_ends = coords.node_ends(positions.len());
        match kind {
            BasisKind::Sparse => coords.fill_sparse(&node_ends, positions, pinned),
            BasisKind::Dense => coords.fill_dense(&node_ends, positions, pinned)?,
        }
        Ok(coords)
    }

    /// General constraints `N P = D` on the bar ends (`constraints` with right-hand sides
    /// `d`), eliminated by SVD; used for constraint sets other than joints and pins.
    pub fn general(
        bars: &[(usize, usize)],
        n_nodes: usize,
        constraints: Vec<ConstraintColumn>,
        d: Vec<Vector3<f64>>,
    ) -> Result<Self, SceneError> {
        let mut coords = Self::skeleton(bars, n_nodes, &vec![false; n_nodes]);
        coords.constraints = constraints;
        coords.eliminate(d)?;
        Ok(coords)
    }

    fn skeleton(bars: &[(usize, usize)], n_nodes: usize, pinned: &[bool]) -> Self {
        let end_node: Vec<usize> = bars.iter().flat_map(|&(a, b)| [a, b]).collect();
        let mut node_end = vec![None; n_nodes];
        for (e, &n) in end_node.iter().enumerate().rev() {
            node_end[n] = Some(e);
        }
        Self {
            r: 0,
            end_node,
            node_end,
            fixed: Vec::new(),
            row_start: Vec::new(),
            entries: Vec::new(),
            single: None,
            constraints: Vec::new(),
            static_bar: bars.iter().map(|&(a, b)| pinned[a] && pinned[b]).collect(),
        }
    }

    fn node_ends(&self, n_nodes: usize) -> Vec<Vec<End>> {
        let mut node_ends = vec![Vec::new(); n_nodes];
        for (e, &n) in self.end_node.iter().enumerate() {
            node_ends[n].push(e);
        }
        node_ends
    }

    fn fill_sparse(&mut self, node_ends: &[Vec<End>], positions: &[Vector3<f64>], pinned: &[bool]) {
        let n_ends = self.end_node.len();
        let mut rows: Vec<Option<(usize, f64)>> = vec![None; n_ends];
        self.fixed = vec![Vector3::zeros(); n_ends];
        for (n, ends) in node_ends.iter().enumerate() {
            if ends.is_empty() {
                continue;
            }
            if pinned[n] {
                for &e in ends {
                    self.fixed[e] = positions[n];
                    // A bar pinned at both ends is static; its pins carry no dynamics.
                    if !self.static_bar[e / 2] {
                        self.constraints.push(ConstraintColumn {
                            terms: vec![(e, 1.0)],
                        });
                    }
                }
            } else {
                let g = self.r;
                self.r += 1;
                let c = 1.0 / (ends.len() as f64).sqrt();
                for &e in ends {
                    rows[e] = Some((g, c));
                }
                for &e in &ends[1..] {
                    self.constraints.push(ConstraintColumn {
                        terms: vec![(e, 1.0), (ends[0], -1.0)],
                    });
                }
            }
        }
        self.row_start.push(0);
        for row in &rows {
            self.entries.extend(row);
            self.row_start.push(self.entries.len());
        }
        self.single = Some(rows);
    }

    /// The paper's `P` (k−1 joint columns per shared node, one pin column per pinned
    /// end, so pinned joints are redundant), eliminated through its SVD and rank.
    fn fill_dense(
        &mut self,
        node_ends: &[Vec<End>],
        positions: &[Vector3<f64>],
        pinned: &[bool],
    ) -> Result<(), SceneError> {
        let mut d_cols = Vec::new();
        for (n, ends) in node_ends.iter().enumerate() {
            for &e in ends.iter().skip(1) {
                self.constraints.push(ConstraintColumn {
                    terms: vec![(e, 1.0), (ends[0], -1.0)],
                });
                d_cols.push(Vector3::zeros());
            }
            if pinned[n] {
                for &e in ends {
                    self.constraints.push(ConstraintColumn {
                        terms: vec![(e, 1.0)],
                    });
                    d_cols.push(positions[n]);
                }
            }
        }
        self.eliminate(d_cols)
    }

    /// Eliminates general constraints `N P = D` (the columns in `self.constraints`, with
    /// `d_cols` their right-hand sides) through the SVD of `P`: the rank it reveals drops
    /// redundant columns, and a `D` outside the range of `P` is a contradiction.
    pub fn eliminate(&mut self, d_cols: Vec<Vector3<f64>>) -> Result<(), SceneError> {
        let n_ends = self.end_node.len();
        let nc = self.constraints.len();
        // Pad P to square so that the SVD returns a full U.
        let mut p = DMatrix::<f64>::zeros(n_ends, n_ends.max(nc));
        for (c, col) in self.constraints.iter().enumerate() {
            for &(e, coef) in &col.terms {
                p[(e, c)] += coef;
            }
        }
        let svd = p.clone().svd(true, true);
        let u = svd.u.as_ref().expect("requested U");
        let v_t = svd.v_t.as_ref().expect("requested V");
        let s_max = svd.singular_values.max();
        let tol = 1e-10 * s_max.max(1.0);
        let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
        order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
        let rank = order
            .iter()
            .filter(|&&k| svd.singular_values[k] > tol)
            .count();
        // N₀ = D P⁺ = D V Σ⁻¹ U₁ᵀ over the revealed rank.
        let mut n0 = DMatrix::<f64>::zeros(3, n_ends);
        for &k in &order[..rank] {
            let s = svd.singular_values[k];
            for e in 0..n_ends {
                let mut dv = Vector3::zeros();
                for (c, d) in d_cols.iter().enumerate() {
                    dv += d * v_t[(k, c)];
                }
                let col = dv * (u[(e, k)] / s);
                for i in 0..3 {
                    n0[(i, e)] += col[i];
                }
            }
        }
        for (c, d) in d_cols.iter().enumerate() {
            let mut np = Vector3::zeros();
            for &(e, coef) in &self.constraints[c].terms {
                np += n0.column(e) * coef;
            }
            if (np - d).norm() > 1e-9 * (1.0 + d.norm()) {
                return Err(SceneError::invalid(
                    "fixed",
                    format!(
                        "contradictory node constraints: column {} of N P = D cannot hold",
                        c + 1
                    ),
                ));
            }
        }
        self.fixed = (0..n_ends)
            .map(|e| Vector3::new(n0[(0, e)], n0[(1, e)], n0[(2, e)]))
            .collect();
        self.r = n_ends - rank;
        self.row_start.push(0);
        for e in 0..n_ends {
            for (g, &k) in order[rank..].iter().enumerate() {
                self.entries.push((g, u[(e, k)]));
            }
            self.row_start.push(self.entries.len());
        }
        Ok(())
    }

    /// Number of bar ends, 2β.
    pub fn n_ends(&self) -> usize {
        self.end_node.len()
    }

    /// Row `e` of `U₂`.
    #[inline]
    pub fn row(&self, e: End) -> &[(usize, f64)] {
        &self.entries[self.row_start[e]..self.row_start[e + 1]]
    }

    /// Column `e` of `N = N₀ + η₂ U₂ᵀ` (with `offset` false: of `Ṅ = η̇₂ U₂ᵀ`).
    #[inline(always)]
    pub fn end_vector(&self, e: End, eta: &[f64], offset: bool) -> Vector3<f64> {
        let Some(single) = &self.single else {
            return self.end_vector_csr(e, eta, offset);
        };
        let mut x = if offset {
            self.fixed[e]
        } else {
            Vector3::zeros()
        };
        if let Some((g, c)) = single[e] {
            x += Vector3::from(eta.as_chunks::<3>().0[g]) * c;
        }
        x
    }

    /// [`Self::end_vector`] of the positions (`offset`) of ends `first..first + out.len()`,
    /// by the same arithmetic, in one loop over the sparse basis where there is one (end by
    /// end, the switch location's pass took 1.6% of tower20's instructions, so 1.0%).
    pub fn end_positions(&self, first: usize, eta: &[f64], out: &mut [Vector3<f64>]) {
        let Some(single) = &self.single else {
            for (e, x) in (first..).zip(out) {
                *x = self.end_vector_csr(e, eta, true);
            }
            return;
        };
        let eta = eta.as_chunks::<3>().0;
        let basis = single[first..].iter().zip(&self.fixed[first..]);
        for (x, (term, fixed)) in out.iter_mut().zip(basis) {
            let mut at = *fixed;
            if let Some((g, c)) = *term {
                at += Vector3::from(eta[g]) * c;
            }
            *x = at;
        }
    }

    /// Component `axis` of [`Self::end_vector`], by the same arithmetic (so the same bits).
    #[inline]
    pub fn end_component(&self, e: End, eta: &[f64], offset: bool, axis: usize) -> f64 {
        let mut x = if offset { self.fixed[e][axis] } else { 0.0 };
        match &self.single {
            Some(single) => {
                if let Some((g, c)) = single[e] {
                    x += eta[3 * g + axis] * c;
                }
            }
            None => {
                for &(g, c) in self.row(e) {
                    x += eta[3 * g + axis] * c;
                }
            }
        }
        x
    }

    /// [`Self::end_vector`] through the general rows (the dense basis).
    fn end_vector_csr(&self, e: End, eta: &[f64], offset: bool) -> Vector3<f64> {
        let mut x = if offset {
            self.fixed[e]
        } else {
            Vector3::zeros()
        };
        for &(g, c) in self.row(e) {
            x += Vector3::new(eta[3 * g], eta[3 * g + 1], eta[3 * g + 2]) * c;
        }
        x
    }

    /// Adds `value · U₂[e, :]` to η (flat), i.e. the reduced image of a per-end quantity.
    #[inline]
    pub fn scatter(&self, e: End, value: &Vector3<f64>, eta: &mut [f64]) {
        for &(g, c) in self.row(e) {
            for k in 0..3 {
                eta[3 * g + k] += c * value[k];
            }
        }
    }

    /// `ψ = U₂ᵀ c_b,iᵀ` for bar `i`, as sparse `(g, value)` pairs.
    pub fn psi(&self, bar: usize) -> Vec<(usize, f64)> {
        let mut psi: Vec<(usize, f64)> = Vec::new();
        for (e, sign) in [(2 * bar, -1.0), (2 * bar + 1, 1.0)] {
            for &(g, c) in self.row(e) {
                match psi.iter_mut().find(|(h, _)| *h == g) {
                    Some((_, v)) => *v += sign * c,
                    None => psi.push((g, sign * c)),
                }
            }
        }
        psi.retain(|&(_, v)| v != 0.0);
        psi.sort_by_key(|&(g, _)| g);
        psi
    }
}
