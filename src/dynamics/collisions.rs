//! Stage 2's bar–bar contact: the broad phase (sweep and prune over the capsules' bounds)
//! finds the pairs whose boxes overlap, the narrow phase their closest points; a pair
//! closer than the sum of its radii pushes apart along the line between those points. A
//! force at fraction s of a bar splits onto its ends as `(1 − s, s)`, as terrain's does.
//!
//! The broad phase runs only when a node has moved more than half a margin since it last
//! ran: it keeps the pairs closer than their radii plus the margin, and no other pair can
//! touch before then (each point of a bar has moved less than half the margin). The kept
//! pairs are sorted, so the forces add up in the same order whenever the list was built:
//! a restored state gives the same bits.

use nalgebra::{Matrix3, Vector3};

use crate::contact::segments::{capsule_bounds, closest_params, overlapping_pairs, Bounds};
use crate::model::terrain::{Capsule, Collisions};

/// The broad phase's buffers and what the last evaluation found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CollisionScratch {
    /// Each capsule's bounds, grown by half the margin.
    boxes: Vec<Bounds>,
    /// Capsules sorted along the sweep axis (kept between evaluations: almost sorted).
    order: Vec<u32>,
    /// Pairs closer than their radii plus the margin at the last broad phase, sorted.
    near: Vec<(u32, u32)>,
    /// Node positions at the last broad phase (empty: none yet).
    anchor: Vec<Vector3<f64>>,
    /// Pairs whose capsules overlap.
    pub contacts: u32,
    /// The deepest interpenetration of two capsules, m (0 without contact).
    pub max_penetration: f64,
}

impl CollisionScratch {
    /// Buffers for `n` capsules.
    pub fn new(n: usize) -> Self {
        Self {
            boxes: vec![[[0.0; 2]; 3]; n],
            order: (0..n as u32).collect(),
            near: Vec::with_capacity(4 * n),
            anchor: Vec::new(),
            contacts: 0,
            max_penetration: 0.0,
        }
    }

    /// Pairs kept by the last broad phase.
    pub fn kept(&self) -> usize {
        self.near.len()
    }

    /// Makes the next evaluation run the broad phase (to time it).
    pub fn forget(&mut self) {
        self.anchor.clear();
    }

    /// Whether the pairs kept hold at the node positions `x`: no node has moved half the
    /// margin since the broad phase ran.
    fn holds(&self, x: &[Vector3<f64>], margin: f64) -> bool {
        let limit = 0.25 * margin * margin;
        self.anchor.len() == x.len()
            && self
                .anchor
                .iter()
                .zip(x)
                .all(|(a, b)| (a - b).norm_squared() < limit)
    }
}

/// One pair's contact: the force on capsule i (capsule j takes its opposite), at `s` along
/// i and `t` along j, and the depth; `None` when they do not touch.
#[inline]
pub fn pair_force(
    c: &Collisions,
    pair: [&Capsule; 2],
    x: [[&Vector3<f64>; 2]; 2],
    v: [[&Vector3<f64>; 2]; 2],
) -> Option<(Vector3<f64>, f64, f64, f64)> {
    let (s, t) = closest_params(x[0][0], x[0][1], x[1][0], x[1][1]);
    let p = x[0][0] + (x[0][1] - x[0][0]) * s;
    let q = x[1][0] + (x[1][1] - x[1][0]) * t;
    let gap = p - q;
    let distance = gap.norm();
    let depth = pair[0].radius + pair[1].radius - distance;
    if depth <= 0.0 {
        return None;
    }
    let normal = if distance > 0.0 {
        gap / distance
    } else {
        // Axes that cross: push along their common normal.
        let n = (x[0][1] - x[0][0]).cross(&(x[1][1] - x[1][0]));
        if n.norm() > 0.0 {
            n.normalize()
        } else {
            Vector3::z()
        }
    };
    let vp = v[0][0] + (v[0][1] - v[0][0]) * s;
    let vq = v[1][0] + (v[1][1] - v[1][0]) * t;
    Some((c.law.force(depth, &normal, &(vp - vq)), s, t, depth))
}

/// Whether two bars share a node (they are joined, not colliding).
#[inline]
fn joined(a: &Capsule, b: &Capsule) -> bool {
    a.nodes.iter().any(|n| b.nodes.contains(n))
}

/// The broad phase at the node positions `x`: keeps the pairs that share no node and are
/// closer than their radii plus the margin, sorted.
fn broad_phase(c: &Collisions, x: &[Vector3<f64>], scratch: &mut CollisionScratch) {
    let grow = 0.5 * c.margin;
    for (b, cap) in scratch.boxes.iter_mut().zip(&c.capsules) {
        let [n0, n1] = cap.nodes;
        *b = capsule_bounds(&x[n0], &x[n1], cap.radius + grow);
    }
    let near = &mut scratch.near;
    near.clear();
    overlapping_pairs(&scratch.boxes, &mut scratch.order, |i, j| {
        let (a, b) = (&c.capsules[i], &c.capsules[j]);
        let fixed = |c: &Capsule| c.ends.iter().all(Option::is_none);
        if joined(a, b) || (fixed(a) && fixed(b)) {
            return;
        }
        let (p, q) = (
            [a.nodes[0], a.nodes[1]].map(|n| &x[n]),
            [b.nodes[0], b.nodes[1]].map(|n| &x[n]),
        );
        let (s, t) = closest_params(p[0], p[1], q[0], q[1]);
        let gap = (p[0] + (p[1] - p[0]) * s) - (q[0] + (q[1] - q[0]) * t);
        if gap.norm() < a.radius + b.radius + c.margin {
            near.push((i as u32, j as u32));
        }
    });
    near.sort_unstable();
    scratch.anchor.clear();
    scratch.anchor.extend_from_slice(x);
}

