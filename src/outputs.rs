//! Named output quantities. One table, built from the model, names every reported value
//! the same way in CSV columns and FMU variables (1-based, structured names).

use std::io::Write;

use nalgebra::Vector3;

pub use crate::scene::OutputGroup;
use crate::sim::Simulation;

mod row_reader;
mod row_thread;
pub use row_reader::RowReader;
pub use row_thread::RowThread;

/// A reportable value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Node position component (node, axis), m.
    NodePosition(usize, usize),
    /// Node velocity component (node, axis), m/s.
    NodeVelocity(usize, usize),
    /// Cable tension, N.
    CableTension(usize),
    /// Bar axial force, N, compression positive.
    BarForce(usize),
    /// `max |‖bᵢ‖ − lᵢ|`, m.
    LengthError,
    /// `max |bᵢ · ḃᵢ|`, m²/s.
    OrthogonalityError,
    /// Total energy, J.
    Energy,
    /// Normal ground force on contact point `k` (`Ground::nodes` order), N.
    ContactForce(usize),
    /// Total ground force component along an axis, N.
    GroundForce(usize),
    /// Support reaction (support, axis), N.
    SupportReaction(usize, usize),
    /// Total force of terrain shape k on the structure (shape, axis), N.
    TerrainForce(usize, usize),
    /// Contact points penetrating terrain shape k.
    TerrainContacts(usize),
    /// Pairs of bars whose capsules overlap.
    Collisions,
    /// The deepest interpenetration of two bars' capsules, m.
    CollisionPenetration,
}

/// One named output.
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    /// Structured name, e.g. `node[7].x`.
    pub name: String,
    /// Unit symbol.
    pub unit: &'static str,
    /// What it means.
    pub description: String,
    /// How to read it.
    pub quantity: Quantity,
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl Quantity {
    /// The output group it belongs to.
    pub fn group(self) -> OutputGroup {
        match self {
            Self::NodePosition(..) => OutputGroup::Positions,
            Self::NodeVelocity(..) => OutputGroup::Velocities,
            Self::CableTension(_) => OutputGroup::Tensions,
            Self::BarForce(_) => OutputGroup::BarForces,
            Self::LengthError | Self::OrthogonalityError => OutputGroup::Diagnostics,
            Self::Energy => OutputGroup::Energy,
            Self::ContactForce(_)
            | Self::GroundForce(_)
            | Self::TerrainForce(..)
            | Self::TerrainContacts(_)
            | Self::Collisions
            | Self::CollisionPenetration => OutputGroup::Contact,
            Self::SupportReaction(..) => OutputGroup::Reactions,
        }
    }
}

impl Quantity {
    /// Whether reading it needs an evaluation at the current state ([`Simulation::refresh`]):
    /// positions and velocities come straight from the state, everything else from forces,
    /// λ or Ω.
    pub fn needs_evaluation(self) -> bool {
        !matches!(self, Self::NodePosition(..) | Self::NodeVelocity(..))
    }

    /// Reads the value from a simulation whose outputs are fresh (for positions and
    /// velocities, at any time: they are read from the state).
    pub fn value(self, sim: &Simulation) -> f64 {
        match self {
            Self::NodePosition(n, k) => node_from_state(sim, n, k, true),
            Self::NodeVelocity(n, k) => node_from_state(sim, n, k, false),
            Self::CableTension(j) => sim.cable_tension(j),
            Self::BarForce(i) => sim.bar_force(i),
            Self::LengthError => sim.length_error(),
            Self::OrthogonalityError => sim.orthogonality_error(),
            Self::Energy => sim.energy(),
            Self::ContactForce(k) => sim.contact_force(k),
            Self::GroundForce(axis) => sim.ground_force()[axis],
            Self::SupportReaction(k, axis) => sim.support_reaction(k)[axis],
            Self::TerrainForce(k, axis) => sim.shape_load(k).force[axis],
            Self::TerrainContacts(k) => f64::from(sim.shape_load(k).contacts),
            Self::Collisions => f64::from(sim.workspace().collision.contacts),
            Self::CollisionPenetration => sim.workspace().collision.max_penetration,
        }
    }
}

/// Component `axis` of the position (with `position`) or velocity of node `n` from the
/// state, as the evaluation's kinematics computes it: the same arithmetic, so the same bits
/// (one axis only: an importer reads them one by one).
fn node_from_state(sim: &Simulation, n: usize, axis: usize, position: bool) -> f64 {
    match node_source(sim, n, position) {
        Ok((e, eta)) => sim.model().coords.end_component(e, eta, position, axis),
        Err(fixed) => fixed[axis],
    }
}

