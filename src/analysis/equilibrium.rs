//! Static equilibrium in the reduced coordinates: Newton's method in the minimal
//! coordinates ξ of the bar-constraint tangent space, with the tangent stiffness, a
//! backtracking line search, and the exact bar lengths restored after every update by
//! the paper's correction. The equilibrium must be stable: `Zᵀ K Z` positive definite
//! apart from the rigid-body motions of an unpinned structure.

use nalgebra::{DVector, Vector3};

use super::modes::{ModeKind, Spectrum};
use super::reduced::symmetric_eigen;
use super::{Reduced, Tangent};
use crate::dynamics::{self, Inputs, Workspace};
use crate::error::SceneError;
use crate::model::{CableLaw, Model, StartReport};

/// Newton iterations before the solve gives up.
pub const MAX_ITERATIONS: usize = 100;
/// Converged when `‖M̄ η̈₂‖` is below this fraction of the applied forces' size.
pub const TOLERANCE: f64 = 1e-11;
/// Stiffness eigenvalues below this fraction of the largest are not inverted by a Newton
/// step (rigid motions, mechanisms, round-off).
const SINGULAR: f64 = 1e-9;
/// A stalled line search still counts as converged below this fraction (round-off).
const ROUND_OFF: f64 = 1e-9;

/// A solved equilibrium.
#[derive(Debug, Clone)]
pub struct Settled {
    /// Reduced positions η₂ (flat).
    pub q: Vec<f64>,
    /// Node positions, m.
    pub positions: Vec<Vector3<f64>>,
    /// What the solve did.
    pub report: StartReport,
}

/// Moves `model.positions` to the static equilibrium under everything the scene declares,
/// at the inputs' start values and the loads at t = 0.
pub fn settle(model: &mut Model) -> Result<(), SceneError> {
    let settled = solve(model, &Inputs::start(model))?;
    model.positions = settled.positions;
    model.start = Some(settled.report);
    Ok(())
}

/// The reduced positions of the model's node positions ([`Model::reduced_positions`]).
pub fn reduced_positions(model: &Model) -> Vec<f64> {
    model.reduced_positions()
}

/// Newton's method from the model's positions.
pub fn solve(model: &Model, inputs: &Inputs) -> Result<Settled, SceneError> {
    let mut q = reduced_positions(model);
    project(model, &mut q);
    let mut ws = Workspace::new(model);
    let mut residual = residual(model, inputs, &q, &mut ws);
    let scale = force_scale(&ws);
    let tolerance = TOLERANCE * scale;
    let round_off = (ROUND_OFF * scale).max(round_off_floor(model, &ws));
    let mut iterations = 0;
    'newton: while residual > tolerance {
        if iterations == MAX_ITERATIONS {
            return Err(failure(format!(
                "Newton's method did not converge in {MAX_ITERATIONS} iterations (force \
                 residual {residual:.3e} N of {scale:.3e} N): the structure may have no \
                 equilibrium near the given geometry; start nearer to one, or use start = \
                 \"as_given\""
            )));
        }
        iterations += 1;
        let tangent = Tangent::new(model, inputs, 0.0, &q, &vec![0.0; q.len()]);
        let reduced = Reduced::new(&tangent);
        let r = reduced.basis.tr_mul(&tangent.force);
        let step = newton_step(&reduced, &r, scale)
            .map_err(|unbalanced| cannot_carry(model, &ws, unbalanced))?;
        let direction = &reduced.basis * step;
        let mut alpha = 1.0;
        loop {
            let mut trial = q.clone();
            trial
                .iter_mut()
                .zip(direction.iter())
                .for_each(|(x, d)| *x += alpha * d);
            project(model, &mut trial);
            let trial_residual = self::residual(model, inputs, &trial, &mut ws);
            if trial_residual < (1.0 - 1e-4 * alpha) * residual {
                q = trial;
                residual = trial_residual;
                break;
            }
            alpha *= 0.5;
            if alpha < 1e-10 && residual <= round_off {
                // No step improves on round-off: converged as far as doubles allow.
                break 'newton;
            }
            if alpha < 1e-10 {
                return Err(failure(format!(
                    "Newton's method stalled after {iterations} iterations (force residual \
                     {residual:.3e} N): no step along the tangent reduces the unbalanced \
                     force; the structure may have no equilibrium near the given geometry \
                     (a load beyond what it carries, cables going slack); lower the loads, \
                     raise the prestress, or use start = \"as_given\""
                )));
            }
        }
    }
    check_stable(model, inputs, &q)?;
    dynamics::kinematics(model, &q, &vec![0.0; q.len()], &mut ws);
    let mut positions = model.positions.clone();
    for (n, end) in model.coords.node_end.iter().enumerate() {
        if end.is_some() {
            positions[n] = ws.node_pos[n];
        }
    }
    Ok(Settled {
        q,
        positions,
        report: StartReport {
            iterations,
            residual,
        },
    })
}

/// `Δξ = K_ξ⁻¹ r` through the eigenvectors of `K_ξ`, with `|eigenvalue|` so that a saddle
/// is left, not approached. A force along a zero-stiffness direction cannot be balanced:
/// its size comes back as the error.
fn newton_step(reduced: &Reduced, r: &DVector<f64>, scale: f64) -> Result<DVector<f64>, f64> {
    let eigen = symmetric_eigen(reduced.stiffness.clone());
    let largest = eigen.eigenvalues.amax().max(f64::MIN_POSITIVE);
    let mut step = DVector::zeros(r.len());
    for k in 0..r.len() {
        let v = eigen.eigenvectors.column(k);
        let along = v.dot(r);
        let value = eigen.eigenvalues[k];
        if value.abs() <= SINGULAR * largest {
            if along.abs() > 1e-6 * scale {
                return Err(along.abs());
            }
            continue;
        }
        step += v * (along / value.abs());
    }
    Ok(step)
}

