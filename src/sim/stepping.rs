//! Advancing a simulation: fixed steps on a grid or adaptive steps clipped to the target,
//! each accepted step followed by the exact correction and a finiteness check. A failed
//! advance leaves the state where it began.

use super::{events, Simulation, System};
use crate::correction::{bar_vector, MAX_UNCORRECTED_DRIFT};
use crate::error::StepError;
use crate::integrator::Outcome;

/// Communication points closer than this (relative) count as reached.
const TIME_EPS: f64 = 1e-12;

/// The spacing of doubles at the current time may be at most this fraction of a step.
const TIME_RESOLUTION: f64 = 1e-6;
/// Largest reduced position or velocity component a step may leave: far past anything the
/// scene limits allow, a state beyond it has blown up, and the forces computed from it
/// (squared speeds over lengths) would overflow while the state itself stays finite.
const MAX_STATE: f64 = 1e100;

impl Simulation {
    /// Takes `n` steps of `h` from the current time; time is `t₀ + k h`, not a running sum.
    pub fn advance(&mut self, n: u64, h: f64) -> Result<(), StepError> {
        let t0 = self.state.time;
        for k in 0..n {
            self.step_to(t0 + k as f64 * h, t0 + (k + 1) as f64 * h)?;
        }
        Ok(())
    }

    /// One step from `t` to `t_next`. On failure the state stays at `t`.
    pub fn step_to(&mut self, t: f64, t_next: f64) -> Result<(), StepError> {
        self.step(t, t_next - t, t_next)
    }

    /// One step of exactly `h` from `t`, after which the time is `t_next` (≈ `t + h`; a
    /// caller on a fixed grid passes both so that round-off in `t_next − t` cannot make
    /// otherwise identical runs differ). An adaptive method takes its own steps to
    /// `t_next`.
    pub fn step(&mut self, t: f64, h: f64, t_next: f64) -> Result<(), StepError> {
        if self.integrator.adaptive() {
            self.state.time = t;
            return self.advance_to(t_next).map(|_| ());
        }
        self.check_inputs()?;
        self.check_step_stability()?;
        self.note_input_changes();
        self.keep_last_good();
        self.attempt_located(t, h)?;
        self.state.time = t_next;
        Ok(())
    }

    /// Integrates from the current time to `t_end`: a fixed-step method in steps of
    /// `solver.step_size` on a grid from the current time (the last one shortened to meet
    /// `t_end`), an adaptive one with its own steps, the last clipped to `t_end`.
    /// Returns the number of accepted steps; on failure the state is left as it was.
    pub fn advance_to(&mut self, t_end: f64) -> Result<u64, StepError> {
        self.check_inputs()?;
        self.check_time_resolution(t_end)?;
        self.check_step_stability()?;
        self.note_input_changes();
        self.advance_start.time = self.state.time;
        self.advance_start.y.copy_from_slice(&self.state.y);
        self.advance_grip.copy_from_slice(&self.inputs.grip);
        let result = if self.integrator.adaptive() {
            self.advance_adaptive(t_end)
        } else {
            self.advance_grid(t_end)
        };
        if result.is_err() {
            self.state.time = self.advance_start.time;
            self.state.y.copy_from_slice(&self.advance_start.y);
            self.inputs.grip.copy_from_slice(&self.advance_grip);
            self.integrator.invalidate();
            self.refresh();
        }
        result
    }

    fn advance_grid(&mut self, t_end: f64) -> Result<u64, StepError> {
        let t = self.state.time;
        let dt = self.model.solver.step_size;
        let steps = (((t_end - t) / dt) - 1e-9).ceil().max(1.0);
        let max = self.model.solver.max_steps;
        if steps.is_nan() || steps > max as f64 {
            return Err(StepError::TooManySteps {
                what: format!("this advance ({steps:.3e} steps of {dt} s)"),
                fixes: "Use shorter communication steps or intervals, a larger \
                        solver.step_size, or raise solver.max_steps"
                    .into(),
                max,
                from: t,
                to: t_end,
            });
        }
        let n = steps as u64;
        for k in 0..n {
            let t0 = t + k as f64 * dt;
            let t1 = if k + 1 == n {
                t_end
            } else {
                t + (k + 1) as f64 * dt
            };
            // Full steps use dt itself, so any split into communication steps that lands
            // on the grid takes bit-identical internal steps.
            let rest = t_end - t0;
            let h = if k + 1 < n || (rest - dt).abs() <= 1e-9 * dt {
                dt
            } else {
                rest
            };
            self.keep_last_good();
            self.attempt_located(t0, h)?;
            self.state.time = t1;
        }
        Ok(n)
    }

