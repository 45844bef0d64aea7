//! Kinks located: the force laws switch where a cable goes slack or taut (`|s| = s₀`) and
//! where a contact point touches or leaves the ground (`n·x = h`). There the force is
//! continuous but its derivative jumps, and a step across such a point loses the method's
//! order. After a trial step the switching functions are compared at both ends; if one
//! changed sign, the earliest crossing is found by the Illinois method on a cubic Hermite
//! interpolant of the bar ends from `(q₀, q̇₀, q₁, q̇₁)` (O(h⁴), to 1e-12 of the step), and
//! the caller redoes the step in two parts, split at the crossing.
//!
//! Friction grips switch too (stick↔slip, see `grip`); their functions also need the
//! velocities, from the interpolant's derivative.
//!
//! Not located (documented limits): a switch crossed twice inside one step (no sign change
//! at its ends), the clamp `max(0, ·)` of cable and contact damping, and the friction law's
//! change at the slip velocity. The switching functions depend only on the state and the
//! inputs held over the step, so the split is deterministic.

use nalgebra::Vector3;

mod far;
mod grips;

use super::grip::{Cut, GripSwitch};
use super::locate::{crossing, hermite};
use crate::contact::{interior_excess, Grip, Proximity, Shape};
use crate::dynamics::{Inputs, Workspace};
use crate::model::effects::{CableLink, ForceEffect};
use crate::model::terrain::Terrain;
use crate::model::Model;

/// Crossings this close after the earliest, as a fraction of the step, happen with it.
const CUT_TIE: f64 = 1e-9;

/// Most events split off one step; the rest of the step is then taken whole.
pub const MAX_SPLITS: u32 = 8;

/// Crossings closer than this fraction of the step to either end are not split off (but a
/// grip's near the start, see [`GRIP_START`]): the kink there costs little (its error grows
/// with the square of that distance), a crossing just located lies this close to the start
/// of the next part, and a node grazing the ground would otherwise be chased into ever
/// shorter steps.
const EDGE: f64 = 1e-3;

/// The shortest cut at a grip's switch, as a fraction of the step. A grip changes its mode
/// where its switch crosses, even just after the start: left to the step's end, it would
/// change a whole step late.
const GRIP_START: f64 = 1e-6;

/// A point a switching function watches.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Point {
    /// A bar end (index into the model's ends).
    End(usize),
    /// A fixed (pinned, bar-less) node, m.
    Fixed(Vector3<f64>),
}

/// A cable's rest length.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Rest {
    Fixed(f64),
    /// Index into [`Inputs::rest_length`].
    Input(usize),
}

/// One switching function; its sign tells which branch of the force law is active.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Switch {
    /// `|x_b − x_a| − s₀`: positive while taut.
    Cable { a: Point, b: Point, rest: Rest },
    /// `n·x − h`: negative while in contact.
    Ground {
        end: usize,
        normal: Vector3<f64>,
        height: f64,
    },
    /// `φ(x) − r` of a capsule's end against terrain shape `shape`: negative in contact.
    TerrainEnd {
        at: Point,
        shape: usize,
        radius: f64,
    },
    /// Minus the largest excess depth of a capsule's side against a shape: negative once
    /// the side touches between the ends.
    TerrainSide {
        a: Point,
        b: Point,
        shape: usize,
        radius: f64,
    },
}

/// The switching functions of a model and the buffers to locate their crossings, sized
/// once. A step without a crossing costs one pass over the bar-end positions and a sign
/// per switch: the signs and positions at its end are those at the next step's start,
/// velocities and exact values are computed only once a sign has changed.
#[derive(Debug, Clone)]
pub struct Events {
    switches: Vec<Switch>,
    /// The terrain shapes the terrain switches name.
    shapes: Vec<Shape>,
    /// The terrain switches too far from their shapes to change sign soon, the terrain's
    /// margin (0: no terrain), and each grip's switch of touch (`far::grip_touches`).
    near: Proximity,
    margin: f64,
    grip_touch: Vec<usize>,
    /// The grips whose touch switch is not marked far.
    near_grips: Vec<usize>,
    /// The friction grips' switches, the terrain they are on, and their signs at both ends
    /// of the step (always taken with the velocities: the grips move between steps).
    grips: Vec<GripSwitch>,
    terrain: Option<Terrain>,
    grip0: Vec<bool>,
    grip1: Vec<bool>,
    /// The grips `grip1` was taken with.
    grips1: Vec<Grip>,
    /// Whether a grip's sign changed over the last step located: its crossing waits for
    /// the accelerations at both ends ([`Events::locate_grips`]).
    grips_changed: bool,
    /// Reduced accelerations at both ends of the step, for the grips' quintic.
    acc0: Vec<f64>,
    acc1: Vec<f64>,
    a0: Vec<Vector3<f64>>,
    a1: Vec<Vector3<f64>>,
    /// The grips' switches that the last [`Events::locate`] found crossed by the time it
    /// cut the step at (several at once where a structure is symmetric), with their times.
    crossed: Vec<(Cut, f64)>,
    cuts: Vec<Cut>,
    /// The state at the start of the current (part of a) step.
    pub y0: Vec<f64>,
    /// Signs (`> 0`) of the switching functions at `y0` and at the end of the last step.
    positive0: Vec<bool>,
    positive1: Vec<bool>,
    /// The state and the rest-length inputs `positive1` and `x1` belong to (valid while
    /// `end_known`).
    y1: Vec<f64>,
    rest1: Vec<f64>,
    end_known: bool,
    /// Bar-end positions and velocities at both ends of the step (velocities only after
    /// a sign change).
    x0: Vec<Vector3<f64>>,
    v0: Vec<Vector3<f64>>,
    x1: Vec<Vector3<f64>>,
    v1: Vec<Vector3<f64>>,
}

