//! Hand-built scenes of the stress cases.

use tensegrity_fmu::scene::Scene;

use super::{bar, bare, cable};

// ------------------------------------------------------------------ hand-built scenes

/// A class-3 joint: a free apex (node 1) shared by three bars from free feet (2–4), feet
/// tied in a ring and to pinned anchors (5–7), the apex tied to the anchors; gravity and
/// a push on the apex.
pub fn tripod() -> Scene {
    let ring = |r: f64, z: f64, i: usize| {
        let a = (90.0 + 120.0 * i as f64).to_radians();
        [r * a.cos(), r * a.sin(), z]
    };
    let mut nodes = vec![[0.0, 0.0, 1.0]];
    nodes.extend((0..3).map(|i| ring(1.0, 0.0, i)));
    nodes.extend((0..3).map(|i| ring(1.6, -0.2, i)));
    let mut s = bare("tripod", nodes, vec![5, 6, 7]);
    s.bars = (2..=4).map(|f| bar(f, 1)).collect();
    let mut cables = Vec::new();
    for i in 0..3 {
        let (foot, next, anchor) = (2 + i, 2 + (i + 1) % 3, 5 + i);
        cables.push(cable(&s, foot, next, 300.0, 0.8));
        cables.push(cable(&s, foot, anchor, 300.0, 0.8));
        cables.push(cable(&s, 1, anchor, 300.0, 0.8));
    }
    s.cables = cables;
    s.gravity = Some([0.0, 0.0, -9.81]);
    let mut v = vec![[0.0; 3]; 7];
    v[0] = [0.4, -0.3, 0.1];
    s.velocities = Some(v);
    s
}

/// Two bars at a free joint (node 2), bent by `delta` rad from collinear; node 1 pinned
/// (or nodes 1 and 3 when `pin_both`); cables to pinned anchors, gravity.
pub fn two_bar_chain(delta: f64, pin_both: bool) -> Scene {
    let nodes = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0 + delta.cos(), delta.sin(), 0.0],
        [1.0, 1.0, 0.5],
        [1.0, -1.0, 0.5],
        [2.0, 1.0, 0.5],
        [2.0, -1.0, 0.5],
    ];
    let fixed = if pin_both {
        vec![1, 3, 4, 5, 6, 7]
    } else {
        vec![1, 4, 5, 6, 7]
    };
    let mut s = bare("two-bar-chain", nodes, fixed);
    s.bars = vec![bar(1, 2), bar(2, 3)];
    s.cables = vec![cable(&s, 2, 4, 200.0, 0.7), cable(&s, 2, 5, 200.0, 0.7)];
    if !pin_both {
        s.cables.push(cable(&s, 3, 6, 200.0, 0.7));
        s.cables.push(cable(&s, 3, 7, 200.0, 0.7));
    }
    s.gravity = Some([0.0, 0.0, -9.81]);
    s
}

/// A rigid triangle of bars, vertex 1 pinned, tied by a cable to a pinned anchor.
pub fn pinned_triangle() -> Scene {
    let nodes = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.5, 0.8, 0.0],
        [1.0, 1.0, 1.0],
    ];
    let mut s = bare("triangle", nodes, vec![1, 4]);
    s.bars = vec![bar(1, 2), bar(2, 3), bar(3, 1)];
    s.cables = vec![cable(&s, 3, 4, 200.0, 0.8)];
    s.gravity = Some([0.0, 0.0, -9.81]);
    s
}

/// Three bars from one pinned node (1) to free tips (2–4), listed twice in `fixed`; the
/// tips hang from pinned anchors (5–7); gravity. The paper's P has two joint
/// columns and three pin columns at node 1, of rank 3.
pub fn pinned_fan() -> Scene {
    let nodes = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.6],
        [-0.5, 0.8, 0.6],
        [-0.5, -0.8, 0.6],
        [1.5, 0.0, 1.5],
        [-0.8, 1.3, 1.5],
        [-0.8, -1.3, 1.5],
    ];
    let mut s = bare("fan", nodes, vec![1, 5, 6, 7, 1]);
    s.bars = vec![bar(1, 2), bar(1, 3), bar(1, 4)];
    for (a, b) in [(2, 5), (3, 6), (4, 7)] {
        s.cables.push(cable(&s, a, b, 300.0, 0.9));
    }
    s.gravity = Some([0.0, 0.0, -9.81]);
    s.velocities = Some(vec![
        [0.0; 3],
        [0.0, 0.5, 0.0],
        [0.3, 0.0, 0.2],
        [0.0; 3],
        [0.0; 3],
        [0.0; 3],
        [0.0; 3],
    ]);
    s
}

/// Two pendulum bars whose free ends (2 and 4) are `gap` m apart, joined by a cable of
/// rest length `gap / 2`; gravity, and a push on bar 2 that stretches the cable.
pub fn short_cable(gap: f64) -> Scene {
    let nodes = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0 + gap, 0.0, 0.0],
        [1.0 + gap, 0.0, 0.0],
    ];
    let mut s = bare("short-cable", nodes, vec![1, 3]);
    s.bars = vec![bar(1, 2), bar(3, 4)];
    s.cables = vec![cable(&s, 2, 4, 1000.0, 0.5)];
    s.gravity = Some([0.0, 0.0, -9.81]);
    s.velocities = Some(vec![[0.0; 3], [0.0; 3], [0.0; 3], [0.0, 0.2, 0.0]]);
    s
}

/// One free bar of 1 m and 1 kg along x spinning about z at `omega` rad/s.
pub fn spinning_bar(omega: f64) -> Scene {
    let mut s = bare("spin", vec![[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]], vec![]);
    s.bars = vec![bar(1, 2)];
    let v = omega * 0.5;
    s.velocities = Some(vec![[0.0, -v, 0.0], [0.0, v, 0.0]]);
    s
}
