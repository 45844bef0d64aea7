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

impl Integrator for Rk4 {
    fn attempt(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64) -> Outcome {
        let [k1, k2, k3, k4] = &mut self.k;
        rhs.eval(t, y, k1);
        for ((s, y), k) in self.stage.iter_mut().zip(y.iter()).zip(k1.iter()) {
            *s = y + 0.5 * h * k;
        }
        rhs.eval(t + 0.5 * h, &self.stage, k2);
        for ((s, y), k) in self.stage.iter_mut().zip(y.iter()).zip(k2.iter()) {
            *s = y + 0.5 * h * k;
        }
        rhs.eval(t + 0.5 * h, &self.stage, k3);
        for ((s, y), k) in self.stage.iter_mut().zip(y.iter()).zip(k3.iter()) {
            *s = y + h * k;
        }
        rhs.eval(t + h, &self.stage, k4);
        for (i, y) in y.iter_mut().enumerate() {
            *y += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        self.evaluations += 4;
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
