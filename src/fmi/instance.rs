//! A safe FMI 2.0 co-simulation instance: the state machine, get/set through the variable
//! table, `DoStep`, and FMU state snapshots. It holds no C types; the `extern "C"` layer
//! in `fmu/` converts arguments, calls these methods and maps their results to
//! `fmi2Status`. Messages are queued here and forwarded to the importer's logger there.

use std::path::Path;

use super::snapshot::Snapshot;
use super::state::Core;
use super::variables::VariableTable;
use super::{guid_for, Category, Message, Mode, Status};
use crate::scene::Scene;
use crate::sim::Simulation;

/// A failed call: what the importer is told.
#[derive(Debug, Clone, PartialEq)]
pub struct FmiError {
    /// `Error` or `Discard`.
    pub status: Status,
    /// The message, naming the call and the reason.
    pub message: String,
    /// A failed computation puts the instance into the Error mode (left by `fmi2Reset` or
    /// `fmi2SetFMUstate`); a refused call changed nothing, so the instance carries on.
    pub enters_error_mode: bool,
}

impl FmiError {
    /// A call refused before it changed anything (bad arguments, illegal sequence,
    /// rejected values): `fmi2Error`, and the instance stays in its mode.
    pub fn refused(message: impl Into<String>) -> Self {
        Self {
            status: Status::Error,
            message: message.into(),
            enters_error_mode: false,
        }
    }

    /// A computation that failed (numerical failure, a model that cannot be built, an
    /// internal error): `fmi2Error`, and the instance enters the Error mode.
    pub fn failed(message: impl Into<String>) -> Self {
        Self {
            enters_error_mode: true,
            ..Self::refused(message)
        }
    }
}

/// Result of an instance method: the status to return on success.
pub type FmiResult<T = Status> = Result<T, FmiError>;

/// One FMU instance.
pub struct Instance {
    name: String,
    guid: String,
    pub(super) core: Core,
    fresh: Core,
    pub(super) logging: [bool; 3],
    messages: Vec<Message>,
}

/// Tolerance for matching a communication point with the current time.
pub(super) fn time_tolerance(t: f64) -> f64 {
    1e-9 * t.abs().max(1.0)
}

impl Instance {
    /// `fmi2Instantiate`: reads `resources/scene.toml`, checks the GUID, builds the model.
    pub fn instantiate(
        name: &str,
        guid: &str,
        resources: &Path,
        logging_on: bool,
    ) -> Result<Self, String> {
        if name.is_empty() {
            return Err("fmi2Instantiate: instanceName is empty".into());
        }
        crate::simd::forced_scalar().map_err(|e| format!("fmi2Instantiate: {e}"))?;
        let path = resources.join("scene.toml");
        let text = std::fs::read_to_string(&path).map_err(|e| {
            format!(
                "fmi2Instantiate: cannot read the scene {}: {e}",
                path.display()
            )
        })?;
        let expected = guid_for(&text);
        if guid != expected {
            return Err(format!(
                "fmi2Instantiate: GUID mismatch: the importer passed {guid} but this binary and \
                 scene give {expected} (modelDescription.xml, binary and resources do not belong together)"
            ));
        }
        let scene = Scene::from_toml_str(&text).map_err(|e| format!("fmi2Instantiate: {e}"))?;
        let model =
            crate::analysis::load(&scene).map_err(|e| format!("fmi2Instantiate: scene: {e}"))?;
        let sim = Simulation::new(model);
        let core = Core {
            scene: sim.model().explicit_scene(),
            table: VariableTable::new(&sim),
            warned_negative: vec![false; sim.model().controlled.len() + sim.model().reeled.len()],
            sim,
            mode: Mode::Instantiated,
            time: 0.0,
            stop_time: None,
            rebuild: false,
            stale: false,
        };
        let mut instance = Self {
            name: name.to_string(),
            guid: expected,
            fresh: core.clone(),
            core,
            // Warnings and errors reach the importer unless it switches them off with
            // fmi2SetDebugLogging; loggingOn governs the informational category.
            logging: [logging_on, true, true],
            messages: Vec::new(),
        };
        instance.log(
            Category::Events,
            format!("kernels: {}", crate::simd::kernels()),
        );
        for w in instance.core.sim.warnings().to_vec() {
            instance.log(Category::Warning, format!("scene: {w}"));
        }
        Ok(instance)
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The current mode.
    pub fn mode(&self) -> Mode {
        self.core.mode
    }

    /// The variable table.
    pub fn table(&self) -> &VariableTable {
        &self.core.table
    }

    /// The simulation (read-only).
    pub fn simulation(&self) -> &Simulation {
        &self.core.sim
    }

    /// Queued messages for the logger, with their categories.
    pub fn drain_messages(&mut self) -> Vec<Message> {
        std::mem::take(&mut self.messages)
    }

    /// Whether messages are queued (so a call that logged nothing costs nothing to flush).
    pub fn has_messages(&self) -> bool {
        !self.messages.is_empty()
    }

    /// Queues a message if its category is enabled.
    pub fn log(&mut self, category: Category, text: impl Into<String>) {
        if self.logging[category as usize] {
            self.messages.push(Message {
                category,
                text: text.into(),
            });
        }
    }

    /// Records a failed call: logs it and, for an error, enters the Error mode.
    pub fn fail(&mut self, err: &FmiError) {
        if err.enters_error_mode {
            self.core.mode = Mode::Error;
        }
        self.log(Category::Error, err.message.clone());
    }

    /// `fmi2SetDebugLogging`; an empty list means every category.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> FmiResult {
        if categories.is_empty() {
            self.logging = [on; 3];
            return Ok(Status::Ok);
        }
        let mut logging = self.logging;
        for c in categories {
            let category = Category::from_name(c).ok_or_else(|| {
                FmiError::refused(format!(
                    "fmi2SetDebugLogging: unknown log category '{c}'; nothing was changed. Use one of {}",
                    Category::ALL.map(Category::name).join(", ")
                ))
            })?;
            logging[category as usize] = on;
        }
        self.logging = logging;
        Ok(Status::Ok)
    }

