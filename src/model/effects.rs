//! The force contributions of a scene, one per effect it declares, built once when the
//! model is built. An evaluation runs exactly this list: an effect the scene does not
//! declare is not in it, so the step never tests for it.

use nalgebra::Vector3;

use super::contact::Ground;
use super::terrain::{Collisions, Terrain};
use super::{CableLaw, Model};
use crate::scene::LoadSpec;

/// A bar end a force acts on (`None`: a bar-less pinned node, whose pin takes it).
pub type Target = Option<usize>;

/// One cable as its effect sees it: index, node numbers and the ends they move.
#[derive(Debug, Clone, PartialEq)]
pub struct CableLink {
    /// Cable index (for the reported force density).
    pub cable: usize,
    /// Nodes (0-based); `s = x_b − x_a`.
    pub nodes: [usize; 2],
    /// Bar ends at those nodes.
    pub ends: [Target; 2],
}

/// A force contribution.
#[derive(Debug, Clone, PartialEq)]
pub enum ForceEffect {
    /// Weight of bars and point masses, per end, N.
    Gravity(Vec<(usize, Vector3<f64>)>),
    /// Elastic cables without damping: (link, κ, s₀).
    ElasticCables(Vec<(CableLink, f64, f64)>),
    /// Elastic cables with damping: (link, κ, s₀, c).
    DampedCables(Vec<(CableLink, f64, f64, f64)>),
    /// Cables whose force density is an input: (link, input).
    ForceDensityCables(Vec<(CableLink, usize)>),
    /// Cables whose rest length is an input: (link, κ, c (0 without damping), input).
    ReeledCables(Vec<(CableLink, f64, f64, usize)>),
    /// External force inputs: (input, end).
    NodeForces(Vec<(usize, Target)>),
    /// Scripted loads: (end, law).
    ScriptedLoads(Vec<(Target, LoadSpec)>),
    /// Penalty contact with a ground plane at the nodes in `ground.nodes`.
    GroundContact(Ground),
    /// Bars' capsules against terrain shapes, along their length.
    Terrain(Box<Terrain>),
    /// Bars' capsules against each other.
    Collisions(Box<Collisions>),
}

/// A constraint contribution beyond the bars' own length constraints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintEffect {
    /// Class-k joints and pins (`N P = D`): reactions Ω, then λ again.
    JointsAndPins,
}

/// The lists an evaluation runs.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Pipeline {
    /// Force contributions.
    pub forces: Vec<ForceEffect>,
    /// Constraint contributions.
    pub constraints: Vec<ConstraintEffect>,
}

impl Pipeline {
    /// Builds the contributions of a model's declared effects.
    pub fn new(model: &Model) -> Self {
        let node_end = &model.coords.node_end;
        let link = |j: usize| {
            let nodes = model.cables[j].nodes;
            CableLink {
                cable: j,
                nodes,
                ends: [node_end[nodes[0]], node_end[nodes[1]]],
            }
        };
        let mut elastic = Vec::new();
        let mut damped = Vec::new();
        let mut controlled = Vec::new();
        let mut reeled = Vec::new();
        for (j, cable) in model.cables.iter().enumerate() {
            match cable.law {
                CableLaw::Elastic {
                    stiffness,
                    rest_length,
                    damping: None,
                } => elastic.push((link(j), stiffness, rest_length)),
                CableLaw::Elastic {
                    stiffness,
                    rest_length,
                    damping: Some(c),
                } => damped.push((link(j), stiffness, rest_length, c)),
                CableLaw::Controlled { input } => controlled.push((link(j), input)),
                CableLaw::RestLengthControlled {
                    stiffness,
                    damping,
                    input,
                } => reeled.push((link(j), stiffness, damping.unwrap_or(0.0), input)),
            }
        }
        let mut forces = Vec::new();
        let mut push = |effect: ForceEffect, present: bool| {
            if present {
                forces.push(effect);
            }
        };
        push(
            ForceEffect::ElasticCables(elastic.clone()),
            !elastic.is_empty(),
        );
        push(
            ForceEffect::DampedCables(damped.clone()),
            !damped.is_empty(),
        );
        push(
            ForceEffect::ForceDensityCables(controlled.clone()),
            !controlled.is_empty(),
        );
        push(
            ForceEffect::ReeledCables(reeled.clone()),
            !reeled.is_empty(),
        );
        let node_forces: Vec<_> = model
            .force_inputs
            .iter()
            .enumerate()
            .map(|(k, &n)| (k, node_end[n]))
            .collect();
        push(
            ForceEffect::NodeForces(node_forces.clone()),
            !node_forces.is_empty(),
        );
        let loads: Vec<_> = model
            .loads
            .iter()
            .map(|(n, law)| (node_end[*n], law.clone()))
            .collect();
        push(ForceEffect::ScriptedLoads(loads.clone()), !loads.is_empty());
        if let Some(g) = model.gravity {
            let weights = (0..model.coords.n_ends())
                .map(|e| (e, g * model.end_mass(e)))
                .collect();
            push(ForceEffect::Gravity(weights), true);
        }
        if let Some(ground) = &model.ground {
            push(ForceEffect::GroundContact(ground.clone()), true);
        }
        if let Some(terrain) = &model.terrain {
            push(ForceEffect::Terrain(Box::new(terrain.clone())), true);
        }
        if let Some(collisions) = &model.collisions {
            push(ForceEffect::Collisions(Box::new(collisions.clone())), true);
        }
        let constraints = if model.reactions.size() > 0 {
            vec![ConstraintEffect::JointsAndPins]
        } else {
            Vec::new()
        };
        Self {
            forces,
            constraints,
        }
    }
}
