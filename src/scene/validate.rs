//! Scene validation: every rejection names the key (1-based indices) and the reason.

use super::{CableControl, GroundSpec, LoadSpec, Scene};
use crate::error::SceneError;

/// Lengths below this fraction of the structure's size count as zero.
const ZERO_LENGTH_FRACTION: f64 = 1e-9;
/// Largest magnitude of any number in a scene: far beyond physical values in SI units,
/// and small enough that the products the dynamics form (stiffness × length², load ×
/// length / mass) cannot overflow to ∞ or NaN.
const MAX_MAGNITUDE: f64 = 1e30;

pub(super) fn validate(scene: &Scene) -> Result<(), SceneError> {
    let n = scene.nodes.len();
    if scene.name.trim().is_empty() {
        return Err(SceneError::invalid("name", "must not be empty"));
    }
    if n == 0 {
        return Err(SceneError::invalid("nodes", "the scene has no nodes"));
    }
    if scene.bars.is_empty() {
        return Err(SceneError::invalid("bars", "the scene has no bars"));
    }
    for (i, p) in scene.nodes.iter().enumerate() {
        finite_vec(&format!("nodes[{}]", i + 1), p)?;
        super::limits::check_position(&format!("nodes[{}]", i + 1), p)?;
    }
    let scale = size_of(scene);
    let node = |key: String, v: usize| -> Result<usize, SceneError> {
        if v == 0 || v > n {
            Err(SceneError::invalid(
                key,
                format!("node {v} is out of range: nodes are numbered 1 to {n}"),
            ))
        } else {
            Ok(v - 1)
        }
    };
    let length = |a: usize, b: usize| {
        let d: Vec<f64> = (0..3)
            .map(|k| scene.nodes[b][k] - scene.nodes[a][k])
            .collect();
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    };
    let mut used = vec![false; n];
    for (i, bar) in scene.bars.iter().enumerate() {
        let key = format!("bars[{}]", i + 1);
        let a = node(format!("{key}.nodes"), bar.nodes[0])?;
        let b = node(format!("{key}.nodes"), bar.nodes[1])?;
        if length(a, b) <= ZERO_LENGTH_FRACTION * scale {
            return Err(SceneError::invalid(
                format!("{key}.nodes"),
                format!(
                    "zero-length bar: nodes {} and {} coincide (closer than 1e-9 of the structure's size)",
                    a + 1,
                    b + 1
                ),
            ));
        }
        finite(&format!("{key}.mass"), bar.mass)?;
        finite(&format!("{key}.radius"), bar.radius)?;
        if bar.radius < 0.0 {
            return Err(SceneError::invalid(
                format!("{key}.radius"),
                format!("must be ≥ 0, got {}", bar.radius),
            ));
        }
        if bar.mass <= 0.0 {
            return Err(SceneError::invalid(
                format!("{key}.mass"),
                format!("mass must be positive, got {}", bar.mass),
            ));
        }
        used[a] = true;
        used[b] = true;
    }
    for (j, cable) in scene.cables.iter().enumerate() {
        let key = format!("cables[{}]", j + 1);
        let a = node(format!("{key}.nodes"), cable.nodes[0])?;
        let b = node(format!("{key}.nodes"), cable.nodes[1])?;
        if length(a, b) <= ZERO_LENGTH_FRACTION * scale {
            return Err(SceneError::invalid(
                format!("{key}.nodes"),
                format!(
                    "zero-length cable: nodes {} and {} coincide (closer than 1e-9 of the structure's size)",
                    a + 1,
                    b + 1
                ),
            ));
        }
        validate_cable_law(scene, &key, j)?;
    }
    let mut fixed = vec![false; n];
    for (k, &p) in scene.fixed.iter().enumerate() {
        fixed[node(format!("fixed[{}]", k + 1), p)?] = true;
    }
    for (k, &p) in scene.force_inputs.iter().enumerate() {
        let i = node(format!("force_inputs[{}]", k + 1), p)?;
        if fixed[i] {
            return Err(SceneError::invalid(
                format!("force_inputs[{}]", k + 1),
                format!("node {p} is pinned, so a force on it would have no effect"),
            ));
        }
        if scene.force_inputs[..k].contains(&p) {
            return Err(SceneError::invalid(
                format!("force_inputs[{}]", k + 1),
                format!("node {p} is listed twice"),
            ));
        }
    }
    if let Some(i) = (0..n).find(|&i| !used[i] && !fixed[i]) {
        return Err(SceneError::invalid(
            format!("nodes[{}]", i + 1),
            format!(
                "node {} is used by no bar and not pinned: a massless free node has no dynamics",
                i + 1
            ),
        ));
    }
    if let Some(groups) = &scene.outputs {
        if groups.is_empty() {
            return Err(SceneError::invalid(
                "outputs",
                "selects no output group; omit the key to expose all of them",
            ));
        }
        if let Some(k) = (1..groups.len()).find(|&k| groups[..k].contains(&groups[k])) {
            return Err(SceneError::invalid(
                format!("outputs[{}]", k + 1),
                "group listed twice",
            ));
        }
    }
    for (k, load) in scene.loads.iter().enumerate() {
        let key = format!("loads[{}]", k + 1);
        let i = node(format!("{key}.node"), load.node())?;
        if fixed[i] {
            return Err(SceneError::invalid(
                format!("{key}.node"),
                format!(
                    "node {} is pinned, so a load on it would have no effect",
                    i + 1
                ),
            ));
        }
        match load {
            LoadSpec::Constant { force, .. } => finite_vec(&format!("{key}.force"), force)?,
            LoadSpec::Sinusoidal {
                amplitude,
                frequency,
                phase,
                ..
            } => {
                finite_vec(&format!("{key}.amplitude"), amplitude)?;
                finite(&format!("{key}.frequency"), *frequency)?;
                finite(&format!("{key}.phase"), *phase)?;
                if *frequency < 0.0 {
                    return Err(SceneError::invalid(
                        format!("{key}.frequency"),
                        format!("must be ≥ 0, got {frequency}"),
                    ));
                }
            }
            LoadSpec::Step { force, time, .. } => {
                finite_vec(&format!("{key}.force"), force)?;
                finite(&format!("{key}.time"), *time)?;
            }
        }
    }
    if let Some(g) = &scene.gravity {
        finite_vec("gravity", g)?;
    }
    for (k, pm) in scene.point_masses.iter().enumerate() {
        let key = format!("point_masses[{}]", k + 1);
        let i = node(format!("{key}.node"), pm.node)?;
        if fixed[i] || !used[i] {
            return Err(SceneError::invalid(
                format!("{key}.node"),
                format!(
                    "node {} is {}: a payload must ride on a free bar end",
                    i + 1,
                    if fixed[i] { "pinned" } else { "on no bar" }
                ),
            ));
        }
        finite(&format!("{key}.mass"), pm.mass)?;
        if pm.mass < 0.0 {
            return Err(SceneError::invalid(
                format!("{key}.mass"),
                format!("must be ≥ 0, got {}", pm.mass),
            ));
        }
    }
    if let Some(ground) = &scene.ground {
        validate_ground(ground)?;
    }
    for (i, t) in scene.terrain.iter().enumerate() {
        t.validate(&format!("terrain[{}]", i + 1))?;
    }
    if let Some(c) = &scene.collisions {
        c.validate()?;
        if scene.bars.iter().all(|b| b.radius == 0.0) {
            return Err(SceneError::invalid(
                "collisions",
                "every bar has radius 0, so no two bars can ever touch: give the bars a \
                 bars[].radius",
            ));
        }
    }
    super::limits::check(scene)?;
    if let Some(vs) = &scene.velocities {
        if vs.len() != n {
            return Err(SceneError::invalid(
                "velocities",
                format!("has {} entries but the scene has {n} nodes", vs.len()),
            ));
        }
        for (i, v) in vs.iter().enumerate() {
            finite_vec(&format!("velocities[{}]", i + 1), v)?;
            super::limits::check_velocity(&format!("velocities[{}]", i + 1), v)?;
        }
    }
    if let Some(p) = &scene.prestress {
        finite("prestress.min_tension", p.min_tension)?;
        if p.min_tension <= 0.0 {
            return Err(SceneError::invalid(
                "prestress.min_tension",
                format!("must be positive, got {}", p.min_tension),
            ));
        }
    }
    finite("solver.step_size", scene.solver.step_size)?;
    if scene.solver.step_size <= 0.0 {
        return Err(SceneError::invalid(
            "solver.step_size",
            format!("must be positive, got {}", scene.solver.step_size),
        ));
    }
    for (key, v) in [
        ("solver.rtol", scene.solver.rtol),
        ("solver.atol", scene.solver.atol),
    ] {
        finite(key, v)?;
        if v < 0.0 {
            return Err(SceneError::invalid(key, format!("must be ≥ 0, got {v}")));
        }
    }
    if scene.solver.max_steps == 0 {
        return Err(SceneError::invalid(
            "solver.max_steps",
            "must be at least 1 (it caps the internal steps of one call)",
        ));
    }
    if scene.solver.rtol == 0.0 && scene.solver.atol == 0.0 {
        return Err(SceneError::invalid(
            "solver.rtol",
            "solver.rtol and solver.atol cannot both be 0",
        ));
    }
    Ok(())
}

