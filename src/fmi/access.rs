//! `fmi2Get*` / `fmi2Set*` through the variable table. Every value reference is checked
//! before anything is read or written, nothing is allocated per value (a hostile `nvr`
//! costs nothing), and a set changes nothing unless every value is accepted.

use fmi2_model_description::Variability;

use super::instance::{FmiError, FmiResult, Instance};
use super::parameters::{apply_parameter, refused_value};
use super::variables::{BaseType, Binding};
use super::{Category, Mode, Status};

impl Instance {
    fn lookup(&self, call: &str, vr: u32, expected: BaseType) -> FmiResult<Binding> {
        let v =
            self.core.table.get(vr).ok_or_else(|| {
                FmiError::refused(format!("{call}: unknown value reference {vr}"))
            })?;
        if v.base_type != expected {
            return Err(FmiError::refused(format!(
                "{call}: value reference {vr} ({}) is not of this type",
                v.name
            )));
        }
        Ok(v.binding)
    }

    /// `fmi2GetReal` / `fmi2GetBoolean` / `fmi2GetInteger`: `store(k, value)` receives the
    /// value of `vrs[k]` (Booleans as 0/1), only once every reference has been checked.
    pub fn get_each(
        &mut self,
        call: &str,
        base: BaseType,
        vrs: &[u32],
        mut store: impl FnMut(usize, f64),
    ) -> FmiResult {
        self.require(
            call,
            &[
                Mode::InitializationMode,
                Mode::StepComplete,
                Mode::Terminated,
                Mode::Error,
            ],
        )?;
        let mut evaluate = false;
        for &vr in vrs {
            evaluate |= match self.lookup(call, vr, base)? {
                Binding::Output(q) => q.needs_evaluation(),
                _ => false,
            };
        }
        // Positions, velocities, inputs and parameters need no evaluation: a step followed
        // by reading them costs the step alone.
        self.refresh_outputs(call, evaluate)?;
        for (k, &vr) in vrs.iter().enumerate() {
            let binding = self.lookup(call, vr, base)?;
            store(k, self.core.read(binding));
        }
        Ok(Status::Ok)
    }

    /// [`Instance::get_each`] into a slice of the same length as `vrs`.
    pub fn get(
        &mut self,
        call: &str,
        base: BaseType,
        vrs: &[u32],
        values: &mut [f64],
    ) -> FmiResult {
        if values.len() != vrs.len() {
            return Err(FmiError::refused(format!(
                "{call}: {} value references but room for {} values",
                vrs.len(),
                values.len()
            )));
        }
        self.get_each(call, base, vrs, |k, v| values[k] = v)
    }

    /// Get or set of a type this FMU has no variables of (String): only an empty request
    /// succeeds.
    pub fn untyped(&mut self, call: &str, vrs: &[u32]) -> FmiResult {
        self.require(
            call,
            &[
                Mode::Instantiated,
                Mode::InitializationMode,
                Mode::StepComplete,
                Mode::Terminated,
                Mode::Error,
            ],
        )?;
        match vrs.first() {
            None => Ok(Status::Ok),
            Some(vr) => Err(FmiError::refused(format!(
                "{call}: value reference {vr} is not a variable of this type (this FMU has no String variables)"
            ))),
        }
    }

    /// [`Instance::set_each`] from a slice of the same length as `vrs`.
    pub fn set(&mut self, call: &str, base: BaseType, vrs: &[u32], values: &[f64]) -> FmiResult {
        if values.len() != vrs.len() {
            return Err(FmiError::refused(format!(
                "{call}: {} value references but {} values",
                vrs.len(),
                values.len()
            )));
        }
        self.set_each(call, base, vrs, |k| values[k])
    }

