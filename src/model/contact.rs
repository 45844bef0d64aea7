//! Penalty contact of bar ends with a ground plane `n·x = h`.
//!
//! Normal force `f_n = max(0, k d − c ḋ_n)` for penetration `d = h − n·x > 0`
//! (`ḋ_n = n·v`), so the ground only pushes. Coulomb friction `−μ f_n v_t / max(|v_t|, v_s)`
//! opposes the tangential velocity `v_t`; below the slip velocity `v_s` it is viscous, which
//! keeps the force continuous for the explicit integrators.

use nalgebra::Vector3;

use crate::scene::GroundSpec;

/// The ground as the step sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct Ground {
    /// Unit normal, pointing out of the ground.
    pub normal: Vector3<f64>,
    /// Plane offset h: the surface is `n·x = h`, m.
    pub height: f64,
    /// Penalty stiffness k, N/m.
    pub stiffness: f64,
    /// Penalty damping c, N·s/m (acts only while in contact).
    pub damping: f64,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    /// Slip velocity v_s below which friction is viscous, m/s.
    pub slip_velocity: f64,
    /// Contact points: (node, the bar end that carries it), free nodes on bars only.
    pub nodes: Vec<(usize, usize)>,
}

impl Ground {
    /// The ground of a validated spec, at the given free bar-end nodes.
    pub fn new(spec: &GroundSpec, nodes: Vec<(usize, usize)>) -> Self {
        let n = Vector3::from(spec.normal);
        Self {
            normal: n / n.norm(),
            height: spec.height,
            stiffness: spec.stiffness,
            damping: spec.damping,
            friction: spec.friction,
            slip_velocity: spec.slip_velocity,
            nodes,
        }
    }

    /// Penetration depth of a point, m (positive inside the ground).
    #[inline]
    pub fn penetration(&self, x: &Vector3<f64>) -> f64 {
        self.height - self.normal.dot(x)
    }

    /// Contact force on a node at `x` moving with `v`, N.
    #[inline]
    pub fn force(&self, x: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
        let d = self.penetration(x);
        if d <= 0.0 {
            return Vector3::zeros();
        }
        let vn = self.normal.dot(v);
        let fn_ = (self.stiffness * d - self.damping * vn).max(0.0);
        let vt = v - self.normal * vn;
        let friction = self.friction * fn_ / vt.norm().max(self.slip_velocity);
        self.normal * fn_ - vt * friction
    }

    /// Stored penalty energy `½ k d²` of a point, J.
    pub fn energy(&self, x: &Vector3<f64>) -> f64 {
        let d = self.penetration(x).max(0.0);
        0.5 * self.stiffness * d * d
    }
}
