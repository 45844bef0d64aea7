//! Stage 2 of an evaluation: the forces of the effects a scene declares, as listed once in
//! the model's [`Pipeline`]. An effect the scene does not declare is not in it, so the step
//! never tests for it.

use nalgebra::Vector3;

use super::{Inputs, Workspace};
pub use crate::model::effects::{CableLink, ConstraintEffect, ForceEffect, Pipeline, Target};
use crate::model::Model;

/// Stage 2: every declared force on the bar ends at time `t`.
#[inline(always)]
pub fn applied_forces(model: &Model, inputs: &Inputs, t: f64, ws: &mut Workspace) {
    ws.end_force.iter_mut().for_each(|f| *f = Vector3::zeros());
    for effect in &model.pipeline.forces {
        match effect {
            ForceEffect::ElasticCables(cables) => {
                for (link, stiffness, rest) in cables {
                    apply_cable(link, ws, |s| taut_density(*stiffness, *rest, s.norm()));
                }
            }
            ForceEffect::DampedCables(cables) => {
                for (link, stiffness, rest, c) in cables {
                    apply_damped_cable(link, ws, |s, s_dot| {
                        damped_density(*stiffness, *rest, *c, s, s_dot)
                    });
                }
            }
            ForceEffect::ForceDensityCables(cables) => {
                for (link, input) in cables {
                    let gamma = inputs.force_density[*input].max(0.0);
                    apply_cable(link, ws, |_| gamma);
                }
            }
            ForceEffect::ReeledCables(cables) => {
                for (link, stiffness, c, input) in cables {
                    let rest = inputs.rest_length[*input].max(0.0);
                    apply_damped_cable(link, ws, |s, s_dot| {
                        damped_density(*stiffness, rest, *c, s, s_dot)
                    });
                }
            }
            ForceEffect::NodeForces(targets) => {
                for &(k, end) in targets {
                    add(ws, end, inputs.node_force[k]);
                }
            }
            ForceEffect::ScriptedLoads(loads) => {
                for (end, law) in loads {
                    add(ws, *end, Vector3::from(law.force_at(t)));
                }
            }
            ForceEffect::Gravity(weights) => {
                for &(e, w) in weights {
                    ws.end_force[e] += w;
                }
            }
            ForceEffect::GroundContact(ground) => {
                for (k, &(n, e)) in ground.nodes.iter().enumerate() {
                    let f = ground.force(&ws.node_pos[n], &ws.node_vel[n]);
                    ws.contact_force[k] = f;
                    ws.end_force[e] += f;
                }
            }
        }
    }
}

#[inline(always)]
fn add(ws: &mut Workspace, end: Target, f: Vector3<f64>) {
    if let Some(e) = end {
        ws.end_force[e] += f;
    }
}

/// Applies `γ s` to a cable's ends, with `γ` from its law of `s`, and records `γ`.
#[inline(always)]
fn apply_cable(link: &CableLink, ws: &mut Workspace, law: impl Fn(&Vector3<f64>) -> f64) {
    let [a, b] = link.nodes;
    let s = ws.node_pos[b] - ws.node_pos[a];
    pull(link, ws, s, law(&s));
}

/// [`apply_cable`] for a law of `s` and `ṡ` (only these read the node velocities).
#[inline(always)]
fn apply_damped_cable(
    link: &CableLink,
    ws: &mut Workspace,
    law: impl Fn(&Vector3<f64>, &Vector3<f64>) -> f64,
) {
    let [a, b] = link.nodes;
    let s = ws.node_pos[b] - ws.node_pos[a];
    let s_dot = ws.node_vel[b] - ws.node_vel[a];
    pull(link, ws, s, law(&s, &s_dot));
}

#[inline(always)]
fn pull(link: &CableLink, ws: &mut Workspace, s: Vector3<f64>, gamma: f64) {
    ws.gamma[link.cable] = gamma;
    add(ws, link.ends[0], s * gamma);
    add(ws, link.ends[1], -s * gamma);
}

/// `κ (1 − s₀/|s|)` while taut, else 0.
#[inline(always)]
pub fn taut_density(stiffness: f64, rest_length: f64, len: f64) -> f64 {
    if len <= rest_length {
        0.0
    } else {
        stiffness * (1.0 - rest_length / len)
    }
}

/// `κ (1 − s₀/|s|) + c (s·ṡ)/|s|²` while taut, else 0; clamped at ≥ 0 (a cable only pulls).
#[inline(always)]
pub fn damped_density(
    stiffness: f64,
    rest_length: f64,
    damping: f64,
    s: &Vector3<f64>,
    s_dot: &Vector3<f64>,
) -> f64 {
    let l2 = s.norm_squared();
    let len = l2.sqrt();
    if len <= rest_length {
        return 0.0;
    }
    (stiffness * (1.0 - rest_length / len) + damping * s.dot(s_dot) / l2).max(0.0)
}
