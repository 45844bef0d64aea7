//! Parameters live in the scene: these accessors read and write the scene value behind a
//! parameter binding, so get, set and FMU-state restore share one mapping, and one check
//! of a parameter's value.

use super::variables::{BaseType, Binding, ContactField, GroundField, LoadField, Variable};
use crate::integrator::Method;
use crate::numbers::shortest;
use crate::scene::{CollisionSpec, GroundSpec, LoadSpec, Scene, TerrainSpec};

/// The scene value behind a parameter binding (0 for a non-parameter binding).
pub(super) fn read_parameter(scene: &Scene, binding: Binding) -> f64 {
    match binding {
        Binding::StepSize => scene.solver.step_size,
        Binding::Correction => f64::from(u8::from(scene.solver.correction)),
        Binding::LocateEvents => f64::from(u8::from(scene.solver.locate_events)),
        Binding::Method => f64::from(scene.solver.method.fmi_value()),
        // As fmi2GetInteger reports it: an FMI Integer is 32 bits.
        Binding::MaxSteps => scene.solver.max_steps.min(i32::MAX as u64) as f64,
        Binding::Rtol => scene.solver.rtol,
        Binding::Atol => scene.solver.atol,
        Binding::Stiffness(j) => scene.cables[j].stiffness.unwrap_or(0.0),
        Binding::RestLength(j) => scene.cables[j].rest_length.unwrap_or(0.0),
        Binding::Damping(j) => scene.cables[j].damping.unwrap_or(0.0),
        Binding::Mass(i) => scene.bars[i].mass,
        Binding::Gravity(axis) => scene.gravity.map_or(0.0, |g| g[axis]),
        Binding::PointMass(k) => scene.point_masses[k].mass,
        // Read through the same accessors as writes, on a copy.
        Binding::Ground(field) => scene
            .ground
            .clone()
            .map_or(0.0, |mut g| *ground_field(&mut g, field)),
        Binding::Load(k, field) => {
            load_field(&mut scene.loads[k].clone(), field).map_or(0.0, |v| *v)
        }
        Binding::Radius(i) => scene.bars[i].radius,
        Binding::Terrain(k, field) => *terrain_field(&mut scene.terrain[k].clone(), field),
        Binding::Collision(field) => scene
            .collisions
            .clone()
            .map_or(0.0, |mut c| *collision_field(&mut c, field)),
        Binding::Output(_)
        | Binding::ForceDensity(_)
        | Binding::NodeForce(..)
        | Binding::ReelInput(_) => 0.0,
    }
}

/// Why fmi2SetReal, fmi2SetInteger or fmi2SetBoolean refuse `value` for `parameter`
/// before the scene it changes is validated (as it is next), if they do: the one check
/// of a parameter's value, shared by those calls and restored FMU states.
pub(super) fn refused_value(parameter: &Variable, value: f64) -> Option<String> {
    let name = &parameter.name;
    let why = if !value.is_finite() {
        "is not a finite number".to_string()
    } else if parameter.base_type == BaseType::Boolean && value != 0.0 && value != 1.0 {
        "is not a Boolean (0 or 1)".to_string()
    } else if parameter.base_type == BaseType::Integer
        && (value.fract() != 0.0 || value < f64::from(i32::MIN) || value > f64::from(i32::MAX))
    {
        format!(
            "is not an Integer (a whole number from {} to {})",
            i32::MIN,
            i32::MAX
        )
    } else if parameter.binding == Binding::Method && Method::from_fmi_value(value).is_none() {
        let methods: Vec<String> = Method::ALL
            .iter()
            .map(|m| format!("{} = {}", m.fmi_value(), m.name()))
            .collect();
        format!("is not a method ({})", methods.join(", "))
    } else {
        return None;
    };
    Some(format!("{name} = {} {why}", shortest(value)))
}

