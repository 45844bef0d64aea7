//! A stiffly stable fixed-step method: the three-stage, third-order, L-stable singly
//! diagonally implicit Runge–Kutta method of Alexander (1977), applied to the second-order
//! system `q̇ = v`, `v̇ = a(q, v)`. Each stage solves for its velocity `V` with Newton's
//! method on `V − v_base − hγ a(q_base + hγ V, V) = 0`, whose Jacobian
//! `W = I − hγ J_v − (hγ)² J_q` comes from the exact tangent of the constrained
//! accelerations (factored once per step, shared by the three stages since they have the
//! same γ). The method is stiffly accurate (the step's result is its last stage), so modes
//! with `h ω ≫ 1` are damped away instead of blowing up; the slow motion keeps third order.
//! The exact correction follows every step, as for the other methods.

use nalgebra::{DMatrix, DVector, Dyn, LU};

use super::{Integrator, Outcome, Rhs};

/// γ, the root of `x³ − 3x² + 3x/2 − 1/6` in (1/6, 1/2) that makes the method L-stable.
const GAMMA: f64 = 0.435_866_521_508_459;
/// Newton iterations per stage before the step is split in two.
const MAX_NEWTON: usize = 12;
/// Newton stops when the velocity update is this small relative to the velocities.
const NEWTON_TOL: f64 = 1e-12;
/// Halvings of a step whose Newton iterations fail, before the step gives up.
const MAX_SPLITS: u32 = 6;

/// Butcher tableau: `a[i][j]` for j < i (the diagonal is γ), and the stage times `c`.
fn tableau() -> ([[f64; 3]; 3], [f64; 3]) {
    let tau = (1.0 + GAMMA) / 2.0;
    let b1 = -(6.0 * GAMMA * GAMMA - 16.0 * GAMMA + 1.0) / 4.0;
    let b2 = (6.0 * GAMMA * GAMMA - 20.0 * GAMMA + 5.0) / 4.0;
    (
        [[0.0; 3], [tau - GAMMA, 0.0, 0.0], [b1, b2, 0.0]],
        [GAMMA, tau, 1.0],
    )
}

/// SDIRK3 with its stage buffers.
#[derive(Clone)]
pub struct Sdirk3 {
    m: usize,
    velocities: [Vec<f64>; 3],
    accelerations: [Vec<f64>; 3],
    base: Vec<f64>,
    stage: Vec<f64>,
    dy: Vec<f64>,
    residual: DVector<f64>,
    /// The stage velocity Newton iterates on.
    newton: Vec<f64>,
    /// The state at the start of a step, restored when Newton fails.
    saved: Vec<f64>,
    /// The factored iteration matrix and the step it was made for, kept across steps
    /// while Newton still converges with it (simplified Newton).
    factored: Option<(f64, LU<f64, Dyn, Dyn>)>,
    /// Where that matrix was taken: step, time and state (for FMU state snapshots, which
    /// rebuild it there so that a restored run is bit-identical).
    taken_at: Option<(f64, f64, Vec<f64>)>,
    evaluations: u64,
    factorizations: u64,
}

impl std::fmt::Debug for Sdirk3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sdirk3")
            .field("evaluations", &self.evaluations)
            .field("factorizations", &self.factorizations)
            .finish()
    }
}

impl Sdirk3 {
    /// Buffers for a state of length `n` (`[q; v]`).
    pub fn new(n: usize) -> Self {
        let m = n / 2;
        Self {
            m,
            velocities: std::array::from_fn(|_| vec![0.0; m]),
            accelerations: std::array::from_fn(|_| vec![0.0; m]),
            base: vec![0.0; n],
            stage: vec![0.0; n],
            dy: vec![0.0; n],
            residual: DVector::zeros(m),
            newton: vec![0.0; m],
            saved: vec![0.0; n],
            factored: None,
            taken_at: None,
            evaluations: 0,
            factorizations: 0,
        }
    }

    /// Newton-iteration matrices factored so far (one per step, more when steps split).
    pub fn factorizations(&self) -> u64 {
        self.factorizations
    }

