//! Adaptive Dormand–Prince 5(4) with the classic step-size controller (Hairer, Nørsett &
//! Wanner, *Solving ODEs I*, II.4). The fifth-order solution is propagated; the embedded
//! fourth-order one only estimates the error.

use super::{Integrator, Outcome, Rhs};

const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// Fifth- minus fourth-order weights.
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// Dormand–Prince 5(4) with preallocated stages.
#[derive(Debug, Clone)]
pub struct Dopri5 {
    k: [Vec<f64>; 7],
    stage: Vec<f64>,
    rtol: f64,
    atol: f64,
    /// `k[0]` holds `f(t, y)` for the current point (first same as last).
    fresh_k1: bool,
    evaluations: u64,
}

impl Dopri5 {
    /// Buffers for a state of length `n`, with relative and absolute tolerances.
    pub fn new(n: usize, rtol: f64, atol: f64) -> Self {
        Self {
            k: std::array::from_fn(|_| vec![0.0; n]),
            stage: vec![0.0; n],
            rtol,
            atol,
            fresh_k1: false,
            evaluations: 0,
        }
    }
}

impl Integrator for Dopri5 {
    fn attempt(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64) -> Outcome {
        if !self.fresh_k1 {
            let evaluated = rhs.eval_start(t, y, &mut self.k[0]);
            self.evaluations += u64::from(evaluated);
        }
        for s in 1..7 {
            for (i, (stage, yi)) in self.stage.iter_mut().zip(y.iter()).enumerate() {
                let acc: f64 = A[s][..s].iter().zip(&self.k).map(|(a, k)| a * k[i]).sum();
                *stage = yi + h * acc;
            }
            let (_, rest) = self.k.split_at_mut(s);
            rhs.eval(t + C[s] * h, &self.stage, &mut rest[0]);
            self.evaluations += 1;
        }
        // stage now holds the 5th-order solution (row 7 of A is b).
        let mut sum = 0.0;
        for (i, (yi, new)) in y.iter().zip(&self.stage).enumerate() {
            let e: f64 = E.iter().zip(&self.k).map(|(ej, k)| ej * k[i]).sum();
            let scale = self.atol + self.rtol * yi.abs().max(new.abs());
            sum += (h * e / scale).powi(2);
        }
        let err = (sum / y.len().max(1) as f64).sqrt();
        if !err.is_finite() {
            self.fresh_k1 = true;
            return Outcome::Rejected { next: h * 0.2 };
        }
        let factor = (0.9 * err.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
        if err <= 1.0 {
            y.copy_from_slice(&self.stage);
            self.k.swap(0, 6);
            self.fresh_k1 = true;
            Outcome::Accepted { next: h * factor }
        } else {
            self.fresh_k1 = true;
            Outcome::Rejected {
                next: h * factor.min(1.0),
            }
        }
    }

    fn adaptive(&self) -> bool {
        true
    }

    fn invalidate(&mut self) {
        self.fresh_k1 = false;
    }

    fn name(&self) -> &'static str {
        "dopri5"
    }

    fn rhs_evaluations(&self) -> u64 {
        self.evaluations
    }

    fn boxed_clone(&self) -> Box<dyn Integrator> {
        Box::new(self.clone())
    }

    fn carried(&self) -> Vec<f64> {
        if self.fresh_k1 {
            self.k[0].clone()
        } else {
            Vec::new()
        }
    }

    fn carried_len(&self) -> usize {
        self.k[0].len()
    }

    fn restore_carried(&mut self, values: &[f64]) {
        self.fresh_k1 = values.len() == self.carried_len();
        if self.fresh_k1 {
            self.k[0].copy_from_slice(values);
        }
    }
}
