//! Error values. Scene errors name the offending key; numerical failures say what broke.

use thiserror::Error;

/// Anything wrong with a scene, found while reading, validating or building it.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene file {path}: {message}")]
    Io {
        /// The path that failed.
        path: String,
        /// The OS reason.
        message: String,
    },
    /// The text is not a valid scene document.
    #[error("malformed {format} scene: {message}")]
    Parse {
        /// `TOML` or `JSON`.
        format: &'static str,
        /// The parser's message (it names the key and line).
        message: String,
    },
    /// A key holds an invalid value.
    #[error("{key}: {reason}")]
    Invalid {
        /// The scene key, with 1-based list indices, e.g. `bars[2].mass`.
        key: String,
        /// Why it is rejected.
        reason: String,
    },
}

impl SceneError {
    /// Shorthand for [`SceneError::Invalid`].
    pub fn invalid(key: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::Invalid {
            key: key.into(),
            reason: reason.into(),
        }
    }
}

/// A failure while integrating: the state was left at the last good point.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StepError {
    /// A NaN or an infinity reached the state.
    #[error("non-finite state at t = {time} s ({what}); the state was kept at the last good point. Reduce the step size or check the inputs")]
    NonFinite {
        /// Time at the start of the failed step.
        time: f64,
        /// Which quantity became non-finite.
        what: String,
    },
    /// The adaptive method cannot meet its tolerances.
    #[error("the adaptive step size fell to {step:e} s at t = {time} s without meeting solver.rtol/solver.atol; the state was kept at the last good point. Loosen the tolerances or check for a discontinuity")]
    StepSizeUnderflow {
        /// Time of the failed attempt.
        time: f64,
        /// The step that was too small.
        step: f64,
    },
    /// Without the correction, a bar's length drifted too far for the model to mean anything.
    #[error("with solver.correction off, bar {bar} drifted {error:e} m from its length {length} m (over 1%) by t = {time} s; the state was kept at the last good point. Turn solver.correction on, or reduce the step size")]
    ConstraintDrift {
        /// Time at the start of the failed step.
        time: f64,
        /// 1-based bar number.
        bar: usize,
        /// Its length error, m.
        error: f64,
        /// Its nominal length, m.
        length: f64,
    },
    /// The fixed step is above the explicit method's stability limit.
    #[error("{message}")]
    Unstable {
        /// Names the limit and the fixes.
        message: String,
    },
    /// One call would take more internal steps than `solver.max_steps` allows.
    #[error("{what} takes more than solver.max_steps = {max} internal steps (t = {from} s to {to} s); nothing was integrated. {fixes}")]
    TooManySteps {
        /// What needs the steps, e.g. "this advance (about 1e9 steps of 1e-12 s)".
        what: String,
        /// What keeps the steps short, if known, and the fixes.
        fixes: String,
        /// The cap.
        max: u64,
        /// Start time, s.
        from: f64,
        /// Target time, s.
        to: f64,
    },
    /// Time has grown so large that a step no longer changes it accurately.
    #[error("at t = {time} s the time resolution ({resolution:e} s) is too coarse for solver.step_size = {step} s (the steps would not advance time accurately); nothing was integrated. Start the experiment nearer 0 or use a larger solver.step_size")]
    TimeResolution {
        /// The time reached, s.
        time: f64,
        /// Spacing of doubles at that time, s.
        resolution: f64,
        /// The internal step, s.
        step: f64,
    },
    /// An input holds a NaN or an infinity.
    #[error("input {name} is not finite ({value})")]
    NonFiniteInput {
        /// The input's variable name.
        name: String,
        /// The offending value.
        value: f64,
    },
}

impl StepError {
    /// Refused before any integration (too many steps, coarse time, an unstable fixed
    /// step, a non-finite input): the caller may correct the request and carry on.
    pub fn changed_nothing(&self) -> bool {
        matches!(
            self,
            Self::TooManySteps { .. }
                | Self::TimeResolution { .. }
                | Self::Unstable { .. }
                | Self::NonFiniteInput { .. }
        )
    }
}
