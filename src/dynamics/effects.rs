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
    let mut sink = Slices {
        end_force: &mut ws.end_force,
        gamma: &mut ws.gamma,
        contact_force: &mut ws.contact_force,
    };
    let nodes = (ws.node_pos.as_slice(), ws.node_vel.as_slice());
    apply(&model.pipeline.forces, inputs, t, nodes, &mut sink);
}

/// Where the forces go: the end forces, the cables' force densities and the contact
/// forces (all of them, or one thread's part).
pub(super) trait ForceSink {
    /// Adds `f` to end `end`'s force.
    fn add(&mut self, end: usize, f: Vector3<f64>);
    /// Records cable `cable`'s force density.
    fn gamma(&mut self, cable: usize, gamma: f64);
    /// Records the force of contact point `k`.
    fn contact(&mut self, k: usize, f: Vector3<f64>);
}

/// The whole of each output.
pub(super) struct Slices<'a> {
    pub end_force: &'a mut [Vector3<f64>],
    pub gamma: &'a mut [f64],
    pub contact_force: &'a mut [Vector3<f64>],
}

impl ForceSink for Slices<'_> {
    #[inline(always)]
    fn add(&mut self, end: usize, f: Vector3<f64>) {
        self.end_force[end] += f;
    }
    #[inline(always)]
    fn gamma(&mut self, cable: usize, gamma: f64) {
        self.gamma[cable] = gamma;
    }
    #[inline(always)]
    fn contact(&mut self, k: usize, f: Vector3<f64>) {
        self.contact_force[k] = f;
    }
}

/// Adds the forces of `effects` for the node positions and velocities `(x, ẋ)` to `sink`.
#[inline(always)]
pub(super) fn apply(
    effects: &[ForceEffect],
    inputs: &Inputs,
    t: f64,
    nodes: (&[Vector3<f64>], &[Vector3<f64>]),
    sink: &mut impl ForceSink,
) {
    for effect in effects {
        match effect {
            ForceEffect::ElasticCables(cables) => {
                for (link, stiffness, rest) in cables {
                    let s = extension(link, nodes.0);
                    pull(link, sink, s, taut_density(*stiffness, *rest, s.norm()));
                }
            }
            ForceEffect::DampedCables(cables) => {
                for (link, stiffness, rest, c) in cables {
                    let (s, s_dot) = (extension(link, nodes.0), extension(link, nodes.1));
                    let gamma = damped_density(*stiffness, *rest, *c, &s, &s_dot);
                    pull(link, sink, s, gamma);
                }
            }
            ForceEffect::ForceDensityCables(cables) => {
                for (link, input) in cables {
                    let gamma = inputs.force_density[*input].max(0.0);
                    pull(link, sink, extension(link, nodes.0), gamma);
                }
            }
            ForceEffect::ReeledCables(cables) => {
                for (link, stiffness, c, input) in cables {
                    let rest = inputs.rest_length[*input].max(0.0);
                    let (s, s_dot) = (extension(link, nodes.0), extension(link, nodes.1));
                    pull(
                        link,
                        sink,
                        s,
                        damped_density(*stiffness, rest, *c, &s, &s_dot),
                    );
                }
            }
            ForceEffect::NodeForces(targets) => {
                for &(k, end) in targets {
                    add(sink, end, inputs.node_force[k]);
                }
            }
            ForceEffect::ScriptedLoads(loads) => {
                for (end, law) in loads {
                    add(sink, *end, Vector3::from(law.force_at(t)));
                }
            }
            ForceEffect::Gravity(weights) => {
                for &(e, w) in weights {
                    sink.add(e, w);
                }
            }
            ForceEffect::GroundContact(ground) => {
                for (k, &(n, e)) in ground.nodes.iter().enumerate() {
                    let f = ground.force(&nodes.0[n], &nodes.1[n]);
                    sink.contact(k, f);
                    sink.add(e, f);
                }
            }
        }
    }
}

#[inline(always)]
fn add(sink: &mut impl ForceSink, end: Target, f: Vector3<f64>) {
    if let Some(e) = end {
        sink.add(e, f);
    }
}

/// A cable's `x_b − x_a` of node vectors `x` (positions for `s`, velocities for `ṡ`).
#[inline(always)]
fn extension(link: &CableLink, x: &[Vector3<f64>]) -> Vector3<f64> {
    let [a, b] = link.nodes;
    x[b] - x[a]
}

/// Applies `γ s` to a cable's ends and records `γ`.
#[inline(always)]
fn pull(link: &CableLink, sink: &mut impl ForceSink, s: Vector3<f64>, gamma: f64) {
    sink.gamma(link.cable, gamma);
    add(sink, link.ends[0], s * gamma);
    add(sink, link.ends[1], -s * gamma);
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
