//! The parameter rows of the variable table: solver settings, cable and bar properties,
//! and the settings of the optional effects the scene declares.

use fmi2_model_description::{Causality, Initial, Variability};

use super::{is_tunable, BaseType, Binding, ContactField, GroundField, LoadField, Variable, AXES};
use crate::model::{CableLaw, Model};
use crate::scene::LoadSpec;

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
            Binding::Correction | Binding::LocateEvents => BaseType::Boolean,
            Binding::Method | Binding::MaxSteps => BaseType::Integer,
            _ => BaseType::Real,
        },
        causality: Causality::Parameter,
        variability: if is_tunable(binding) {
            Variability::Tunable
        } else {
            Variability::Fixed
        },
        initial: Some(Initial::Exact),
        unit,
        description,
        start: Some(start),
        binding,
    }
}

pub(super) fn parameters(model: &Model, vars: &mut Vec<Variable>) {
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
    vars.push(parameter(
        "solver.locate_events".into(),
        None,
        "split an internal step where a cable goes slack or taut or a node touches or leaves the ground, so the method keeps its order there".into(),
        f64::from(u8::from(model.solver.locate_events)),
        Binding::LocateEvents,
    ));
    let method = model.solver.method;
    vars.push(parameter(
        "solver.method".into(),
        None,
        "integration method: 1 = rk4, 2 = dopri5 (adaptive), 3 = rattle, 4 = sdirk3 (implicit, for stiff cables)".into(),
        f64::from(method.fmi_value()),
        Binding::Method,
    ));
    vars.push(parameter(
        "solver.max_steps".into(),
        None,
        "the most internal steps one fmi2DoStep may take".into(),
        // An FMI Integer is 32 bits; larger scene values read as its maximum.
        model.solver.max_steps.min(i32::MAX as u64) as f64,
        Binding::MaxSteps,
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
    // A radius matters once something touches the bars' capsules.
    let touched = model.terrain.is_some()
        || model.collisions.is_some()
        || model.bars.iter().any(|b| b.radius > 0.0);
    for (i, bar) in model.bars.iter().enumerate().filter(|_| touched) {
        vars.push(parameter(
            format!("bar[{}].radius", i + 1),
            Some("m"),
            format!(
                "radius of bar {}'s capsule, where it touches the ground, terrain and other bars",
                i + 1
            ),
            bar.radius,
            Binding::Radius(i),
        ));
    }
}

/// Parameters of the optional effects: only those the scene declares.
pub(super) fn effect_parameters(model: &Model, vars: &mut Vec<Variable>) {
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
    for (k, t) in scene.terrain.iter().enumerate() {
        let values = [t.stiffness, t.damping, t.friction, t.slip_velocity];
        let what = format!("terrain[{}] ({})", k + 1, t.kind.name());
        let key = format!("terrain[{}]", k + 1);
        contact_parameters(&key, &what, values, |f| Binding::Terrain(k, f), vars);
    }
    if let Some(c) = &scene.collisions {
        let values = [c.stiffness, c.damping, c.friction, c.slip_velocity];
        let what = "contact between bars";
        contact_parameters("collisions", what, values, Binding::Collision, vars);
    }
}

/// The four settings of a contact law under `key`: `[stiffness, damping, friction,
/// slip_velocity]`.
fn contact_parameters(
    key: &str,
    what: &str,
    values: [f64; 4],
    binding: impl Fn(ContactField) -> Binding,
    vars: &mut Vec<Variable>,
) {
    let fields = [
        (
            ContactField::Stiffness,
            "stiffness",
            Some("N/m"),
            "penalty stiffness",
        ),
        (
            ContactField::Damping,
            "damping",
            Some("N.s/m"),
            "penalty damping on the normal approach speed",
        ),
        (
            ContactField::Friction,
            "friction",
            None,
            "Coulomb friction coefficient",
        ),
        (
            ContactField::SlipVelocity,
            "slip_velocity",
            Some("m/s"),
            "tangential speed below which friction is viscous (regularised Coulomb)",
        ),
    ];
    for ((field, name, unit, description), value) in fields.into_iter().zip(values) {
        vars.push(parameter(
            format!("{key}.{name}"),
            unit,
            format!("{what}: {description}"),
            value,
            binding(field),
        ));
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
