//! Terrain switches too far from their shapes to change sign before a bar end has moved
//! half the terrain's margin: their signs are positive without computing them.

use nalgebra::Vector3;

use super::{Events, Point, Switch};
use crate::contact::{Proximity, Shape};
use crate::sim::grip::GripSwitch;

/// Brings the far marks of `switches` (by index) up to the bar-end positions `x`; whether
/// it marked anew.
pub(super) fn mark_far(
    switches: &[Switch],
    shapes: &[Shape],
    x: &[Vector3<f64>],
    margin: f64,
    near: &mut Proximity,
) -> bool {
    let at = |p: Point| match p {
        Point::End(e) => x[e],
        Point::Fixed(x) => x,
    };
    near.update(x, margin, switches.len(), |i, grow| match switches[i] {
        Switch::TerrainEnd {
            at: p,
            shape,
            radius,
        } => {
            let p = at(p);
            !shapes[shape].may_touch(&p, &p, radius + grow)
        }
        Switch::TerrainSide {
            a,
            b,
            shape,
            radius,
        } => !shapes[shape].may_touch(&at(a), &at(b), radius + grow),
        Switch::Cable { .. } | Switch::Ground { .. } => false,
    })
}

/// For each grip, the index of its end's touch switch on its shape.
pub(super) fn grip_touches(switches: &[Switch], grips: &[GripSwitch]) -> Vec<usize> {
    grips
        .iter()
        .map(|g| {
            let touch = |s: &Switch| {
                matches!(*s, Switch::TerrainEnd { at: Point::End(e), shape, .. }
                    if e == g.end && shape == g.shape)
            };
            switches
                .iter()
                .position(touch)
                .expect("a grip's end has a touch switch")
        })
        .collect()
}

impl Events {
    /// Brings the far marks up to the step's end positions (`end`) or its start's.
    pub(super) fn mark_far(&mut self, end: bool) {
        if self.margin > 0.0 {
            let x = if end { &self.x1 } else { &self.x0 };
            if mark_far(&self.switches, &self.shapes, x, self.margin, &mut self.near) {
                self.near_grips.clear();
                let near = (0..self.grips.len()).filter(|&j| !self.near.is_far(self.grip_touch[j]));
                self.near_grips.extend(near);
            }
        }
    }

    /// Whether the far marks are those of the state `y` (the end of the last step
    /// located, where nothing crossed).
    pub(in crate::sim) fn marks_hold_at(&self, y: &[f64]) -> bool {
        self.end_known && self.margin > 0.0 && self.y1 == y
    }

    /// Whether free grip `j` stays free at the end of the last step located (where
    /// [`Events::marks_hold_at`] the current state): its end is marked far from its shape,
    /// or its touch switch is positive there (`φ − r > 0`: not touching).
    pub(in crate::sim) fn stays_free(&self, j: usize) -> bool {
        let touch = self.grip_touch[j];
        self.near.is_far(touch) || self.positive1[touch]
    }
}
