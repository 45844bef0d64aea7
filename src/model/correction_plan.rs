//! The precomputed directions of the paper's exact recursive correction (section 3),
//! written as Gram–Schmidt: `q_i = φ_i / (φ_i·ψ_i)`, with `φ_i` the bar's `ψ_i`
//! orthogonalised against the earlier `φ_j`, so correcting bar `i` never disturbs a bar
//! corrected before it. Built once with the model; `crate::correction` applies them.

use std::collections::BTreeSet;

use super::coords::Coordinates;

/// |φ_i| below this fraction of |ψ_i| means earlier bars or pins already fix bar i.
const VANISHING: f64 = 1e-9;
/// Entries of φ_i at round-off level of the orthogonalisation are exact zeros.
const ROUND_OFF: f64 = 1e-14;

/// Precomputed correction directions.
#[derive(Debug, Clone)]
pub struct CorrectionPlan {
    /// Per bar, `q_i` as sparse `(g, value)` pairs; empty for a skipped bar.
    pub(crate) directions: Directions,
    /// Nominal bar lengths l_i, m.
    pub(crate) lengths: Vec<f64>,
    /// Bars (0-based) whose correction direction vanishes.
    pub skipped: Vec<usize>,
    /// When a skipped bar can still move (its ψ depends on earlier bars' ψ, but its 3-D
    /// constraint does not, as in a closed loop of bars), every bar's `ψ_i/|ψ_i|²`, for
    /// the iterative projection that then follows the exact pass; empty otherwise.
    pub(crate) loop_patterns: Vec<Vec<(usize, f64)>>,
}

impl CorrectionPlan {
    /// Orthogonalises the bars' ψ vectors in bar order (modified Gram–Schmidt, sparse).
    pub fn new(coords: &Coordinates, lengths: &[f64]) -> Self {
        let n_bars = lengths.len();
        let mut phis: Vec<Vec<(usize, f64)>> = Vec::with_capacity(n_bars);
        let mut phi_norm2 = Vec::with_capacity(n_bars);
        // For each reduced column, the earlier φ_j that touch it.
        let mut touching: Vec<Vec<usize>> = vec![Vec::new(); coords.r];
        let mut work = vec![0.0; coords.r];
        let mut in_support = vec![false; coords.r];
        let mut directions = Vec::with_capacity(n_bars);
        let mut skipped = Vec::new();
        for bar in 0..n_bars {
            let psi = coords.psi(bar);
            let psi_norm = psi.iter().map(|(_, v)| v * v).sum::<f64>().sqrt();
            let mut support: Vec<usize> = Vec::new();
            let mut pending = BTreeSet::new();
            for &(g, v) in &psi {
                work[g] = v;
                in_support[g] = true;
                support.push(g);
                pending.extend(touching[g].iter().copied());
            }
            while let Some(j) = pending.pop_first() {
                let dot: f64 = phis[j].iter().map(|&(g, v)| v * work[g]).sum();
                let coef = dot / phi_norm2[j];
                for &(g, v) in &phis[j] {
                    work[g] -= coef * v;
                    if !in_support[g] {
                        in_support[g] = true;
                        support.push(g);
                        pending.extend(touching[g].iter().copied().filter(|&k| k > j));
                    }
                }
            }
            support.sort_unstable();
            let mut phi: Vec<(usize, f64)> = Vec::with_capacity(support.len());
            for &g in &support {
                if work[g].abs() > ROUND_OFF * psi_norm {
                    phi.push((g, work[g]));
                }
                work[g] = 0.0;
                in_support[g] = false;
            }
            let norm2: f64 = phi.iter().map(|(_, v)| v * v).sum();
            if psi_norm == 0.0 || norm2.sqrt() <= VANISHING * psi_norm {
                skipped.push(bar);
                phi.clear();
                directions.push(Vec::new());
            } else {
                let phi_dot_psi: f64 = phi
                    .iter()
                    .map(|&(g, v)| v * psi.iter().find(|(h, _)| *h == g).map_or(0.0, |p| p.1))
                    .sum();
                directions.push(phi.iter().map(|&(g, v)| (g, v / phi_dot_psi)).collect());
                for &(g, _) in &phi {
                    touching[g].push(bar);
                }
            }
            phi_norm2.push(norm2);
            phis.push(phi);
        }
        let moving_skipped = skipped.iter().any(|&bar| !coords.static_bar[bar]);
        let loop_patterns = if moving_skipped {
            (0..n_bars)
                .map(|bar| {
                    let psi = coords.psi(bar);
                    let n2: f64 = psi.iter().map(|(_, v)| v * v).sum();
                    if n2 == 0.0 {
                        Vec::new()
                    } else {
                        psi.iter().map(|&(g, v)| (g, v / n2)).collect()
                    }
                })
                .collect()
        } else {
            Vec::new()
        };
        Self {
            directions: Directions::new(&directions),
            lengths: lengths.to_vec(),
            skipped,
            loop_patterns,
        }
    }

    /// Number of nonzeros over all directions (the correction's cost per pass).
    pub fn nnz(&self) -> usize {
        self.directions.terms.len()
    }
}

/// Per bar, its direction's `(g, value)` pairs, all in one array (the correction walks
/// them in order every step: one stream, not a heap block per bar).
#[derive(Debug, Clone)]
pub(crate) struct Directions {
    start: Vec<usize>,
    terms: Vec<(usize, f64)>,
}

impl Directions {
    fn new(per_bar: &[Vec<(usize, f64)>]) -> Self {
        let (start, terms) = crate::linalg::pattern::flatten(per_bar);
        Self { start, terms }
    }

    /// Each bar's direction, in bar order.
    #[inline(always)]
    pub fn iter(&self) -> impl Iterator<Item = &[(usize, f64)]> {
        self.start.windows(2).map(|w| &self.terms[w[0]..w[1]])
    }
}
