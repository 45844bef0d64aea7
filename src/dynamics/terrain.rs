//! Stage 2's terrain contact: every capsule against every shape it may touch, each
//! contact's penalty force split onto the bar's two ends. A force `f` at `a + s (b − a)`
//! is the generalized force `(1 − s) f` on end a and `s f` on end b: the same resultant
//! and the same moment about any point, and no work on the bar's length (see
//! docs/design.md). The ends of a shape whose friction sticks follow their grips
//! ([`crate::contact::grip`]).

use nalgebra::{Matrix3, Vector3};

use crate::contact::{capsule_contacts, grip, Grip, Proximity};
use crate::model::terrain::{Capsule, Terrain};

/// What one shape does to the structure: its total force and how many points touch it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ShapeLoad {
    /// Total force on the structure, N.
    pub force: Vector3<f64>,
    /// Contact points that penetrate it.
    pub contacts: u32,
}

/// Calls `each(s, f)` for every contact force of one capsule on shape `k`, with its end
/// nodes at `x` moving with `v`, its ends held by `grips` (the capsule's, shape by shape).
#[inline]
pub fn shape_forces(
    terrain: &Terrain,
    k: usize,
    (x, v): ([&Vector3<f64>; 2], [&Vector3<f64>; 2]),
    radius: f64,
    grips: &[Grip],
    mut each: impl FnMut(f64, Vector3<f64>),
) {
    let (shape, law) = &terrain.shapes[k];
    let sticks = terrain.sticks[k];
    capsule_contacts(shape, x[0], x[1], radius, |c| {
        let f = match c.end {
            Some(i) if sticks => {
                let touch = grip::Touch {
                    depth: c.depth,
                    normal: &c.normal,
                    x: x[i],
                    v: v[i],
                };
                grip::force(law, &touch, grips[2 * k + i], terrain.trail)
            }
            _ => law.force(c.depth, &c.normal, &(v[0] + (v[1] - v[0]) * c.s)),
        };
        each(c.s, f);
    });
}

/// Calls `each(shape, s, f)` for every contact force of one capsule on every shape (as
/// [`shape_forces`]).
#[inline]
pub fn capsule_forces(
    terrain: &Terrain,
    x: [&Vector3<f64>; 2],
    v: [&Vector3<f64>; 2],
    radius: f64,
    grips: &[Grip],
    mut each: impl FnMut(usize, f64, Vector3<f64>),
) {
    for k in 0..terrain.shapes.len() {
        shape_forces(terrain, k, (x, v), radius, grips, |s, f| each(k, s, f));
    }
}

/// The grips of capsule `c` (its ends on every shape, shape by shape).
#[inline]
pub fn capsule_grips<'g>(terrain: &Terrain, grips: &'g [Grip], c: usize) -> &'g [Grip] {
    let n = 2 * terrain.shapes.len();
    &grips[c * n..(c + 1) * n]
}

/// Where one capsule's contact forces go.
pub trait TerrainSink {
    /// Adds `f` to bar end `end`.
    fn add(&mut self, end: usize, f: Vector3<f64>);
    /// Notes a contact force `f` of shape `shape`.
    fn shape(&mut self, shape: usize, f: Vector3<f64>);
}

/// Brings the marks of the capsule–shape pairs (`c · shapes + k`) too far to touch up to
/// the node positions `x`.
#[inline]
pub fn mark_far(terrain: &Terrain, x: &[Vector3<f64>], near: &mut Proximity) {
    let n = terrain.shapes.len();
    let _ = near.update(x, terrain.margin, terrain.capsules.len() * n, |i, grow| {
        let cap = &terrain.capsules[i / n];
        let [a, b] = cap.nodes;
        !terrain.shapes[i % n]
            .0
            .may_touch(&x[a], &x[b], cap.radius + grow)
    });
}

