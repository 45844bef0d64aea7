//! The single variable table of an FMU, built from the model. It drives get/set in the
//! instance and the `ModelVariables` of modelDescription.xml, so the two cannot drift.
//! A variable exists only where the scene calls for it.

use fmi2_model_description::{Causality, Initial, Variability};

use crate::model::{CableLaw, Model};
use crate::outputs::{self, Quantity};
use crate::scene::LoadSpec;
use crate::sim::Simulation;

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
    /// `solver.method` (enumeration value = 1-based index in `Method::ALL`).
    Method,
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
    /// An enumeration, accessed as `fmi2Integer`.
    Enumeration,
}

/// Declared type of `solver.method`.
pub const METHOD_TYPE: &str = "SolverMethod";

/// One FMU variable.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Structured name, 1-based indices.
    pub name: String,
    /// Value reference (the index in the table).
    pub value_reference: u32,
    /// Real or Boolean.
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
    /// Start value (Booleans as 0/1); `None` for calculated outputs.
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

/// Units used by the table, with their SI base-unit exponents `(kg, m, s)`.
pub const UNITS: [(&str, [i32; 3]); 12] = [
    ("m", [0, 1, 0]),
    ("m/s", [0, 1, -1]),
    ("m2/s", [0, 2, -1]),
    ("N", [1, 1, -2]),
    ("N/m", [1, 0, -2]),
    ("N.s/m", [1, 0, -1]),
    ("kg", [1, 0, 0]),
    ("s", [0, 0, 1]),
    ("J", [1, 2, -2]),
    ("m/s2", [0, 1, -2]),
    ("Hz", [0, 0, -1]),
    ("rad", [0, 0, 0]),
];

