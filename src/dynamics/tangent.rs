//! The tangent of the equations of motion in the reduced coordinates η₂ (flat, `q`, 3r):
//! the constant mass `M̄ = J_eᵀ M_E J_e`, the applied generalized force `f = J_eᵀ F`, its
//! derivatives `∂f/∂q`, `∂f/∂q̇`, `∂f/∂u`, the bar-constraint Jacobian `G` and the
//! geometric stiffness `Σ λᵢ Dᵢᵀ Dᵢ` of the bar force densities. `J_e = U₂ ⊗ I₃` maps `q`
//! to the bar ends; the reactions Ω drop out because `J_eᵀ P = 0`.
//!
//! Everything is dense: the analyses that use it (equilibrium, modes, linear models) are
//! dense eigenvalue problems anyway. The force derivatives hold at any state, so a stiff
//! integrator can reuse them; `G` and the multipliers describe the bar constraints.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use super::effects::{self, CableLink, ForceEffect};
use super::{Inputs, Workspace};
use crate::model::Model;

/// One input of the structure (the FMU's inputs, in model numbering).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputChannel {
    /// Force density of controlled-cable input `k`, N/m.
    ForceDensity(usize),
    /// Rest length of reeled-cable input `k`, m.
    RestLength(usize),
    /// Force input `k` along `axis`, N.
    NodeForce(usize, usize),
}

/// The tangent of the dynamics at one state.
#[derive(Debug, Clone)]
pub struct Tangent {
    /// Bar ends to reduced coordinates: `x_E = N₀ + J_e q` (6β × 3r).
    pub ends: DMatrix<f64>,
    /// `M̄` (3r × 3r), constant.
    pub mass: DMatrix<f64>,
    /// Applied generalized force `f` (cables, weight, loads, inputs, contact), N.
    pub force: DVector<f64>,
    /// `∂f/∂q`.
    pub stiffness: DMatrix<f64>,
    /// `∂f/∂q̇`.
    pub damping: DMatrix<f64>,
    /// `Σ λᵢ Dᵢᵀ Dᵢ` with `Dᵢ = ∂bᵢ/∂q` and λ the bar force densities of this state.
    pub geometric: DMatrix<f64>,
    /// `G`: row i is `∂|bᵢ|²/∂q = 2 bᵢᵀ Dᵢ` for each moving bar (static bars have none).
    pub constraints: DMatrix<f64>,
    /// Bars of the rows of `constraints`.
    pub constraint_bars: Vec<usize>,
    /// The evaluation at this state (positions, γ, λ), kept to form input columns.
    pub workspace: Workspace,
    /// Generalized accelerations η̈₂ of this state.
    pub acceleration: DVector<f64>,
}

impl Tangent {
    /// The tangent at time `t`, positions `q`, velocities `v` and `inputs`.
    pub fn new(model: &Model, inputs: &Inputs, t: f64, q: &[f64], v: &[f64]) -> Self {
        let mut ws = Workspace::new(model);
        let mut acc = vec![0.0; q.len()];
        super::accelerations(model, inputs, t, q, v, &mut ws, &mut acc);
        let ends = end_jacobian(model);
        let n_ends = model.coords.n_ends();
        let mut end_mass = DMatrix::zeros(3 * n_ends, 3 * n_ends);
        for (i, inertia) in model.inertia.iter().enumerate() {
            for (r, row) in inertia.m.iter().enumerate() {
                for (c, &value) in row.iter().enumerate() {
                    add_block(
                        &mut end_mass,
                        2 * i + r,
                        2 * i + c,
                        &(Matrix3::identity() * value),
                    );
                }
            }
        }
        let mut forces = EndDerivatives::new(n_ends);
        for effect in &model.pipeline.forces {
            forces.add_effect(effect, inputs, &ws);
        }
        let mut end_geometric = DMatrix::zeros(3 * n_ends, 3 * n_ends);
        let mut constraints = Vec::new();
        let mut constraint_bars = Vec::new();
        for (i, &lambda) in ws.lambda.iter().enumerate() {
            if model.coords.static_bar[i] {
                continue;
            }
            let id = Matrix3::identity() * lambda;
            add_pair(&mut end_geometric, [2 * i, 2 * i + 1], &id);
            let b = ws.end_pos[2 * i + 1] - ws.end_pos[2 * i];
            let mut row = DVector::zeros(3 * n_ends);
            for k in 0..3 {
                row[6 * i + k] = -2.0 * b[k];
                row[6 * i + 3 + k] = 2.0 * b[k];
            }
            constraints.push(ends.tr_mul(&row));
            constraint_bars.push(i);
        }
        let n = q.len();
        let mut g = DMatrix::zeros(constraints.len(), n);
        for (r, row) in constraints.iter().enumerate() {
            g.row_mut(r).copy_from(&row.transpose());
        }
        // `ws.end_force` includes the reactions Ω, which `J_eᵀ` annihilates.
        let force = ends.tr_mul(&DVector::from_iterator(
            3 * n_ends,
            ws.end_force.iter().flat_map(|f| f.iter().copied()),
        ));
        let project = |m: &DMatrix<f64>| ends.tr_mul(&(m * &ends));
        Self {
            mass: project(&end_mass),
            force,
            stiffness: project(&forces.position),
            damping: project(&forces.velocity),
            geometric: project(&end_geometric),
            constraints: g,
            constraint_bars,
            acceleration: DVector::from_vec(acc),
            ends,
            workspace: ws,
        }
    }

