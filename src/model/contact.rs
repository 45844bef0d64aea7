//! Penalty contact of bar ends with a ground plane `n·x = h`.
//!
//! Normal force `f_n = max(0, k d − c ḋ_n)` for penetration `d = h − n·x > 0`
//! (`ḋ_n = n·v`), so the ground only pushes. Coulomb friction `−μ f_n v_t / max(|v_t|, v_s)`
//! opposes the tangential velocity `v_t`; below the slip velocity `v_s` it is viscous, which
//! keeps the force continuous for the explicit integrators.

use nalgebra::Vector3;

use crate::contact::Penalty;
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
    /// Radius of each contact point's sphere (the widest bar at the node), m.
    pub radii: Vec<f64>,
}

impl Ground {
    /// The ground of a validated spec, at the given free bar-end nodes.
    pub fn new(spec: &GroundSpec, nodes: Vec<(usize, usize)>, radii: Vec<f64>) -> Self {
        let n = Vector3::from(spec.normal);
        Self {
            normal: n / n.norm(),
            height: spec.height,
            stiffness: spec.stiffness,
            damping: spec.damping,
            friction: spec.friction,
            slip_velocity: spec.slip_velocity,
            nodes,
            radii,
        }
    }

    /// Penetration depth of a sphere of radius `r` at `x`, m (positive inside the ground).
    #[inline]
    pub fn penetration(&self, x: &Vector3<f64>, r: f64) -> f64 {
        self.height + r - self.normal.dot(x)
    }

    /// The contact law of every point.
    pub fn penalty(&self) -> Penalty {
        Penalty {
            stiffness: self.stiffness,
            damping: self.damping,
            friction: self.friction,
            slip_velocity: self.slip_velocity,
        }
    }

    /// Contact force on a sphere of radius `r` at `x` moving with `v`, N.
    #[inline]
    pub fn force(&self, x: &Vector3<f64>, v: &Vector3<f64>, r: f64) -> Vector3<f64> {
        let d = self.penetration(x, r);
        if d <= 0.0 {
            return Vector3::zeros();
        }
        self.penalty().force(d, &self.normal, v)
    }

    /// Stored penalty energy `½ k d²` of a sphere of radius `r` at `x`, J.
    pub fn energy(&self, x: &Vector3<f64>, r: f64) -> f64 {
        let d = self.penetration(x, r).max(0.0);
        0.5 * self.stiffness * d * d
    }
}
