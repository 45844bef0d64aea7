//! Classical fixed-step fourth-order Runge–Kutta.

use super::{Integrator, Outcome, Rhs};

/// RK4 with preallocated stage buffers.
#[derive(Debug, Clone)]
pub struct Rk4 {
    k: [Vec<f64>; 4],
    stage: Vec<f64>,
    evaluations: u64,
}

impl Rk4 {
    /// Buffers for a state of length `n`.
    pub fn new(n: usize) -> Self {
        Self {
            k: std::array::from_fn(|_| vec![0.0; n]),
            stage: vec![0.0; n],
            evaluations: 0,
        }
    }
}

/// `stage = y + c k`, entry by entry (split over threads where the evaluation has two).
fn set_stage(rhs: &dyn Rhs, stage: &mut [f64], y: &[f64], c: f64, k: &[f64]) {
    rhs.for_each_half(stage, &|start, s| {
        let part = start..start + s.len();
        stage_part(s, &y[part.clone()], c, &k[part]);
    });
}

/// `s = y + c k` over a part.
fn stage_part(s: &mut [f64], y: &[f64], c: f64, k: &[f64]) {
    #[inline(always)]
    fn kernel(s: &mut [f64], y: &[f64], c: f64, k: &[f64]) {
        for ((s, y), k) in s.iter_mut().zip(y).zip(k) {
            *s = y + c * k;
        }
    }
    crate::simd::dispatch!(kernel(s: &mut [f64], y: &[f64], c: f64, k: &[f64]))
}

/// `y += h/6 (k₁ + 2k₂ + 2k₃ + k₄)` over a part.
fn combine_part(y: &mut [f64], h: f64, [k1, k2, k3, k4]: [&[f64]; 4]) {
    #[inline(always)]
    fn kernel(y: &mut [f64], h: f64, [k1, k2, k3, k4]: [&[f64]; 4]) {
        let k12 = k1.iter().zip(k2);
        let k34 = k3.iter().zip(k4);
        for (y, ((a, b), (c, d))) in y.iter_mut().zip(k12.zip(k34)) {
            *y += h / 6.0 * (a + 2.0 * b + 2.0 * c + d);
        }
    }
    crate::simd::dispatch!(kernel(y: &mut [f64], h: f64, k: [&[f64]; 4] = [k1, k2, k3, k4]))
}

impl Integrator for Rk4 {
    fn attempt(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64) -> Outcome {
        let [k1, k2, k3, k4] = &mut self.k;
        let evaluated = rhs.eval_start(t, y, k1);
        set_stage(rhs, &mut self.stage, y, 0.5 * h, k1);
        rhs.eval(t + 0.5 * h, &self.stage, k2);
        set_stage(rhs, &mut self.stage, y, 0.5 * h, k2);
        rhs.eval(t + 0.5 * h, &self.stage, k3);
        set_stage(rhs, &mut self.stage, y, h, k3);
        rhs.eval(t + h, &self.stage, k4);
        let (k1, k2, k3, k4) = (&*k1, &*k2, &*k3, &*k4);
        rhs.for_each_half(y, &|start, y| {
            let part = start..start + y.len();
            let k = [k1, k2, k3, k4].map(|k| &k[part.clone()]);
            combine_part(y, h, k);
        });
        self.evaluations += 3 + u64::from(evaluated);
        Outcome::Accepted { next: h }
    }

    fn adaptive(&self) -> bool {
        false
    }

    fn name(&self) -> &'static str {
        "rk4"
    }

    fn rhs_evaluations(&self) -> u64 {
        self.evaluations
    }

    fn boxed_clone(&self) -> Box<dyn Integrator> {
        Box::new(self.clone())
    }
}