    /// The tangent stiffness at fixed multipliers, `K = −∂f/∂q − Σ λᵢ Dᵢᵀ Dᵢ`: positive
    /// along a direction where the structure pulls back.
    pub fn tangent_stiffness(&self) -> DMatrix<f64> {
        let k = -(&self.stiffness + &self.geometric);
        (&k + k.transpose()) * 0.5
    }

    /// `∂η̈₂/∂q` and `∂η̈₂/∂q̇` of the constrained accelerations at this state (`v` its
    /// velocities), on or off the constraint manifold. From `M̄ η̈₂ = f + Gᵀμ` and
    /// `G η̈₂ + c = 0` (`cᵢ = q̇ᵀ Hᵢ q̇`, `Hᵢ = 2 DᵢᵀDᵢ` constant), with `S = G M̄⁻¹ Gᵀ` and
    /// `P = I − M̄⁻¹ Gᵀ S⁻¹ G`:
    /// `J_q = P M̄⁻¹ (∂f/∂q + Σ λᵢ DᵢᵀDᵢ) − M̄⁻¹ Gᵀ S⁻¹ Q` with `Qᵢ = η̈₂ᵀ Hᵢ`, and
    /// `J_v = P M̄⁻¹ ∂f/∂q̇ − M̄⁻¹ Gᵀ S⁻¹ R` with `Rᵢ = 2 q̇ᵀ Hᵢ`.
    pub fn acceleration_jacobian(&self, v: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = self.mass.nrows();
        let mass_inv = self
            .mass
            .clone()
            .cholesky()
            .expect("the mass matrix is positive definite")
            .inverse();
        let g = &self.constraints;
        let minv_gt = &mass_inv * g.transpose();
        let s = g * &minv_gt;
        let tolerance = 1e-14 * s.amax().max(f64::MIN_POSITIVE);
        let s_inv = s.pseudo_inverse(tolerance).expect("tolerance ≥ 0");
        // −M̄⁻¹ Gᵀ S⁻¹, shared by both Jacobians.
        let back = -(&minv_gt * &s_inv);
        let projector = DMatrix::identity(n, n) + &back * g;
        let v = DVector::from_column_slice(v);
        let mut q_rows = DMatrix::zeros(g.nrows(), n);
        let mut r_rows = DMatrix::zeros(g.nrows(), n);
        for (r, &bar) in self.constraint_bars.iter().enumerate() {
            let d = self.ends.rows(6 * bar + 3, 3) - self.ends.rows(6 * bar, 3);
            q_rows
                .row_mut(r)
                .copy_from(&((&d * &self.acceleration).transpose() * &d * 2.0));
            r_rows
                .row_mut(r)
                .copy_from(&((&d * &v).transpose() * &d * 4.0));
        }
        let jq = &projector * &mass_inv * (&self.stiffness + &self.geometric) + &back * q_rows;
        let jv = &projector * &mass_inv * &self.damping + &back * r_rows;
        (jq, jv)
    }

