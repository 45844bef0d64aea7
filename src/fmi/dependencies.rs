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

use super::variables::{Binding, ContactField, GroundField, VariableTable};
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
    /// It enters the terrain shapes' forces.
    terrain_force: bool,
    /// It enters which points touch the terrain.
    terrain_touch: bool,
    /// It enters which bars touch each other.
    collision_touch: bool,
}

/// A row of `<InitialUnknowns>` that reads every input and more than this many parameters
/// omits its list ("depends on all Knowns"): the parameters it then claims too are never
/// connected to another FMU, so no loop can follow, and the file stays linear in the scene.
const DENSE_ROW: usize = 64;

/// Dependency entries that `<InitialUnknowns>` lists at most: a fixed floor, so that small
/// structures keep every row exact (tower20 lists 13,455), and beyond it a number per
/// variable of the table, so that the file grows no faster than the structure.
const LISTED_FLOOR: usize = 100_000;
const LISTED_PER_VARIABLE: usize = 8;

/// The Knowns an output reads, split by causality (1-based table indices, ascending).
#[derive(Debug, Default, Clone)]
struct Reads {
    inputs: Vec<u32>,
    parameters: Vec<u32>,
}

impl Reads {
    fn push(&mut self, index: u32, causality: Causality) {
        if causality == Causality::Input {
            self.inputs.push(index);
        } else {
            self.parameters.push(index);
        }
    }

    /// The union of `parts`, each ascending.
    fn union<'a>(parts: impl IntoIterator<Item = &'a Reads>) -> Reads {
        let mut all = Reads::default();
        for part in parts {
            all.inputs.extend(&part.inputs);
            all.parameters.extend(&part.parameters);
        }
        for list in [&mut all.inputs, &mut all.parameters] {
            list.sort_unstable();
            list.dedup();
        }
        all
    }
}

/// Who reads each Known's footprint, inverted: per cable, bar end, constraint group and
/// global quantity, the Knowns that enter it. Building it visits each footprint once.
#[derive(Debug, Default)]
struct Readers {
    cable: Vec<Reads>,
    end: Vec<Reads>,
    group: Vec<Reads>,
    energy: Reads,
    contact_normal: Reads,
    contact_total: Reads,
    terrain_force: Reads,
    terrain_touch: Reads,
    collision_touch: Reads,
}

/// `<Outputs>` and `<InitialUnknowns>` with their dependencies (1-based table indices), in
/// the shortest exact form: see [`outputs_row`] and [`initial_row`].
pub fn model_structure(model: &Model, table: &VariableTable) -> (Vec<Unknown>, Vec<Unknown>) {
    let groups = constraint_groups(model);
    let readers = readers(model, table, &groups);
    let known = |c: Causality| table.variables.iter().filter(|v| v.causality == c).count();
    let (n_inputs, n_parameters) = (known(Causality::Input), known(Causality::Parameter));
    let none = Reads::default();
    let coords = &model.coords;
    let mut node_ends = vec![Vec::new(); coords.node_end.len()];
    for (e, &n) in coords.end_node.iter().enumerate() {
        node_ends[n].push(e);
    }
    let mut node_cables = vec![Vec::new(); coords.node_end.len()];
    for (j, cable) in model.cables.iter().enumerate() {
        for &n in &cable.nodes {
            node_cables[n].push(j);
        }
    }
    let mut outputs = Vec::new();
    let mut initial = Vec::new();
    for (i, v) in table.variables.iter().enumerate() {
        let Binding::Output(q) = v.binding else {
            continue;
        };
        let support;
        let reads = match q {
            Quantity::NodePosition(..)
            | Quantity::NodeVelocity(..)
            | Quantity::LengthError
            | Quantity::OrthogonalityError => &none,
            Quantity::CableTension(j) => &readers.cable[j],
            Quantity::BarForce(b) if coords.static_bar[b] => &none,
            Quantity::BarForce(b) => &readers.group[groups[b]],
            Quantity::SupportReaction(k, _) => {
                let n = model.supports[k].node;
                // A held end passes on its group's reactions, a static one its own loads;
                // a bar-less pin holds its cables' tensions.
                let held = node_ends[n].iter().map(|&e| {
                    if coords.static_bar[e / 2] {
                        &readers.end[e]
                    } else {
                        &readers.group[groups[e / 2]]
                    }
                });
                let anchored = node_cables[n]
                    .iter()
                    .filter(|_| coords.node_end[n].is_none())
                    .map(|&j| &readers.cable[j]);
                support = Reads::union(held.chain(anchored));
                &support
            }
            Quantity::Energy => &readers.energy,
            Quantity::ContactForce(_) => &readers.contact_normal,
            Quantity::GroundForce(_) => &readers.contact_total,
            Quantity::TerrainForce(..) => &readers.terrain_force,
            Quantity::TerrainContacts(_) => &readers.terrain_touch,
            Quantity::Collisions | Quantity::CollisionPenetration => &readers.collision_touch,
        };
        outputs.push(outputs_row(i, reads, n_inputs));
        initial.push(initial_row(i, reads, n_inputs, n_parameters));
    }
    let budget = LISTED_FLOOR.max(LISTED_PER_VARIABLE * table.variables.len());
    fit_budget(&mut initial, budget);
    (outputs, initial)
}

