//! Which terrain contacts can begin soon, for shapes that do not move: each item (a
//! capsule or a point against one shape) is marked far when even grown by half a margin
//! it cannot touch. The marks hold until some point has moved half the margin since they
//! were set (a Verlet list), so a step far from every shape tests nothing but how far its
//! points moved. A far item has no contact force and a positive switching function, which
//! is what testing it would have given: results do not depend on when the marks were set.

use nalgebra::Vector3;

/// Far marks and the points they were set at.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Proximity {
    /// The points at the last marking (empty: none yet).
    anchor: Vec<Vector3<f64>>,
    far: Vec<bool>,
    /// The items not marked far, ascending.
    near: Vec<u32>,
}

impl Proximity {
    /// Brings the marks up to the points `x`: keeps them while no point has moved half of
    /// `margin` since they were set, else marks every one of `items` anew with
    /// `far(i, grow)` (`grow` is half the margin: how far a point may move before the next
    /// marking). Returns whether it marked anew.
    #[inline]
    pub fn update(
        &mut self,
        x: &[Vector3<f64>],
        margin: f64,
        items: usize,
        mut far: impl FnMut(usize, f64) -> bool,
    ) -> bool {
        // A hair under half the margin, for the round-off of the far tests.
        let limit = 0.25 * margin * margin * (1.0 - 1e-9);
        let holds = self.anchor.len() == x.len()
            && self.far.len() == items
            && self
                .anchor
                .iter()
                .zip(x)
                .all(|(a, b)| (a - b).norm_squared() < limit);
        if holds {
            return false;
        }
        self.anchor.clear();
        self.anchor.extend_from_slice(x);
        self.far.clear();
        self.far.extend((0..items).map(|i| far(i, 0.5 * margin)));
        self.near.clear();
        // Room for every item, so that no later marking allocates.
        self.near.reserve(items);
        let near = self.far.iter().enumerate().filter(|(_, &f)| !f);
        self.near.extend(near.map(|(i, _)| i as u32));
        true
    }

    /// The items not marked far, ascending (after an [`Proximity::update`]).
    #[inline(always)]
    pub fn near(&self) -> &[u32] {
        &self.near
    }

    /// Whether item `i` cannot touch (false before the first marking).
    #[inline(always)]
    pub fn is_far(&self, i: usize) -> bool {
        self.far.get(i).copied().unwrap_or(false)
    }

    /// Makes the next update mark anew.
    pub fn forget(&mut self) {
        self.anchor.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mark(p: &mut Proximity, x: &[Vector3<f64>], calls: &mut usize) {
        let _ = p.update(x, 0.1, x.len(), |i, grow| {
            *calls += 1;
            x[i].z - grow > 1.0
        });
    }

    #[test]
    fn marks_hold_until_a_point_moves_half_the_margin() {
        let mut p = Proximity::default();
        let mut calls = 0;
        let mut x = vec![Vector3::new(0.0, 0.0, 2.0), Vector3::new(0.0, 0.0, 1.02)];
        mark(&mut p, &x, &mut calls);
        assert_eq!(calls, 2);
        assert!(
            p.is_far(0) && !p.is_far(1),
            "1.02 − 0.05 is within reach of 1"
        );
        x[0].z -= 0.049;
        mark(&mut p, &x, &mut calls);
        assert_eq!(calls, 2, "moved less than half the margin: marks kept");
        x[0].z -= 0.002;
        mark(&mut p, &x, &mut calls);
        assert_eq!(calls, 4, "moved past half the margin: marked anew");
        assert!(!p.is_far(7), "an item never marked is not far");
    }
}
