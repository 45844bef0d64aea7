//! Support reactions at pinned nodes: the force each pin exerts on the structure.
//!
//! A moving bar end at a pin receives the constraint forces `Σ coef Ω_c` of the columns
//! that hold it; a static bar (both ends pinned) is balanced by its pins, `R = −f`; a
//! bar-less anchor takes its cables' pull. Joint columns at the same node cancel.

use nalgebra::Vector3;

use super::Workspace;
use crate::model::coords::Coordinates;
use crate::model::Cable;

/// How to read one pinned node's reaction after an evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// The pinned node (0-based).
    pub node: usize,
    /// `(column, coefficient)` of every constraint term on an end at this node.
    columns: Vec<(usize, f64)>,
    /// Ends of static bars at this node.
    static_ends: Vec<usize>,
    /// Cables ending here when no bar does: (cable, +1 at its start node, −1 at its end).
    anchor_cables: Vec<(usize, f64)>,
}

impl Support {
    /// The supports of every pinned node, in node order.
    pub fn all(coords: &Coordinates, pinned: &[bool], cables: &[Cable]) -> Vec<Self> {
        (0..pinned.len())
            .filter(|&n| pinned[n])
            .map(|n| {
                let at_node = |e: usize| coords.end_node[e] == n;
                let columns = coords
                    .constraints
                    .iter()
                    .enumerate()
                    .flat_map(|(c, col)| {
                        col.terms
                            .iter()
                            .filter(|(e, _)| at_node(*e))
                            .map(move |&(_, coef)| (c, coef))
                    })
                    .collect();
                let static_ends = (0..coords.n_ends())
                    .filter(|&e| at_node(e) && coords.static_bar[e / 2])
                    .collect();
                let anchor_cables = if coords.node_end[n].is_none() {
                    cables
                        .iter()
                        .enumerate()
                        .filter_map(|(j, c)| {
                            (c.nodes[0] == n)
                                .then_some((j, 1.0))
                                .or((c.nodes[1] == n).then_some((j, -1.0)))
                        })
                        .collect()
                } else {
                    Vec::new()
                };
                Self {
                    node: n,
                    columns,
                    static_ends,
                    anchor_cables,
                }
            })
            .collect()
    }

    /// The force the pin exerts on the structure, N (from the last evaluation).
    pub fn reaction(&self, cables: &[Cable], ws: &Workspace) -> Vector3<f64> {
        let omega = |c: usize| ws.reaction_solution(c);
        let constrained: Vector3<f64> = self.columns.iter().map(|&(c, k)| omega(c) * k).sum();
        let statics: Vector3<f64> = self.static_ends.iter().map(|&e| -ws.end_force[e]).sum();
        let anchors: Vector3<f64> = self
            .anchor_cables
            .iter()
            .map(|&(j, sign)| {
                let [a, b] = cables[j].nodes;
                // The cable pulls its start towards its end: γ s on a, −γ s on b.
                -(ws.node_pos[b] - ws.node_pos[a]) * (ws.gamma[j] * sign)
            })
            .sum();
        constrained + statics + anchors
    }
}
