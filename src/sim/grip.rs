//! Friction grips between steps. The grips (`Inputs::grip`) are held over a step; after
//! each step that is kept, every grip on a shape whose friction sticks takes its next mode
//! and anchor at the step's end ([`crate::contact::grip::next`]). Where a grip's switching
//! function changes sign inside a step, `events` splits the step there first, so the
//! switch happens where it belongs.

use nalgebra::Vector3;

use super::Simulation;
use crate::contact::grip::{self, Touch};
use crate::contact::Grip;
use crate::dynamics;
use crate::model::terrain::Terrain;
use crate::model::Model;

/// The switching function of one grip: a bar end on a shape whose friction sticks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct GripSwitch {
    /// Index into `Inputs::grip`.
    pub slot: usize,
    /// The bar end (its capsule end's centre).
    pub end: usize,
    /// The terrain shape.
    pub shape: usize,
    /// The capsule's radius, m.
    pub radius: f64,
}

/// A switch that a located event cut a step at: its grip changes there whatever the sign
/// at the step's end, which a step's error may leave just short of the switch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Cut {
    /// Grip switch `j` (index into the grip switches).
    Grip(usize),
    /// A bar end starts (`touching`) or stops touching a shape.
    Touch {
        end: usize,
        shape: usize,
        touching: bool,
    },
}

/// Every grip of `model` that can act: a moving bar end on a shape whose friction sticks.
pub(super) fn grip_switches(model: &Model) -> Vec<GripSwitch> {
    let Some(terrain) = &model.terrain else {
        return Vec::new();
    };
    // End by end, so that the grips of one end follow each other.
    let mut out = Vec::new();
    for (c, cap) in terrain.capsules.iter().enumerate() {
        for (i, end) in cap.ends.iter().enumerate() {
            for (shape, &sticks) in terrain.sticks.iter().enumerate() {
                if let (true, Some(end)) = (sticks, *end) {
                    out.push(GripSwitch {
                        slot: terrain.grip(c, shape, i),
                        end,
                        shape,
                        radius: cap.radius,
                    });
                }
            }
        }
    }
    out
}

/// Calls `with(touch)` for the contact of the sphere at `x` (moving with `v`) on the
/// switch's shape, `None` if it does not touch; `touching` counts a sphere within
/// round-off of the surface as touching (an onset just located).
#[inline]
fn touching<R>(
    s: &GripSwitch,
    terrain: &Terrain,
    (x, v): (&Vector3<f64>, &Vector3<f64>),
    touching: bool,
    with: impl FnOnce(Option<&Touch>) -> R,
) -> R {
    let (shape, _) = &terrain.shapes[s.shape];
    match shape.distance(x) {
        Some((phi, normal)) if s.radius - phi > 0.0 || touching => with(Some(&Touch {
            depth: (s.radius - phi).max(f64::MIN_POSITIVE),
            normal: &normal,
            x,
            v,
        })),
        _ => with(None),
    }
}

/// The grip's switching function at `(x, v)` (`f64::MAX` where it does not touch: the
/// contact's own switch watches that).
#[inline]
pub(super) fn value(
    s: &GripSwitch,
    terrain: &Terrain,
    grips: &[Grip],
    x: &Vector3<f64>,
    v: &Vector3<f64>,
) -> f64 {
    let grip = grips[s.slot];
    if grip == Grip::Free {
        return f64::MAX;
    }
    let law = &terrain.shapes[s.shape].1;
    touching(s, terrain, (x, v), false, |t| {
        t.map_or(f64::MAX, |t| grip::switch(law, t, grip, terrain.trail))
    })
}