/// Where node `n`'s position (with `position`) or velocity comes from: the end standing for
/// it and the state's positions or velocities, or, for a bar-less node, which is pinned and
/// stays where it starts, the value itself.
#[inline]
fn node_source(
    sim: &Simulation,
    n: usize,
    position: bool,
) -> Result<(usize, &[f64]), Vector3<f64>> {
    let model = sim.model();
    match model.coords.node_end[n] {
        Some(e) => {
            let y = &sim.state().y;
            let (positions, velocities) = y.split_at(y.len() / 2);
            Ok((e, if position { positions } else { velocities }))
        }
        None if position => Err(model.positions[n]),
        None => Err(Vector3::zeros()),
    }
}

/// Whether any output of `table` needs an evaluation ([`Quantity::needs_evaluation`]).
pub fn needs_evaluation(table: &[Output]) -> bool {
    table.iter().any(|o| o.quantity.needs_evaluation())
}

/// The outputs of a model, in a fixed order: the groups its scene selects (all by default).
pub fn outputs(sim: &Simulation) -> Vec<Output> {
    let mut out = all_outputs(sim);
    if let Some(groups) = &sim.model().scene.outputs {
        out.retain(|o| groups.contains(&o.quantity.group()));
    }
    out
}

fn all_outputs(sim: &Simulation) -> Vec<Output> {
    let model = sim.model();
    let mut out = Vec::new();
    for n in 0..model.n_nodes() {
        for (k, axis) in AXES.iter().enumerate() {
            out.push(Output {
                name: format!("node[{}].{axis}", n + 1),
                unit: "m",
                description: format!("position of node {} along {axis}", n + 1),
                quantity: Quantity::NodePosition(n, k),
            });
        }
    }
    for n in 0..model.n_nodes() {
        for (k, axis) in AXES.iter().enumerate() {
            out.push(Output {
                name: format!("node[{}].v{axis}", n + 1),
                unit: "m/s",
                description: format!("velocity of node {} along {axis}", n + 1),
                quantity: Quantity::NodeVelocity(n, k),
            });
        }
    }
    for (j, c) in model.cables.iter().enumerate() {
        out.push(Output {
            name: format!("cable[{}].tension", j + 1),
            unit: "N",
            description: format!(
                "tension of cable {} (nodes {}–{})",
                j + 1,
                c.nodes[0] + 1,
                c.nodes[1] + 1
            ),
            quantity: Quantity::CableTension(j),
        });
    }
    for (i, b) in model.bars.iter().enumerate() {
        out.push(Output {
            name: format!("bar[{}].force", i + 1),
            unit: "N",
            description: format!(
                "axial force of bar {} (nodes {}–{}), compression positive",
                i + 1,
                b.nodes[0] + 1,
                b.nodes[1] + 1
            ),
            quantity: Quantity::BarForce(i),
        });
    }
    for (k, support) in model.supports.iter().enumerate() {
        for (axis, name) in AXES.iter().enumerate() {
            out.push(Output {
                name: format!("node[{}].reaction_{name}", support.node + 1),
                unit: "N",
                description: format!("force of the pin on node {} along {name}", support.node + 1),
                quantity: Quantity::SupportReaction(k, axis),
            });
        }
    }
    out.push(Output {
        name: "constraint.length_error".into(),
        unit: "m",
        description: "largest bar-length violation max |‖b‖ − l|".into(),
        quantity: Quantity::LengthError,
    });
    out.push(Output {
        name: "constraint.orthogonality_error".into(),
        unit: "m2/s",
        description: "largest bar-velocity orthogonality violation max |b·ḃ|".into(),
        quantity: Quantity::OrthogonalityError,
    });
    out.push(Output {
        name: "energy.total".into(),
        unit: "J",
        description: energy_terms(model),
        quantity: Quantity::Energy,
    });
    if let Some(ground) = &model.ground {
        for (k, &(n, _)) in ground.nodes.iter().enumerate() {
            out.push(Output {
                name: format!("node[{}].contact_force", n + 1),
                unit: "N",
                description: format!(
                    "normal ground force on node {} (0 when not touching)",
                    n + 1
                ),
                quantity: Quantity::ContactForce(k),
            });
        }
        for (k, axis) in AXES.iter().enumerate() {
            out.push(Output {
                name: format!("ground.force_{axis}"),
                unit: "N",
                description: format!(
                    "total ground force on the structure along {axis} (normal and friction)"
                ),
                quantity: Quantity::GroundForce(k),
            });
        }
    }
    for (k, t) in model.scene.terrain.iter().enumerate() {
        let shape = format!("terrain[{}]", k + 1);
        for (axis, name) in AXES.iter().enumerate() {
            out.push(Output {
                name: format!("{shape}.force_{name}"),
                unit: "N",
                description: format!(
                    "total force of {shape} ({}) on the structure along {name} (normal and friction)",
                    t.kind.name()
                ),
                quantity: Quantity::TerrainForce(k, axis),
            });
        }
        out.push(Output {
            name: format!("{shape}.contacts"),
            unit: "1",
            description: format!(
                "number of contact points penetrating {shape} (bar ends and sides)"
            ),
            quantity: Quantity::TerrainContacts(k),
        });
    }
    if model.collisions.is_some() {
        out.push(Output {
            name: "collisions.contacts".into(),
            unit: "1",
            description: "number of pairs of bars whose capsules overlap".into(),
            quantity: Quantity::Collisions,
        });
        out.push(Output {
            name: "collisions.max_penetration".into(),
            unit: "m",
            description: "deepest interpenetration of two bars' capsules (0 without contact)"
                .into(),
            quantity: Quantity::CollisionPenetration,
        });
    }
    out
}

