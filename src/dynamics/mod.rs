//! The equations of motion in reduced coordinates, evaluated in named stages:
//! kinematics → forces → bar force densities λ → reactions Ω → accelerations η̈₂.
//!
//! Per bar, `(m/12) b̈ = (f_b − f_a)/2 + λ b` with `b·b̈ = −|ḃ|²` gives λ in closed form;
//! M is block diagonal per bar, so end accelerations follow from the inverse block
//! `[4 −2; −2 4]/m`. Ω enters λ through the end forces and comes from `N̈ P = 0`.

mod block_cholesky;
pub mod energy;
pub mod reactions;

use nalgebra::Vector3;

use crate::model::{CableLaw, Model};
use reactions::Reactions;

/// Values an importer sets between steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Inputs {
    /// Commanded force density per controlled cable, N/m (clamped at ≥ 0 when used).
    pub force_density: Vec<f64>,
    /// External force per force-input node, N.
    pub node_force: Vec<Vector3<f64>>,
    /// Commanded rest length per rest-length controlled cable, m (clamped at ≥ 0 when used).
    pub rest_length: Vec<f64>,
}

impl Inputs {
    /// The scene's start values.
    pub fn start(model: &Model) -> Self {
        Self {
            force_density: model.controlled_start.clone(),
            node_force: vec![Vector3::zeros(); model.force_inputs.len()],
            rest_length: model.reeled_start.clone(),
        }
    }

    /// Copies `other` in place (same model, so no allocation).
    pub fn copy_from(&mut self, other: &Inputs) {
        self.force_density.copy_from_slice(&other.force_density);
        self.node_force.copy_from_slice(&other.node_force);
        self.rest_length.copy_from_slice(&other.rest_length);
    }
}

/// Scratch space for one evaluation; allocated once per simulation.
#[derive(Debug, Clone)]
pub struct Workspace {
    /// Bar-end positions (columns of N), m.
    pub end_pos: Vec<Vector3<f64>>,
    /// Bar-end velocities, m/s.
    pub end_vel: Vec<Vector3<f64>>,
    /// Bar-end forces including reactions, N.
    pub end_force: Vec<Vector3<f64>>,
    /// Bar-end accelerations, m/s².
    pub end_acc: Vec<Vector3<f64>>,
    /// Physical node positions, m.
    pub node_pos: Vec<Vector3<f64>>,
    /// Physical node velocities, m/s.
    pub node_vel: Vec<Vector3<f64>>,
    /// Cable force densities γ, N/m.
    pub gamma: Vec<f64>,
    /// Bar force densities λ (compression positive), N/m.
    pub lambda: Vec<f64>,
    units: Vec<Vector3<f64>>,
    masses: Vec<f64>,
    reactions: Reactions,
    /// Evaluations where the sparse reaction factor failed and the dense solve was used.
    pub dense_fallbacks: u64,
}

impl Workspace {
    /// Allocates everything an evaluation needs.
    pub fn new(model: &Model) -> Self {
        let ends = model.coords.n_ends();
        let nodes = model.n_nodes();
        Self {
            end_pos: vec![Vector3::zeros(); ends],
            end_vel: vec![Vector3::zeros(); ends],
            end_force: vec![Vector3::zeros(); ends],
            end_acc: vec![Vector3::zeros(); ends],
            node_pos: model.positions.clone(),
            node_vel: vec![Vector3::zeros(); nodes],
            gamma: vec![0.0; model.cables.len()],
            lambda: vec![0.0; model.bars.len()],
            units: vec![Vector3::zeros(); model.bars.len()],
            masses: model.masses(),
            reactions: model.reactions.clone(),
            dense_fallbacks: 0,
        }
    }
}

/// Computes `η̈₂` (flat, length 3r) at time `t` for reduced positions `q` and velocities `v`.
pub fn accelerations(
    model: &Model,
    inputs: &Inputs,
    t: f64,
    q: &[f64],
    v: &[f64],
    ws: &mut Workspace,
    acc: &mut [f64],
) {
    kinematics(model, q, v, ws);
    applied_forces(model, inputs, t, ws);
    bar_response(model, ws);
    if ws.reactions.size() > 0 {
        add_reactions(model, ws);
        bar_response(model, ws);
    }
    acc.iter_mut().for_each(|a| *a = 0.0);
    for (e, a) in ws.end_acc.iter().enumerate() {
        model.coords.scatter(e, a, acc);
    }
}

/// Stage 1: end and node positions and velocities from the reduced state.
pub fn kinematics(model: &Model, q: &[f64], v: &[f64], ws: &mut Workspace) {
    let coords = &model.coords;
    for e in 0..coords.n_ends() {
        ws.end_pos[e] = coords.end_vector(e, q, true);
        ws.end_vel[e] = coords.end_vector(e, v, false);
    }
    for (n, end) in coords.node_end.iter().enumerate() {
        if let Some(e) = *end {
            ws.node_pos[n] = ws.end_pos[e];
            ws.node_vel[n] = ws.end_vel[e];
        }
    }
}

