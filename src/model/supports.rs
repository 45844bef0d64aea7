//! Which constraint columns, static bars and anchor cables make up the reaction of each
//! pinned node (read after an evaluation by `dynamics::supports`).
//!
//! A moving bar end at a pin receives the constraint forces `Σ coef Ω_c` of the columns
//! that hold it; a static bar (both ends pinned) is balanced by its pins, `R = −f`; a
//! bar-less anchor takes its cables' pull. Joint columns at the same node cancel.

use super::coords::Coordinates;
use super::Cable;

/// How to read one pinned node's reaction after an evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// The pinned node (0-based).
    pub node: usize,
    /// `(column, coefficient)` of every constraint term on an end at this node.
    pub(crate) columns: Vec<(usize, f64)>,
    /// Ends of static bars at this node.
    pub(crate) static_ends: Vec<usize>,
    /// Cables ending here when no bar does: (cable, +1 at its start node, −1 at its end).
    pub(crate) anchor_cables: Vec<(usize, f64)>,
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
}