    fn advance_adaptive(&mut self, t_end: f64) -> Result<u64, StepError> {
        let mut accepted = 0;
        let mut attempts = 0;
        let max = self.model.solver.max_steps;
        let locate = self.locate_events && !self.events.is_empty();
        // The natural next step while a step is clipped at a located event, and the clipped
        // step with the switch it ends at.
        let mut resume: Option<f64> = None;
        let mut clip: Option<f64> = None;
        loop {
            let t = self.state.time;
            let rest = t_end - t;
            if rest <= TIME_EPS * t_end.abs().max(1.0) {
                self.state.time = t_end;
                return Ok(accepted);
            }
            let last = self.h_next >= rest * (1.0 - TIME_EPS);
            let h = if last { rest } else { self.h_next };
            if h <= 1e-14 * t.abs().max(1.0) {
                return Err(StepError::StepSizeUnderflow { time: t, step: h });
            }
            if attempts == max {
                return Err(StepError::TooManySteps {
                    what: format!("this advance with {}", self.integrator.name()),
                    fixes: self.short_steps_note(),
                    max,
                    from: self.advance_start.time,
                    to: t_end,
                });
            }
            attempts += 1;
            self.keep_last_good();
            if locate {
                self.events
                    .start(&self.model, &self.inputs, &self.state.y, &self.ws);
            }
            match self.attempt(t, h)? {
                Outcome::Accepted { next } => {
                    // A step clipped at an event is not checked again: its end lies just
                    // past the switch, and a second look could only clip it ever shorter.
                    if locate && resume.is_none() {
                        if let Some(theta) = self.locate_switch(t, h) {
                            // Redo the step, clipped to end just past the switch.
                            clip = Some(theta);
                            self.discard_trial();
                            self.stats.events += 1;
                            resume = Some(next);
                            self.h_next = theta;
                            continue;
                        }
                    }
                    let at_cut = clip.take() == Some(h);
                    self.update_grips(at_cut);
                    let next = resume.take().map_or(next, |r| r.max(next));
                    accepted += 1;
                    self.state.time = if last { t_end } else { t + h };
                    // A step clipped to the target says nothing about the natural step.
                    if !last || next < self.h_next {
                        self.h_next = next;
                    }
                }
                Outcome::Rejected { next } => {
                    self.stats.rejected += 1;
                    self.h_next = next;
                }
            }
        }
    }

    /// A fixed step of `h` from `t`, split where a force law switches inside it: after a
    /// trial step the earliest switch is located, the trial is discarded and the step is
    /// redone up to the switch, then over the rest (which is checked again, up to
    /// [`events::MAX_SPLITS`] times). Each part is a full step of the method followed by
    /// the correction, so a part starts, like any step, from a corrected state.
    fn attempt_located(&mut self, t: f64, h: f64) -> Result<(), StepError> {
        if !self.locate_events || self.events.is_empty() {
            self.attempt(t, h)?;
            self.update_grips(false);
            return Ok(());
        }
        let end = t + h;
        let (mut t0, mut rest) = (t, h);
        for split in 0..=events::MAX_SPLITS {
            self.events
                .start(&self.model, &self.inputs, &self.state.y, &self.ws);
            self.attempt(t0, rest)?;
            if split == events::MAX_SPLITS {
                self.update_grips(false);
                break;
            }
            let Some(theta) = self.locate_switch(t0, rest) else {
                self.update_grips(false);
                break;
            };
            self.discard_trial();
            self.attempt(t0, theta)?;
            self.update_grips(true);
            self.stats.events += 1;
            t0 += theta;
            rest = end - t0;
        }
        Ok(())
    }

    /// Goes back to the start of a trial step that crossed a switch.
    fn discard_trial(&mut self) {
        self.state.y.copy_from_slice(&self.events.y0);
        self.integrator.invalidate();
        self.stats.steps -= 1;
        self.stats.rejected += 1;
    }