fn validate_ground(g: &GroundSpec) -> Result<(), SceneError> {
    finite("ground.height", g.height)?;
    finite_vec("ground.normal", &g.normal)?;
    if g.normal.iter().map(|x| x * x).sum::<f64>() == 0.0 {
        return Err(SceneError::invalid(
            "ground.normal",
            "must not be the zero vector",
        ));
    }
    for (key, v, positive) in [
        ("ground.stiffness", g.stiffness, true),
        ("ground.damping", g.damping, false),
        ("ground.friction", g.friction, false),
        ("ground.slip_velocity", g.slip_velocity, true),
    ] {
        finite(key, v)?;
        if v < 0.0 || (positive && v == 0.0) {
            let bound = if positive { "> 0" } else { "≥ 0" };
            return Err(SceneError::invalid(
                key,
                format!("must be {bound}, got {v}"),
            ));
        }
    }
    Ok(())
}

fn validate_cable_law(scene: &Scene, key: &str, j: usize) -> Result<(), SceneError> {
    let cable = &scene.cables[j];
    let prestressed = scene.prestress.is_some();
    let non_negative = |name: &str, v: Option<f64>| -> Result<(), SceneError> {
        if let Some(v) = v {
            let k = format!("{key}.{name}");
            finite(&k, v)?;
            if v < 0.0 {
                return Err(SceneError::invalid(k, format!("must be ≥ 0, got {v}")));
            }
        }
        Ok(())
    };
    non_negative("stiffness", cable.stiffness)?;
    non_negative("rest_length", cable.rest_length)?;
    non_negative("damping", cable.damping)?;
    non_negative("force_density", cable.force_density)?;
    let conflict = |name: &str, why: &str| Err(SceneError::invalid(format!("{key}.{name}"), why));
    match cable.control {
        Some(CableControl::ForceDensity) => {
            for (name, v) in [
                ("stiffness", cable.stiffness),
                ("rest_length", cable.rest_length),
                ("damping", cable.damping),
            ] {
                if v.is_some() {
                    return conflict(name, "not allowed on a force-density controlled cable");
                }
            }
            match (cable.force_density.is_some(), prestressed) {
                (true, true) => conflict(
                    "force_density",
                    "conflicts with `prestress`, which derives the start force density",
                ),
                (false, false) => conflict(
                    "force_density",
                    "required for a controlled cable (or give the scene a `prestress` table)",
                ),
                _ => Ok(()),
            }
        }
        None | Some(CableControl::RestLength) => {
            if cable.force_density.is_some() {
                return conflict(
                    "force_density",
                    "only allowed with control = \"force_density\"",
                );
            }
            if cable.stiffness.is_none() {
                return conflict("stiffness", "required for an elastic cable");
            }
            match (cable.rest_length.is_some(), prestressed) {
                (true, true) => conflict(
                    "rest_length",
                    "conflicts with `prestress`, which derives the rest length",
                ),
                (false, false) => conflict(
                    "rest_length",
                    "required for an elastic cable (or give the scene a `prestress` table)",
                ),
                _ => Ok(()),
            }
        }
    }
}

fn size_of(scene: &Scene) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &scene.nodes {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let d: f64 = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    if d > 0.0 {
        d
    } else {
        1.0
    }
}

pub(super) fn finite(key: &str, v: f64) -> Result<(), SceneError> {
    if !v.is_finite() {
        return Err(SceneError::invalid(
            key,
            format!("must be a finite number, got {v}"),
        ));
    }
    within_magnitude(key, v)
}

pub(super) fn finite_vec(key: &str, v: &[f64; 3]) -> Result<(), SceneError> {
    if !v.iter().all(|x| x.is_finite()) {
        return Err(SceneError::invalid(
            key,
            format!("must hold finite numbers, got {v:?}"),
        ));
    }
    v.iter().try_for_each(|&x| within_magnitude(key, x))
}

fn within_magnitude(key: &str, v: f64) -> Result<(), SceneError> {
    if v.abs() <= MAX_MAGNITUDE {
        return Ok(());
    }
    Err(SceneError::invalid(
        key,
        format!(
            "{v:e} is beyond ±{MAX_MAGNITUDE:e}, the largest magnitude a scene number may have \
             (the forces and energies computed from it would overflow); express the scene in \
             other units, or use a smaller value"
        ),
    ))
}