    /// `∂f/∂u` for each channel (3r × channels).
    pub fn input_matrix(
        &self,
        model: &Model,
        inputs: &Inputs,
        channels: &[InputChannel],
    ) -> DMatrix<f64> {
        let n_ends = model.coords.n_ends();
        let mut end_b = DMatrix::zeros(3 * n_ends, channels.len());
        let ws = &self.workspace;
        for effect in &model.pipeline.forces {
            match effect {
                ForceEffect::ForceDensityCables(cables) => {
                    for (link, input) in cables {
                        // At 0 the derivative for increasing u: a positive command pulls.
                        if inputs.force_density[*input] < 0.0 {
                            continue;
                        }
                        let col = channels
                            .iter()
                            .position(|c| *c == InputChannel::ForceDensity(*input));
                        if let Some(col) = col {
                            put_cable(&mut end_b, col, link, &(cable_vector(link, ws)));
                        }
                    }
                }
                ForceEffect::ReeledCables(cables) => {
                    for (link, stiffness, c, input) in cables {
                        let rest = inputs.rest_length[*input];
                        let (s, s_dot) = (cable_vector(link, ws), cable_rate(link, ws));
                        if rest <= 0.0 || density(*stiffness, rest, *c, &s, &s_dot) <= 0.0 {
                            continue;
                        }
                        let col = channels
                            .iter()
                            .position(|ch| *ch == InputChannel::RestLength(*input));
                        if let Some(col) = col {
                            put_cable(&mut end_b, col, link, &(s * (-stiffness / s.norm())));
                        }
                    }
                }
                ForceEffect::NodeForces(targets) => {
                    for &(k, end) in targets {
                        for axis in 0..3 {
                            let col = channels
                                .iter()
                                .position(|c| *c == InputChannel::NodeForce(k, axis));
                            if let (Some(col), Some(e)) = (col, end) {
                                end_b[(3 * e + axis, col)] += 1.0;
                            }
                        }
                    }
                }
                _ => {}
            }
        }
        self.ends.tr_mul(&end_b)
    }
}

/// `J_e`: `x_e = N₀_e + Σ_g U₂[e, g] q_g` per axis.
pub fn end_jacobian(model: &Model) -> DMatrix<f64> {
    let coords = &model.coords;
    let mut j = DMatrix::zeros(3 * coords.n_ends(), 3 * coords.r);
    for e in 0..coords.n_ends() {
        for &(g, c) in coords.row(e) {
            for k in 0..3 {
                j[(3 * e + k, 3 * g + k)] += c;
            }
        }
    }
    j
}

/// `∂F/∂x_E` and `∂F/∂ẋ_E` of the applied end forces.
struct EndDerivatives {
    position: DMatrix<f64>,
    velocity: DMatrix<f64>,
}

impl EndDerivatives {
    fn new(n_ends: usize) -> Self {
        Self {
            position: DMatrix::zeros(3 * n_ends, 3 * n_ends),
            velocity: DMatrix::zeros(3 * n_ends, 3 * n_ends),
        }
    }