/// Omits the longest `<InitialUnknowns>` lists, longest first, until the lists left hold
/// at most `budget` entries. Exact lists can grow with the square of the structure (every
/// bar force of a jointed column reads most of its cables and some of the inputs); past
/// the budget such a row claims all Knowns instead: an over-claim of inputs confined to
/// Initialization Mode, while `<Outputs>`, which decides loops during a run, stays exact.
fn fit_budget(rows: &mut [Unknown], budget: usize) {
    let listed = |u: &Unknown| u.dependencies.as_ref().map_or(0, Vec::len);
    let mut total: usize = rows.iter().map(listed).sum();
    if total <= budget {
        return;
    }
    let mut longest: Vec<usize> = (0..rows.len()).filter(|&i| listed(&rows[i]) > 0).collect();
    longest.sort_by_key(|&i| std::cmp::Reverse(listed(&rows[i])));
    for i in longest {
        if total <= budget {
            break;
        }
        total -= listed(&rows[i]);
        rows[i] = unknown(rows[i].index as usize - 1, None);
    }
}

/// An `<Outputs>` row (the Knowns are the inputs): the list, omitted only when it names
/// every input. Never more: a claimed input would be a false algebraic loop.
fn outputs_row(index: usize, reads: &Reads, n_inputs: usize) -> Unknown {
    if !reads.inputs.is_empty() && reads.inputs.len() == n_inputs {
        return unknown(index, None);
    }
    unknown(index, Some(reads.inputs.clone()))
}

/// An `<InitialUnknowns>` row (the Knowns are the inputs and the parameters, all
/// `initial="exact"`): omitted when it reads every Known, or every input and more than
/// [`DENSE_ROW`] parameters; listed otherwise.
fn initial_row(index: usize, reads: &Reads, n_inputs: usize, n_parameters: usize) -> Unknown {
    let count = reads.inputs.len() + reads.parameters.len();
    let every_input = reads.inputs.len() == n_inputs;
    let all = count > 0 && count == n_inputs + n_parameters;
    if all || (every_input && reads.parameters.len() > DENSE_ROW) {
        return unknown(index, None);
    }
    let mut list = [reads.inputs.as_slice(), &reads.parameters].concat();
    list.sort_unstable();
    unknown(index, Some(list))
}

/// `dependencies: None` omits the attribute: the row depends on all Knowns.
fn unknown(index: usize, dependencies: Option<Vec<u32>>) -> Unknown {
    Unknown {
        index: index as u32 + 1,
        // No Known enters an output through a constant factor: clamps, lengths and
        // solves make every dependency a general one.
        dependencies_kind: dependencies
            .as_ref()
            .filter(|d| !d.is_empty())
            .map(|d| vec![DependencyKind::Dependent; d.len()]),
        dependencies,
    }
}

/// The readers of every input and parameter in `table`.
fn readers(model: &Model, table: &VariableTable, groups: &[usize]) -> Readers {
    let mut r = Readers {
        cable: vec![Reads::default(); model.cables.len()],
        end: vec![Reads::default(); model.coords.n_ends()],
        group: vec![Reads::default(); model.bars.len()],
        ..Readers::default()
    };
    let mut pushed = Vec::new();
    for (i, v) in table.variables.iter().enumerate() {
        if !matches!(v.causality, Causality::Input | Causality::Parameter) {
            continue;
        }
        let (index, c) = (i as u32 + 1, v.causality);
        let f = footprint(model, v.binding);
        for &j in &f.cables {
            r.cable[j].push(index, c);
        }
        for &e in &f.ends {
            r.end[e].push(index, c);
        }
        // A Known pushes a group through an end or an inertia; listed once per group.
        pushed.clear();
        pushed.extend(f.ends.iter().map(|&e| groups[e / 2]));
        pushed.extend(f.inertia.iter().map(|&b| groups[b]));
        pushed.sort_unstable();
        pushed.dedup();
        for &g in &pushed {
            r.group[g].push(index, c);
        }
        for (flag, reads) in [
            (f.energy, &mut r.energy),
            (f.contact_normal, &mut r.contact_normal),
            (f.contact_total, &mut r.contact_total),
            (f.terrain_force, &mut r.terrain_force),
            (f.terrain_touch, &mut r.terrain_touch),
            (f.collision_touch, &mut r.collision_touch),
        ] {
            if flag {
                reads.push(index, c);
            }
        }
    }
    r
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
        Binding::Radius(i) => {
            let grounded = model.ground.is_some();
            // With collisions, a bar's radius moves whichever bar it touches.
            let ends = if model.collisions.is_some() {
                (0..model.coords.n_ends()).collect()
            } else {
                model.bars[i]
                    .nodes
                    .iter()
                    .filter_map(|&n| node_end[n])
                    .collect()
            };
            Footprint {
                ends,
                energy: true,
                contact_normal: grounded,
                contact_total: grounded,
                terrain_force: model.terrain.is_some(),
                terrain_touch: model.terrain.is_some(),
                collision_touch: model.collisions.is_some(),
                ..Footprint::default()
            }
        }
        Binding::Terrain(_, field) => Footprint {
            ends: model.terrain.as_ref().map_or(Vec::new(), |t| {
                t.capsules
                    .iter()
                    .flat_map(|c| c.ends.into_iter().flatten())
                    .collect()
            }),
            energy: field == ContactField::Stiffness,
            terrain_force: true,
            ..Footprint::default()
        },
        Binding::Collision(field) => Footprint {
            ends: (0..model.coords.n_ends()).collect(),
            energy: field == ContactField::Stiffness,
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
