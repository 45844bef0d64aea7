//! An estimate of the fastest mode, for the explicit fixed-step methods' stability limit.
//!
//! Power iteration on the position Jacobian of the constrained acceleration (by finite
//! differences, at rest): its largest eigenvalue magnitude is ω²_max. Velocity-dependent
//! terms (damping, centrifugal) are left out; cables' slack/taut state is the current one.
//! Ground contact, usually inactive when the check runs, adds a bound of its own.

use super::Simulation;
use crate::dynamics;
use crate::integrator::Method;
use crate::model::Model;

/// Smallest sensible `h ω`: below it a step resolves a millionth of the fastest mode's
/// period/2π, round-off dominates the truncation error, and runs take millions of steps.
pub const MIN_STEP_PER_TIME_SCALE: f64 = 1e-6;

/// Largest stable `h ω` on the imaginary axis: RK4 2√2; velocity Verlet 2.
pub fn stability_limit(method: Method) -> Option<f64> {
    match method {
        Method::Rk4 => Some(2.0 * 2f64.sqrt()),
        Method::Rattle => Some(2.0),
        Method::Dopri5 => None,
    }
}

/// A bound on the fastest rate of ground contact, 1/s: the damped penalty oscillator
/// `√(k w) + c w` or the viscous friction `μ F w / v_s`, with `w` the largest end compliance
/// and `F` the whole weight (contact is not active at rest, so the power iteration misses it).
pub fn contact_rate(model: &Model) -> f64 {
    let Some(ground) = &model.ground else {
        return 0.0;
    };
    let w = ground
        .nodes
        .iter()
        .map(|&(_, e)| model.inertia[e / 2].w[e % 2][e % 2])
        .fold(0.0, f64::max);
    let weight = model.gravity.map_or(0.0, |g| {
        g.norm()
            * (0..model.coords.n_ends())
                .map(|e| model.end_mass(e))
                .sum::<f64>()
    });
    let oscillator = (ground.stiffness * w).sqrt() + ground.damping * w;
    let friction = ground.friction * weight * w / ground.slip_velocity;
    oscillator.max(friction)
}

impl Simulation {
    /// Estimated highest angular frequency of the structure at the current state, rad/s.
    pub fn max_frequency(&mut self) -> f64 {
        let half = self.state.y.len() / 2;
        if half == 0 {
            return 0.0;
        }
        let q0: Vec<f64> = self.state.y[..half].to_vec();
        let zero = vec![0.0; half];
        let mut a0 = vec![0.0; half];
        let t = self.state.time;
        dynamics::accelerations(
            &self.model,
            &self.inputs,
            t,
            &q0,
            &zero,
            &mut self.ws,
            &mut a0,
        );
        let scale = self
            .model
            .lengths()
            .into_iter()
            .fold(0.0, f64::max)
            .max(1e-3);
        let eps = 1e-7 * scale;
        // A fixed, non-symmetric start vector so no mode is missed by symmetry.
        let mut x: Vec<f64> = (0..half)
            .map(|i| ((i * 7 + 3) % 11) as f64 - 5.0 + 0.5)
            .collect();
        let mut q = vec![0.0; half];
        let mut a = vec![0.0; half];
        let mut lambda = 0.0;
        for _ in 0..60 {
            let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm == 0.0 || !norm.is_finite() {
                break;
            }
            for ((qi, q0i), xi) in q.iter_mut().zip(&q0).zip(&x) {
                *qi = q0i + eps * xi / norm;
            }
            dynamics::accelerations(
                &self.model,
                &self.inputs,
                t,
                &q,
                &zero,
                &mut self.ws,
                &mut a,
            );
            for ((xi, ai), a0i) in x.iter_mut().zip(&a).zip(&a0) {
                *xi = (ai - a0i) / eps;
            }
            lambda = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        }
        self.refresh();
        lambda.sqrt()
    }

    /// The cached stability verdict, re-checked when the commanded force densities (which
    /// add stiffness) have more than doubled since the last check, or fell after an
    /// unstable verdict.
    pub fn check_stability(&mut self) -> Option<&str> {
        let density = self
            .inputs
            .force_density
            .iter()
            .fold(0.0, |m: f64, &g| m.max(g));
        // A stable verdict holds until the densities double; an unstable one is re-examined
        // as soon as they fall (e.g. after a state with the old inputs is restored).
        let unstable = self.stability.problem.is_some();
        let stale = self
            .stability
            .checked_density
            .is_none_or(|checked| density > 2.0 * checked || (unstable && density < checked));
        if stale {
            self.stability.problem = self.stability_problem();
            self.stability.checked_density = Some(density);
        }
        self.stability.problem.as_deref()
    }

    /// `Some(message)` when `solver.step_size` is absurdly small for the structure's fastest
    /// time scale `1/ω` (for dopri5 it is the first trial step, held to the same bound).
    pub fn step_size_problem(&mut self) -> Option<String> {
        let h = self.model.solver.step_size;
        let omega = self.max_frequency().max(contact_rate(&self.model));
        let floor = MIN_STEP_PER_TIME_SCALE / omega;
        (omega > 0.0 && h < floor).then(|| {
            format!(
                "solver.step_size = {h:e} s is below {MIN_STEP_PER_TIME_SCALE:e} of the structure's \
                 fastest time scale (1/ω ≈ {:.3e} s): every step would resolve nothing but \
                 round-off and a run would take billions of steps. Use solver.step_size ≥ {floor:.3e} s \
                 (about {:.3e} s resolves the fastest mode well with rk4)",
                1.0 / omega,
                0.1 / omega
            )
        })
    }

    /// `Some(message)` when the fixed step exceeds the method's stability limit for the
    /// fastest mode, naming the limit and the fixes.
    pub fn stability_problem(&mut self) -> Option<String> {
        let method = self.model.solver.method;
        let limit = stability_limit(method)?;
        let h = self.model.solver.step_size;
        let omega = self.max_frequency().max(contact_rate(&self.model));
        (h * omega > limit).then(|| {
            format!(
                "solver.step_size = {h} s is above the stability limit of {} for the fastest mode \
                 (ω ≈ {omega:.3e} rad/s, limit h ≤ {:.3e} s): the run would blow up. Use \
                 solver.method = dopri5, or solver.step_size ≤ {:.3e} s",
                method.name(),
                limit / omega,
                0.9 * limit / omega
            )
        })
    }
}