impl VariableTable {
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

fn parameter(
    name: String,
    unit: Option<&'static str>,
    description: String,
    start: f64,
    binding: Binding,
) -> Variable {
    Variable {
        name,
        value_reference: 0,
        base_type: match binding {
            Binding::Correction => BaseType::Boolean,
            Binding::Method => BaseType::Enumeration,
            _ => BaseType::Real,
        },
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        initial: Some(Initial::Exact),
        unit,
        description,
        start: Some(start),
        binding,
    }
}

fn parameters(model: &Model, vars: &mut Vec<Variable>) {
    vars.push(parameter(
        "solver.step_size".into(),
        Some("s"),
        "internal integration step (the last step of a communication interval is shortened to meet it)".into(),
        model.solver.step_size,
        Binding::StepSize,
    ));
    vars.push(parameter(
        "solver.correction".into(),
        None,
        "apply the exact bar-length and orthogonality correction after every internal step".into(),
        f64::from(u8::from(model.solver.correction)),
        Binding::Correction,
    ));
    let method = model.solver.method;
    vars.push(parameter(
        "solver.method".into(),
        None,
        "integration method: 1 = rk4, 2 = dopri5 (adaptive), 3 = rattle".into(),
        f64::from(method.fmi_value()),
        Binding::Method,
    ));
    vars.push(parameter(
        "solver.rtol".into(),
        None,
        "relative tolerance of the adaptive method (dopri5)".into(),
        model.solver.rtol,
        Binding::Rtol,
    ));
    vars.push(parameter(
        "solver.atol".into(),
        None,
        "absolute tolerance of the adaptive method (dopri5), on positions (m) and velocities (m/s)"
            .into(),
        model.solver.atol,
        Binding::Atol,
    ));
    for (j, cable) in model.cables.iter().enumerate() {
        let c = j + 1;
        let (stiffness, rest_length, damping, kind) = match cable.law {
            CableLaw::Elastic {
                stiffness,
                rest_length,
                damping,
            } => (stiffness, Some(rest_length), damping, "elastic"),
            // A reeled cable's rest length is an input, not a parameter.
            CableLaw::RestLengthControlled {
                stiffness, damping, ..
            } => (stiffness, None, damping, "reeled"),
            CableLaw::Controlled { .. } => continue,
        };
        vars.push(parameter(
            format!("cable[{c}].stiffness"),
            Some("N/m"),
            format!("stiffness of {kind} cable {c}"),
            stiffness,
            Binding::Stiffness(j),
        ));
        if let Some(l) = rest_length {
            vars.push(parameter(
                format!("cable[{c}].rest_length"),
                Some("m"),
                format!("rest length of elastic cable {c}"),
                l,
                Binding::RestLength(j),
            ));
        }
        if let Some(d) = damping {
            vars.push(parameter(
                format!("cable[{c}].damping"),
                Some("N.s/m"),
                format!("damping of cable {c} on its extension rate, while taut"),
                d,
                Binding::Damping(j),
            ));
        }
    }
    for (i, bar) in model.bars.iter().enumerate() {
        vars.push(parameter(
            format!("bar[{}].mass", i + 1),
            Some("kg"),
            format!("mass of bar {} (thin uniform rod)", i + 1),
            bar.mass,
            Binding::Mass(i),
        ));
    }
}

/// Parameters of the optional effects: only those the scene declares.
fn effect_parameters(model: &Model, vars: &mut Vec<Variable>) {
    let scene = &model.scene;
    if let Some(g) = scene.gravity {
        for (axis, name) in AXES.iter().enumerate() {
            vars.push(parameter(
                format!("gravity.{name}"),
                Some("m/s2"),
                format!("gravitational acceleration along {name}"),
                g[axis],
                Binding::Gravity(axis),
            ));
        }
    }
    for (k, pm) in scene.point_masses.iter().enumerate() {
        vars.push(parameter(
            format!("point_mass[{}].mass", k + 1),
            Some("kg"),
            format!("payload {} carried by node {}", k + 1, pm.node),
            pm.mass,
            Binding::PointMass(k),
        ));
    }
    if let Some(ground) = &scene.ground {
        let fields = [
            (
                GroundField::Height,
                "height",
                Some("m"),
                "offset of the ground plane along its normal",
                ground.height,
            ),
            (
                GroundField::Stiffness,
                "stiffness",
                Some("N/m"),
                "penalty stiffness of contact at bar ends",
                ground.stiffness,
            ),
            (
                GroundField::Damping,
                "damping",
                Some("N.s/m"),
                "penalty damping on the normal approach speed",
                ground.damping,
            ),
            (
                GroundField::Friction,
                "friction",
                None,
                "Coulomb friction coefficient",
                ground.friction,
            ),
            (
                GroundField::SlipVelocity,
                "slip_velocity",
                Some("m/s"),
                "tangential speed below which friction is viscous (regularised Coulomb)",
                ground.slip_velocity,
            ),
        ];
        for (field, name, unit, description, value) in fields {
            vars.push(parameter(
                format!("ground.{name}"),
                unit,
                description.into(),
                value,
                Binding::Ground(field),
            ));
        }
    }
    for (k, load) in scene.loads.iter().enumerate() {
        load_parameters(k, load, vars);
    }
}

fn load_parameters(k: usize, load: &LoadSpec, vars: &mut Vec<Variable>) {
    let l = k + 1;
    let node = load.node();
    let (force, what) = match *load {
        LoadSpec::Constant { force, .. } => (force, "constant force"),
        LoadSpec::Sinusoidal { amplitude, .. } => (amplitude, "amplitude of the sinusoidal force"),
        LoadSpec::Step { force, .. } => (force, "force of the step"),
    };
    for (axis, name) in AXES.iter().enumerate() {
        vars.push(parameter(
            format!("load[{l}].f{name}"),
            Some("N"),
            format!("scripted load {l} on node {node}: {what} along {name}"),
            force[axis],
            Binding::Load(k, LoadField::Force(axis)),
        ));
    }
    match *load {
        LoadSpec::Sinusoidal {
            frequency, phase, ..
        } => {
            vars.push(parameter(
                format!("load[{l}].frequency"),
                Some("Hz"),
                format!("scripted load {l}: frequency of the sinusoid"),
                frequency,
                Binding::Load(k, LoadField::Frequency),
            ));
            vars.push(parameter(
                format!("load[{l}].phase"),
                Some("rad"),
                format!("scripted load {l}: phase of the sinusoid"),
                phase,
                Binding::Load(k, LoadField::Phase),
            ));
        }
        LoadSpec::Step { time, .. } => vars.push(parameter(
            format!("load[{l}].time"),
            Some("s"),
            format!("scripted load {l}: switch-on time of the step"),
            time,
            Binding::Load(k, LoadField::Time),
        )),
        LoadSpec::Constant { .. } => {}
    }
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