    pub(super) fn require(&self, call: &str, allowed: &[Mode]) -> FmiResult<()> {
        if allowed.contains(&self.core.mode) {
            Ok(())
        } else {
            Err(FmiError::refused(format!(
                "{call}: illegal call sequence: not allowed in mode {:?}",
                self.core.mode
            )))
        }
    }

    /// `fmi2SetupExperiment`.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> FmiResult {
        self.require("fmi2SetupExperiment", &[Mode::Instantiated])?;
        if !start.is_finite() || stop.is_some_and(|s| !(s.is_finite() && s >= start)) {
            return Err(FmiError::refused(format!(
                "fmi2SetupExperiment: start time {start} and stop time {stop:?} must be finite with stop ≥ start"
            )));
        }
        self.core.time = start;
        self.core.sim.set_time(start);
        self.core.stop_time = stop;
        Ok(Status::Ok)
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> FmiResult {
        self.require("fmi2EnterInitializationMode", &[Mode::Instantiated])?;
        self.core.mode = Mode::InitializationMode;
        Ok(Status::Ok)
    }

    /// `fmi2ExitInitializationMode`: rebuilds the model if parameters changed.
    pub fn exit_initialization_mode(&mut self) -> FmiResult {
        self.require("fmi2ExitInitializationMode", &[Mode::InitializationMode])?;
        self.rebuild_if_needed("fmi2ExitInitializationMode")?;
        self.check_start("fmi2ExitInitializationMode")?;
        self.core.mode = Mode::StepComplete;
        if let Some(why) = self.core.sim.check_stability().map(str::to_string) {
            self.log(
                Category::Warning,
                format!("fmi2ExitInitializationMode: {why}"),
            );
        } else if let Some(why) = self.core.sim.accuracy_problem() {
            self.log(
                Category::Warning,
                format!("fmi2ExitInitializationMode: {why}"),
            );
        }
        self.core.stale = true;
        let model = self.core.sim.model();
        let summary = format!(
            "fmi2ExitInitializationMode: {} bars, {} cables, {} reduced coordinates, {}",
            model.bars.len(),
            model.cables.len(),
            model.coords.r,
            self.core.scene.solver.summary()
        );
        self.log(Category::Events, summary);
        Ok(Status::Ok)
    }