    /// `fmi2SetReal` / `fmi2SetBoolean` / `fmi2SetInteger`: `value(k)` is the value for
    /// `vrs[k]`. Inputs are settable at any time before termination, tunable parameters
    /// also between steps (re-validated, applied at the next step), fixed ones only before
    /// initialization ends. A refusal changes nothing and leaves the instance running.
    pub fn set_each(
        &mut self,
        call: &str,
        base: BaseType,
        vrs: &[u32],
        value: impl Fn(usize) -> f64,
    ) -> FmiResult {
        self.require(
            call,
            &[
                Mode::Instantiated,
                Mode::InitializationMode,
                Mode::StepComplete,
            ],
        )?;
        let mut inputs_only = true;
        for &vr in vrs {
            inputs_only &= is_input(self.lookup(call, vr, base)?);
        }
        if inputs_only {
            return self.set_inputs(call, vrs, value);
        }
        let mut next = self.core.clone_for_set();
        let mut warnings = Vec::new();
        for (k, &vr) in vrs.iter().enumerate() {
            let value = value(k);
            let variable = &self.core.table.variables[vr as usize];
            let (binding, name) = (variable.binding, variable.name.clone());
            if !value.is_finite() {
                return Err(FmiError::refused(format!(
                    "{call}: {name} = {value} is not a finite number"
                )));
            }
            if matches!(binding, Binding::Output(_)) {
                return Err(FmiError::refused(format!(
                    "{call}: {name} is an output and cannot be set"
                )));
            }
            let input = is_input(binding);
            let tunable = variable.variability == Variability::Tunable;
            if !input && !tunable && self.core.mode == Mode::StepComplete {
                return Err(FmiError::refused(format!(
                    "{call}: {name} is a fixed parameter and cannot be set after initialization \
                     (set it before fmi2ExitInitializationMode, or use fmi2Reset); the value \
                     was not changed"
                )));
            }
            let model = self.core.sim.model();
            match binding {
                Binding::ForceDensity(k) => {
                    if value < 0.0 && !next.warned_negative[k] {
                        next.warned_negative[k] = true;
                        warnings.push(format!("{call}: {name} = {value} is negative; a cable cannot push, so it acts as 0 (warned once)"));
                    }
                    next.inputs.force_density[k] = value;
                }
                Binding::ReelInput(k) => {
                    let flag = model.controlled.len() + k;
                    if value < 0.0 && !next.warned_negative[flag] {
                        next.warned_negative[flag] = true;
                        warnings.push(format!(
                            "{call}: {name} = {value} is negative; it acts as 0 (warned once)"
                        ));
                    }
                    next.inputs.rest_length[k] = value;
                }
                Binding::NodeForce(k, axis) => next.inputs.node_force[k][axis] = value,
                _ => {
                    if let Some(why) = refused_value(variable, value) {
                        return Err(FmiError::refused(format!("{call}: {why}")));
                    }
                    apply_parameter(&mut next.scene, binding, value);
                    next.scene.validate().map_err(|e| {
                        FmiError::refused(format!(
                            "{call}: {name} = {value} rejected, the value was not changed: {e}"
                        ))
                    })?;
                    next.rebuild = true;
                }
            }
        }
        if next.rebuild && self.core.mode == Mode::StepComplete {
            // A tunable parameter acts from here on: rebuild now, keeping the state, so a
            // value the model refuses is refused by this call.
            self.core.sim = self.core.rebuilt(&next.scene).map_err(|e| {
                FmiError::refused(format!("{call}: rejected, nothing was changed: {e}"))
            })?;
            next.rebuild = false;
        }
        self.core.commit_set(next);
        let status = if warnings.is_empty() {
            Status::Ok
        } else {
            Status::Warning
        };
        for w in warnings {
            self.log(Category::Warning, w);
        }
        Ok(status)
    }

    /// [`Instance::set_each`] of inputs only, the call an importer makes every step: the
    /// values are checked, then written in place, with nothing cloned or allocated (unless
    /// a warning is logged).
    fn set_inputs(&mut self, call: &str, vrs: &[u32], value: impl Fn(usize) -> f64) -> FmiResult {
        for (k, &vr) in vrs.iter().enumerate() {
            let value = value(k);
            if !value.is_finite() {
                let name = &self.core.table.variables[vr as usize].name;
                return Err(FmiError::refused(format!(
                    "{call}: {name} = {value} is not a finite number"
                )));
            }
        }
        let mut status = Status::Ok;
        for (k, &vr) in vrs.iter().enumerate() {
            let value = value(k);
            let core = &mut self.core;
            let inputs = &mut core.sim.inputs;
            let negative = match core.table.variables[vr as usize].binding {
                Binding::ForceDensity(k) => {
                    inputs.force_density[k] = value;
                    Some(k)
                }
                Binding::ReelInput(k) => {
                    inputs.rest_length[k] = value;
                    Some(core.sim.model().controlled.len() + k)
                }
                Binding::NodeForce(k, axis) => {
                    inputs.node_force[k][axis] = value;
                    None
                }
                _ => unreachable!("set_inputs is called with inputs only"),
            };
            core.stale = true;
            let Some(flag) = negative.filter(|&f| value < 0.0 && !core.warned_negative[f]) else {
                continue;
            };
            core.warned_negative[flag] = true;
            let name = &core.table.variables[vr as usize].name;
            let why = if flag < core.sim.model().controlled.len() {
                "a cable cannot push, so it acts as 0"
            } else {
                "it acts as 0"
            };
            let text = format!("{call}: {name} = {value} is negative; {why} (warned once)");
            self.log(Category::Warning, text);
            status = Status::Warning;
        }
        Ok(status)
    }
}

/// Whether a binding is an input (settable at any time before termination).
fn is_input(binding: Binding) -> bool {
    matches!(
        binding,
        Binding::ForceDensity(_) | Binding::NodeForce(..) | Binding::ReelInput(_)
    )
}
