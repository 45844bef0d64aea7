//! A row of output values read in one pass: a node's three components, a support's three
//! reactions and runs of cable tensions or bar forces computed together.

use nalgebra::Vector3;

use super::{node_source, Output, Quantity};
use crate::sim::Simulation;

/// Reads a table's values faster than output by output: the three position (or velocity)
/// components of a node, one after the other as [`outputs`] lists them, are read together
/// as the kinematics computes them ([`Coordinates::end_vector`]), which shares the node's
/// lookups, a support's three reactions from one computation, and runs of consecutive
/// cable tensions or bar forces in one loop each; the same bits as [`Quantity::value`].
///
/// [`Coordinates::end_vector`]: crate::model::coords::Coordinates::end_vector
#[derive(Debug, Clone)]
pub struct RowReader {
    reads: Vec<Read>,
    /// Values per row, the time included.
    row_len: usize,
}

#[derive(Debug, Clone)]
enum Read {
    /// The x, y and z of one vector, computed once.
    Vector(Triple),
    /// Consecutive cables' tensions, in one loop.
    Tensions(std::ops::Range<usize>),
    /// Consecutive bars' axial forces, in one loop.
    BarForces(std::ops::Range<usize>),
    One(Quantity),
}

impl RowReader {
    /// A reader for `table`.
    pub fn new(table: &[Output]) -> Self {
        let mut reads = Vec::new();
        let mut rest = table;
        while let Some(first) = rest.first() {
            let read = triple_at(rest)
                .or_else(|| run_at(rest))
                .unwrap_or(Read::One(first.quantity));
            rest = &rest[read.len()..];
            reads.push(read);
        }
        let row_len = table.len() + 1;
        Self { reads, row_len }
    }

    /// Appends the time, then each value of the table, to `out`.
    pub fn read(&self, sim: &Simulation, out: &mut Vec<f64>) {
        out.reserve(self.row_len);
        out.push(sim.time());
        for read in &self.reads {
            match read {
                Read::Vector(triple) => {
                    let x = triple.value(sim);
                    out.extend([x.x, x.y, x.z]);
                }
                Read::Tensions(cables) => extend_tensions(sim, cables.clone(), out),
                Read::BarForces(bars) => out.extend(bars.clone().map(|i| sim.bar_force(i))),
                Read::One(q) => out.push(q.value(sim)),
            }
        }
    }
}

impl Read {
    /// Values it reads.
    fn len(&self) -> usize {
        match self {
            Self::Vector(_) => 3,
            Self::Tensions(range) | Self::BarForces(range) => range.len(),
            Self::One(_) => 1,
        }
    }
}

/// The run of consecutive cable tensions or bar forces (j, j + 1, …) that starts `table`,
/// if one does.
fn run_at(table: &[Output]) -> Option<Read> {
    // (whether a tension, index)
    let index = |q: Quantity| match q {
        Quantity::CableTension(j) => Some((true, j)),
        Quantity::BarForce(i) => Some((false, i)),
        _ => None,
    };
    let (tension, first) = index(table.first()?.quantity)?;
    let len = table
        .iter()
        .enumerate()
        .take_while(|(k, o)| index(o.quantity) == Some((tension, first + k)))
        .count();
    let range = first..first + len;
    Some(if tension {
        Read::Tensions(range)
    } else {
        Read::BarForces(range)
    })
}

/// Three outputs that [`outputs`] lists one after the other as x, y and z of one vector.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Triple {
    /// A node's position (with `position`) or velocity, as the kinematics computes it
    /// ([`Coordinates::end_vector`](crate::model::coords::Coordinates::end_vector)).
    Node { node: usize, position: bool },
    /// A support's reaction.
    Reaction(usize),
}

impl Triple {
    fn value(self, sim: &Simulation) -> Vector3<f64> {
        match self {
            Self::Node { node, position } => node_vector_from_state(sim, node, position),
            Self::Reaction(k) => sim.support_reaction(k),
        }
    }
}

/// The vector whose x, y and z start `table`, if they do.
fn triple_at(table: &[Output]) -> Option<Read> {
    let [a, b, c, ..] = table else { return None };
    let (triple, 0) = component(a.quantity)? else {
        return None;
    };
    [(b, 1), (c, 2)]
        .iter()
        .all(|(o, axis)| component(o.quantity) == Some((triple, *axis)))
        .then_some(Read::Vector(triple))
}

/// The vector and axis of an output that is one component of a [`Triple`].
fn component(q: Quantity) -> Option<(Triple, usize)> {
    match q {
        Quantity::NodePosition(node, axis) => Some((
            Triple::Node {
                node,
                position: true,
            },
            axis,
        )),
        Quantity::NodeVelocity(node, axis) => Some((
            Triple::Node {
                node,
                position: false,
            },
            axis,
        )),
        Quantity::SupportReaction(k, axis) => Some((Triple::Reaction(k), axis)),
        _ => None,
    }
}

/// Appends the tensions of `cables`: [`Simulation::cable_tension`]'s arithmetic, the
/// squared lengths first and then the square roots a block at a time, so that the roots
/// (a quarter of a row's reading, one by one) are taken two or four at once.
fn extend_tensions(sim: &Simulation, cables: std::ops::Range<usize>, out: &mut Vec<f64>) {
    const BLOCK: usize = 16;
    let (model, ws) = (sim.model(), sim.workspace());
    let mut start = cables.start;
    while start < cables.end {
        let end = cables.end.min(start + BLOCK);
        let mut block = [0.0; BLOCK];
        let block = &mut block[..end - start];
        for (squared, cable) in block.iter_mut().zip(&model.cables[start..end]) {
            let [a, b] = cable.nodes;
            *squared = (ws.node_pos[b] - ws.node_pos[a]).norm_squared();
        }
        for (value, gamma) in block.iter_mut().zip(&ws.gamma[start..end]) {
            *value = gamma * value.sqrt();
        }
        out.extend_from_slice(block);
        start = end;
    }
}

/// The position (with `position`) or velocity of node `n` from the state, through the
/// kinematics' own [`Coordinates::end_vector`](crate::model::coords::Coordinates::end_vector).
fn node_vector_from_state(sim: &Simulation, n: usize, position: bool) -> Vector3<f64> {
    match node_source(sim, n, position) {
        Ok((e, eta)) => sim.model().coords.end_vector(e, eta, position),
        Err(fixed) => fixed,
    }
}