    /// Refuses a step size the structure's time scale makes absurd, or a start time at which
    /// the step cannot advance time; the instance stays in initialization mode to be fixed.
    fn check_start(&mut self, call: &str) -> FmiResult<()> {
        if let Some(why) = self.core.sim.step_size_problem() {
            return Err(FmiError::refused(format!("{call}: {why}")));
        }
        let step = self.core.scene.solver.step_size;
        let resolution = self.core.time.abs() * f64::EPSILON;
        if resolution > 1e-6 * step {
            return Err(FmiError::refused(format!(
                "{call}: the start time {} s is so large that its resolution ({resolution:e} s) \
                 is too coarse for solver.step_size = {step} s, so time would not advance \
                 accurately. Call fmi2Reset, then fmi2SetupExperiment with a start nearer 0, or \
                 set a larger solver.step_size",
                self.core.time
            )));
        }
        Ok(())
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> FmiResult {
        self.require("fmi2Terminate", &[Mode::StepComplete])?;
        self.core.mode = Mode::Terminated;
        Ok(Status::Ok)
    }

    /// `fmi2Reset`: exactly the post-instantiate state.
    pub fn reset(&mut self) -> FmiResult {
        self.core = self.fresh.clone();
        self.log(
            Category::Events,
            "fmi2Reset: back to the state after fmi2Instantiate",
        );
        Ok(Status::Ok)
    }

    fn rebuild_if_needed(&mut self, call: &str) -> FmiResult<()> {
        if !self.core.rebuild {
            return Ok(());
        }
        self.core.sim = self
            .core
            .rebuilt(&self.core.scene)
            .map_err(|e| FmiError::failed(format!("{call}: parameters: {e}")))?;
        self.core.rebuild = false;
        self.core.stale = true;
        Ok(())
    }

    /// Rebuilds the model if parameters changed and, with `evaluate`, evaluates at the
    /// current state unless that was done since it last changed.
    pub(super) fn refresh_outputs(&mut self, call: &str, evaluate: bool) -> FmiResult<()> {
        self.rebuild_if_needed(call)?;
        if evaluate && self.core.stale {
            self.core.sim.refresh();
            self.core.stale = false;
        }
        Ok(())
    }

    /// `fmi2DoStep`: internal steps of `solver.step_size` from `t` to `t + h`, the last one
    /// shortened; on failure the instance is left exactly as before the call.
    pub fn do_step(&mut self, t: f64, h: f64) -> FmiResult {
        self.require("fmi2DoStep", &[Mode::StepComplete])?;
        let now = self.core.time;
        if !(h > 0.0 && h.is_finite()) {
            return Err(FmiError::refused(format!(
                "fmi2DoStep: communicationStepSize must be > 0, got {h}"
            )));
        }
        if !t.is_finite() || (t - now).abs() > time_tolerance(now) {
            return Err(FmiError::refused(format!(
                "fmi2DoStep: currentCommunicationPoint {t} does not continue from the last step, which ended at {now}"
            )));
        }
        let end = t + h;
        if let Some(stop) = self.core.stop_time {
            if end > stop + time_tolerance(stop) {
                return Err(FmiError::refused(format!(
                    "fmi2DoStep: step to {end} goes past the stop time {stop}"
                )));
            }
        }
        let steps = self.core.sim.advance_to(end).map_err(|e| {
            let message = format!("fmi2DoStep: {e}");
            if e.changed_nothing() {
                FmiError::refused(message)
            } else {
                FmiError::failed(message)
            }
        })?;
        self.core.time = end;
        self.core.stale = true;
        if self.logging[Category::Events as usize] {
            self.log(
                Category::Events,
                format!("fmi2DoStep: {t} -> {end} s in {steps} internal steps"),
            );
        }
        Ok(Status::Ok)
    }

    /// `fmi2GetRealStatus(fmi2LastSuccessfulTime)`.
    pub fn last_successful_time(&self) -> FmiResult<f64> {
        self.require(
            "fmi2GetRealStatus",
            &[Mode::StepComplete, Mode::Terminated, Mode::Error],
        )?;
        Ok(self.core.time)
    }

    /// `fmi2GetBooleanStatus(fmi2Terminated)`: the FMU never asks to stop early.
    pub fn terminated(&self) -> FmiResult<bool> {
        self.require(
            "fmi2GetBooleanStatus",
            &[Mode::StepComplete, Mode::Terminated, Mode::Error],
        )?;
        Ok(self.core.mode == Mode::Terminated)
    }

    /// `fmi2GetFMUstate`.
    pub fn get_state(&self) -> FmiResult<Snapshot> {
        self.require(
            "fmi2GetFMUstate",
            &[
                Mode::Instantiated,
                Mode::InitializationMode,
                Mode::StepComplete,
                Mode::Terminated,
            ],
        )?;
        Ok(Snapshot::take(&self.guid, &self.core))
    }

    /// `fmi2SetFMUstate` (also legal after an error, to recover): the state is checked
    /// against the model first, as a state handed in may not come from this instance.
    pub fn set_state(&mut self, snapshot: &Snapshot) -> FmiResult {
        self.require(
            "fmi2SetFMUstate",
            &[
                Mode::Instantiated,
                Mode::InitializationMode,
                Mode::StepComplete,
                Mode::Terminated,
                Mode::Error,
            ],
        )?;
        snapshot
            .restore(&self.guid, &mut self.core)
            .map_err(|e| FmiError::refused(format!("fmi2SetFMUstate: {e}; nothing was changed")))?;
        Ok(Status::Ok)
    }

    /// `fmi2DeSerializeFMUstate`: the buffer is parsed, then every field is checked
    /// against this instance's model.
    pub fn deserialize_state(&self, bytes: &[u8]) -> FmiResult<Snapshot> {
        let refused = |e: String| {
            FmiError::refused(format!(
                "fmi2DeSerializeFMUstate: {e}; nothing was changed. Pass a buffer that \
                 fmi2SerializeFMUstate wrote for this FMU, unchanged"
            ))
        };
        let snapshot = Snapshot::from_bytes(&self.guid, bytes).map_err(refused)?;
        snapshot.check(&self.core).map_err(refused)?;
        Ok(snapshot)
    }
}
