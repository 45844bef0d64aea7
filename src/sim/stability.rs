//! An estimate of the fastest mode, for the explicit fixed-step methods' stability limit.
//!
//! Power iteration on the position Jacobian of the constrained acceleration (by one-sided
//! differences, at rest, on the stiffer side): its largest eigenvalue magnitude is ω²_max.
//! Velocity-dependent terms (damping, centrifugal) are left out; a cable at the edge of
//! slack counts with its stiffness.
//! Ground contact, usually inactive when the check runs, adds bounds of its own. Each rate
//! names its cause (see [`super::cause`]), so the messages can name the key to change.

use super::cause::{self, Cause, Rate};
use super::Simulation;
use crate::dynamics;
use crate::integrator::Method;

/// Smallest sensible `h ω`: below it a step resolves a millionth of the fastest mode's
/// period/2π, round-off dominates the truncation error, and runs take millions of steps.
pub const MIN_STEP_PER_TIME_SCALE: f64 = 1e-6;

/// Largest `h ω` at which an explicit fixed step still follows the fastest mode: rk4 then
/// damps it by at most `(h ω)⁶/144` ≈ 0.7 % and shifts its phase by `(h ω)⁵/120` ≈ 0.8 %
/// per step; beyond it that mode's share of the motion is lost.
pub const RESOLVED_STEP_PER_TIME_SCALE: f64 = 1.0;

/// Largest stable `h ω` on the imaginary axis: RK4 2√2; velocity Verlet 2.
pub fn stability_limit(method: Method) -> Option<f64> {
    match method {
        Method::Rk4 => Some(2.0 * 2f64.sqrt()),
        Method::Rattle => Some(2.0),
        Method::Dopri5 | Method::Sdirk3 => None,
    }
}

impl Simulation {
    /// Estimated highest angular frequency of the structure at the current state, rad/s.
    pub fn max_frequency(&mut self) -> f64 {
        self.fastest_mode().map_or(0.0, |(omega, _)| omega)
    }

    /// The fastest rates at the current state, largest first: the structure's fastest mode
    /// (attributed to the cables or contacts that make it stiff) and the contact bounds.
    pub fn fastest_rates(&mut self) -> Vec<Rate> {
        let mut rates = cause::contact_rates(&self.model);
        if let Some((omega, x)) = self.fastest_mode() {
            let half = self.state.y.len() / 2;
            let q0 = self.state.y[..half].to_vec();
            let (pos, dx) = cause::node_displacements(&self.model, &mut self.ws, &q0, &x, 1e-7);
            self.refresh();
            let mode = cause::attribute(&self.model, &self.inputs, &pos, &dx);
            rates.push(Rate { omega, ..mode });
        }
        rates.retain(|r| r.omega > 0.0);
        rates.sort_by(|a, b| b.omega.total_cmp(&a.omega));
        rates
    }

