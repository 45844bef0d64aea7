//! Friction that sticks: an elastic–plastic tangential spring per contact point (the
//! Cundall–Strack model of discrete-element codes), held by an anchor.
//!
//! - **Stick**: the point `x` is tied to its anchor `a` by a tangential spring and damper
//!   with the normal law's `k` and `c`, `f_t = −k P(x − a) − c v_t` (`P` drops the normal
//!   part), up to `μ N`. At rest under a load below `μ N` the spring holds it exactly: no
//!   creep.
//! - **Slip**: kinetic friction `f_t = −μ N ê`, with `ê` the tangential direction from the
//!   anchor to the point. The anchor trails the point by a short length `L` (the
//!   terrain's `trail`) and stays put while the point slides. Once the point is `2 L` from
//!   it and its path has turned more than 0.3° from `ê`, the anchor is dragged up to `L`
//!   behind the point along `ê`. So `ê` turns toward the sliding direction within a few `L`
//!   of sliding (the lag halves every `L`), as the stretch of a Cundall–Strack spring drags
//!   behind a sliding contact; a straight slide is never dragged.
//!
//! The mode and the anchor change only between steps (`sim::grip`), where a switching
//! function ([`switch`]) says so: stick→slip when `|f_t|` reaches `μ N`, slip→stick when
//! the point stops moving away from its anchor, a dragged anchor (above). Every new anchor
//! continues the force, so the force is continuous at each switch: a switch located a
//! little earlier or later moves the run only a little, and since every switch depends
//! only on the state, an event-locating method keeps its order across them.

use nalgebra::Vector3;

use super::Penalty;

/// How far past the Coulomb limit a stick may be, relative, before it slips: a stick just
/// begun from a slip sits at the limit to round-off, and must not slip again at once.
const STICK_SLACK: f64 = 1e-9;

/// The sine of the angle (about 0.3°) between a slip's path and the friction's direction `ê`
/// beyond which its anchor is dragged (once `2 L` behind): friction opposes a turning slide
/// to within about this, at an event per trail or two of sliding.
const LAG: f64 = 0.005;

/// Speed toward the anchor, m/s, at which a slip ends (below round-off of any real speed).
const SLIP_SLACK: f64 = 1e-12;

/// The friction state of one contact point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Grip {
    /// Not touching (or touched inside a step): the regularised law applies.
    #[default]
    Free,
    /// Held by a tangential spring to the anchor, m.
    Stick(Vector3<f64>),
    /// Sliding away from the anchor, m.
    Slip(Vector3<f64>),
}

impl Grip {
    /// The mode code and anchor, as an FMU state stores them: 0 free, 1 stick, 2 slip.
    pub fn to_values(self) -> [f64; 4] {
        match self {
            Self::Free => [0.0; 4],
            Self::Stick(a) => [1.0, a.x, a.y, a.z],
            Self::Slip(a) => [2.0, a.x, a.y, a.z],
        }
    }

    /// The inverse of [`Grip::to_values`]; `None` for an unknown mode.
    pub fn from_values(v: [f64; 4]) -> Option<Self> {
        let a = Vector3::new(v[1], v[2], v[3]);
        match v[0] {
            0.0 => Some(Self::Free),
            1.0 => Some(Self::Stick(a)),
            2.0 => Some(Self::Slip(a)),
            _ => None,
        }
    }
}

/// One contact point as the law sees it.
#[derive(Debug, Clone, Copy)]
pub struct Touch<'a> {
    /// Penetration depth, m (> 0 while touching).
    pub depth: f64,
    /// The shape's outward unit normal.
    pub normal: &'a Vector3<f64>,
    /// The point (a capsule end's centre), m.
    pub x: &'a Vector3<f64>,
    /// Its velocity, m/s.
    pub v: &'a Vector3<f64>,
}

impl Touch<'_> {
    /// The normal force `N = max(0, k d − c n·v)`, N.
    fn normal_force(&self, law: &Penalty) -> f64 {
        law.normal_force(self.depth, self.normal.dot(self.v))
    }

    /// The tangential part of `w`.
    fn tangential(&self, w: &Vector3<f64>) -> Vector3<f64> {
        w - self.normal * self.normal.dot(w)
    }

    /// The stick spring's force, N.
    fn spring(&self, law: &Penalty, anchor: &Vector3<f64>) -> Vector3<f64> {
        -(self.tangential(&(self.x - anchor)) * law.stiffness
            + self.tangential(self.v) * law.damping)
    }

    /// The direction a slip is pulled back along, from its anchor to the point, shortened
    /// within the trail: `d / max(|d|, L)`, `d = P(x − a)`. A slip starts `L` from its
    /// anchor and moves away, but a step's trial stages or an implicit method's iterates may
    /// come nearer, and must not meet a flip of the direction there.
    fn pulled(&self, anchor: &Vector3<f64>, trail: f64) -> Vector3<f64> {
        let d = self.tangential(&(self.x - anchor));
        d / d.norm().max(trail)
    }

    /// The unit tangential direction from `anchor` to the point (zero if there is none).
    fn away(&self, anchor: &Vector3<f64>) -> Vector3<f64> {
        let d = self.tangential(&(self.x - anchor));
        let n = d.norm();
        if n > 0.0 {
            d / n
        } else {
            Vector3::zeros()
        }
    }
}

