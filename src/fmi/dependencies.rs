//! The `dependencies` of `<ModelStructure>`: which Knowns each output reads at the same
//! instant, worked out from the model's topology the way an evaluation computes it
//! (`dynamics::accelerations` after a set: kinematics → forces → λ → reactions Ω → λ).
//!
//! Every Known (an input, or for `<InitialUnknowns>` also a parameter) has a footprint:
//! the cable force densities γ it enters, the bar ends it pushes, the bars whose inertia
//! it changes, and whether it enters the energy or the ground force. An output depends on
//! the Knowns whose footprint meets what the output reads:
//!
//! - node positions and velocities and the constraint errors read the state only;
//! - `cable[j].tension` = γⱼ·length reads γⱼ;
//! - `bar[i].force` = λᵢ·length: λᵢ is closed-form in the end forces of bar i, and with
//!   pins or joints the reactions Ω couple every bar of its constraint group (bars joined
//!   through shared constraint columns), so it reads the forces on and the inertia of
//!   that group; a bar pinned at both ends never moves and has λ = 0;
//! - `node[i].reaction_*` reads Ω of the groups held at node i, the applied forces on
//!   static bar ends there, and γ of cables anchored at a bar-less pinned node;
//! - `energy.total` reads masses, gravity, the elastic cable laws, the force-density and
//!   rest-length inputs (strain of controlled and reeled cables) and the ground penalty;
//! - contact forces read the state and the ground settings only.

use fmi2_model_description::{Causality, DependencyKind, Unknown};

use super::variables::{Binding, GroundField, Variable, VariableTable};
use crate::model::coords::End;
use crate::model::Model;
use crate::outputs::Quantity;

/// What one Known enters in an evaluation.
#[derive(Debug, Default)]
struct Footprint {
    /// Cables whose force density γ it enters.
    cables: Vec<usize>,
    /// Bar ends whose applied force it enters.
    ends: Vec<End>,
    /// Bars whose inertia it enters.
    inertia: Vec<usize>,
    /// It enters `energy.total`.
    energy: bool,
    /// It enters the normal contact forces.
    contact_normal: bool,
    /// It enters the total ground force (normal and friction).
    contact_total: bool,
}

/// `<Outputs>` and `<InitialUnknowns>` with their dependencies (1-based table indices).
pub fn model_structure(model: &Model, table: &VariableTable) -> (Vec<Unknown>, Vec<Unknown>) {
    let groups = constraint_groups(model);
    let known = |v: &Variable| footprint(model, v.binding);
    let footprints: Vec<Option<Footprint>> = table
        .variables
        .iter()
        .map(|v| matches!(v.causality, Causality::Input | Causality::Parameter).then(|| known(v)))
        .collect();
    let mut outputs = Vec::new();
    let mut initial = Vec::new();
    for (i, v) in table.variables.iter().enumerate() {
        let Binding::Output(q) = v.binding else {
            continue;
        };
        let reads = |f: &Footprint| reads(model, &groups, q, f);
        let deps = |causalities: &[Causality]| -> Vec<u32> {
            table
                .variables
                .iter()
                .zip(&footprints)
                .enumerate()
                .filter(|(_, (k, f))| {
                    causalities.contains(&k.causality) && f.as_ref().is_some_and(reads)
                })
                .map(|(j, _)| j as u32 + 1)
                .collect()
        };
        outputs.push(unknown(i, deps(&[Causality::Input])));
        initial.push(unknown(i, deps(&[Causality::Input, Causality::Parameter])));
    }
    (outputs, initial)
}

fn unknown(index: usize, dependencies: Vec<u32>) -> Unknown {
    Unknown {
        index: index as u32 + 1,
        // No Known enters an output through a constant factor: clamps, lengths and
        // solves make every dependency a general one.
        dependencies_kind: (!dependencies.is_empty())
            .then(|| vec![DependencyKind::Dependent; dependencies.len()]),
        dependencies: Some(dependencies),
    }
}

