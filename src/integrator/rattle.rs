//! RATTLE: velocity Verlet (kick–drift–kick) whose drift is projected back onto the bar
//! lengths along the bars' directions at the start of the step (SHAKE), and whose closing
//! kick is followed by the velocity projection (the correction), with one evaluation of
//! the constrained acceleration per step. Components of the acceleration along the bars
//! are absorbed by the projections, so λ's centrifugal term drops out as in RATTLE. The
//! closing kick needs `a(q₁, v₁)`, which still depends on `v₁` through cable damping; it is
//! evaluated at the predicted `v₁ ≈ v½ + h/2 a₀` (error O(h²), second order kept) and
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
            let evaluated = rhs.eval_start(t, y, &mut self.f);
            self.evaluations += u64::from(evaluated);
        }
        self.stage.copy_from_slice(y);
        // Kick: v½ = v + h/2 a.
        let (q, v) = y.split_at_mut(half);
        let a = &self.f[half..];
        for (vi, ai) in v.iter_mut().zip(a) {
            *vi += 0.5 * h * ai;
        }
        // Drift, then project onto the bar lengths; the projection's displacement belongs
        // to the half-step velocity too (RATTLE's position multiplier acts on v½).
        for (qi, vi) in q.iter_mut().zip(v.iter()) {
            *qi += h * vi;
        }
        let moved = &mut self.f_new[..half];
        moved.fill(0.0);
        rhs.project_positions(y, &self.stage, moved);
        for (vi, di) in y[half..].iter_mut().zip(moved.iter()) {
            *vi += di / h;
        }
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

    fn carried(&self) -> Vec<f64> {
        if self.fresh {
            self.f.clone()
        } else {
            Vec::new()
        }
    }

    fn carried_len(&self) -> usize {
        self.f.len()
    }

    fn restore_carried(&mut self, values: &[f64]) {
        self.fresh = values.len() == self.carried_len();
        if self.fresh {
            self.f.copy_from_slice(values);
        }
    }
}