    /// One attempt from `t` with step `h`, then the correction and the finiteness check.
    pub(super) fn attempt(&mut self, t: f64, h: f64) -> Result<Outcome, StepError> {
        // The state moves: what the last refresh evaluated serves this step's start only.
        let fresh = self.evaluated.take() == Some(t) && self.evaluated_inputs == self.inputs;
        let mut system = System {
            model: &self.model,
            inputs: &self.inputs,
            ws: &mut self.ws,
            correction: self.correction,
            start: fresh.then_some(&self.acc[..]),
        };
        let outcome = self
            .integrator
            .attempt(&mut system, t, &mut self.state.y, h);
        if let Outcome::Rejected { .. } = outcome {
            return Ok(outcome);
        }
        if self.correction {
            self.correct();
            self.integrator.after_correction();
        }
        if let Some(i) = self
            .state
            .y
            .iter()
            .position(|x| x.is_nan() || x.abs() > MAX_STATE)
        {
            let value = self.state.y[i];
            self.restore_last_good();
            let half = self.state.y.len() / 2;
            let what = if i < half { "position" } else { "velocity" };
            let mut what = format!("reduced {what} component {}", i % half + 1);
            if value.is_finite() {
                what += &format!(" = {value:e}, past ±{MAX_STATE:e}, where its forces overflow");
            }
            return Err(StepError::NonFinite { time: t, what });
        }
        if !self.correction {
            if let Err(e) = self.check_drift(t) {
                self.restore_last_good();
                return Err(e);
            }
        }
        self.stats.steps += 1;
        Ok(outcome)
    }

    /// Refuses a target whose doubles are too coarse for the internal step: beyond it
    /// `t + h` rounds so much that the grid (or the stepping itself) breaks down.
    fn check_time_resolution(&self, t_end: f64) -> Result<(), StepError> {
        let step = self.model.solver.step_size;
        let time = t_end.abs().max(self.state.time.abs());
        let resolution = time * f64::EPSILON;
        if resolution > TIME_RESOLUTION * step {
            return Err(StepError::TimeResolution {
                time,
                resolution,
                step,
            });
        }
        Ok(())
    }

    /// Notes the state a step starts from, to return to if it fails.
    fn keep_last_good(&mut self) {
        self.ws.copy_in_halves(&mut self.last_good, &self.state.y);
        self.last_good_grip.copy_from_slice(&self.inputs.grip);
    }

    fn restore_last_good(&mut self) {
        self.state.y.copy_from_slice(&self.last_good);
        self.inputs.grip.copy_from_slice(&self.last_good_grip);
        self.integrator.invalidate();
        self.refresh();
    }

    /// Without the correction nothing holds the bars; past 1% of a length the run is
    /// meaningless, so it stops rather than return it.
    fn check_drift(&self, t: f64) -> Result<(), StepError> {
        let half = self.state.y.len() / 2;
        let q = &self.state.y[..half];
        for (i, bar) in self.model.bars.iter().enumerate() {
            let error = (bar_vector(&self.model.coords, i, q, true).norm() - bar.length).abs();
            if error > MAX_UNCORRECTED_DRIFT * bar.length {
                return Err(StepError::ConstraintDrift {
                    time: t,
                    bar: i + 1,
                    error,
                    length: bar.length,
                });
            }
        }
        Ok(())
    }

    fn check_step_stability(&mut self) -> Result<(), StepError> {
        if !self.guard_stability || self.integrator.adaptive() {
            return Ok(());
        }
        match self.check_stability() {
            Some(message) => Err(StepError::Unstable {
                message: message.to_string(),
            }),
            None => Ok(()),
        }
    }

    /// Values an integrator carries between steps (RATTLE's acceleration, Dormand–Prince's
    /// last stage) were computed with the old inputs: drop them when the inputs changed.
    fn note_input_changes(&mut self) {
        if self.stepped_inputs != self.inputs {
            self.stepped_inputs.copy_from(&self.inputs);
            self.integrator.invalidate();
        }
    }

    fn correct(&mut self) {
        let half = self.state.y.len() / 2;
        let (q, v) = self.state.y.split_at_mut(half);
        self.model.correction.correct(&self.model.coords, q, v);
    }
}
