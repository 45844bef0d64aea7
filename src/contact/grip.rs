//! Friction that sticks: an elastic–plastic tangential spring per contact point (the
//! Cundall–Strack model of discrete-element codes), held by an anchor.
//!
//! - **Stick**: the point `x` is tied to its anchor `a` by a tangential spring and damper
//!   with the normal law's `k` and `c`, `f_t = −k P(x − a) − c v_t` (`P` drops the normal
//!   part), up to `μ N`. At rest under a load below `μ N` the spring holds it exactly: no
//!   creep.
//! - **Slip**: kinetic friction `f_t = −μ N ê`, with `ê` the tangential direction from the
//!   anchor to the point. The anchor is set far behind the point ([`TRAIL`]) and stays
//!   put while the point slides straight away from it; once the sliding direction turns
//!   more than 10° from `ê`, it moves behind the point again, onto its velocity.
//!
//! The mode and the anchor change only between steps (`sim::grip`), where a switching
//! function ([`switch`]) says so: stick→slip when `|f_t|` reaches `μ N`, slip→stick when
//! the point stops moving away from its anchor, a new slip anchor at a turn. A new stick
//! anchor continues the force, so the force is continuous there; every switch depends only
//! on the state, so an event-locating method keeps its order across them.

use nalgebra::Vector3;

use super::Penalty;

/// How far behind the point a slip's anchor is set, m: far enough that the friction's
/// direction, the chord from the anchor, barely moves with the structure's vibrations.
const TRAIL: f64 = 1.0;

/// The cosine of the largest angle, 10°, between the sliding direction and the direction
/// from the anchor (that of the friction) before the anchor moves onto the velocity: each
/// turn is an event: a tumbling icosahedron took five times as many at 5°, a third as
/// many at 15° (for half again the direction's error).
const TURN: f64 = 0.984_807_753_012_208;

/// How far past the Coulomb limit a stick may be, relative, before it slips: a stick just
/// begun from a slip sits at the limit to round-off, and must not slip again at once.
const STICK_SLACK: f64 = 1e-9;

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

/// The contact force of a point held by `grip`, N. A sticking spring is not capped at
/// `μ N` here: its switch to slip is located where it reaches the cap, and a cap inside the
/// step would make the force a discontinuous sign of the tangential velocity wherever the
/// spring is slack (which an implicit method's Newton iteration cannot solve).
#[inline]
pub fn force(law: &Penalty, touch: &Touch, grip: Grip) -> Vector3<f64> {
    let normal = touch.normal_force(law);
    let friction = match grip {
        Grip::Free => return law.force(touch.depth, touch.normal, touch.v),
        Grip::Stick(a) => touch.spring(law, &a),
        Grip::Slip(a) => -touch.away(&a) * (law.friction * normal),
    };
    touch.normal * normal + friction
}

/// Positive while `grip` keeps its mode and anchor: `μ N − |f_t|` while it sticks; while it
/// slips, the lesser of its two switching functions ([`slip_switches`]: it stops, or its
/// path turns); `f64::MAX` when it is free.
#[inline]
pub fn switch(law: &Penalty, touch: &Touch, grip: Grip) -> f64 {
    match grip {
        Grip::Free => f64::MAX,
        Grip::Stick(a) => {
            let limit = law.friction * touch.normal_force(law);
            limit * (1.0 + STICK_SLACK) - touch.spring(law, &a).norm()
        }
        Grip::Slip(a) => {
            let (stop, turn) = slip_switches(law, touch, &a);
            stop.min(turn)
        }
    }
}

/// The grip after a step that ended at `touch` (`None` if the point no longer touches).
/// A frictionless law never grips. `switched` says that the step was cut where this grip's
/// switch changes sign: it switches then, whatever the sign at the step's end (which, a
/// step's error away from the interpolant that located it, may still lie before it).
pub fn next(law: &Penalty, touch: Option<&Touch>, grip: Grip, switched: bool) -> Grip {
    let Some(touch) = touch.filter(|t| t.depth > 0.0 && law.friction > 0.0) else {
        return Grip::Free;
    };
    let limit = law.friction * touch.normal_force(law);
    if let Grip::Free = grip {
        // Anchored where it first touched, unless it already slides harder than μ N holds.
        return next(law, Some(touch), Grip::Stick(*touch.x), false);
    }
    if !switched && switch(law, touch, grip) > 0.0 {
        return grip;
    }
    match grip {
        Grip::Free => grip,
        // It slips the way the spring pulled it back from.
        Grip::Stick(a) => {
            let f = touch.spring(law, &a);
            let m = f.norm();
            let away = if m > 0.0 { -f / m } else { touch.away(&a) };
            Grip::Slip(touch.x - away * TRAIL)
        }
        // Turned: the anchor moves behind the point, onto its velocity.
        Grip::Slip(a) if turned(law, touch, &a) => {
            let v = touch.tangential(touch.v);
            Grip::Slip(touch.x - v * (TRAIL / v.norm()))
        }
        // Stopped: the new spring pulls as the sliding friction did,
        // `k P(x − a') = μ N ê − c v_t`.
        Grip::Slip(a) => {
            let pull = touch.away(&a) * limit - touch.tangential(touch.v) * law.damping;
            Grip::Stick(touch.x - pull / law.stiffness)
        }
    }
}

/// A slip's two switching functions, positive while it slides on: `v_t·ê` (the speed away
/// from the anchor; zero where it stops), and `v_t·ê − cos 10° |v_t| + (1 − cos 10°) v_s`
/// (zero where the path has turned 10° from `ê`, once faster than the shape's slip velocity
/// `v_s`: slower wobbles of a structure sliding off do not turn it).
fn slip_switches(law: &Penalty, touch: &Touch, anchor: &Vector3<f64>) -> (f64, f64) {
    let v = touch.tangential(touch.v);
    let along = v.dot(&touch.away(anchor));
    (
        along + SLIP_SLACK,
        along - TURN * v.norm() + (1.0 - TURN) * law.slip_velocity,
    )
}

/// Whether a slip's switch fired because the path turned, not because it stopped.
fn turned(law: &Penalty, touch: &Touch, anchor: &Vector3<f64>) -> bool {
    let (stop, turn) = slip_switches(law, touch, anchor);
    turn < stop && touch.tangential(touch.v).norm() > 0.0
}

/// Energy in a sticking spring, `½ k |P(x − a)|²`, J.
pub fn energy(law: &Penalty, touch: &Touch, grip: Grip) -> f64 {
    let Grip::Stick(a) = grip else {
        return 0.0;
    };
    0.5 * law.stiffness * touch.tangential(&(touch.x - a)).norm_squared()
}
