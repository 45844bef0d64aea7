//! The single variable table of an FMU, built from the model. It drives get/set in the
//! instance and the `ModelVariables` of modelDescription.xml, so the two cannot drift.
//! A variable exists only where the scene calls for it.
//!
//! A parameter's variability lives in the table too ([`Variable::variability`]): tunable
//! parameters are [`Variability::Tunable`], and nothing else lists them.

pub mod kinds;
mod parameter_table;

use fmi2_model_description::{Causality, Initial, Variability};

use crate::analysis::InputChannel;
use crate::model::Model;
use crate::outputs::{self, Quantity};
use crate::sim::Simulation;
use parameter_table::{effect_parameters, parameters};

/// What a variable reads or writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binding {
    /// A computed output.
    Output(Quantity),
    /// Force density input of controlled cable input `k`.
    ForceDensity(usize),
    /// Force input `k` (node in `force_inputs` order), axis 0..3.
    NodeForce(usize, usize),
    /// Rest-length input of reeled cable input `k`.
    ReelInput(usize),
    /// `solver.step_size`.
    StepSize,
    /// `solver.correction`.
    Correction,
    /// `solver.locate_events`.
    LocateEvents,
    /// `solver.method` (Integer: 1-based index in `Method::ALL`).
    Method,
    /// `solver.max_steps` (Integer).
    MaxSteps,
    /// `solver.rtol`.
    Rtol,
    /// `solver.atol`.
    Atol,
    /// Stiffness of elastic cable `j`.
    Stiffness(usize),
    /// Rest length of elastic cable `j`.
    RestLength(usize),
    /// Damping of elastic cable `j`.
    Damping(usize),
    /// Mass of bar `i`.
    Mass(usize),
    /// Gravity component, axis 0..3.
    Gravity(usize),
    /// A ground-plane setting.
    Ground(GroundField),
    /// Mass of point mass `k`.
    PointMass(usize),
    /// A setting of scripted load `k`.
    Load(usize, LoadField),
    /// Radius of bar `i`'s capsule.
    Radius(usize),
    /// A contact setting of terrain shape `k`.
    Terrain(usize, ContactField),
    /// A setting of bar–bar contact.
    Collision(ContactField),
}

/// The contact settings of a terrain shape or of bar–bar contact exposed as parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactField {
    /// `terrain[k].stiffness`.
    Stiffness,
    /// `terrain[k].damping`.
    Damping,
    /// `terrain[k].friction`.
    Friction,
    /// `terrain[k].slip_velocity`.
    SlipVelocity,
}

/// The ground-plane settings exposed as parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GroundField {
    /// `ground.height`.
    Height,
    /// `ground.stiffness`.
    Stiffness,
    /// `ground.damping`.
    Damping,
    /// `ground.friction`.
    Friction,
    /// `ground.slip_velocity`.
    SlipVelocity,
}

/// The scripted-load settings exposed as parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadField {
    /// Force (constant, step) or amplitude (sinusoidal) along an axis 0..3.
    Force(usize),
    /// Sinusoid frequency.
    Frequency,
    /// Sinusoid phase.
    Phase,
    /// Step switch-on time.
    Time,
}

/// FMI base type of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BaseType {
    /// `fmi2Real`.
    Real,
    /// `fmi2Boolean`.
    Boolean,
    /// `fmi2Integer`.
    Integer,
}

/// One FMU variable.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Structured name, 1-based indices.
    pub name: String,
    /// Value reference (the index in the table).
    pub value_reference: u32,
    /// Real, Integer or Boolean.
    pub base_type: BaseType,
    /// FMI causality.
    pub causality: Causality,
    /// FMI variability.
    pub variability: Variability,
    /// FMI initial, where the combination needs one.
    pub initial: Option<Initial>,
    /// Unit symbol (declared in UnitDefinitions).
    pub unit: Option<&'static str>,
    /// Meaning.
    pub description: String,
    /// Start value (Booleans as 0/1, Integers exact); `None` for calculated outputs.
    pub start: Option<f64>,
    /// What it reads or writes.
    pub binding: Binding,
}

/// Every variable of an FMU, indexed by value reference.
#[derive(Debug, Clone, PartialEq)]
pub struct VariableTable {
    /// Variables; `variables[vr]` has value reference `vr`.
    pub variables: Vec<Variable>,
}

