//! Closest points of two segments, and a sweep-and-prune broad phase over many.

use nalgebra::Vector3;

/// The closest points `p₁ + s d₁` and `p₂ + t d₂` of two segments, as `(s, t)` in
/// `[0, 1]²` (Ericson, Real-Time Collision Detection, 5.1.9). Where the segments are
/// parallel, the middle of their overlap along the first, so that two bars lying side by
/// side touch at the middle of their common stretch rather than at an arbitrary end.
pub fn closest_params(
    p1: &Vector3<f64>,
    q1: &Vector3<f64>,
    p2: &Vector3<f64>,
    q2: &Vector3<f64>,
) -> (f64, f64) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.norm_squared(), d2.norm_squared(), d2.dot(&r));
    let c = d1.dot(&r);
    let b = d1.dot(&d2);
    let denom = a * e - b * b;
    let s = if denom > 1e-12 * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        // Parallel: the overlap of the second's projection onto the first.
        let (u0, u1) = ((-c) / a, (b - c) / a);
        let (lo, hi) = (u0.min(u1).max(0.0), u0.max(u1).min(1.0));
        if lo <= hi {
            0.5 * (lo + hi)
        } else if u0.max(u1) < 0.0 {
            0.0
        } else {
            1.0
        }
    };
    let mut t = (b * s + f) / e;
    if !(0.0..=1.0).contains(&t) {
        t = t.clamp(0.0, 1.0);
        let s = ((t * b - c) / a).clamp(0.0, 1.0);
        return (s, t);
    }
    (s, t)
}

/// An axis-aligned box.
pub type Bounds = [[f64; 2]; 3];

/// The bounds of a capsule around `a`–`b` of radius `r`.
#[inline]
pub fn capsule_bounds(a: &Vector3<f64>, b: &Vector3<f64>, r: f64) -> Bounds {
    [0, 1, 2].map(|k| [a[k].min(b[k]) - r, a[k].max(b[k]) + r])
}

/// Sweep and prune: sorts `order` by the lower bound along the axis where the boxes'
/// centres spread most, then calls `pair(i, j)` (i < j) for every two boxes that overlap
/// on all three axes. The order of the calls depends only on the boxes (ties by index),
/// so a run gives the same bits whatever `order` held before. Cost: a sort of an almost
/// sorted list and a pass, plus the overlapping pairs.
pub fn overlapping_pairs(boxes: &[Bounds], order: &mut [u32], mut pair: impl FnMut(usize, usize)) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for b in boxes {
        for k in 0..3 {
            let c = b[k][0] + b[k][1];
            lo[k] = lo[k].min(c);
            hi[k] = hi[k].max(c);
        }
    }
    let axis = (0..3)
        .max_by(|&i, &j| (hi[i] - lo[i]).total_cmp(&(hi[j] - lo[j])))
        .unwrap_or(0);
    order.sort_unstable_by(|&i, &j| {
        boxes[i as usize][axis][0]
            .total_cmp(&boxes[j as usize][axis][0])
            .then(i.cmp(&j))
    });
    for (n, &i) in order.iter().enumerate() {
        let bi = &boxes[i as usize];
        for &j in &order[n + 1..] {
            let bj = &boxes[j as usize];
            if bj[axis][0] > bi[axis][1] {
                break;
            }
            if (0..3).all(|k| bj[k][0] <= bi[k][1] && bi[k][0] <= bj[k][1]) {
                let (a, b) = (i.min(j) as usize, i.max(j) as usize);
                pair(a, b);
            }
        }
    }
}