/// Every capsule's contact forces, for the node positions and velocities `(x, ẋ)`, on the
/// shapes it is not marked far from (`near`, brought up to `x` by [`mark_far`]), capsule by
/// capsule and shape by shape.
#[inline]
pub fn apply(
    terrain: &Terrain,
    grips: &[Grip],
    near: &Proximity,
    nodes: (&[Vector3<f64>], &[Vector3<f64>]),
    sink: &mut impl TerrainSink,
) {
    let n = terrain.shapes.len();
    for &i in near.near() {
        let (c, k) = (i as usize / n, i as usize % n);
        let Capsule {
            nodes: [a, b],
            ends,
            radius,
            ..
        } = terrain.capsules[c];
        let (x, v) = ([&nodes.0[a], &nodes.0[b]], [&nodes.1[a], &nodes.1[b]]);
        let grips = capsule_grips(terrain, grips, c);
        shape_forces(terrain, k, (x, v), radius, grips, |s, f| {
            if let Some(e) = ends[0] {
                sink.add(e, f * (1.0 - s));
            }
            if let Some(e) = ends[1] {
                sink.add(e, f * s);
            }
            sink.shape(k, f);
        });
    }
}

/// `∂F/∂x` and `∂F/∂ẋ` of one capsule's end forces (6 × 6 blocks `[a, b] × [a, b]`) by
/// central differences: the contact set is piecewise smooth, and the analyses and the
/// implicit method need it only near a state.
pub fn capsule_derivatives(
    terrain: &Terrain,
    x: [Vector3<f64>; 2],
    v: [Vector3<f64>; 2],
    radius: f64,
    grips: &[Grip],
) -> [[[Matrix3<f64>; 2]; 2]; 2] {
    let forces = |x: &[Vector3<f64>; 2], v: &[Vector3<f64>; 2]| {
        let mut f = [Vector3::zeros(); 2];
        capsule_forces(
            terrain,
            [&x[0], &x[1]],
            [&v[0], &v[1]],
            radius,
            grips,
            |_, s, g| {
                f[0] += g * (1.0 - s);
                f[1] += g * s;
            },
        );
        f
    };
    let mut out = [[[Matrix3::zeros(); 2]; 2]; 2];
    for (which, blocks) in out.iter_mut().enumerate() {
        for col_end in 0..2 {
            for k in 0..3 {
                let (mut xp, mut xm, mut vp, mut vm) = (x, x, v, v);
                let base = if which == 0 {
                    x[col_end][k]
                } else {
                    v[col_end][k]
                };
                let h = 1e-7 * base.abs().max(1e-3);
                if which == 0 {
                    xp[col_end][k] += h;
                    xm[col_end][k] -= h;
                } else {
                    vp[col_end][k] += h;
                    vm[col_end][k] -= h;
                }
                let (fp, fm) = (forces(&xp, &vp), forces(&xm, &vm));
                for row_end in 0..2 {
                    let d = (fp[row_end] - fm[row_end]) / (2.0 * h);
                    blocks[row_end][col_end].set_column(k, &d);
                }
            }
        }
    }
    out
}

/// Stored penalty energy `½ k d²` of every contact point at the node positions `x`, and
/// that of the sticking springs at the velocities `ẋ`, J.
pub fn energy(terrain: &Terrain, grips: &[Grip], x: &[Vector3<f64>], v: &[Vector3<f64>]) -> f64 {
    let mut total = 0.0;
    for (ci, cap) in terrain.capsules.iter().enumerate() {
        let [a, b] = cap.nodes;
        let grips = capsule_grips(terrain, grips, ci);
        for (k, (shape, law)) in terrain.shapes.iter().enumerate() {
            capsule_contacts(shape, &x[a], &x[b], cap.radius, |c| {
                total += 0.5 * law.stiffness * c.depth * c.depth;
                if let Some(i) = c.end {
                    let n = cap.nodes[i];
                    let touch = grip::Touch {
                        depth: c.depth,
                        normal: &c.normal,
                        x: &x[n],
                        v: &v[n],
                    };
                    total += grip::energy(law, &touch, grips[2 * k + i]);
                }
            });
        }
    }
    total
}