impl Simulation {
    /// Moves every grip on to the current state (after a kept step, or a new state;
    /// `at_cut` if a located event cut the step short, which then switches the grips whose
    /// switches it crossed). Values the integrator carries were computed with the old
    /// grips: any change drops them (a grip only changes where its force law does).
    pub(super) fn update_grips(&mut self, at_cut: bool) {
        let Some(terrain) = &self.model.terrain else {
            return;
        };
        let mut moved = false;
        let half = self.state.y.len() / 2;
        let (q, qd) = self.state.y.split_at(half);
        let coords = &self.model.coords;
        let cuts = if at_cut { self.events.cuts() } else { &[] };
        let events = &self.events;
        let marked = cuts.is_empty() && events.marks_hold_at(&self.state.y);
        let mut at: Option<(usize, Vector3<f64>, Vector3<f64>)> = None;
        for (j, s) in events.grip_switches().iter().enumerate() {
            let grip = &mut self.inputs.grip[s.slot];
            // A free end stays free where the signs at the step's end, which the events
            // took, say it is far or apart; else where it fails a bounds test (not a
            // distance). A held grip is always moved on (they are few).
            if *grip == Grip::Free && marked && events.stays_free(j) {
                continue;
            }
            let (shape, law) = &terrain.shapes[s.shape];
            let x = match at {
                Some((end, x, _)) if end == s.end => x,
                _ => coords.end_vector(s.end, q, true),
            };
            if *grip == Grip::Free && cuts.is_empty() && !shape.may_touch(&x, &x, s.radius) {
                continue;
            }
            let v = match at {
                Some((end, _, v)) if end == s.end => v,
                _ => coords.end_vector(s.end, qd, false),
            };
            at = Some((s.end, x, v));
            let switched = cuts.contains(&Cut::Grip(j));
            let onset = cuts.iter().find_map(|c| match *c {
                Cut::Touch {
                    end,
                    shape,
                    touching,
                } if end == s.end && shape == s.shape => Some(touching),
                _ => None,
            });
            let next = if onset == Some(false) {
                Grip::Free
            } else {
                touching(s, terrain, (&x, &v), onset == Some(true), |t| {
                    grip::next(law, t, *grip, switched, terrain.trail)
                })
            };
            moved |= next != *grip;
            *grip = next;
        }
        if moved {
            self.integrator.invalidate();
            self.stepped_inputs.grip.copy_from_slice(&self.inputs.grip);
        }
    }

    /// After a trial step of `h` from `t` (to the current state): the time into it of the
    /// earliest switch to locate, the grips' included (those with the accelerations at both
    /// ends, evaluated here only where a grip's sign changed).
    pub(super) fn locate_switch(&mut self, t: f64, h: f64) -> Option<f64> {
        let earliest = self
            .events
            .locate(&self.model, &self.inputs, &self.state.y, h, &self.ws);
        if !self.events.grips_changed() {
            return earliest;
        }
        let half = self.state.y.len() / 2;
        let (y0, acc0, acc1) = self.events.acceleration_buffers();
        let (q0, v0) = y0.split_at(half);
        dynamics::accelerations(&self.model, &self.inputs, t, q0, v0, &mut self.ws, acc0);
        let (q1, v1) = self.state.y.split_at(half);
        dynamics::accelerations(&self.model, &self.inputs, t + h, q1, v1, &mut self.ws, acc1);
        let earliest = self
            .events
            .locate_grips(&self.model, &self.inputs, h, earliest);
        // No cut shorter than a step may be (the time must move: `StepSizeUnderflow`).
        let shortest = 1e-13 * t.abs().max(1.0);
        earliest
            .map(|theta| theta.max(shortest))
            .filter(|&theta| theta < h)
    }

    /// The friction grips (`Inputs::grip`).
    pub fn grips(&self) -> &[Grip] {
        &self.inputs.grip
    }

    /// Replaces the grips (from a snapshot, after [`Simulation::set_state`]) and
    /// re-evaluates the outputs.
    pub fn set_grips(&mut self, grips: &[Grip]) {
        assert_eq!(grips.len(), self.inputs.grip.len(), "grip count");
        self.inputs.grip.copy_from_slice(grips);
        self.integrator.invalidate();
        self.refresh();
    }

    /// Lets every grip go, then grips where the state touches (a state set from outside).
    pub(super) fn reset_grips(&mut self) {
        self.inputs.grip.fill(Grip::Free);
        self.update_grips(false);
    }
}
