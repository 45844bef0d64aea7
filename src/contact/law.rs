//! The penalty law of one contact point: a spring and damper along the normal that only
//! pushes, and regularised Coulomb friction against the tangential velocity.

use nalgebra::Vector3;

/// The contact settings of a shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Penalty {
    /// Stiffness k, N/m.
    pub stiffness: f64,
    /// Damping c on the approach speed, N·s/m.
    pub damping: f64,
    /// Coulomb coefficient μ.
    pub friction: f64,
    /// Tangential speed v_s below which friction is viscous, m/s.
    pub slip_velocity: f64,
}

impl Penalty {
    /// The normal force `max(0, k d − c v_n)` at depth `d` approaching at `v_n`, N.
    #[inline]
    pub fn normal_force(&self, depth: f64, vn: f64) -> f64 {
        (self.stiffness * depth - self.damping * vn).max(0.0)
    }

    /// The force on a point at depth `d > 0` moving with `v` against a surface of outward
    /// normal `n`: `n max(0, k d − c n·v) − μ f_n v_t / max(|v_t|, v_s)`, N.
    #[inline]
    pub fn force(&self, depth: f64, n: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
        let vn = n.dot(v);
        let fn_ = self.normal_force(depth, vn);
        let vt = v - n * vn;
        let friction = self.friction * fn_ / vt.norm().max(self.slip_velocity);
        n * fn_ - vt * friction
    }
}
