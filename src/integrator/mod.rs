//! Time integration of `ẏ = f(t, y)` behind one pluggable step interface. The exact
//! correction runs after each accepted step, outside the integrator; a method that needs
//! the position projection inside its step (RATTLE-type) asks the right-hand side for it.

mod dopri5;
mod rattle;
mod rk4;
mod sdirk;

pub use dopri5::Dopri5;
pub use rattle::Rattle;
pub use rk4::Rk4;
pub use sdirk::Sdirk3;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// A right-hand side `f(t, y)`, with `y = [q; v]`.
pub trait Rhs {
    /// Writes `f(t, y)` into `dy`.
    fn eval(&mut self, t: f64, y: &[f64], dy: &mut [f64]);
    /// Writes `f(t, y)` at the start of a step (`y` the state the step starts from) into
    /// `dy`: an evaluation, unless the caller evaluated there already (for its outputs).
    /// Returns whether it evaluated.
    fn eval_start(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> bool {
        self.eval(t, y, dy);
        true
    }
    /// Projects the positions of `y` onto the constraints along the constraint directions
    /// of `before` (the start of the step), adding the displacement to `moved`; a no-op
    /// when the correction is off.
    fn project_positions(&mut self, _y: &mut [f64], _before: &[f64], _moved: &mut [f64]) {}
    /// Runs `f(start, part)` over parts of `out` that together make it, perhaps on several
    /// threads at once (the evaluation's, for large structures); for loops over independent
    /// entries, whose results do not depend on the split.
    fn for_each_half(&self, out: &mut [f64], f: &(dyn Fn(usize, &mut [f64]) + Sync)) {
        f(0, out);
    }
    /// `∂a/∂q` and `∂a/∂v` of the accelerations (the second half of `f`) at `(t, y)`, each
    /// `n/2 × n/2`, for implicit methods; `None` where there is no tangent.
    fn jacobian(&mut self, _t: f64, _y: &[f64]) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        None
    }
}

/// What an attempted step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// `y` now holds the solution at `t + h`; `next` is the proposed next step.
    Accepted {
        /// Proposed next step, s.
        next: f64,
    },
    /// The error estimate was too large; `y` is unchanged. Retry with `next`.
    Rejected {
        /// Proposed retry step, s.
        next: f64,
    },
}

/// One step of a one-step method; buffers are owned by the integrator and sized once.
pub trait Integrator: Send {
    /// Attempts a step of `h` from `t`, updating `y` in place when accepted.
    fn attempt(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64) -> Outcome;
    /// True if the method chooses its own steps from `rtol`/`atol`.
    fn adaptive(&self) -> bool;
    /// Forgets values carried between steps (the state was changed from outside).
    fn invalidate(&mut self) {}
    /// The exact correction just moved the accepted state; by default forget carried
    /// values, since they belong to the uncorrected state.
    fn after_correction(&mut self) {
        self.invalidate();
    }
    /// Short name, as used in reports.
    fn name(&self) -> &'static str;
    /// Right-hand-side evaluations so far.
    fn rhs_evaluations(&self) -> u64;
    /// A boxed copy (for FMU state snapshots).
    fn boxed_clone(&self) -> Box<dyn Integrator>;
    /// Values carried to the next step (empty if none are valid), for FMU state
    /// snapshots: restoring them makes a resumed run bit-identical.
    fn carried(&self) -> Vec<f64> {
        Vec::new()
    }
    /// The length of [`Integrator::carried`] when it is not empty.
    fn carried_len(&self) -> usize {
        0
    }
    /// Restores what [`Integrator::carried`] returned; a wrong length is ignored (the
    /// values are then recomputed).
    fn restore_carried(&mut self, _values: &[f64]) {}
}

/// The integration methods a scene, the CLI or an FMU parameter can choose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Classical fixed-step fourth-order Runge–Kutta (4 evaluations per step).
    #[default]
    Rk4,
    /// Adaptive Dormand–Prince 5(4) with `rtol`/`atol` (6–7 evaluations per step).
    Dopri5,
    /// Fixed-step second-order velocity Verlet with the exact position projection inside
    /// the step (RATTLE-type, 1 evaluation per step).
    Rattle,
    /// Fixed-step, L-stable, third-order singly diagonally implicit Runge–Kutta with
    /// Newton iterations on the exact tangent (for stiff cables at controller-rate steps).
    Sdirk3,
}

impl Method {
    /// Every method, in FMU enumeration order (values 1, 2, 3, 4).
    pub const ALL: [Method; 4] = [Method::Rk4, Method::Dopri5, Method::Rattle, Method::Sdirk3];

    /// The name used in scenes, on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rk4 => "rk4",
            Self::Dopri5 => "dopri5",
            Self::Rattle => "rattle",
            Self::Sdirk3 => "sdirk3",
        }
    }

    /// One line on what it is.
    pub fn description(self) -> &'static str {
        match self {
            Self::Rk4 => "classical fixed-step 4th-order Runge-Kutta, 4 evaluations per step",
            Self::Dopri5 => "adaptive Dormand-Prince 5(4) controlled by solver.rtol and solver.atol; solver.step_size is the first trial step",
            Self::Rattle => "fixed-step 2nd-order velocity Verlet with the exact position projection inside the step (RATTLE-type), 1 evaluation per step",
            Self::Sdirk3 => "fixed-step, L-stable 3rd-order implicit SDIRK (Alexander) with Newton iterations on the exact tangent: stable at any step, damps modes faster than the step resolves; a dense Jacobian per step",
        }
    }

    /// Its value in the FMU's `SolverMethod` enumeration (1, 2, 3, 4).
    pub fn fmi_value(self) -> i32 {
        Self::ALL
            .iter()
            .position(|&m| m == self)
            .map_or(1, |i| i as i32 + 1)
    }

    /// The method with this enumeration value.
    pub fn from_fmi_value(value: f64) -> Option<Self> {
        if value.fract() != 0.0 || value < 1.0 {
            return None;
        }
        Self::ALL.get(value as usize - 1).copied()
    }

    /// The method with this name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// A fresh integrator for a state of length `n`.
    pub fn integrator(self, n: usize, rtol: f64, atol: f64) -> Box<dyn Integrator> {
        match self {
            Self::Rk4 => Box::new(Rk4::new(n)),
            Self::Dopri5 => Box::new(Dopri5::new(n, rtol, atol)),
            Self::Rattle => Box::new(Rattle::new(n)),
            Self::Sdirk3 => Box::new(Sdirk3::new(n)),
        }
    }
}
