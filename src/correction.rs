//! The paper's exact recursive correction (section 3), applied after every integrator
//! step: first bar lengths, then bar-velocity orthogonality, along the directions the model
//! precomputed once ([`CorrectionPlan`]).

use nalgebra::Vector3;

use crate::model::coords::Coordinates;
pub use crate::model::correction_plan::CorrectionPlan;

/// Relative residual at which the iterative projection stops: round-off. Bar lengths hold
/// to it after every step, apart from the rounding of the end positions themselves.
pub const HELD_TO: f64 = 16.0 * f64::EPSILON;
/// Without the correction, a run stops once a bar's length drifts by this fraction.
pub const MAX_UNCORRECTED_DRIFT: f64 = 0.01;

/// Sweeps of the iterative projection before giving up (it converges linearly from
/// round-off-sized residuals, in a handful of sweeps).
const LOOP_SWEEPS: usize = 100;

impl CorrectionPlan {
    /// Both corrections after a step, positions then velocities, compiled for AVX2 where
    /// the processor has it (as the evaluation is, [`crate::dynamics::accelerations`]; the
    /// same bits).
    pub fn correct(&self, coords: &Coordinates, q: &mut [f64], v: &mut [f64]) {
        crate::simd::dispatch!(CorrectionPlan::correct_both(
            plan: &CorrectionPlan = self,
            coords: &Coordinates,
            q: &mut [f64],
            v: &mut [f64],
        ))
    }

    #[inline(always)]
    fn correct_both(&self, coords: &Coordinates, q: &mut [f64], v: &mut [f64]) {
        self.correct_positions(coords, q);
        self.correct_velocities(coords, q, v);
    }

    /// Restores `|b_i| = l_i` for every bar, in order.
    #[inline(always)]
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
            if worst <= HELD_TO {
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
            if worst <= HELD_TO {
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
    #[inline(always)]
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
}

/// `b_i = n_end − n_start` from η (positions with `offset`, velocities without).
#[inline(always)]
pub fn bar_vector(coords: &Coordinates, bar: usize, eta: &[f64], offset: bool) -> Vector3<f64> {
    coords.end_vector(2 * bar + 1, eta, offset) - coords.end_vector(2 * bar, eta, offset)
}

#[inline(always)]
fn apply(dir: &[(usize, f64)], delta: &Vector3<f64>, eta: &mut [f64]) {
    let eta = eta.as_chunks_mut::<3>().0;
    for &(g, c) in dir {
        let at = &mut eta[g];
        for k in 0..3 {
            at[k] += c * delta[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::model::Model;
    use crate::scene::builtin;

    /// The correction compiled for AVX2 gives the bits of the baseline one, on tower20
    /// moved off its constraints.
    #[test]
    fn the_avx2_correction_gives_the_portable_bits() {
        let model = Model::new(&builtin("tower20").unwrap()).unwrap();
        let coords = &model.coords;
        let mut q = model.reduced_positions();
        let wave = |i: usize, f: f64| 1e-3 * (i as f64 * f).sin();
        q.iter_mut()
            .enumerate()
            .for_each(|(i, x)| *x += wave(i, 0.37));
        let v: Vec<f64> = (0..q.len()).map(|i| wave(i, 0.71)).collect();
        let (mut q1, mut v1, mut q2, mut v2) = (q.clone(), v.clone(), q.clone(), v.clone());
        model.correction.correct(coords, &mut q1, &mut v1);
        model.correction.correct_both(coords, &mut q2, &mut v2);
        assert!(
            q1.iter().zip(&q).any(|(a, b)| a != b),
            "the correction moved q"
        );
        for (a, b) in q1.iter().chain(&v1).zip(q2.iter().chain(&v2)) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }
}
