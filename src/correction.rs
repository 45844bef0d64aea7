//! The paper's exact recursive correction (section 3), written as Gram–Schmidt.
//!
//! Runs after every integrator step: first bar lengths, then bar-velocity orthogonality.
//! The directions `q_i = φ_i / (φ_i·ψ_i)` are precomputed once, sparsely: `φ_i` is `ψ_i`
//! orthogonalised against the earlier `φ_j`, so correcting bar `i` never disturbs a bar
//! corrected before it.

use std::collections::BTreeSet;

use nalgebra::Vector3;

use crate::model::coords::Coordinates;

/// |φ_i| below this fraction of |ψ_i| means earlier bars or pins already fix bar i.
const VANISHING: f64 = 1e-9;
/// Entries of φ_i at round-off level of the orthogonalisation are exact zeros.
const ROUND_OFF: f64 = 1e-14;

/// Precomputed correction directions.
#[derive(Debug, Clone)]
pub struct CorrectionPlan {
    /// Per bar, `q_i` as sparse `(g, value)` pairs; empty for a skipped bar.
    directions: Vec<Vec<(usize, f64)>>,
    /// Nominal bar lengths l_i, m.
    lengths: Vec<f64>,
    /// Bars (0-based) whose correction direction vanishes.
    pub skipped: Vec<usize>,
    /// When a skipped bar can still move (its ψ depends on earlier bars' ψ, but its 3-D
    /// constraint does not, as in a closed loop of bars), every bar's `ψ_i/|ψ_i|²`, for
    /// the iterative projection that then follows the exact pass; empty otherwise.
    loop_patterns: Vec<Vec<(usize, f64)>>,
}

/// Sweeps of the iterative projection before giving up (it converges linearly from
/// round-off-sized residuals, in a handful of sweeps).
const LOOP_SWEEPS: usize = 100;

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
            directions,
            lengths: lengths.to_vec(),
            skipped,
            loop_patterns,
        }
    }

    /// Restores `|b_i| = l_i` for every bar, in order.
    pub fn correct_positions(&self, coords: &Coordinates, q: &mut [f64]) {
        for (bar, dir) in self.directions.iter().enumerate() {
            if dir.is_empty() {
                continue;
            }
            let b = bar_vector(coords, bar, q, true);
            let delta = b * (self.lengths[bar] / b.norm()) - b;
            apply(dir, &delta, q);
        }
        self.loop_positions(coords, q);
    }

    /// Nonlinear Gauss–Seidel (SHAKE) over all bars, each moved along itself with the
    /// minimum-norm pattern `ψ_i/|ψ_i|²`, until every length holds to round-off. Only
    /// runs when a moving bar was skipped by the exact pass.
    fn loop_positions(&self, coords: &Coordinates, q: &mut [f64]) {
        for _ in 0..LOOP_SWEEPS {
            let mut worst = 0.0f64;
            for (bar, pattern) in self.loop_patterns.iter().enumerate() {
                if pattern.is_empty() {
                    continue;
                }
                let b = bar_vector(coords, bar, q, true);
                let l = self.lengths[bar];
                worst = worst.max((b.norm() - l).abs() / l);
                apply(pattern, &(b * (l / b.norm()) - b), q);
            }
            if worst <= 16.0 * f64::EPSILON {
                return;
            }
        }
    }

    /// The velocity counterpart of [`Self::loop_positions`] (a linear Gauss–Seidel).
    fn loop_velocities(&self, coords: &Coordinates, q: &[f64], v: &mut [f64]) {
        for _ in 0..LOOP_SWEEPS {
            let mut worst = 0.0f64;
            for (bar, pattern) in self.loop_patterns.iter().enumerate() {
                if pattern.is_empty() {
                    continue;
                }
                let b = bar_vector(coords, bar, q, true);
                let bdot = bar_vector(coords, bar, v, false);
                let dot = b.dot(&bdot);
                worst = worst.max(dot.abs() / (b.norm() * bdot.norm()).max(f64::MIN_POSITIVE));
                apply(pattern, &(-b * (dot / b.norm_squared())), v);
            }
            if worst <= 16.0 * f64::EPSILON {
                return;
            }
        }
    }

    /// Restores `|b_i| = l_i` like [`Self::correct_positions`], but moving each bar along
    /// its direction at the start of the step, `b_i(q_old)` (SHAKE): with that choice a
    /// kick–drift–kick step is RATTLE, whose energy error stays bounded. Falls back to the
    /// radial move when the step was too large for a root to exist.
    /// The displacement is also added to `moved`, exactly as applied, for the velocity.
    pub fn correct_positions_shake(
        &self,
        coords: &Coordinates,
        q: &mut [f64],
        q_old: &[f64],
        moved: &mut [f64],
    ) {
        for (bar, dir) in self.directions.iter().enumerate() {
            if dir.is_empty() {
                continue;
            }
            let b = bar_vector(coords, bar, q, true);
            let b0 = bar_vector(coords, bar, q_old, true);
            let l = self.lengths[bar];
            // |b + μ b0|² = l², the root nearest 0.
            let (a2, a1, a0) = (b0.norm_squared(), b.dot(&b0), b.norm_squared() - l * l);
            let disc = a1 * a1 - a2 * a0;
            let delta = if disc >= 0.0 && a2 > 0.0 {
                let mu = if a1 >= 0.0 {
                    -a0 / (a1 + disc.sqrt())
                } else {
                    (-a1 + disc.sqrt()) / a2
                };
                b0 * mu
            } else {
                b * (l / b.norm()) - b
            };
            apply(dir, &delta, q);
            apply(dir, &delta, moved);
        }
    }

    /// Restores `b_i · ḃ_i = 0` for every bar, in order (positions already corrected).
    pub fn correct_velocities(&self, coords: &Coordinates, q: &[f64], v: &mut [f64]) {
        for (bar, dir) in self.directions.iter().enumerate() {
            if dir.is_empty() {
                continue;
            }
            let b = bar_vector(coords, bar, q, true);
            let bdot = bar_vector(coords, bar, v, false);
            let delta = -b * (b.dot(&bdot) / b.norm_squared());
            apply(dir, &delta, v);
        }
        self.loop_velocities(coords, q, v);
    }

    /// Number of nonzeros over all directions (the correction's cost per pass).
    pub fn nnz(&self) -> usize {
        self.directions.iter().map(Vec::len).sum()
    }
}

/// `b_i = n_end − n_start` from η (positions with `offset`, velocities without).
#[inline]
pub fn bar_vector(coords: &Coordinates, bar: usize, eta: &[f64], offset: bool) -> Vector3<f64> {
    coords.end_vector(2 * bar + 1, eta, offset) - coords.end_vector(2 * bar, eta, offset)
}

#[inline]
fn apply(dir: &[(usize, f64)], delta: &Vector3<f64>, eta: &mut [f64]) {
    for &(g, c) in dir {
        for k in 0..3 {
            eta[3 * g + k] += c * delta[k];
        }
    }
}