/// Force density of one cable for extension vector `s` and its rate `s_dot`.
#[inline]
pub fn cable_force_density(
    law: &CableLaw,
    inputs: &Inputs,
    s: &Vector3<f64>,
    s_dot: &Vector3<f64>,
) -> f64 {
    match *law {
        CableLaw::Elastic {
            stiffness,
            rest_length,
            damping,
        } => elastic_force_density(stiffness, rest_length, damping, s, s_dot),
        CableLaw::RestLengthControlled {
            stiffness,
            damping,
            input,
        } => {
            let rest_length = inputs.rest_length[input].max(0.0);
            elastic_force_density(stiffness, rest_length, damping, s, s_dot)
        }
        CableLaw::Controlled { input } => inputs.force_density[input].max(0.0),
    }
}

/// `κ (1 − s₀/|s|) + c (s·ṡ)/|s|²` while taut, else 0; clamped at ≥ 0.
#[inline]
fn elastic_force_density(
    stiffness: f64,
    rest_length: f64,
    damping: Option<f64>,
    s: &Vector3<f64>,
    s_dot: &Vector3<f64>,
) -> f64 {
    let len = s.norm();
    if len <= rest_length {
        return 0.0;
    }
    let elastic = stiffness * (1.0 - rest_length / len);
    let viscous = damping.map_or(0.0, |c| c * s.dot(s_dot) / (len * len));
    (elastic + viscous).max(0.0)
}

/// Stage 2: cable, input, scripted-load and gravity forces on the bar ends at time `t`
/// (forces on a bar-less pinned node are taken by its pin).
pub fn applied_forces(model: &Model, inputs: &Inputs, t: f64, ws: &mut Workspace) {
    ws.end_force.iter_mut().for_each(|f| *f = Vector3::zeros());
    let node_end = &model.coords.node_end;
    for (j, cable) in model.cables.iter().enumerate() {
        let [a, b] = cable.nodes;
        let s = ws.node_pos[b] - ws.node_pos[a];
        let s_dot = ws.node_vel[b] - ws.node_vel[a];
        let gamma = cable_force_density(&cable.law, inputs, &s, &s_dot);
        ws.gamma[j] = gamma;
        if let Some(e) = node_end[a] {
            ws.end_force[e] += s * gamma;
        }
        if let Some(e) = node_end[b] {
            ws.end_force[e] -= s * gamma;
        }
    }
    for (k, &n) in model.force_inputs.iter().enumerate() {
        if let Some(e) = node_end[n] {
            ws.end_force[e] += inputs.node_force[k];
        }
    }
    for (n, load) in &model.loads {
        if let Some(e) = node_end[*n] {
            ws.end_force[e] += Vector3::from(load.force_at(t));
        }
    }
    if let Some(g) = model.gravity {
        for (i, bar) in model.bars.iter().enumerate() {
            let w = g * (bar.mass / 2.0);
            ws.end_force[2 * i] += w;
            ws.end_force[2 * i + 1] += w;
        }
    }
}

/// Stage 3: λ in closed form and the end accelerations of every moving bar.
pub fn bar_response(model: &Model, ws: &mut Workspace) {
    for (i, bar) in model.bars.iter().enumerate() {
        let (a, b) = (2 * i, 2 * i + 1);
        if model.coords.static_bar[i] {
            ws.lambda[i] = 0.0;
            ws.end_acc[a] = Vector3::zeros();
            ws.end_acc[b] = Vector3::zeros();
            continue;
        }
        let m = bar.mass;
        let bv = ws.end_pos[b] - ws.end_pos[a];
        let bdot = ws.end_vel[b] - ws.end_vel[a];
        let (fa, fb) = (ws.end_force[a], ws.end_force[b]);
        let l2 = bv.norm_squared();
        let lambda = (-(m / 12.0) * bdot.norm_squared() - bv.dot(&(fb - fa)) / 2.0) / l2;
        ws.lambda[i] = lambda;
        ws.units[i] = bv / l2.sqrt();
        let (ga, gb) = (fa - bv * lambda, fb + bv * lambda);
        ws.end_acc[a] = (ga * 4.0 - gb * 2.0) / m;
        ws.end_acc[b] = (gb * 4.0 - ga * 2.0) / m;
    }
}

/// Stage 4: reactions Ω from `N̈ P = 0`, added to the end forces.
fn add_reactions(model: &Model, ws: &mut Workspace) {
    let constraints = &model.coords.constraints;
    for (c, col) in constraints.iter().enumerate() {
        let mut r = Vector3::zeros();
        for &(e, coef) in &col.terms {
            r += ws.end_acc[e] * coef;
        }
        for k in 0..3 {
            ws.reactions.rhs[3 * c + k] = -r[k];
        }
    }
    ws.reactions.assemble(&ws.units, &ws.masses);
    if !ws.reactions.solve() {
        ws.dense_fallbacks += 1;
    }
    for (c, col) in constraints.iter().enumerate() {
        let omega = Vector3::new(
            ws.reactions.rhs[3 * c],
            ws.reactions.rhs[3 * c + 1],
            ws.reactions.rhs[3 * c + 2],
        );
        for &(e, coef) in &col.terms {
            ws.end_force[e] += omega * coef;
        }
    }
}