    /// The power iteration: ω of the fastest mode and its shape (unit length in the
    /// reduced coordinates), or `None` without coordinates.
    fn fastest_mode(&mut self) -> Option<(f64, Vec<f64>)> {
        let half = self.state.y.len() / 2;
        if half == 0 {
            return None;
        }
        let q0: Vec<f64> = self.state.y[..half].to_vec();
        let zero = vec![0.0; half];
        let t = self.state.time;
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
        let mut a0 = vec![0.0; half];
        dynamics::accelerations(
            &self.model,
            &self.inputs,
            t,
            &q0,
            &zero,
            &mut self.ws,
            &mut a0,
        );
        let mut q = vec![0.0; half];
        let (mut ahead, mut behind) = (vec![0.0; half], vec![0.0; half]);
        let mut lambda = 0.0;
        for _ in 0..60 {
            let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm == 0.0 || !norm.is_finite() {
                break;
            }
            for (a, sign) in [(&mut ahead, 1.0), (&mut behind, -1.0)] {
                for ((qi, q0i), xi) in q.iter_mut().zip(&q0).zip(&x) {
                    *qi = q0i + sign * eps * xi / norm;
                }
                dynamics::accelerations(&self.model, &self.inputs, t, &q, &zero, &mut self.ws, a);
            }
            // The stiffer side: a cable at the edge of slack is stiff one way only, and
            // bounces on that side.
            let change = |a: &[f64]| a.iter().zip(&a0).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
            let (side, sign) = if change(&ahead) >= change(&behind) {
                (&ahead, 1.0)
            } else {
                (&behind, -1.0)
            };
            for ((xi, a), b) in x.iter_mut().zip(side).zip(&a0) {
                *xi = sign * (a - b) / eps;
            }
            lambda = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        }
        self.refresh();
        let norm = lambda.max(f64::MIN_POSITIVE);
        x.iter_mut().for_each(|v| *v /= norm);
        Some((lambda.sqrt(), x))
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
    /// time scale `1/ω` (for dopri5 it is the first trial step, held to the same bound),
    /// naming what sets that time scale.
    pub fn step_size_problem(&mut self) -> Option<String> {
        let h = self.model.solver.step_size;
        let rates = self.fastest_rates();
        let fastest = rates.first()?;
        let omega = fastest.omega;
        let floor = MIN_STEP_PER_TIME_SCALE / omega;
        (h < floor).then(|| {
            format!(
                "solver.step_size = {h:e} s is below {MIN_STEP_PER_TIME_SCALE:e} of the structure's \
                 fastest time scale (1/ω ≈ {:.3e} s, set by {}): every step would resolve nothing \
                 but round-off and a run would take billions of steps. Use solver.step_size ≥ \
                 {floor:.3e} s (about {:.3e} s resolves the fastest mode well with rk4)",
                1.0 / omega,
                fastest.describe(&self.model, &self.inputs),
                0.1 / omega
            )
        })
    }

    /// `Some(message)` when an explicit fixed step is stable but too long to follow the
    /// structure's fastest mode (`h ω` above [`RESOLVED_STEP_PER_TIME_SCALE`]): the run is
    /// stable but inaccurate wherever that mode moves. Names the cause and the fixes.
    pub fn accuracy_problem(&mut self) -> Option<String> {
        let method = self.model.solver.method;
        let limit = stability_limit(method)?;
        let h = self.model.solver.step_size;
        let rates = self.fastest_rates();
        // Friction's regularisation is a decay, not an oscillation: a step need not follow
        // it, only stay stable (the stability guard's part).
        let fastest = rates.iter().find(|r| {
            !matches!(
                r.cause,
                Cause::Friction | Cause::TerrainFriction(_) | Cause::CollisionFriction
            )
        })?;
        let hw = h * fastest.omega;
        // Above the limit the stability guard refuses the step instead.
        if hw <= RESOLVED_STEP_PER_TIME_SCALE || h * rates[0].omega > limit {
            return None;
        }
        Some(format!(
            "solver.step_size = {h} s is stable with {} but too long to follow this scene's \
             fastest mode (h ω = {hw:.2} > {RESOLVED_STEP_PER_TIME_SCALE}; ω ≈ {:.3e} 1/s from \
             {}): the method damps and detunes that mode every step, so results are off \
             wherever it moves (a sudden load, steel-stiff cables). For accuracy use \
             solver.method = \"dopri5\" (the default: it keeps its error within rtol/atol), \
             or solver.step_size ≤ {:.3e} s",
            method.name(),
            fastest.omega,
            fastest.describe(&self.model, &self.inputs),
            // Like the guard's fixes, 10 % inside the bound.
            0.9 * RESOLVED_STEP_PER_TIME_SCALE / fastest.omega
        ))
    }

    /// `Some(message)` when the fixed step exceeds the method's stability limit for the
    /// fastest rate: the limit, what sets the rate (as scene keys) and the fixes, with the
    /// values they need.
    pub fn stability_problem(&mut self) -> Option<String> {
        let method = self.model.solver.method;
        let limit = stability_limit(method)?;
        let h = self.model.solver.step_size;
        let rates = self.fastest_rates();
        let fastest = rates.first()?;
        let omega = fastest.omega;
        if h * omega <= limit {
            return None;
        }
        // The fixes aim 10 % inside the limit.
        let target = 0.9 * limit / h;
        let mut keys = Vec::new();
        let mut unfixed: f64 = 0.0;
        for rate in rates.iter().filter(|r| r.omega > target) {
            match rate.fix(&self.model, &self.inputs, target) {
                Some(fix) => keys.push(fix),
                None => unfixed = unfixed.max(rate.omega),
            }
        }
        let mut fixes = vec![format!("solver.step_size ≤ {:.3e} s", 0.9 * limit / omega)];
        if !keys.is_empty() {
            let mut fix = keys.join(" and ");
            if unfixed > 0.0 {
                fix += &format!(" with solver.step_size ≤ {:.3e} s", 0.9 * limit / unfixed);
            }
            fixes.push(fix);
        }
        fixes.push("solver.method = \"dopri5\" (adaptive steps, the default)".into());
        fixes.push(
            "solver.method = \"sdirk3\" (implicit: stable at this step, it damps the modes faster than 1/h)"
                .into(),
        );
        Some(format!(
            "solver.step_size = {h} s is above {}'s stability limit for this scene, h ≤ {:.3e} s \
             (h ω ≤ {limit:.3}), so the run would blow up: its fastest rate, ω ≈ {omega:.3e} 1/s, \
             comes from {}. Fixes: {}",
            method.name(),
            limit / omega,
            fastest.describe(&self.model, &self.inputs),
            fixes.join(", or ")
        ))
    }
}