/// The contact force of a point held by `grip`, N, slips trailing by `trail`, m. A
/// sticking spring is not capped at `μ N` here: its switch to slip is located where it
/// reaches the cap, and a cap inside the step would make the force a discontinuous sign of
/// the tangential velocity wherever the spring is slack (which an implicit method's Newton
/// iteration cannot solve).
#[inline]
pub fn force(law: &Penalty, touch: &Touch, grip: Grip, trail: f64) -> Vector3<f64> {
    let normal = touch.normal_force(law);
    let friction = match grip {
        Grip::Free => return law.force(touch.depth, touch.normal, touch.v),
        Grip::Stick(a) => touch.spring(law, &a),
        Grip::Slip(a) => -touch.pulled(&a, trail) * (law.friction * normal),
    };
    touch.normal * normal + friction
}

/// Positive while `grip` keeps its mode and anchor: `μ N − |f_t|` while it sticks; while it
/// slips, the lesser of its two switching functions ([`slip_switches`]: it stops, or its
/// anchor is dragged, slips trailing by `trail`, m); `f64::MAX` when it is free.
#[inline]
pub fn switch(law: &Penalty, touch: &Touch, grip: Grip, trail: f64) -> f64 {
    match grip {
        Grip::Free => f64::MAX,
        Grip::Stick(a) => {
            let limit = law.friction * touch.normal_force(law);
            limit * (1.0 + STICK_SLACK) - touch.spring(law, &a).norm()
        }
        Grip::Slip(a) => {
            // Both in m/s, so that the root finder's secant sees one scale.
            let (stop, drag, speed) = slip_switches(law, touch, &a, trail);
            stop.min(drag * speed.max(SLIP_SLACK))
        }
    }
}

/// The grip after a step that ended at `touch` (`None` if the point no longer touches).
/// A frictionless law never grips. `switched` says that the step was cut where this grip's
/// switch changes sign: it switches then, whatever the sign at the step's end (which, a
/// step's error away from the interpolant that located it, may still lie before it).
pub fn next(law: &Penalty, touch: Option<&Touch>, grip: Grip, switched: bool, trail: f64) -> Grip {
    let Some(touch) = touch.filter(|t| t.depth > 0.0 && law.friction > 0.0) else {
        return Grip::Free;
    };
    let limit = law.friction * touch.normal_force(law);
    if let Grip::Free = grip {
        // Anchored where it first touched, unless it already slides harder than μ N holds.
        return next(law, Some(touch), Grip::Stick(*touch.x), false, trail);
    }
    if !switched && switch(law, touch, grip, trail) > 0.0 {
        return grip;
    }
    match grip {
        Grip::Free => grip,
        // It slips the way the spring pulled it back from.
        Grip::Stick(a) => {
            let f = touch.spring(law, &a);
            let m = f.norm();
            let away = if m > 0.0 { -f / m } else { touch.away(&a) };
            Grip::Slip(touch.x - away * trail)
        }
        // Dragged: the anchor moves up behind the point, the friction's direction kept.
        Grip::Slip(a) if dragged(law, touch, &a, trail) => {
            Grip::Slip(touch.x - touch.away(&a) * trail)
        }
        // Stopped: the new spring pulls as the sliding friction did,
        // `k P(x − a') = μ N ê − c v_t`.
        Grip::Slip(a) => {
            let pulled = touch.pulled(&a, trail);
            let pull = pulled * limit - touch.tangential(touch.v) * law.damping;
            Grip::Stick(touch.x - pull / law.stiffness)
        }
    }
}

/// A slip's two switching functions, positive while it slides on, and its speed: `v_t·ê`
/// (the speed away from the anchor; zero where it stops), and `max(2 − r / L, 1 − s / s₀)`
/// (zero where the point is at least twice its trail `L` from the anchor and its path has
/// turned from `ê` by `s = |v_t − (v_t·ê) ê| / max(|v_t|, v_s) ≥ s₀` ([`LAG`], `v_s` the
/// shape's slip velocity): its anchor is then dragged). A straight slide is never dragged.
fn slip_switches(
    law: &Penalty,
    touch: &Touch,
    anchor: &Vector3<f64>,
    trail: f64,
) -> (f64, f64, f64) {
    let v = touch.tangential(touch.v);
    let d = touch.tangential(&(touch.x - anchor));
    let behind = d.norm();
    let away = if behind > 0.0 { d / behind } else { d };
    let along = v.dot(&away);
    let speed = v.norm();
    let lag = (v - away * along).norm() / speed.max(law.slip_velocity);
    let drag = (2.0 - behind / trail).max(1.0 - lag / LAG);
    (along + SLIP_SLACK, drag, speed)
}

/// Whether a slip's switch fired because its anchor is dragged, not because it stopped:
/// the point still moves away from its anchor, and the drag switch is the nearer its zero
/// and well inside the range it falls through (from 1 at a drag to 0 an `L` later; a slip
/// slowing to a stop in a straight line keeps it at 1).
fn dragged(law: &Penalty, touch: &Touch, anchor: &Vector3<f64>, trail: f64) -> bool {
    let (stop, drag, speed) = slip_switches(law, touch, anchor, trail);
    stop > 0.0 && drag < 0.5 && drag * speed.max(SLIP_SLACK) < stop
}

/// Energy in a sticking spring, `½ k |P(x − a)|²`, J.
pub fn energy(law: &Penalty, touch: &Touch, grip: Grip) -> f64 {
    let Grip::Stick(a) = grip else {
        return 0.0;
    };
    0.5 * law.stiffness * touch.tangential(&(touch.x - a)).norm_squared()
}