impl Events {
    /// The switching functions of the effects `model` declares.
    pub fn new(model: &Model) -> Self {
        let point = |link: &CableLink, i: usize| match link.ends[i] {
            Some(e) => Point::End(e),
            None => Point::Fixed(model.positions[link.nodes[i]]),
        };
        let cable = |link: &CableLink, rest: Rest| Switch::Cable {
            a: point(link, 0),
            b: point(link, 1),
            rest,
        };
        let mut switches = Vec::new();
        for effect in &model.pipeline.forces {
            match effect {
                ForceEffect::ElasticCables(cables) => {
                    for (link, _, rest) in cables {
                        switches.push(cable(link, Rest::Fixed(*rest)));
                    }
                }
                ForceEffect::DampedCables(cables) => {
                    for (link, _, rest, _) in cables {
                        switches.push(cable(link, Rest::Fixed(*rest)));
                    }
                }
                ForceEffect::ReeledCables(cables) => {
                    for (link, _, _, input) in cables {
                        switches.push(cable(link, Rest::Input(*input)));
                    }
                }
                ForceEffect::GroundContact(ground) => {
                    // A node touches as a sphere of its widest bar's radius.
                    for (&(_, end), &r) in ground.nodes.iter().zip(&ground.radii) {
                        switches.push(Switch::Ground {
                            end,
                            normal: ground.normal,
                            height: ground.height + r,
                        });
                    }
                }
                ForceEffect::Terrain(terrain) => {
                    for cap in &terrain.capsules {
                        let at = |i: usize| match cap.ends[i] {
                            Some(e) => Point::End(e),
                            None => Point::Fixed(model.positions[cap.nodes[i]]),
                        };
                        for (shape, (kind, _)) in terrain.shapes.iter().enumerate() {
                            let radius = cap.radius;
                            for i in 0..2 {
                                switches.push(Switch::TerrainEnd {
                                    at: at(i),
                                    shape,
                                    radius,
                                });
                            }
                            if !matches!(kind, Shape::Plane { .. }) {
                                switches.push(Switch::TerrainSide {
                                    a: at(0),
                                    b: at(1),
                                    shape,
                                    radius,
                                });
                            }
                        }
                    }
                }
                // Collision onsets are not located: a switch per pair would grow with the
                // square of the bars (see docs/contact.md).
                ForceEffect::Collisions(_) => {}
                ForceEffect::ForceDensityCables(_)
                | ForceEffect::NodeForces(_)
                | ForceEffect::ScriptedLoads(_)
                | ForceEffect::Gravity(_) => {}
            }
        }
        let n = model.state_len();
        let ends = model.coords.n_ends();
        let shapes = model.terrain.as_ref().map_or(Vec::new(), |t| {
            t.shapes.iter().map(|(s, _)| s.clone()).collect()
        });
        let grips = super::grip::grip_switches(model);
        Self {
            shapes,
            near: Proximity::default(),
            margin: model.terrain.as_ref().map_or(0.0, |t| t.margin),
            grip_touch: far::grip_touches(&switches, &grips),
            near_grips: Vec::with_capacity(grips.len()),
            terrain: model.terrain.clone().filter(|_| !grips.is_empty()),
            grip0: vec![false; grips.len()],
            grips1: Vec::with_capacity(grips.len()),
            grip1: vec![false; grips.len()],
            grips_changed: false,
            acc0: vec![0.0; if grips.is_empty() { 0 } else { n / 2 }],
            acc1: vec![0.0; if grips.is_empty() { 0 } else { n / 2 }],
            a0: vec![Vector3::zeros(); if grips.is_empty() { 0 } else { ends }],
            a1: vec![Vector3::zeros(); if grips.is_empty() { 0 } else { ends }],
            // Each switch and grip is crossed, and cut at, once per step at most.
            crossed: Vec::with_capacity(switches.len() + grips.len()),
            cuts: Vec::with_capacity(switches.len() + grips.len()),
            grips,
            positive0: vec![false; switches.len()],
            positive1: vec![false; switches.len()],
            switches,
            y0: vec![0.0; n],
            y1: vec![0.0; n],
            rest1: vec![0.0; model.reeled_start.len()],
            end_known: false,
            x0: vec![Vector3::zeros(); ends],
            v0: vec![Vector3::zeros(); ends],
            x1: vec![Vector3::zeros(); ends],
            v1: vec![Vector3::zeros(); ends],
        }
    }