/// Units used by the table, with their base-unit exponents `(kg, m, s, rad)`.
pub const UNITS: [(&str, [i32; 4]); 13] = [
    ("m", [0, 1, 0, 0]),
    ("m/s", [0, 1, -1, 0]),
    ("m2/s", [0, 2, -1, 0]),
    ("N", [1, 1, -2, 0]),
    ("N/m", [1, 0, -2, 0]),
    ("N.s/m", [1, 0, -1, 0]),
    ("kg", [1, 0, 0, 0]),
    ("s", [0, 0, 1, 0]),
    ("J", [1, 2, -2, 0]),
    ("m/s2", [0, 1, -2, 0]),
    ("Hz", [0, 0, -1, 0]),
    ("rad", [0, 0, 0, 1]),
    ("1", [0, 0, 0, 0]),
];

impl VariableTable {
    /// The inputs by name, as channels of the linear model (the FMU's `u`, in its order).
    pub fn input_channels(&self) -> Vec<(String, InputChannel)> {
        self.variables
            .iter()
            .filter_map(|v| {
                let channel = match v.binding {
                    Binding::ForceDensity(k) => InputChannel::ForceDensity(k),
                    Binding::ReelInput(k) => InputChannel::RestLength(k),
                    Binding::NodeForce(k, axis) => InputChannel::NodeForce(k, axis),
                    _ => return None,
                };
                Some((v.name.clone(), channel))
            })
            .collect()
    }

    /// Builds the table for a simulation's model (start values from its current inputs).
    pub fn new(sim: &Simulation) -> Self {
        let model = sim.model();
        let mut vars = Vec::new();
        parameters(model, &mut vars);
        effect_parameters(model, &mut vars);
        inputs(model, &mut vars);
        for o in outputs::outputs(sim) {
            vars.push(Variable {
                name: o.name,
                value_reference: 0,
                base_type: BaseType::Real,
                causality: Causality::Output,
                variability: Variability::Continuous,
                initial: Some(Initial::Calculated),
                unit: Some(o.unit),
                description: o.description,
                start: None,
                binding: Binding::Output(o.quantity),
            });
        }
        for (vr, v) in vars.iter_mut().enumerate() {
            v.value_reference = vr as u32;
        }
        Self { variables: vars }
    }

    /// The variable with value reference `vr`.
    pub fn get(&self, vr: u32) -> Option<&Variable> {
        self.variables.get(vr as usize)
    }

    /// The variable called `name`.
    pub fn by_name(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }
}

/// Whether a user may change the parameter behind `binding` in a running co-simulation:
/// everything except the integrator's set-up (step size, method, correction, events).
pub(crate) fn is_tunable(binding: Binding) -> bool {
    !matches!(
        binding,
        Binding::StepSize | Binding::Method | Binding::Correction | Binding::LocateEvents
    )
}

const AXES: [&str; 3] = ["x", "y", "z"];

fn input(
    name: String,
    unit: &'static str,
    description: String,
    start: f64,
    binding: Binding,
) -> Variable {
    Variable {
        name,
        value_reference: 0,
        base_type: BaseType::Real,
        causality: Causality::Input,
        variability: Variability::Continuous,
        initial: None,
        unit: Some(unit),
        description,
        start: Some(start),
        binding,
    }
}

fn inputs(model: &Model, vars: &mut Vec<Variable>) {
    let cable_inputs = [
        (
            &model.controlled,
            &model.controlled_start,
            "force_density",
            "N/m",
            "commanded force density of cable {j} (tension / length; negative values act as 0)",
            Binding::ForceDensity as fn(usize) -> Binding,
        ),
        (
            &model.reeled,
            &model.reeled_start,
            "rest_length",
            "m",
            "commanded rest length of cable {j} (reeled by a motor; negative values act as 0)",
            Binding::ReelInput,
        ),
    ];
    for (cables, starts, key, unit, text, binding) in cable_inputs {
        for (k, (&j, &start)) in cables.iter().zip(starts).enumerate() {
            let j = (j + 1).to_string();
            vars.push(input(
                format!("cable[{j}].{key}"),
                unit,
                text.replace("{j}", &j),
                start,
                binding(k),
            ));
        }
    }
    for (k, &n) in model.force_inputs.iter().enumerate() {
        for (axis, name) in ["fx", "fy", "fz"].iter().enumerate() {
            vars.push(input(
                format!("node[{}].{name}", n + 1),
                "N",
                format!("external force on node {} along {}", n + 1, &name[1..]),
                0.0,
                Binding::NodeForce(k, axis),
            ));
        }
    }
}
