//! The contacts of a capsule (a bar's axis `a`–`b` with radius r) with one shape.
//!
//! The gap along the axis is `g(s) = φ(a + s (b − a)) − r`, and the depth `d = −g`.
//! - Each end is a sphere: a contact at `s = 0` or `s = 1` wherever `d > 0` there, with
//!   the shape's normal. On a plane the depth is linear in s, so the deepest points of a
//!   bar are always among its ends: a bar lying on a plane rests on both.
//! - Between the ends the gap is smooth except at the shape's kinks (a box's edges and
//!   the planes where its nearest face changes, a heightfield's grid lines), so the bar's
//!   side touches there. Such a point carries only the depth its ends do not already
//!   carry, `e(s) = d(s) − [(1 − s) d₀⁺ + s d₁⁺]` (`x⁺ = max(x, 0)`), less a round-off
//!   slack of 1e-10 m, when that is positive. This
//!   keeps every force continuous: a kink that reaches an end carries nothing there, and
//!   a heightfield that is a plane gives exactly the plane's two end contacts.
//!
//! A bar across a box therefore rests on the two points where it crosses the top face's
//! edges, each with its own depth, and tips over an edge the way its weight says.

use nalgebra::Vector3;

use super::Shape;

/// Excess depth a kink must pass before it carries load, m: the round-off of a depth that
/// is linear along the bar stays far below it, so a heightfield that is a plane adds no
/// contact of 1e-17 m (nor events), and the force still grows continuously from 0.
pub const KINK_SLACK: f64 = 1e-10;

/// One contact point of a capsule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Where along the bar: the point is `a + s (b − a)`.
    pub s: f64,
    /// Penetration depth carried by this point, m (> 0).
    pub depth: f64,
    /// The shape's outward unit normal there.
    pub normal: Vector3<f64>,
    /// The end (0 at `a`, 1 at `b`) whose sphere this is; `None` on the side.
    pub end: Option<usize>,
}

/// Depth `r − φ(x)` and normal at `x`, if the shape can touch there.
#[inline]
fn depth(shape: &Shape, x: &Vector3<f64>, r: f64) -> Option<(f64, Vector3<f64>)> {
    shape.distance(x).map(|(phi, n)| (r - phi, n))
}

/// Calls `each` for every contact of the capsule `a`–`b` (radius `r`) with `shape`.
#[inline]
pub fn capsule_contacts(
    shape: &Shape,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    r: f64,
    mut each: impl FnMut(Contact),
) {
    if !shape.may_touch(a, b, r) {
        return;
    }
    let mut ends = [0.0; 2];
    for (i, (x, s)) in [(a, 0.0), (b, 1.0)].into_iter().enumerate() {
        if let Some((d, normal)) = depth(shape, x, r) {
            if d > 0.0 {
                ends[i] = d;
                each(Contact {
                    s,
                    depth: d,
                    normal,
                    end: Some(i),
                });
            }
        }
    }
    shape.kinks(a, b, |s| {
        if let Some((d, normal)) = depth(shape, &(a + (b - a) * s), r) {
            let excess = d - ((1.0 - s) * ends[0] + s * ends[1]) - KINK_SLACK;
            if excess > 0.0 {
                each(Contact {
                    s,
                    depth: excess,
                    normal,
                    end: None,
                });
            }
        }
    });
}

/// The largest excess `e(s) − KINK_SLACK` over the kinks between the ends (`−∞` without
/// kinks that can touch): positive once the bar's side touches. Event location watches
/// its sign.
pub fn interior_excess(shape: &Shape, a: &Vector3<f64>, b: &Vector3<f64>, r: f64) -> f64 {
    let mut most = f64::NEG_INFINITY;
    if !shape.may_touch(a, b, r) {
        return most;
    }
    let end = |x: &Vector3<f64>| depth(shape, x, r).map_or(0.0, |(d, _)| d.max(0.0));
    let (d0, d1) = (end(a), end(b));
    shape.kinks(a, b, |s| {
        if let Some((d, _)) = depth(shape, &(a + (b - a) * s), r) {
            most = most.max(d - ((1.0 - s) * d0 + s * d1) - KINK_SLACK);
        }
    });
    most
}
