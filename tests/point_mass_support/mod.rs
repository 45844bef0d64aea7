//! Helpers shared by the point-mass suites (`tests/point_masses.rs`,
//! `tests/point_mass_frequencies.rs`): scenes from JSON text, payload bookkeeping
//! and the cable-held bar.

use serde_json::{json, Value};
use tensegrity_fmu::scene::PointMassSpec;
use tensegrity_fmu::Scene;

pub fn scene_from(v: &Value) -> Scene {
    Scene::from_json_str(&v.to_string()).expect("the test scene parses")
}

/// `[[point_masses]]` entries from (1-based node, kg) pairs, through serde like a file.
#[allow(dead_code)] // not used by tests/point_mass_frequencies.rs
pub fn payloads(list: &[(usize, f64)]) -> Vec<PointMassSpec> {
    list.iter()
        .map(|&(node, mass)| {
            serde_json::from_value(json!({ "node": node, "mass": mass })).expect("payload entry")
        })
        .collect()
}

/// Payload per node (0-based), kg, summed from the scene: the test's own bookkeeping.
#[allow(dead_code)] // not used by tests/point_mass_frequencies.rs
pub fn node_payload(scene: &Scene) -> Vec<f64> {
    let mut p = vec![0.0; scene.nodes.len()];
    for pm in &scene.point_masses {
        p[pm.node - 1] += pm.mass;
    }
    p
}

/// A horizontal bar (length L, mass m) pinned at node 1, its free end (node 2) held by two
/// vertical elastic cables (stiffness κ, rest length s₀) to pinned anchors at ±H above and
/// below it, no gravity, payload p at the tip; the start velocity `tip_velocity` excites one
/// mode. Both cables carry the same prestress `T₀ = κ (H − s₀)`, so the start is an
/// equilibrium.
pub fn cable_held_bar(p: Option<f64>, tip_velocity: [f64; 3]) -> Scene {
    let (l, m, h, k, s0) = CABLE_BAR;
    let mut s = json!({
        "name": "cable-held-bar",
        "nodes": [[0.0, 0.0, 0.0], [l, 0.0, 0.0], [l, 0.0, h], [l, 0.0, -h]],
        "fixed": [1, 3, 4],
        "bars": [{ "nodes": [1, 2], "mass": m }],
        "cables": [
            { "nodes": [2, 3], "stiffness": k, "rest_length": s0 },
            { "nodes": [2, 4], "stiffness": k, "rest_length": s0 },
        ],
        "velocities": [[0.0, 0.0, 0.0], tip_velocity, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
    });
    if let Some(p) = p {
        s["point_masses"] = json!([{ "node": 2, "mass": p }]);
    }
    scene_from(&s)
}

/// (L, m, H, κ, s₀): T₀ = 500 · 0.05 = 25 N.
pub const CABLE_BAR: (f64, f64, f64, f64, f64) = (1.0, 1.0, 0.5, 500.0, 0.45);
