//! What a run will cost, before it starts: its internal steps from the method, the
//! tolerance, the stop time and the fastest time scale, and the element that sets it.
//!
//! A fixed-step method takes `⌈interval / h⌉` steps per output interval (exactly, but for
//! steps split at events). dopri5 takes the shorter of two steps:
//! - near its stability bound for the fastest stiff rate ω (the structure's fastest mode,
//!   the ground's bounds, damped cables): about ω/2 attempts per second, rejections
//!   included (its bound is |h λ| ≈ 3.3; it hovers below it, rejecting a third);
//! - the step that follows the fastest motion to its tolerance: a rate `√(a / L)` for an
//!   acceleration `a` (gravity, a load, forces unbalanced at the start) over the structure's
//!   size `L`, and a step of [`RESOLVING_STEP`]` · tol^(1/5) / ω`.
//!
//! Each advance ends at an output row, so it takes at least one step per row. The
//! constants were measured on the built-in scenes and seven extreme ones (`bench work`).

use std::time::{Duration, Instant};

use super::cause::{self, Cause, Rate};
use super::Simulation;
use crate::model::Model;

/// dopri5's attempts per second per unit of the stiff rate that holds its step.
pub const STABLE_ATTEMPTS_PER_RATE: f64 = 0.5;

/// dopri5's step that follows a motion of rate ω to the relative tolerance `tol`, in units
/// of `tol^(1/5) / ω` (at rtol = 1e-6 about `1/(30 ω)`).
pub const RESOLVING_STEP: f64 = 0.53;

/// What holds the step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pace {
    /// A fixed step, `solver.step_size`.
    Fixed,
    /// dopri5 near its stability bound for a stiff rate.
    Stability,
    /// dopri5 following a fast motion to its tolerance.
    Accuracy,
    /// dopri5 clipped to the output rows: it would take longer steps than their interval.
    Rows,
}

/// A run's predicted work.
#[derive(Debug, Clone, PartialEq)]
pub struct Work {
    /// Internal step attempts, accepted and rejected.
    pub steps: f64,
    /// The typical internal step, s.
    pub step: f64,
    /// What holds it.
    pub pace: Pace,
    /// The rate behind it: for dopri5 the one that sets the step, for a fixed step the
    /// fastest stiff rate (`None` for a structure without one).
    pub rate: Option<Rate>,
}

impl Simulation {
    /// The work of a run from the current time to `stop`, with an output row (the end of
    /// an advance) every `interval` and at `stop`, at the current inputs.
    pub fn predict_work(&mut self, stop: f64, interval: f64) -> Work {
        let span = (stop - self.time()).max(0.0);
        let count = |per_row: &dyn Fn(f64) -> f64| rows(span, interval, per_row);
        if !self.integrator.adaptive() {
            let h = self.model.solver.step_size;
            let steps = fixed_steps(span, interval, h);
            let rate = self.fastest_rates().into_iter().next();
            return Work {
                steps,
                step: h,
                pace: Pace::Fixed,
                rate,
            };
        }
        let (pace, rate, per_second) = self.adaptive_pace();
        let pace = if interval * per_second <= 1.0 {
            Pace::Rows
        } else {
            pace
        };
        Work {
            steps: count(&|d| (d * per_second).ceil().max(1.0)),
            step: 1.0 / per_second,
            pace,
            rate: Some(rate),
        }
    }

    /// What holds dopri5's step at the current state and inputs, the rate behind it and
    /// the attempts per second it takes.
    pub fn adaptive_pace(&mut self) -> (Pace, Rate, f64) {
        let solver = &self.model.solver;
        let size = cause::size(&self.model);
        let tol = solver.rtol.max(solver.atol / size).clamp(1e-300, 1.0);
        let mut stiff = self.fastest_rates();
        stiff.extend(damping_rates(&self.model));
        let stiff = stiff
            .into_iter()
            .max_by(|a, b| a.omega.total_cmp(&b.omega))
            .map(|r| (STABLE_ATTEMPTS_PER_RATE * r.omega, r));
        let motion = self.fastest_motion();
        let resolving = (motion.omega / (RESOLVING_STEP * tol.powf(0.2)), motion);
        match stiff {
            Some((per_second, rate)) if per_second >= resolving.0 => {
                (Pace::Stability, rate, per_second)
            }
            // At least one attempt per second of simulated time: a scene at rest still
            // takes steps, and rates of zero give no division by zero.
            _ => (Pace::Accuracy, resolving.1, resolving.0.max(1.0)),
        }
    }