/// What `energy.total` sums, naming only the effects the model has.
fn energy_terms(model: &crate::model::Model) -> String {
    let mut terms = vec!["kinetic", "cable strain"];
    if model.gravity.is_some() {
        terms.push("gravity");
    }
    if model.ground.is_some() {
        terms.push("ground penalty");
    }
    if model.terrain.is_some() {
        terms.push("terrain penalty");
    }
    if model.collisions.is_some() {
        terms.push("collision penalty");
    }
    format!("{} energy", terms.join(" + "))
}

/// Writes a CSV header (`time` then the output names).
pub fn write_header(w: &mut impl Write, table: &[Output]) -> std::io::Result<()> {
    write!(w, "time")?;
    for o in table {
        write!(w, ",{}", o.name)?;
    }
    writeln!(w)
}

/// Writes CSV rows: the time, then each output, as [`write_number`] writes them. A row is
/// formatted into a buffer sized once for the longest possible row of its table, so
/// writing rows allocates nothing, and handed to the writer in one piece. [`RowThread`]
/// writes the same bytes from a thread of its own.
#[derive(Debug)]
pub struct RowWriter {
    line: Vec<u8>,
}

/// Longest text of one value, `-2.2250738585072014e-308`, and the comma or newline after it.
const MAX_CELL: usize = 25;

impl RowWriter {
    /// A writer for rows of `table`.
    pub fn new(table: &[Output]) -> Self {
        Self {
            line: Vec::with_capacity(MAX_CELL * (table.len() + 1) + 1),
        }
    }

    /// Writes one row for the current state of `sim` (whose outputs are fresh).
    pub fn write_row(
        &mut self,
        w: &mut impl Write,
        table: &[Output],
        sim: &Simulation,
    ) -> std::io::Result<()> {
        let values = std::iter::once(sim.time()).chain(table.iter().map(|o| o.quantity.value(sim)));
        self.write_values(w, values)
    }

    /// Writes one row of `values` (the time first) as [`Self::write_row`] writes them.
    pub fn write_values(
        &mut self,
        w: &mut impl Write,
        values: impl IntoIterator<Item = f64>,
    ) -> std::io::Result<()> {
        self.line.clear();
        push_row(&mut self.line, values);
        w.write_all(&self.line)
    }
}

/// Appends one CSV line to `line`: `values` as [`number`] writes them, separated by commas,
/// and a newline. The one place a row's text is made, so every writer writes the same bytes.
fn push_row(line: &mut Vec<u8>, values: impl IntoIterator<Item = f64>) {
    let mut digits = zmij::Buffer::new();
    let mut values = values.into_iter();
    if let Some(first) = values.next() {
        line.extend_from_slice(number(&mut digits, first).as_bytes());
    }
    for x in values {
        line.push(b',');
        line.extend_from_slice(number(&mut digits, x).as_bytes());
    }
    line.push(b'\n');
}

pub use crate::numbers::{number, write_number};
