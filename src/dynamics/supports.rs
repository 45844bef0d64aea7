//! Support reactions at pinned nodes: the force each pin exerts on the structure.
//!
//! A moving bar end at a pin receives the constraint forces `Σ coef Ω_c` of the columns
//! that hold it; a static bar (both ends pinned) is balanced by its pins, `R = −f`; a
//! bar-less anchor takes its cables' pull. Joint columns at the same node cancel.

use nalgebra::Vector3;

use super::Workspace;
use crate::model::supports::Support;
use crate::model::Cable;

impl Support {
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