    /// The fastest motion: the largest acceleration at the start (or the largest a
    /// scripted load can give its node, at any time) over the structure's size, named by
    /// what causes it. Reads the last evaluation's accelerations.
    fn fastest_motion(&self) -> Rate {
        let model = &self.model;
        let (node, start) = (0..model.n_nodes())
            .map(|n| (n, self.node_acceleration(n).norm()))
            .fold((0, 0.0), |best, c| if c.1 > best.1 { c } else { best });
        let (load, pushed) = (0..model.scene.loads.len())
            .map(|k| {
                let n = model.scene.loads[k].node() - 1;
                (
                    k,
                    cause::load_force(model, k) * cause::node_compliance(model, n),
                )
            })
            .fold((0, 0.0), |best, c| if c.1 > best.1 { c } else { best });
        let gravity = model.gravity.map_or(0.0, |g| g.norm());
        let acceleration = start.max(pushed);
        let cause = if pushed >= 0.5 * acceleration && pushed > 0.0 {
            Cause::Load(load)
        } else if gravity >= 0.5 * acceleration && gravity > 0.0 {
            Cause::Gravity
        } else {
            Cause::Unbalanced
        };
        let node = match cause {
            Cause::Load(k) => Some(model.scene.loads[k].node() - 1),
            _ => Some(node),
        };
        let omega = (acceleration / cause::size(model)).sqrt();
        Rate {
            omega: if omega.is_finite() { omega } else { 0.0 },
            cause,
            node,
        }
    }

    /// Why the adaptive method's steps are short and the fixes, for a call that ran out of
    /// `solver.max_steps`, from the current inputs (worked out per refusal, never per step).
    pub(super) fn short_steps_note(&mut self) -> String {
        let (pace, rate, per_second) = self.adaptive_pace();
        let why = match pace {
            Pace::Stability => "at its stability bound for",
            _ => "to follow the motion set by",
        };
        format!(
            "Its steps are about {:.2e} s, {why} {}. Use solver.method = \"sdirk3\" \
             (implicit, stable at any stiffness: fixed steps of solver.step_size), a softer \
             element, shorter communication steps, or raise solver.max_steps",
            1.0 / per_second,
            rate.describe(&self.model, &self.inputs)
        )
    }

    /// Wall time per internal step attempt, s, measured on a copy with steps of `step`
    /// over `attempts` attempts or about `budget`, whichever ends first (at least one);
    /// `None` when the copy fails at once.
    pub fn seconds_per_step(&self, step: f64, attempts: u32, budget: Duration) -> Option<f64> {
        let mut probe = self.clone();
        let mut taken = 0u32;
        let started = Instant::now();
        while taken == 0 || (taken < attempts && started.elapsed() < budget) {
            let t = probe.time();
            if probe.attempt(t, step).is_err() {
                break;
            }
            probe.state.time = t + step;
            taken += 1;
        }
        (taken > 0).then(|| started.elapsed().as_secs_f64() / f64::from(taken))
    }
}

/// The steps of a fixed step `h` over `span` with a row every `interval`.
pub fn fixed_steps(span: f64, interval: f64, h: f64) -> f64 {
    rows(span, interval, &|d| (d / h - 1e-9).ceil().max(1.0))
}

/// `per_row(interval)` summed over the full intervals of `span`, plus `per_row(rest)`
/// for a last, shorter one.
fn rows(span: f64, interval: f64, per_row: &dyn Fn(f64) -> f64) -> f64 {
    let full = (span / interval + 1e-9).floor();
    let rest = span - full * interval;
    full * per_row(interval)
        + if rest > 1e-9 * interval {
            per_row(rest)
        } else {
            0.0
        }
}

/// The damped cables' decay rates `c (w_a + w_b)`.
fn damping_rates(model: &Model) -> Vec<Rate> {
    (0..model.cables.len())
        .filter_map(|j| {
            let [a, b] = model.cables[j].nodes;
            let (wa, wb) = (
                cause::node_compliance(model, a),
                cause::node_compliance(model, b),
            );
            let omega = cause::cable_damping(model, j) * (wa + wb);
            (omega > 0.0).then_some(Rate {
                omega,
                cause: Cause::CableDamping(j),
                node: Some(if wa >= wb { a } else { b }),
            })
        })
        .collect()
}
