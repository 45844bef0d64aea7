//! The contacts of a state as a list: where each contact force acts and how large it is,
//! from terrain (every capsule–shape contact point), collisions (each touching pair, one
//! point and force per bar) and the `[ground]` (each node that touches it). The forces are
//! those the step applies, by the same laws and with the same grips; nothing here is on
//! the step's path (a caller lists contacts between steps, to show them).
//!
//! A point is where the capsule's surface meets what it touches: the point on the bar's
//! axis moved by the bar's radius against the contact normal (the node itself for a line
//! bar). For a shape that normal is the shape's outward normal at the axis point; for a
//! pair, the line between their axes' closest points.

use nalgebra::Vector3;

use super::collisions::{for_each_contact, CollisionScratch};
use super::terrain::{capsule_forces, capsule_grips};
use crate::contact::Grip;
use crate::model::Model;

/// What a contact point touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactKind {
    /// Bar `bar` (0-based) on terrain shape `shape` (0-based, scene order).
    Terrain {
        /// The bar.
        bar: usize,
        /// The shape.
        shape: usize,
    },
    /// Bar `bar` pushed by bar `other` (both 0-based).
    Collision {
        /// The bar the force acts on.
        bar: usize,
        /// The bar that pushes it.
        other: usize,
    },
    /// Node `node` (0-based) on the `[ground]` plane.
    Ground {
        /// The node.
        node: usize,
    },
}

/// One contact force on the structure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    /// Where it acts, m.
    pub point: Vector3<f64>,
    /// The force on the structure there (normal force and friction), N.
    pub force: Vector3<f64>,
    /// What touches what.
    pub kind: ContactKind,
}

/// Every contact of `model` at the node positions `x` and velocities `v` (all nodes,
/// 0-based), with the terrain's friction held by `grips` ([`super::Inputs::grip`]):
/// terrain contacts capsule by capsule and shape by shape, then collisions pair by pair
/// (the force on the first bar, then on the second), then the ground node by node.
pub fn contact_points(
    model: &Model,
    grips: &[Grip],
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
) -> Vec<ContactPoint> {
    let mut out = Vec::new();
    if let Some(terrain) = &model.terrain {
        for (c, cap) in terrain.capsules.iter().enumerate() {
            let [a, b] = cap.nodes;
            let grips = capsule_grips(terrain, grips, c);
            let (xs, vs) = ([&x[a], &x[b]], [&v[a], &v[b]]);
            capsule_forces(terrain, xs, vs, cap.radius, grips, |k, s, f| {
                let axis = x[a] + (x[b] - x[a]) * s;
                let normal = terrain.shapes[k].0.distance(&axis).map(|(_, n)| n);
                out.push(ContactPoint {
                    point: axis - normal.unwrap_or_else(Vector3::zeros) * cap.radius,
                    force: f,
                    kind: ContactKind::Terrain {
                        bar: cap.bar,
                        shape: k,
                    },
                });
            });
        }
    }
    if let Some(collisions) = &model.collisions {
        let mut scratch = CollisionScratch::new(collisions.capsules.len());
        for_each_contact(collisions, (x, v), &mut scratch, |i, j, f, s, t, _| {
            let (ci, cj) = (&collisions.capsules[i], &collisions.capsules[j]);
            let along = |nodes: [usize; 2], u: f64| x[nodes[0]] + (x[nodes[1]] - x[nodes[0]]) * u;
            let (p, q) = (along(ci.nodes, s), along(cj.nodes, t));
            // From j towards i (zero for axes that cross: the points stay on the axes).
            let normal = (p - q).try_normalize(0.0).unwrap_or_else(Vector3::zeros);
            out.push(ContactPoint {
                point: p - normal * ci.radius,
                force: f,
                kind: ContactKind::Collision {
                    bar: ci.bar,
                    other: cj.bar,
                },
            });
            out.push(ContactPoint {
                point: q + normal * cj.radius,
                force: -f,
                kind: ContactKind::Collision {
                    bar: cj.bar,
                    other: ci.bar,
                },
            });
        });
    }
    if let Some(ground) = &model.ground {
        for (&(n, _), &r) in ground.nodes.iter().zip(&ground.radii) {
            let f = ground.force(&x[n], &v[n], r);
            if ground.penetration(&x[n], r) > 0.0 {
                out.push(ContactPoint {
                    point: x[n] - ground.normal * r,
                    force: f,
                    kind: ContactKind::Ground { node: n },
                });
            }
        }
    }
    out
}

/// Whether `model` declares any contact: terrain, collisions or the ground.
pub fn has_contacts(model: &Model) -> bool {
    model.terrain.is_some() || model.collisions.is_some() || model.ground.is_some()
}
