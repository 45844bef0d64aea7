//! Per-bar inertia in end coordinates: a thin uniform rod plus the payloads at its ends.
//!
//! The rod's end mass matrix is `m [1/3 1/6; 1/6 1/3]`; a point mass adds to its diagonal.
//! The step uses the inverse `W` and, for λ, `b̈ = α g_a + β g_b` with `α = W_ab − W_aa`,
//! `β = W_bb − W_ab`.

/// The constant inverse mass data of one bar.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarInertia {
    /// End mass matrix `[[m/3 + p_a, m/6], [m/6, m/3 + p_b]]`, kg.
    pub m: [[f64; 2]; 2],
    /// Inverse end mass matrix `[[W_aa, W_ab], [W_ab, W_bb]]`, 1/kg.
    pub w: [[f64; 2]; 2],
    /// `α = W_ab − W_aa`, 1/kg.
    pub alpha: f64,
    /// `β = W_bb − W_ab`, 1/kg.
    pub beta: f64,
    /// `1/(β − α)`, kg (λ's denominator without `|b|²`, inverted once).
    pub inv_beta_minus_alpha: f64,
}

impl BarInertia {
    /// A rod of mass `m` carrying `payload[0]`, `payload[1]` at its ends, kg.
    pub fn new(m: f64, payload: [f64; 2]) -> Self {
        let (maa, mbb, mab) = (m / 3.0 + payload[0], m / 3.0 + payload[1], m / 6.0);
        let det = maa * mbb - mab * mab;
        let w = [[mbb / det, -mab / det], [-mab / det, maa / det]];
        let (alpha, beta) = (w[0][1] - w[0][0], w[1][1] - w[0][1]);
        Self {
            m: [[maa, mab], [mab, mbb]],
            w,
            alpha,
            beta,
            inv_beta_minus_alpha: 1.0 / (beta - alpha),
        }
    }

    /// End-acceleration response to end forces with λ eliminated, block (side i, side j),
    /// is `W_ij I − k_i k_j /(β − α) u uᵀ` with `k = (α, β)`: its two scalars
    /// `(W_ij, k_i k_j /(β − α))`.
    #[inline]
    pub fn compliance_scalars(&self, i: usize, j: usize) -> (f64, f64) {
        let k = [self.alpha, self.beta];
        (self.w[i][j], k[i] * k[j] / (self.beta - self.alpha))
    }
}

/// Four bars' constants of λ and the end accelerations, one bar per lane, for the step's
/// four-bars-at-a-time λ passes (lane `l` of group `g` is bar `4g + l`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InertiaLanes {
    /// Whether all four bars exist and move (else the group is taken bar by bar).
    pub moving: bool,
    /// α per lane, 1/kg.
    pub alpha: [f64; 4],
    /// β per lane, 1/kg.
    pub beta: [f64; 4],
    /// `1/(β − α)` per lane, kg.
    pub inv_beta_minus_alpha: [f64; 4],
    /// `W` per lane, by entry: `W_aa`, `W_ab`, `W_ba`, `W_bb`, 1/kg.
    pub w: [[f64; 4]; 4],
}

impl InertiaLanes {
    /// The groups of four of `inertia` (a last partial group is padded and not `moving`);
    /// `static_bar` tells which bars do not move.
    pub fn groups(inertia: &[BarInertia], static_bar: &[bool]) -> Vec<Self> {
        let lanes = |i: &[BarInertia], f: fn(&BarInertia) -> f64| {
            std::array::from_fn(|l| i.get(l).map_or(0.0, f))
        };
        inertia
            .chunks(4)
            .zip(static_bar.chunks(4))
            .map(|(i, fixed)| Self {
                moving: i.len() == 4 && !fixed.contains(&true),
                alpha: lanes(i, |b| b.alpha),
                beta: lanes(i, |b| b.beta),
                inv_beta_minus_alpha: lanes(i, |b| b.inv_beta_minus_alpha),
                w: [
                    lanes(i, |b| b.w[0][0]),
                    lanes(i, |b| b.w[0][1]),
                    lanes(i, |b| b.w[1][0]),
                    lanes(i, |b| b.w[1][1]),
                ],
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_rod_matches_the_closed_form() {
        let m = 2.5;
        let i = BarInertia::new(m, [0.0, 0.0]);
        assert!((i.w[0][0] - 4.0 / m).abs() < 1e-14);
        assert!((i.w[0][1] + 2.0 / m).abs() < 1e-14);
        assert!((i.alpha + 6.0 / m).abs() < 1e-14 && (i.beta - 6.0 / m).abs() < 1e-14);
    }

    #[test]
    fn inverse_times_mass_matrix_is_identity() {
        let (m, p) = (1.3, [0.7, 2.1]);
        let i = BarInertia::new(m, p);
        let mm = [[m / 3.0 + p[0], m / 6.0], [m / 6.0, m / 3.0 + p[1]]];
        for (r, row) in mm.iter().enumerate() {
            for c in 0..2 {
                let v: f64 = (0..2).map(|k| row[k] * i.w[k][c]).sum();
                assert!((v - f64::from(u8::from(r == c))).abs() < 1e-14);
            }
        }
    }
}