    fn add_effect(&mut self, effect: &ForceEffect, inputs: &Inputs, ws: &Workspace) {
        match effect {
            ForceEffect::ElasticCables(cables) => {
                for (link, stiffness, rest) in cables {
                    self.cable(link, ws, *stiffness, *rest, 0.0);
                }
            }
            ForceEffect::DampedCables(cables) => {
                for (link, stiffness, rest, c) in cables {
                    self.cable(link, ws, *stiffness, *rest, *c);
                }
            }
            ForceEffect::ReeledCables(cables) => {
                for (link, stiffness, c, input) in cables {
                    let rest = inputs.rest_length[*input].max(0.0);
                    self.cable(link, ws, *stiffness, rest, *c);
                }
            }
            ForceEffect::ForceDensityCables(cables) => {
                for (link, input) in cables {
                    let gamma = inputs.force_density[*input].max(0.0);
                    self.pair(link, &(Matrix3::identity() * gamma), &Matrix3::zeros());
                }
            }
            ForceEffect::GroundContact(ground) => {
                for (&(n, e), &r) in ground.nodes.iter().zip(&ground.radii) {
                    let (x, v) = (&ws.node_pos[n], &ws.node_vel[n]);
                    let (dx, dv) = contact_derivatives(ground, x, v, r);
                    add_block(&mut self.position, e, e, &dx);
                    add_block(&mut self.velocity, e, e, &dv);
                }
            }
            ForceEffect::Terrain(terrain) => {
                for (ci, cap) in terrain.capsules.iter().enumerate() {
                    let [a, b] = cap.nodes;
                    let x = [ws.node_pos[a], ws.node_pos[b]];
                    let v = [ws.node_vel[a], ws.node_vel[b]];
                    let grips = super::terrain::capsule_grips(terrain, &inputs.grip, ci);
                    let d = super::terrain::capsule_derivatives(terrain, x, v, cap.radius, grips);
                    for (m, blocks) in [(&mut self.position, &d[0]), (&mut self.velocity, &d[1])] {
                        for (row, row_blocks) in cap.ends.iter().zip(blocks) {
                            for (col, block) in cap.ends.iter().zip(row_blocks) {
                                if let (Some(r), Some(c)) = (row, col) {
                                    add_block(m, *r, *c, block);
                                }
                            }
                        }
                    }
                }
            }
            ForceEffect::Collisions(c) => {
                let nodes = (ws.node_pos.as_slice(), ws.node_vel.as_slice());
                let mut scratch = super::collisions::CollisionScratch::new(c.capsules.len());
                let mut touching = Vec::new();
                super::collisions::for_each_contact(c, nodes, &mut scratch, |i, j, _, _, _, _| {
                    touching.push((i, j));
                });
                for (i, j) in touching {
                    let pair = [&c.capsules[i], &c.capsules[j]];
                    let at = |k: usize| pair[k / 2].nodes[k % 2];
                    let x = [0, 1, 2, 3].map(|k| ws.node_pos[at(k)]);
                    let v = [0, 1, 2, 3].map(|k| ws.node_vel[at(k)]);
                    let d = super::collisions::pair_derivatives(c, pair, x, v);
                    let ends = [0, 1, 2, 3].map(|k| pair[k / 2].ends[k % 2]);
                    for (m, blocks) in [(&mut self.position, &d[0]), (&mut self.velocity, &d[1])] {
                        for (row, row_blocks) in ends.iter().zip(blocks) {
                            for (col, block) in ends.iter().zip(row_blocks) {
                                if let (Some(r), Some(c)) = (row, col) {
                                    add_block(m, *r, *c, block);
                                }
                            }
                        }
                    }
                }
            }
            ForceEffect::Gravity(_)
            | ForceEffect::NodeForces(_)
            | ForceEffect::ScriptedLoads(_) => {}
        }
    }

    /// A cable with `γ = κ (1 − s₀/|s|) + c (s·ṡ)/|s|²` while taut and positive.
    fn cable(&mut self, link: &CableLink, ws: &Workspace, stiffness: f64, rest: f64, c: f64) {
        let (s, s_dot) = (cable_vector(link, ws), cable_rate(link, ws));
        let gamma = density(stiffness, rest, c, &s, &s_dot);
        if gamma <= 0.0 {
            return;
        }
        let (l2, sv) = (s.norm_squared(), s.dot(&s_dot));
        let len = l2.sqrt();
        let grad =
            s * (stiffness * rest / (len * l2)) + (s_dot / l2 - s * (2.0 * sv / (l2 * l2))) * c;
        let ks = Matrix3::identity() * gamma + s * grad.transpose();
        let cs = s * s.transpose() * (c / l2);
        self.pair(link, &ks, &cs);
    }