    /// One step of `h` from `t`; false if a stage's Newton iteration does not converge.
    // Stage vectors are combined component by component across several buffers.
    #[allow(clippy::needless_range_loop)]
    fn try_step(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64) -> bool {
        let m = self.m;
        let hg = h * GAMMA;
        if self.factored.as_ref().is_none_or(|(step, _)| *step != h) {
            // A restored snapshot names the state its matrix was taken at.
            let (t_j, y_j) = match self.taken_at.take() {
                Some((step, t_j, y_j)) if step == h && self.factored.is_none() => (t_j, y_j),
                _ => (t, y.to_vec()),
            };
            let Some((jq, jv)) = rhs.jacobian(t_j, &y_j) else {
                return false;
            };
            self.taken_at = Some((h, t_j, y_j));
            let w = DMatrix::identity(m, m) - &jv * hg - &jq * (hg * hg);
            self.factorizations += 1;
            self.factored = Some((h, w.lu()));
        }
        let lu = &self.factored.as_ref().expect("factored above").1;
        let (a, c) = tableau();
        for i in 0..3 {
            // base = y₀ + h Σ_{j<i} a_ij K_j, with K_j = (V_j, A_j).
            self.base.copy_from_slice(y);
            for j in 0..i {
                for k in 0..m {
                    self.base[k] += h * a[i][j] * self.velocities[j][k];
                    self.base[m + k] += h * a[i][j] * self.accelerations[j][k];
                }
            }
            // The first guess: the step's start velocity, then the previous stage's.
            if i == 0 {
                self.newton.copy_from_slice(&y[m..]);
            } else {
                self.newton.copy_from_slice(&self.velocities[i - 1]);
            }
            let v = &mut self.newton;
            let mut converged = false;
            for _ in 0..MAX_NEWTON {
                for k in 0..m {
                    self.stage[k] = self.base[k] + hg * v[k];
                    self.stage[m + k] = v[k];
                }
                rhs.eval(t + c[i] * h, &self.stage, &mut self.dy);
                self.evaluations += 1;
                for k in 0..m {
                    self.residual[k] = -(v[k] - self.base[m + k] - hg * self.dy[m + k]);
                }
                if !lu.solve_mut(&mut self.residual) {
                    return false;
                }
                let scale = v.iter().fold(1e-300f64, |s, x| s.max(x.abs()));
                let size = self.residual.amax();
                for k in 0..m {
                    v[k] += self.residual[k];
                }
                if !size.is_finite() {
                    return false;
                }
                if size <= NEWTON_TOL * scale.max(1.0) {
                    converged = true;
                    break;
                }
            }
            if !converged {
                return false;
            }
            // The stage's acceleration from its own equation: exact for the converged V.
            for k in 0..m {
                self.accelerations[i][k] = (v[k] - self.base[m + k]) / hg;
            }
            self.velocities[i].copy_from_slice(v);
        }
        // Stiffly accurate: the result is the last stage.
        for k in 0..m {
            y[k] = self.base[k] + hg * self.velocities[2][k];
            y[m + k] = self.velocities[2][k];
        }
        true
    }

    /// The step, split into halves (recursively) where Newton fails.
    fn step(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64, splits: u32) -> bool {
        self.saved.copy_from_slice(y);
        if self.try_step(rhs, t, y, h) {
            return true;
        }
        y.copy_from_slice(&self.saved);
        // A matrix from an earlier state may be too stale: retry with a fresh one.
        self.factored = None;
        self.taken_at = None;
        if self.try_step(rhs, t, y, h) {
            return true;
        }
        // (The halves below reuse `saved`; it is not needed after this.)
        y.copy_from_slice(&self.saved);
        if splits == MAX_SPLITS {
            return false;
        }
        self.step(rhs, t, y, h / 2.0, splits + 1)
            && self.step(rhs, t + h / 2.0, y, h / 2.0, splits + 1)
    }
}

impl Integrator for Sdirk3 {
    fn attempt(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64) -> Outcome {
        if !self.step(rhs, t, y, h, 0) {
            // Newton failed even on h / 64: the state is poisoned so the simulation's
            // finiteness check reports the step as failed and restores the last good state.
            y.iter_mut().for_each(|x| *x = f64::NAN);
        }
        Outcome::Accepted { next: h }
    }

    fn adaptive(&self) -> bool {
        false
    }

    fn invalidate(&mut self) {
        self.factored = None;
        self.taken_at = None;
    }

    fn carried(&self) -> Vec<f64> {
        match (&self.factored, &self.taken_at) {
            (Some(_), Some((h, t, y))) => [*h, *t].into_iter().chain(y.iter().copied()).collect(),
            _ => Vec::new(),
        }
    }

    fn carried_len(&self) -> usize {
        2 + 2 * self.m
    }

    fn restore_carried(&mut self, values: &[f64]) {
        self.factored = None;
        self.taken_at = (values.len() == self.carried_len())
            .then(|| (values[0], values[1], values[2..].to_vec()));
    }

    fn after_correction(&mut self) {
        // The iteration matrix only steers Newton: a corrected state does not stale it.
    }

    fn name(&self) -> &'static str {
        "sdirk3"
    }

    fn rhs_evaluations(&self) -> u64 {
        self.evaluations
    }

    fn boxed_clone(&self) -> Box<dyn Integrator> {
        Box::new(self.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tableau_has_third_order_and_l_stability() {
        let (a, c) = tableau();
        let b = [a[2][0], a[2][1], GAMMA];
        let full = |i: usize, j: usize| if i == j { GAMMA } else { a[i][j] };
        // Order conditions up to 3: Σb = 1, Σb c = 1/2, Σb c² = 1/3, Σ b a c = 1/6.
        let sum = |f: &dyn Fn(usize) -> f64| (0..3).map(f).sum::<f64>();
        assert!((sum(&|i| b[i]) - 1.0).abs() < 1e-14);
        assert!((sum(&|i| b[i] * c[i]) - 0.5).abs() < 1e-14);
        assert!((sum(&|i| b[i] * c[i] * c[i]) - 1.0 / 3.0).abs() < 1e-14);
        let bac = sum(&|i| b[i] * sum(&|j| full(i, j) * c[j]));
        assert!((bac - 1.0 / 6.0).abs() < 1e-14);
        // Row sums equal c.
        for (i, &ci) in c.iter().enumerate() {
            assert!((sum(&|j| full(i, j)) - ci).abs() < 1e-14);
        }
        // γ is the root of x³ − 3x² + 3x/2 − 1/6 (stability function vanishes at ∞).
        let g = GAMMA;
        assert!((g * g * g - 3.0 * g * g + 1.5 * g - 1.0 / 6.0).abs() < 1e-14);
    }
}