/// Whether output `q` reads a Known with footprint `f`.
fn reads(model: &Model, groups: &[usize], q: Quantity, f: &Footprint) -> bool {
    let coords = &model.coords;
    let pushes_group = |g: usize| {
        f.ends.iter().any(|&e| groups[e / 2] == g) || f.inertia.iter().any(|&b| groups[b] == g)
    };
    match q {
        Quantity::NodePosition(..)
        | Quantity::NodeVelocity(..)
        | Quantity::LengthError
        | Quantity::OrthogonalityError => false,
        Quantity::CableTension(j) => f.cables.contains(&j),
        Quantity::BarForce(i) => !coords.static_bar[i] && pushes_group(groups[i]),
        Quantity::SupportReaction(k, _) => {
            let n = model.supports[k].node;
            let at_node = (0..coords.n_ends()).filter(|&e| coords.end_node[e] == n);
            let held = at_node.clone().any(|e| {
                if coords.static_bar[e / 2] {
                    f.ends.contains(&e)
                } else {
                    pushes_group(groups[e / 2])
                }
            });
            let anchored = coords.node_end[n].is_none()
                && f.cables.iter().any(|&j| model.cables[j].nodes.contains(&n));
            held || anchored
        }
        Quantity::Energy => f.energy,
        Quantity::ContactForce(_) => f.contact_normal,
        Quantity::GroundForce(_) => f.contact_total,
    }
}

/// The constraint group of each bar: bars that share a constraint column are one group.
fn constraint_groups(model: &Model) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..model.bars.len()).collect();
    fn root(parent: &mut [usize], mut b: usize) -> usize {
        while parent[b] != b {
            parent[b] = parent[parent[b]];
            b = parent[b];
        }
        b
    }
    for column in &model.coords.constraints {
        let mut bars = column.terms.iter().map(|&(e, _)| e / 2);
        if let Some(first) = bars.next() {
            for b in bars {
                let (ra, rb) = (root(&mut parent, first), root(&mut parent, b));
                parent[ra] = rb;
            }
        }
    }
    (0..model.bars.len())
        .map(|b| root(&mut parent, b))
        .collect()
}

/// What the input or parameter behind `binding` enters.
fn footprint(model: &Model, binding: Binding) -> Footprint {
    let node_end = &model.coords.node_end;
    let cable = |j: usize, energy: bool| Footprint {
        cables: vec![j],
        ends: model.cables[j]
            .nodes
            .iter()
            .filter_map(|&n| node_end[n])
            .collect(),
        energy,
        ..Footprint::default()
    };
    // With gravity, a mass also weighs on its ends.
    let weighs = |ends: Vec<End>| {
        if model.gravity.is_some() {
            ends
        } else {
            Vec::new()
        }
    };
    match binding {
        Binding::ForceDensity(k) => cable(model.controlled[k], true),
        Binding::ReelInput(k) => cable(model.reeled[k], true),
        Binding::Stiffness(j) | Binding::RestLength(j) => cable(j, true),
        Binding::Damping(j) => cable(j, false),
        Binding::NodeForce(k, _) => Footprint {
            ends: node_end[model.force_inputs[k]].into_iter().collect(),
            ..Footprint::default()
        },
        Binding::Load(k, _) => Footprint {
            ends: node_end[model.loads[k].0].into_iter().collect(),
            ..Footprint::default()
        },
        Binding::Mass(i) => Footprint {
            ends: weighs(vec![2 * i, 2 * i + 1]),
            inertia: vec![i],
            energy: true,
            ..Footprint::default()
        },
        Binding::PointMass(k) => {
            let end = node_end[model.scene.point_masses[k].node - 1];
            Footprint {
                ends: weighs(end.into_iter().collect()),
                inertia: end.map(|e| e / 2).into_iter().collect(),
                energy: true,
                ..Footprint::default()
            }
        }
        Binding::Gravity(_) => Footprint {
            ends: (0..model.coords.n_ends()).collect(),
            energy: true,
            ..Footprint::default()
        },
        Binding::Ground(field) => Footprint {
            ends: model
                .ground
                .as_ref()
                .map_or(Vec::new(), |g| g.nodes.iter().map(|&(_, e)| e).collect()),
            energy: matches!(field, GroundField::Height | GroundField::Stiffness),
            contact_normal: matches!(
                field,
                GroundField::Height | GroundField::Stiffness | GroundField::Damping
            ),
            contact_total: true,
            ..Footprint::default()
        },
        Binding::Output(_)
        | Binding::StepSize
        | Binding::Correction
        | Binding::LocateEvents
        | Binding::Method
        | Binding::MaxSteps
        | Binding::Rtol
        | Binding::Atol => Footprint::default(),
    }
}