    /// True when the model has no switching function (nothing to locate).
    pub fn is_empty(&self) -> bool {
        self.switches.is_empty() && self.grips.is_empty()
    }

    /// The grips' switches crossed by the time the last located event cut the step at.
    pub(super) fn cuts(&self) -> &[Cut] {
        &self.cuts
    }

    /// The grips that can act.
    pub(super) fn grip_switches(&self) -> &[GripSwitch] {
        &self.grips
    }

    /// Notes the state a step starts from: copies it and takes the switches' signs there
    /// (from the last step's end when that is this state, with the same inputs).
    pub fn start(&mut self, model: &Model, inputs: &Inputs, y: &[f64], ws: &Workspace) {
        ws.copy_in_halves(&mut self.y0, y);
        let at_end = self.end_known && self.y1 == y && self.rest1 == inputs.rest_length;
        if at_end {
            std::mem::swap(&mut self.x0, &mut self.x1);
            std::mem::swap(&mut self.positive0, &mut self.positive1);
        } else {
            end_positions(model, y, &mut self.x0, ws);
            self.mark_far(false);
            signs(
                &self.switches,
                (&self.shapes, &self.near),
                inputs,
                &self.x0,
                &mut self.positive0,
                ws,
            );
        }
        self.start_grips(model, inputs, &y[y.len() / 2..], at_end);
        self.end_known = false;
    }

    /// After a step of `h` from the noted start to `y`: the time from the start of the
    /// earliest sign change of a switching function that lies inside the step (not
    /// within [`EDGE`] of either end), if any. The time returned is just past the crossing.
    pub fn locate(
        &mut self,
        model: &Model,
        inputs: &Inputs,
        y: &[f64],
        h: f64,
        ws: &Workspace,
    ) -> Option<f64> {
        end_positions(model, y, &mut self.x1, ws);
        self.mark_far(true);
        signs(
            &self.switches,
            (&self.shapes, &self.near),
            inputs,
            &self.x1,
            &mut self.positive1,
            ws,
        );
        let (lo, hi) = (EDGE * h, (1.0 - EDGE) * h);
        let mut earliest: Option<f64> = None;
        let mut velocities = false;
        self.crossed.clear();
        self.cuts.clear();
        self.grips_changed = false;
        self.grips1.clear();
        if holding(inputs) {
            let half = y.len() / 2;
            self.grip_velocities(model, inputs, &y[half..], true);
            let mut signs = std::mem::take(&mut self.grip1);
            self.grip_signs(inputs, &self.x1, &self.v1, &mut signs);
            self.grip1 = signs;
            self.grips1.clone_from(&inputs.grip);
            // Only a switch turning negative changes a grip's mode.
            self.grips_changed = self.grip0.iter().zip(&self.grip1).any(|(&a, &b)| a && !b);
        }
        for (j, s) in self.switches.iter().enumerate() {
            if self.positive0[j] == self.positive1[j] {
                continue;
            }
            if !velocities {
                let half = y.len() / 2;
                end_velocities(model, &self.y0[half..], &mut self.v0);
                end_velocities(model, &y[half..], &mut self.v1);
                velocities = true;
            }
            let (g0, g1) = (
                value(s, &self.shapes, inputs, &self.x0),
                value(s, &self.shapes, inputs, &self.x1),
            );
            let theta = crossing(|c| self.along(s, inputs, c, h), g0, g1, h);
            if let Switch::TerrainEnd {
                at: Point::End(end),
                shape,
                ..
            } = *s
            {
                let touching = g1 < 0.0;
                self.crossed.push((
                    Cut::Touch {
                        end,
                        shape,
                        touching,
                    },
                    theta,
                ));
            }
            if theta > lo && theta < hi && earliest.is_none_or(|e| theta < e) {
                earliest = Some(theta);
            }
        }
        if !self.grips_changed {
            self.note_cuts(earliest, h);
        }
        if earliest.is_none() {
            ws.copy_in_halves(&mut self.y1, y);
            self.rest1.copy_from_slice(&inputs.rest_length);
            self.end_known = true;
        }
        earliest
    }