/// Why an unbalanced force along an unresisted direction cannot be carried.
fn cannot_carry(model: &Model, ws: &Workspace, unbalanced: f64) -> SceneError {
    let lowest = model.ground.as_ref().and_then(|ground| {
        ground
            .nodes
            .iter()
            .zip(&ground.radii)
            .map(|(&(n, _), &r)| -ground.penetration(&ws.node_pos[n], r))
            .min_by(f64::total_cmp)
    });
    match lowest {
        Some(gap) if gap > 1e-9 => failure(format!(
            "a load it cannot carry: {unbalanced:.3e} N of unbalanced force, and no node \
             touches the ground (the lowest is {gap:.3e} m above it), so nothing holds the \
             structure up; place it on the ground, its lowest node on the surface"
        )),
        _ => failure(format!(
            "a load it cannot carry: {unbalanced:.3e} N of unbalanced force acts along a \
             direction the structure does not resist (a free fall, a rigid-body motion or \
             a mechanism); pin it, give it a ground to stand on, or balance the loads"
        )),
    }
}

fn check_stable(model: &Model, inputs: &Inputs, q: &[f64]) -> Result<(), SceneError> {
    let spectrum = Spectrum::new(model, inputs, 0.0, q);
    if let Some(mode) = spectrum.modes.iter().find(|m| m.kind == ModeKind::Unstable) {
        return Err(failure(format!(
            "the equilibrium found is unstable (stiffness eigenvalue ω² = {:.3e} 1/s², \
             largest motion at node {}): the loads or the prestress buckle it; lower the \
             loads or raise the prestress",
            mode.omega_squared,
            largest_node(&mode.shape)
        )));
    }
    if let Some(mode) = spectrum
        .modes
        .iter()
        .find(|m| m.kind == ModeKind::Mechanism)
    {
        return Err(failure(format!(
            "the structure is a mechanism: it can move without stretching any cable (zero \
             stiffness, largest motion at node {}), so its equilibrium is not unique; add \
             cables, pins or prestress",
            largest_node(&mode.shape)
        )));
    }
    Ok(())
}

fn largest_node(shape: &[Vector3<f64>]) -> usize {
    (0..shape.len())
        .max_by(|&a, &b| shape[a].norm().total_cmp(&shape[b].norm()))
        .map_or(0, |n| n + 1)
}

fn failure(reason: String) -> SceneError {
    SceneError::invalid("start", format!("no stable static equilibrium: {reason}"))
}

/// Restores the exact bar lengths (the correction, repeated for loops of bars).
fn project(model: &Model, q: &mut [f64]) {
    model.correction.correct_positions(&model.coords, q);
}

/// The unbalanced force at rest at `q`, the size of the applied forces, and the
/// round-off level of the cable forces, N.
pub fn unbalanced(model: &Model, inputs: &Inputs, q: &[f64]) -> (f64, f64, f64) {
    let mut ws = Workspace::new(model);
    let r = residual(model, inputs, q, &mut ws);
    (r, force_scale(&ws), round_off_floor(model, &ws))
}

/// What round-off leaves of stiff cables' forces, N: `κ (|s| − s₀)` loses about `ε κ |s|`
/// per cable, so a steel-stiff structure at its exact equilibrium still shows this much.
fn round_off_floor(model: &Model, ws: &Workspace) -> f64 {
    let stiff: f64 = model
        .cables
        .iter()
        .map(|c| match c.law {
            CableLaw::Elastic { stiffness, .. }
            | CableLaw::RestLengthControlled { stiffness, .. } => {
                stiffness * (ws.node_pos[c.nodes[1]] - ws.node_pos[c.nodes[0]]).norm()
            }
            CableLaw::Controlled { .. } => 0.0,
        })
        .sum();
    64.0 * f64::EPSILON * stiff
}

/// `‖M̄ η̈₂‖` at rest, N: zero exactly at an equilibrium.
fn residual(model: &Model, inputs: &Inputs, q: &[f64], ws: &mut Workspace) -> f64 {
    let zeros = vec![0.0; q.len()];
    let mut acc = vec![0.0; q.len()];
    dynamics::accelerations(model, inputs, 0.0, q, &zeros, ws, &mut acc);
    // M̄ η̈₂ per end is M_E ẍ_E; its norm in η₂ is the norm of J_eᵀ M_E ẍ_E.
    let mut force = vec![0.0; q.len()];
    for (i, inertia) in model.inertia.iter().enumerate() {
        let (a, b) = (2 * i, 2 * i + 1);
        let m = inertia.m;
        let fa = ws.end_acc[a] * m[0][0] + ws.end_acc[b] * m[0][1];
        let fb = ws.end_acc[a] * m[1][0] + ws.end_acc[b] * m[1][1];
        model.coords.scatter(a, &fa, &mut force);
        model.coords.scatter(b, &fb, &mut force);
    }
    force.iter().map(|f| f * f).sum::<f64>().sqrt()
}

/// The size of the applied forces (cable pulls, weights, loads), N, at least 1 N: a
/// structure without forces is judged against 1 N, not against its round-off.
fn force_scale(ws: &Workspace) -> f64 {
    ws.end_force.iter().map(|f| f.norm()).sum::<f64>().max(1.0)
}
