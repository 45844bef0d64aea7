//! The terrain as the step sees it: each shape with its penalty law, and each bar as a
//! capsule between the nodes it joins.

use crate::contact::{Grid, Penalty, Shape};
use crate::scene::{FrictionModel, TerrainKind, TerrainSpec};

/// A bar's capsule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// Bar index.
    pub bar: usize,
    /// Its nodes (0-based).
    pub nodes: [usize; 2],
    /// The bar ends that carry them (`None` at a pinned node: its pin takes the force).
    pub ends: [Option<usize>; 2],
    /// Radius, m.
    pub radius: f64,
}

/// Terrain shapes and the capsules that touch them.
#[derive(Debug, Clone, PartialEq)]
pub struct Terrain {
    /// Shapes in scene order, each with its contact law.
    pub shapes: Vec<(Shape, Penalty)>,
    /// Every bar whose capsule can move (a bar with both ends pinned never touches).
    pub capsules: Vec<Capsule>,
    /// Per shape, whether friction at the capsules' ends sticks (a grip per end).
    pub sticks: Vec<bool>,
    /// How far beyond touching a capsule is watched, m: contacts farther away are skipped
    /// until a node has moved half of it ([`crate::contact::Proximity`]).
    pub margin: f64,
    /// How far a slip's anchor trails its point, m ([`crate::contact::grip`]): a
    /// five-hundredth of the margin (a ten-thousandth of the mean bar unless a radius is
    /// wider), 0.1 mm for metre-long bars: friction follows a turning slide within a few.
    pub trail: f64,
}

impl Terrain {
    /// The terrain of validated specs for the given capsules.
    pub fn new(specs: &[TerrainSpec], capsules: Vec<Capsule>, margin: f64) -> Self {
        let shapes = specs
            .iter()
            .map(|t| {
                let penalty = Penalty {
                    stiffness: t.stiffness,
                    damping: t.damping,
                    friction: t.friction,
                    slip_velocity: t.slip_velocity,
                };
                (shape(t), penalty)
            })
            .collect();
        let sticks = specs
            .iter()
            .map(|t| t.friction_model == FrictionModel::StickSlip)
            .collect();
        Self {
            shapes,
            capsules,
            sticks,
            margin,
            trail: margin / 500.0,
        }
    }

    /// The number of grips (friction states): one per capsule end and shape.
    pub fn grips(&self) -> usize {
        2 * self.capsules.len() * self.shapes.len()
    }

    /// The grip of capsule `c`'s end `end` on shape `shape`.
    #[inline]
    pub fn grip(&self, c: usize, shape: usize, end: usize) -> usize {
        2 * (c * self.shapes.len() + shape) + end
    }
}

/// The shape of a validated spec.
pub fn shape(t: &TerrainSpec) -> Shape {
    match t.kind {
        TerrainKind::Plane => Shape::plane(
            t.point.expect("validated"),
            t.normal.unwrap_or([0.0, 0.0, 1.0]),
        ),
        TerrainKind::Box => Shape::cuboid(
            t.center.expect("validated"),
            t.size.expect("validated"),
            t.yaw.unwrap_or(0.0),
        ),
        TerrainKind::Heightfield => Shape::Heightfield(Grid::new(
            t.origin.expect("validated"),
            t.spacing.expect("validated"),
            t.heights.as_ref().expect("validated"),
        )),
    }
}

/// Bar–bar contact: every bar's capsule against every other that shares no node with it.
#[derive(Debug, Clone, PartialEq)]
pub struct Collisions {
    /// The contact law of every pair.
    pub law: Penalty,
    /// Every bar's capsule, in bar order (static bars too: moving bars hit them).
    pub capsules: Vec<Capsule>,
    /// How far beyond touching the broad phase keeps a pair, m: it runs again once a node
    /// has moved half of it.
    pub margin: f64,
}
