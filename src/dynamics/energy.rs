//! Reported quantities that depend only on kinematics: energy, momentum and the
//! constraint residuals. Call [`super::kinematics`] (or an evaluation) first.

use nalgebra::Vector3;

use super::{Inputs, Workspace};
use crate::model::{CableLaw, Model};

/// Kinetic energy `½ tr(Ṅ M Ṅᵀ)`, J. Per bar: `(m/6)(|v_a|² + v_a·v_b + |v_b|²)` plus
/// `½ p |v|²` per payload.
pub fn kinetic(model: &Model, ws: &Workspace) -> f64 {
    let rods: f64 = model
        .bars
        .iter()
        .enumerate()
        .map(|(i, bar)| {
            let (va, vb) = (ws.end_vel[2 * i], ws.end_vel[2 * i + 1]);
            bar.mass / 6.0 * (va.norm_squared() + va.dot(&vb) + vb.norm_squared())
        })
        .sum();
    let payloads: f64 = (model.payload.iter().zip(&ws.end_vel))
        .map(|(p, v)| 0.5 * p * v.norm_squared())
        .sum();
    rods + payloads
}

/// Cable strain energy, gravity potential and ground penalty energy, J. A controlled cable at constant γ
/// stores `½ γ |s|²`.
pub fn potential(model: &Model, inputs: &Inputs, ws: &Workspace) -> f64 {
    let mut v = 0.0;
    for cable in &model.cables {
        let s = ws.node_pos[cable.nodes[1]] - ws.node_pos[cable.nodes[0]];
        v += match cable.law {
            CableLaw::Elastic {
                stiffness,
                rest_length,
                ..
            } => 0.5 * stiffness * (s.norm() - rest_length).max(0.0).powi(2),
            CableLaw::RestLengthControlled {
                stiffness, input, ..
            } => {
                let rest_length = inputs.rest_length[input].max(0.0);
                0.5 * stiffness * (s.norm() - rest_length).max(0.0).powi(2)
            }
            // `cable_force_density`'s γ, written out: as a call it kept the sum on the stack.
            CableLaw::Controlled { input } => {
                0.5 * inputs.force_density[input].max(0.0) * s.norm_squared()
            }
        };
    }
    if let Some(g) = model.gravity {
        for (e, x) in ws.end_pos.iter().enumerate() {
            v -= model.end_mass(e) * g.dot(x);
        }
    }
    if let Some(ground) = &model.ground {
        for (&(n, _), &r) in ground.nodes.iter().zip(&ground.radii) {
            v += ground.energy(&ws.node_pos[n], r);
        }
    }
    if let Some(terrain) = &model.terrain {
        v += super::terrain::energy(terrain, &inputs.grip, &ws.node_pos, &ws.node_vel);
    }
    if let Some(c) = &model.collisions {
        let mut scratch = super::collisions::CollisionScratch::new(c.capsules.len());
        v += super::collisions::energy(c, &ws.node_pos, &mut scratch);
    }
    v
}

/// Linear momentum `Σ m ṙ` (rods and payloads), kg·m/s.
pub fn linear_momentum(model: &Model, ws: &Workspace) -> Vector3<f64> {
    (0..ws.end_vel.len())
        .map(|e| ws.end_vel[e] * model.end_mass(e))
        .sum()
}

/// Angular momentum about the origin, `Σ m (r × ṙ + b × ḃ / 12) + Σ p x × ẋ`, kg·m²/s.
pub fn angular_momentum(model: &Model, ws: &Workspace) -> Vector3<f64> {
    let rods: Vector3<f64> = model
        .bars
        .iter()
        .enumerate()
        .map(|(i, bar)| {
            let (a, b) = (2 * i, 2 * i + 1);
            let r = (ws.end_pos[a] + ws.end_pos[b]) / 2.0;
            let rd = (ws.end_vel[a] + ws.end_vel[b]) / 2.0;
            let bv = ws.end_pos[b] - ws.end_pos[a];
            let bd = ws.end_vel[b] - ws.end_vel[a];
            (r.cross(&rd) + bv.cross(&bd) / 12.0) * bar.mass
        })
        .sum();
    let payloads: Vector3<f64> = (model.payload.iter().zip(ws.end_pos.iter().zip(&ws.end_vel)))
        .map(|(p, (x, v))| x.cross(v) * *p)
        .sum();
    rods + payloads
}

/// `max |‖bᵢ‖ − lᵢ|`, m.
pub fn length_error(model: &Model, ws: &Workspace) -> f64 {
    model
        .bars
        .iter()
        .enumerate()
        .map(|(i, bar)| ((ws.end_pos[2 * i + 1] - ws.end_pos[2 * i]).norm() - bar.length).abs())
        .fold(0.0, f64::max)
}

/// `max |bᵢ · ḃᵢ|`, m²/s.
pub fn orthogonality_error(model: &Model, ws: &Workspace) -> f64 {
    (0..model.bars.len())
        .map(|i| {
            let bv = ws.end_pos[2 * i + 1] - ws.end_pos[2 * i];
            let bd = ws.end_vel[2 * i + 1] - ws.end_vel[2 * i];
            bv.dot(&bd).abs()
        })
        .fold(0.0, f64::max)
}