pub(super) fn apply_parameter(scene: &mut Scene, binding: Binding, value: f64) {
    match binding {
        Binding::StepSize => scene.solver.step_size = value,
        Binding::Correction => scene.solver.correction = value != 0.0,
        Binding::LocateEvents => scene.solver.locate_events = value != 0.0,
        Binding::Method => {
            if let Some(m) = Method::from_fmi_value(value) {
                scene.solver.method = m;
            }
        }
        // A negative or fractional value cannot come from fmi2SetInteger; 0 fails validation.
        Binding::MaxSteps => scene.solver.max_steps = value.max(0.0) as u64,
        Binding::Rtol => scene.solver.rtol = value,
        Binding::Atol => scene.solver.atol = value,
        Binding::Stiffness(j) => scene.cables[j].stiffness = Some(value),
        Binding::RestLength(j) => scene.cables[j].rest_length = Some(value),
        Binding::Damping(j) => scene.cables[j].damping = Some(value),
        Binding::Mass(i) => scene.bars[i].mass = value,
        Binding::Gravity(axis) => {
            if let Some(g) = &mut scene.gravity {
                g[axis] = value;
            }
        }
        Binding::PointMass(k) => scene.point_masses[k].mass = value,
        Binding::Ground(field) => {
            if let Some(g) = &mut scene.ground {
                *ground_field(g, field) = value;
            }
        }
        Binding::Load(k, field) => {
            if let Some(v) = load_field(&mut scene.loads[k], field) {
                *v = value;
            }
        }
        Binding::Radius(i) => scene.bars[i].radius = value,
        Binding::Terrain(k, field) => *terrain_field(&mut scene.terrain[k], field) = value,
        Binding::Collision(field) => {
            if let Some(c) = &mut scene.collisions {
                *collision_field(c, field) = value;
            }
        }
        Binding::Output(_)
        | Binding::ForceDensity(_)
        | Binding::NodeForce(..)
        | Binding::ReelInput(_) => {}
    }
}

/// The scene value behind a load parameter (`None` for a field the load lacks).
fn load_field(load: &mut LoadSpec, field: LoadField) -> Option<&mut f64> {
    match (load, field) {
        (
            LoadSpec::Constant { force, .. }
            | LoadSpec::Step { force, .. }
            | LoadSpec::Sinusoidal {
                amplitude: force, ..
            },
            LoadField::Force(axis),
        ) => Some(&mut force[axis]),
        (LoadSpec::Sinusoidal { frequency, .. }, LoadField::Frequency) => Some(frequency),
        (LoadSpec::Sinusoidal { phase, .. }, LoadField::Phase) => Some(phase),
        (LoadSpec::Step { time, .. }, LoadField::Time) => Some(time),
        _ => None,
    }
}

/// The scene value behind a ground parameter.
fn ground_field(g: &mut GroundSpec, field: GroundField) -> &mut f64 {
    match field {
        GroundField::Height => &mut g.height,
        GroundField::Stiffness => &mut g.stiffness,
        GroundField::Damping => &mut g.damping,
        GroundField::Friction => &mut g.friction,
        GroundField::SlipVelocity => &mut g.slip_velocity,
    }
}

/// The scene value behind a terrain parameter.
fn terrain_field(t: &mut TerrainSpec, field: ContactField) -> &mut f64 {
    let law = [
        &mut t.stiffness,
        &mut t.damping,
        &mut t.friction,
        &mut t.slip_velocity,
    ];
    law_field(law, field)
}

/// The scene value behind a bar–bar contact parameter.
fn collision_field(c: &mut CollisionSpec, field: ContactField) -> &mut f64 {
    let law = [
        &mut c.stiffness,
        &mut c.damping,
        &mut c.friction,
        &mut c.slip_velocity,
    ];
    law_field(law, field)
}

/// One of a contact law's `[stiffness, damping, friction, slip_velocity]`.
fn law_field(law: [&mut f64; 4], field: ContactField) -> &mut f64 {
    let [stiffness, damping, friction, slip_velocity] = law;
    match field {
        ContactField::Stiffness => stiffness,
        ContactField::Damping => damping,
        ContactField::Friction => friction,
        ContactField::SlipVelocity => slip_velocity,
    }
}