    /// Adds `∂(γ s)/∂s` (and `/∂ṡ`): `+γ s` acts on end a, `−γ s` on end b.
    fn pair(&mut self, link: &CableLink, ks: &Matrix3<f64>, cs: &Matrix3<f64>) {
        for (m, d) in [(&mut self.position, ks), (&mut self.velocity, cs)] {
            let [a, b] = link.ends;
            for (end, sign) in [(a, 1.0), (b, -1.0)] {
                let Some(row) = end else { continue };
                if let Some(col) = b {
                    add_block(m, row, col, &(d * sign));
                }
                if let Some(col) = a {
                    add_block(m, row, col, &(d * -sign));
                }
            }
        }
    }
}

/// `γ` of an elastic law while taut and positive, else 0 (as the step computes it).
fn density(stiffness: f64, rest: f64, c: f64, s: &Vector3<f64>, s_dot: &Vector3<f64>) -> f64 {
    effects::damped_density(stiffness, rest, c, s, s_dot)
}

fn cable_vector(link: &CableLink, ws: &Workspace) -> Vector3<f64> {
    ws.node_pos[link.nodes[1]] - ws.node_pos[link.nodes[0]]
}

fn cable_rate(link: &CableLink, ws: &Workspace) -> Vector3<f64> {
    ws.node_vel[link.nodes[1]] - ws.node_vel[link.nodes[0]]
}

/// Puts a cable's `∂(γ s)/∂u = value` into column `col`: `+value` on end a, `−value` on b.
fn put_cable(m: &mut DMatrix<f64>, col: usize, link: &CableLink, value: &Vector3<f64>) {
    for (end, sign) in [(link.ends[0], 1.0), (link.ends[1], -1.0)] {
        if let Some(e) = end {
            for k in 0..3 {
                m[(3 * e + k, col)] += sign * value[k];
            }
        }
    }
}

/// Derivatives of the ground force at one node. The penalty's stiffness counts from
/// `TOUCHING` above the surface inward, so a node written onto the surface (within
/// round-off of it) is held from the start.
fn contact_derivatives(
    ground: &crate::model::contact::Ground,
    x: &Vector3<f64>,
    v: &Vector3<f64>,
    r: f64,
) -> (Matrix3<f64>, Matrix3<f64>) {
    let zero = (Matrix3::zeros(), Matrix3::zeros());
    let n = ground.normal;
    let d = ground.penetration(x, r);
    if d < -TOUCHING {
        return zero;
    }
    let d = d.max(0.0);
    let vn = n.dot(v);
    let fn_ = ground.stiffness * d - ground.damping * vn;
    if fn_ < 0.0 || (fn_ == 0.0 && d > 0.0) {
        return zero;
    }
    // f_n depends on x through −k n and on v through −c n.
    let (dfn_dx, dfn_dv) = (-n * ground.stiffness, -n * ground.damping);
    let nn = n * n.transpose();
    let mut dx = n * dfn_dx.transpose();
    let mut dv = n * dfn_dv.transpose();
    let tangential = Matrix3::identity() - nn;
    let vt = v - n * vn;
    let speed = vt.norm();
    let mu = ground.friction;
    if mu > 0.0 {
        if speed <= ground.slip_velocity {
            let k = mu / ground.slip_velocity;
            dx -= vt * dfn_dx.transpose() * k;
            dv -= (tangential * fn_ + vt * dfn_dv.transpose()) * k;
        } else {
            let t = vt / speed;
            dx -= t * dfn_dx.transpose() * mu;
            dv -= ((tangential - t * t.transpose()) * (fn_ / speed) + t * dfn_dv.transpose()) * mu;
        }
    }
    (dx, dv)
}

/// How far above the ground a node still counts as touching it, m.
const TOUCHING: f64 = 1e-9;

fn add_block(m: &mut DMatrix<f64>, row: usize, col: usize, block: &Matrix3<f64>) {
    for r in 0..3 {
        for c in 0..3 {
            m[(3 * row + r, 3 * col + c)] += block[(r, c)];
        }
    }
}

/// `[[B, −B], [−B, B]]` on ends `(a, b)`.
fn add_pair(m: &mut DMatrix<f64>, [a, b]: [usize; 2], block: &Matrix3<f64>) {
    add_block(m, a, a, block);
    add_block(m, b, b, block);
    add_block(m, a, b, &-block);
    add_block(m, b, a, &-block);
}
