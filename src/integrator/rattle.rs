//! A RATTLE-type second-order method: velocity Verlet (kick–drift–kick) whose drift is
//! followed by the exact position projection, with one evaluation of the constrained
//! acceleration per step. The closing kick needs `a(q₁, v₁)`, which depends on `v₁`
//! through the centrifugal part of λ and cable damping; it is evaluated at the
//! predicted `v₁ ≈ v½ + h/2 a₀` (error O(h²), so the method stays second order) and
//! reused as the next step's opening kick.

use super::{Integrator, Outcome, Rhs};

/// Kick–drift–project–kick with a carried acceleration.
#[derive(Debug, Clone)]
pub struct Rattle {
    /// `[v; a]` at the current point, as the right-hand side returns it.
    f: Vec<f64>,
    f_new: Vec<f64>,
    stage: Vec<f64>,
    fresh: bool,
    evaluations: u64,
}

impl Rattle {
    /// Buffers for a state of length `n`.
    pub fn new(n: usize) -> Self {
        Self {
            f: vec![0.0; n],
            f_new: vec![0.0; n],
            stage: vec![0.0; n],
            fresh: false,
            evaluations: 0,
        }
    }
}

impl Integrator for Rattle {
    fn attempt(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64) -> Outcome {
        let half = y.len() / 2;
        if !self.fresh {
            rhs.eval(t, y, &mut self.f);
            self.evaluations += 1;
        }
        // Kick: v½ = v + h/2 a.
        let (q, v) = y.split_at_mut(half);
        let a = &self.f[half..];
        for (vi, ai) in v.iter_mut().zip(a) {
            *vi += 0.5 * h * ai;
        }
        // Drift, then project onto the bar lengths.
        for (qi, vi) in q.iter_mut().zip(v.iter()) {
            *qi += h * vi;
        }
        rhs.project_positions(y);
        // Acceleration at the new positions and the predicted new velocity.
        self.stage.copy_from_slice(y);
        for (si, ai) in self.stage[half..].iter_mut().zip(&self.f[half..]) {
            *si += 0.5 * h * ai;
        }
        rhs.eval(t + h, &self.stage, &mut self.f_new);
        self.evaluations += 1;
        // Kick: v₁ = v½ + h/2 a₁.
        for (vi, ai) in y[half..].iter_mut().zip(&self.f_new[half..]) {
            *vi += 0.5 * h * ai;
        }
        std::mem::swap(&mut self.f, &mut self.f_new);
        self.fresh = true;
        Outcome::Accepted { next: h }
    }

    fn adaptive(&self) -> bool {
        false
    }

    fn invalidate(&mut self) {
        self.fresh = false;
    }

    /// The carried acceleration is already a prediction; the velocity correction's
    /// change is of the same order, so it is kept.
    fn after_correction(&mut self) {}

    fn name(&self) -> &'static str {
        "rattle"
    }

    fn rhs_evaluations(&self) -> u64 {
        self.evaluations
    }

    fn boxed_clone(&self) -> Box<dyn Integrator> {
        Box::new(self.clone())
    }
}