/// Calls `each(i, j, f, s, t, depth)` for every overlapping pair at the node positions and
/// velocities `(x, ẋ)`.
#[inline]
pub fn for_each_contact(
    c: &Collisions,
    nodes: (&[Vector3<f64>], &[Vector3<f64>]),
    scratch: &mut CollisionScratch,
    mut each: impl FnMut(usize, usize, Vector3<f64>, f64, f64, f64),
) {
    let (x, v) = nodes;
    if !scratch.holds(x, c.margin) {
        broad_phase(c, x, scratch);
    }
    for &(i, j) in &scratch.near {
        let (i, j) = (i as usize, j as usize);
        let (a, b) = (&c.capsules[i], &c.capsules[j]);
        let at = |cap: &Capsule, y: &[Vector3<f64>]| [cap.nodes[0], cap.nodes[1]].map(|n| y[n]);
        let (xa, xb, va, vb) = (at(a, x), at(b, x), at(a, v), at(b, v));
        let hit = pair_force(
            c,
            [a, b],
            [[&xa[0], &xa[1]], [&xb[0], &xb[1]]],
            [[&va[0], &va[1]], [&vb[0], &vb[1]]],
        );
        if let Some((f, s, t, depth)) = hit {
            each(i, j, f, s, t, depth);
        }
    }
}

/// Every pair's forces onto the bar ends through `add(end, f)`, and the contact count and
/// deepest interpenetration into `scratch`.
#[inline]
pub fn apply(
    c: &Collisions,
    nodes: (&[Vector3<f64>], &[Vector3<f64>]),
    scratch: &mut CollisionScratch,
    mut add: impl FnMut(usize, Vector3<f64>),
) {
    let (mut contacts, mut deepest) = (0, 0.0f64);
    for_each_contact(c, nodes, scratch, |i, j, f, s, t, depth| {
        for (cap, f, u) in [(&c.capsules[i], f, s), (&c.capsules[j], -f, t)] {
            if let Some(e) = cap.ends[0] {
                add(e, f * (1.0 - u));
            }
            if let Some(e) = cap.ends[1] {
                add(e, f * u);
            }
        }
        contacts += 1;
        deepest = deepest.max(depth);
    });
    scratch.contacts = contacts;
    scratch.max_penetration = deepest;
}

/// Stored penalty energy `½ k d²` of every overlapping pair at the node positions `x`, J.
pub fn energy(c: &Collisions, x: &[Vector3<f64>], scratch: &mut CollisionScratch) -> f64 {
    let zero = vec![Vector3::zeros(); x.len()];
    let mut total = 0.0;
    for_each_contact(c, (x, &zero), scratch, |_, _, _, _, _, depth| {
        total += 0.5 * c.law.stiffness * depth * depth;
    });
    total
}

/// `∂F/∂x` and `∂F/∂ẋ` of the end forces of one touching pair (blocks over the four ends
/// `[i.a, i.b, j.a, j.b]`), by central differences as for terrain.
pub fn pair_derivatives(
    c: &Collisions,
    pair: [&Capsule; 2],
    x: [Vector3<f64>; 4],
    v: [Vector3<f64>; 4],
) -> [[[Matrix3<f64>; 4]; 4]; 2] {
    let forces = |x: &[Vector3<f64>; 4], v: &[Vector3<f64>; 4]| {
        let mut out = [Vector3::zeros(); 4];
        let hit = pair_force(
            c,
            pair,
            [[&x[0], &x[1]], [&x[2], &x[3]]],
            [[&v[0], &v[1]], [&v[2], &v[3]]],
        );
        if let Some((f, s, t, _)) = hit {
            out = [f * (1.0 - s), f * s, -f * (1.0 - t), -f * t];
        }
        out
    };
    let mut out = [[[Matrix3::zeros(); 4]; 4]; 2];
    for (which, blocks) in out.iter_mut().enumerate() {
        for col in 0..4 {
            for k in 0..3 {
                let (mut xp, mut xm, mut vp, mut vm) = (x, x, v, v);
                let base = if which == 0 { x[col][k] } else { v[col][k] };
                let h = 1e-7 * base.abs().max(1e-3);
                let (plus, minus) = if which == 0 {
                    (&mut xp, &mut xm)
                } else {
                    (&mut vp, &mut vm)
                };
                plus[col][k] += h;
                minus[col][k] -= h;
                let (fp, fm) = (forces(&xp, &vp), forces(&xm, &vm));
                for row in 0..4 {
                    blocks[row][col].set_column(k, &((fp[row] - fm[row]) / (2.0 * h)));
                }
            }
        }
    }
    out
}