    /// The switch at time `theta` into the step, on the Hermite cubic of the bar ends.
    fn along(&self, s: &Switch, inputs: &Inputs, theta: f64, h: f64) -> f64 {
        let w = hermite(theta / h, h);
        let at = |e: usize| {
            w[0] * self.x0[e] + w[1] * self.v0[e] + w[2] * self.x1[e] + w[3] * self.v1[e]
        };
        switch_value(s, &self.shapes, inputs, |p| match p {
            Point::End(e) => at(e),
            Point::Fixed(x) => x,
        })
    }
}

/// Whether any grip sticks or slips (a free grip's switch is always positive).
pub(super) fn holding(inputs: &Inputs) -> bool {
    inputs.grip.iter().any(|g| *g != Grip::Free)
}

/// Bar-end positions of the state `y = [q; q̇]` (on two threads where the evaluation has
/// them: the ends are independent).
fn end_positions(model: &Model, y: &[f64], x: &mut [Vector3<f64>], ws: &Workspace) {
    let q = &y[..y.len() / 2];
    ws.for_each_half(x, |start, x| model.coords.end_positions(start, q, x));
}

/// Whether each switch is positive at the bar-end positions `x` (as [`end_positions`]);
/// those marked far are.
fn signs(
    switches: &[Switch],
    (shapes, near): (&[Shape], &Proximity),
    inputs: &Inputs,
    x: &[Vector3<f64>],
    out: &mut [bool],
    ws: &Workspace,
) {
    ws.for_each_half(out, |start, out| {
        for (i, (p, s)) in out.iter_mut().zip(&switches[start..]).enumerate() {
            *p = near.is_far(start + i) || positive(s, shapes, inputs, x);
        }
    });
}

/// Bar-end velocities of the reduced velocities `qd`.
fn end_velocities(model: &Model, qd: &[f64], v: &mut [Vector3<f64>]) {
    for (e, v) in v.iter_mut().enumerate() {
        *v = model.coords.end_vector(e, qd, false);
    }
}

fn rest_length(rest: Rest, inputs: &Inputs) -> f64 {
    match rest {
        Rest::Fixed(r) => r,
        Rest::Input(i) => inputs.rest_length[i].max(0.0),
    }
}

/// Whether [`value`] is `> 0`, without its square root where `|s|²` and `s₀²` are not within
/// round-off of each other (there it takes the root, so the sign is always `value`'s).
#[inline(always)]
fn positive(s: &Switch, shapes: &[Shape], inputs: &Inputs, x: &[Vector3<f64>]) -> bool {
    if let Switch::Cable { a, b, rest } = *s {
        let p = |p: Point| match p {
            Point::End(e) => x[e],
            Point::Fixed(x) => x,
        };
        let n2 = (p(b) - p(a)).norm_squared();
        let s0 = rest_length(rest, inputs);
        let margin = n2 - s0 * s0;
        if margin > 1e-9 * n2 {
            return true;
        }
        if margin < -1e-9 * n2 {
            return false;
        }
    }
    value(s, shapes, inputs, x) > 0.0
}

/// A switch at the bar-end positions `x`.
fn value(s: &Switch, shapes: &[Shape], inputs: &Inputs, x: &[Vector3<f64>]) -> f64 {
    switch_value(s, shapes, inputs, |p| match p {
        Point::End(e) => x[e],
        Point::Fixed(x) => x,
    })
}

/// A switch with its points placed by `p` (ends at a step's end, or along the step).
#[inline(always)]
fn switch_value(
    s: &Switch,
    shapes: &[Shape],
    inputs: &Inputs,
    p: impl Fn(Point) -> Vector3<f64>,
) -> f64 {
    match *s {
        Switch::Cable { a, b, rest } => (p(b) - p(a)).norm() - rest_length(rest, inputs),
        Switch::Ground {
            end,
            normal,
            height,
        } => normal.dot(&p(Point::End(end))) - height,
        Switch::TerrainEnd { at, shape, radius } => shapes[shape]
            .distance(&p(at))
            .map_or(f64::MAX, |(phi, _)| phi - radius),
        Switch::TerrainSide {
            a,
            b,
            shape,
            radius,
        } => (-interior_excess(&shapes[shape], &p(a), &p(b), radius)).min(f64::MAX),
    }
}
