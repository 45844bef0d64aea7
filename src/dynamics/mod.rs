//! The equations of motion in reduced coordinates, evaluated in named stages:
//! kinematics → forces → bar force densities λ → reactions Ω → accelerations η̈₂.
//!
//! The forces are the scene's declared effects ([`effects::Pipeline`]). M is block
//! diagonal per bar, so with `b̈ = α g_a + β g_b` (see [`crate::model::inertia`]) and
//! `b·b̈ = −|ḃ|²`, λ is closed-form per bar. Ω enters λ through the end forces and comes
//! from `N̈ P = 0`; it is a stage only when the scene has pins or joints.

mod bar_response;
pub mod collisions;
pub mod contact_points;
pub mod effects;
pub mod energy;
pub mod parallel;
pub mod supports;
pub mod tangent;
pub mod terrain;

use std::sync::Arc;

use nalgebra::Vector3;

use crate::contact::Grip;
use crate::model::reactions::Reactions;
use crate::model::{CableLaw, Model};
pub use bar_response::bar_response;
use bar_response::{assemble_kept, bar_response_again};
pub use effects::applied_forces;
use parallel::{Halves, Helper};

/// Values an importer sets between steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Inputs {
    /// Commanded force density per controlled cable, N/m (clamped at ≥ 0 when used).
    pub force_density: Vec<f64>,
    /// External force per force-input node, N.
    pub node_force: Vec<Vector3<f64>>,
    /// Commanded rest length per rest-length controlled cable, m (clamped at ≥ 0 when used).
    pub rest_length: Vec<f64>,
    /// The friction state of every terrain grip ([`crate::model::terrain::Terrain::grip`]):
    /// held over a step like the inputs, moved only between steps (see `sim::grip`).
    pub grip: Vec<Grip>,
}

impl Inputs {
    /// The scene's start values.
    pub fn start(model: &Model) -> Self {
        Self {
            force_density: model.controlled_start.clone(),
            node_force: vec![Vector3::zeros(); model.force_inputs.len()],
            rest_length: model.reeled_start.clone(),
            grip: vec![Grip::Free; model.terrain.as_ref().map_or(0, |t| t.grips())],
        }
    }

    /// Copies `other` in place (same model, so no allocation).
    pub fn copy_from(&mut self, other: &Inputs) {
        self.force_density.copy_from_slice(&other.force_density);
        self.node_force.copy_from_slice(&other.node_force);
        self.rest_length.copy_from_slice(&other.rest_length);
        self.grip.copy_from_slice(&other.grip);
    }
}

/// What λ needs of a bar besides its end forces, `(b, −|ḃ|², 1/((β − α)|b|²))`, kept from
/// the first λ pass for the second, and `1/|b|²` for K's assembly after it.
type BarKept = (Vector3<f64>, f64, f64, f64);

/// A workspace's split between two threads and its second thread; a copy of the workspace
/// gets a thread of its own (two simulations must not share one).
#[derive(Debug)]
struct TwoThreads(Arc<(Halves, Helper)>);

impl Clone for TwoThreads {
    fn clone(&self) -> Self {
        Self(Arc::new((self.0 .0.clone(), Helper::default())))
    }
}

/// Scratch space for one evaluation; allocated once per simulation.
#[derive(Debug, Clone)]
pub struct Workspace {
    /// Bar-end positions (columns of N), m.
    pub end_pos: Vec<Vector3<f64>>,
    /// Bar-end velocities, m/s.
    pub end_vel: Vec<Vector3<f64>>,
    /// Bar-end forces including reactions, N.
    pub end_force: Vec<Vector3<f64>>,
    /// Bar-end accelerations, m/s².
    pub end_acc: Vec<Vector3<f64>>,
    /// Physical node positions, m.
    pub node_pos: Vec<Vector3<f64>>,
    /// Physical node velocities, m/s.
    pub node_vel: Vec<Vector3<f64>>,
    /// Cable force densities γ, N/m.
    pub gamma: Vec<f64>,
    /// Bar force densities λ (compression positive), N/m.
    pub lambda: Vec<f64>,
    /// Ground contact force per contact point (`Ground::nodes` order), N.
    pub contact_force: Vec<Vector3<f64>>,
    /// Each terrain shape's total force and contact count.
    pub shape_load: Vec<terrain::ShapeLoad>,
    /// The collision broad phase's buffers and what it found.
    pub collision: collisions::CollisionScratch,
    /// Which capsule–shape pairs are too far from each other to touch soon.
    pub terrain_near: crate::contact::Proximity,
    /// Per bar, what the second λ pass needs, and `b` and `1/|b|²` for K's assembly after
    /// the first (K's bundles, deferred blocks, again after a failed factor).
    bars: Vec<BarKept>,
    reactions: Reactions,
    /// Evaluations where the sparse reaction factor failed and the dense solve was used.
    pub dense_fallbacks: u64,
    /// The split of each evaluation between two threads, for large structures, and the
    /// second thread.
    halves: Option<TwoThreads>,
}

impl Workspace {
    /// Whether evaluations run on two threads.
    pub fn two_threads(&self) -> bool {
        self.halves.is_some()
    }

    /// Runs `f(start, part)` over `out` in two halves, on this thread and the evaluation's
    /// second one, when evaluations run on two threads (else over the whole at once). For
    /// loops over independent items, which give the same bits either way: at the sizes that
    /// take two threads such a loop streams from memory, and two cores draw about twice
    /// what one does.
    pub fn for_each_half<T: Send>(&self, out: &mut [T], f: impl Fn(usize, &mut [T]) + Sync) {
        match &self.halves {
            Some(two) => {
                let mid = out.len() / 2;
                let (first, second) = out.split_at_mut(mid);
                two.0 .1.join(|| f(0, first), || f(mid, second));
            }
            None => f(0, out),
        }
    }

    /// `to.copy_from_slice(from)`, in halves as [`Self::for_each_half`] runs them.
    pub fn copy_in_halves(&self, to: &mut [f64], from: &[f64]) {
        assert_eq!(to.len(), from.len(), "copies of one length");
        self.for_each_half(to, |start, to| {
            to.copy_from_slice(&from[start..start + to.len()]);
        });
    }

    /// Ω of constraint column `c` from the last evaluation (zero without reactions), N.
    pub fn reaction_solution(&self, c: usize) -> Vector3<f64> {
        if self.reactions.size() == 0 {
            return Vector3::zeros();
        }
        self.reactions.solution(c)
    }

    /// Allocates everything an evaluation needs; from [`parallel::MIN_BARS`] bars on (and
    /// where the layout allows), evaluations run on two threads.
    pub fn new(model: &Model) -> Self {
        Self::two_threads_from(model, parallel::MIN_BARS)
    }

    /// [`Self::new`] with two threads from `min_bars` bars on.
    pub fn two_threads_from(model: &Model, min_bars: usize) -> Self {
        let ends = model.coords.n_ends();
        let nodes = model.n_nodes();
        Self {
            end_pos: vec![Vector3::zeros(); ends],
            end_vel: vec![Vector3::zeros(); ends],
            end_force: vec![Vector3::zeros(); ends],
            end_acc: vec![Vector3::zeros(); ends],
            node_pos: model.positions.clone(),
            node_vel: vec![Vector3::zeros(); nodes],
            gamma: vec![0.0; model.cables.len()],
            lambda: vec![0.0; model.bars.len()],
            contact_force: vec![
                Vector3::zeros();
                model.ground.as_ref().map_or(0, |g| g.nodes.len())
            ],
            shape_load: vec![
                terrain::ShapeLoad::default();
                model.terrain.as_ref().map_or(0, |t| t.shapes.len())
            ],
            collision: collisions::CollisionScratch::new(
                model.collisions.as_ref().map_or(0, |c| c.capsules.len()),
            ),
            terrain_near: crate::contact::Proximity::default(),
            bars: vec![(Vector3::zeros(), 0.0, 1.0, 1.0); model.bars.len()],
            reactions: model.reactions.clone(),
            dense_fallbacks: 0,
            halves: Halves::new(model, min_bars)
                .map(|h| TwoThreads(Arc::new((h, Helper::default())))),
        }
    }
}

/// Computes `η̈₂` (flat, length 3r) at time `t` for reduced positions `q` and velocities `v`.
///
/// Every stage is compiled twice: for baseline x86-64 and, used where the processor has
/// it, for AVX2 (wider registers and three-operand instructions; 7% fewer instructions on
/// tower20). Neither fuses a multiply with an add, so both give the same bits. A large
/// structure evaluates on two threads instead ([`parallel`], the baseline build).
pub fn accelerations(
    model: &Model,
    inputs: &Inputs,
    t: f64,
    q: &[f64],
    v: &[f64],
    ws: &mut Workspace,
    acc: &mut [f64],
) {
    if let Some(TwoThreads(two)) = &ws.halves {
        // A second handle on the same split and thread (the workspace stays borrowable);
        // cloning `TwoThreads` would start a thread of its own.
        let two = Arc::clone(two);
        return parallel::evaluate(model, (&two.0, &two.1), inputs, t, q, v, ws, acc);
    }
    crate::simd::dispatch!(evaluate(
        model: &Model,
        inputs: &Inputs,
        t: f64,
        q: &[f64],
        v: &[f64],
        ws: &mut Workspace,
        acc: &mut [f64],
    ))
}

/// The stages, inlined into each of [`accelerations`]' two versions (and, in the tests,
/// into the caller: the baseline version).
#[inline(always)]
fn evaluate(
    model: &Model,
    inputs: &Inputs,
    t: f64,
    q: &[f64],
    v: &[f64],
    ws: &mut Workspace,
    acc: &mut [f64],
) {
    kinematics(model, q, v, ws);
    applied_forces(model, inputs, t, ws);
    bar_response(model, ws);
    for constraint in &model.pipeline.constraints {
        match constraint {
            effects::ConstraintEffect::JointsAndPins => {
                add_reactions(ws);
                bar_response_again(model, ws);
            }
        }
    }
    acc.iter_mut().for_each(|a| *a = 0.0);
    let coords = &model.coords;
    let (acc, _) = acc.as_chunks_mut::<3>();
    if let Some(single) = &coords.single {
        for (term, a) in single.iter().zip(&ws.end_acc) {
            if let Some((g, c)) = *term {
                add_scaled(&mut acc[g], c, a);
            }
        }
        return;
    }
    for (e, a) in ws.end_acc.iter().enumerate() {
        for &(g, c) in coords.row(e) {
            add_scaled(&mut acc[g], c, a);
        }
    }
}

#[inline(always)]
fn add_scaled(at: &mut [f64; 3], c: f64, a: &Vector3<f64>) {
    at[0] += c * a.x;
    at[1] += c * a.y;
    at[2] += c * a.z;
}

/// Stage 1: end and node positions and velocities from the reduced state.
#[inline(always)]
pub fn kinematics(model: &Model, q: &[f64], v: &[f64], ws: &mut Workspace) {
    let coords = &model.coords;
    if let Some(single) = &coords.single {
        let ends = (ws.end_pos.as_mut_slice(), ws.end_vel.as_mut_slice());
        end_states(single, &coords.fixed, q, v, ends);
    } else {
        for e in 0..coords.n_ends() {
            let mut x = coords.fixed[e];
            let mut xdot = Vector3::zeros();
            for &(g, c) in coords.row(e) {
                x += Vector3::new(q[3 * g], q[3 * g + 1], q[3 * g + 2]) * c;
                xdot += Vector3::new(v[3 * g], v[3 * g + 1], v[3 * g + 2]) * c;
            }
            ws.end_pos[e] = x;
            ws.end_vel[e] = xdot;
        }
    }
    let ends = (ws.end_pos.as_slice(), ws.end_vel.as_slice());
    node_states(&coords.node_end, ends, (&mut ws.node_pos, &mut ws.node_vel));
}

/// Positions and velocities of the ends whose single basis terms and fixed parts are
/// given (the sparse basis: at most one term per end).
#[inline(always)]
fn end_states(
    single: &[Option<(usize, f64)>],
    fixed: &[Vector3<f64>],
    q: &[f64],
    v: &[f64],
    (end_pos, end_vel): (&mut [Vector3<f64>], &mut [Vector3<f64>]),
) {
    let (q, v) = (q.as_chunks::<3>().0, v.as_chunks::<3>().0);
    let ends = end_pos.iter_mut().zip(end_vel.iter_mut());
    for ((term, fixed), (x, xdot)) in single.iter().zip(fixed).zip(ends) {
        // Summed in locals and stored once: summed in place, each sum went through memory.
        let (mut at, mut rate) = (*fixed, Vector3::zeros());
        if let Some((g, c)) = *term {
            at += Vector3::from(q[g]) * c;
            rate += Vector3::from(v[g]) * c;
        }
        (*x, *xdot) = (at, rate);
    }
}

/// The positions and velocities of the nodes with an end (given by `node_end`), copied
/// from the ends'.
#[inline(always)]
fn node_states(
    node_end: &[Option<usize>],
    (end_pos, end_vel): (&[Vector3<f64>], &[Vector3<f64>]),
    (node_pos, node_vel): (&mut [Vector3<f64>], &mut [Vector3<f64>]),
) {
    let nodes = node_pos.iter_mut().zip(node_vel.iter_mut());
    for (end, (x, xdot)) in node_end.iter().zip(nodes) {
        if let Some(e) = *end {
            *x = end_pos[e];
            *xdot = end_vel[e];
        }
    }
}

/// Force density of one cable for extension vector `s` and its rate `s_dot` (for
/// reporting; the step runs the same laws through [`effects`]).
pub fn cable_force_density(
    law: &CableLaw,
    inputs: &Inputs,
    s: &Vector3<f64>,
    s_dot: &Vector3<f64>,
) -> f64 {
    match *law {
        CableLaw::Elastic {
            stiffness,
            rest_length,
            damping,
        } => effects::damped_density(stiffness, rest_length, damping.unwrap_or(0.0), s, s_dot),
        CableLaw::RestLengthControlled {
            stiffness,
            damping,
            input,
        } => {
            let rest_length = inputs.rest_length[input].max(0.0);
            effects::damped_density(stiffness, rest_length, damping.unwrap_or(0.0), s, s_dot)
        }
        CableLaw::Controlled { input } => inputs.force_density[input].max(0.0),
    }
}

/// Stage 4: reactions Ω from `N̈ P = 0` (K assembled by [`bar_response`]), added to the end
/// forces.
#[inline(always)]
fn add_reactions(ws: &mut Workspace) {
    ws.reactions.set_rhs(&ws.end_acc);
    // After a failed factor, K and the right-hand side again from the bar vectors
    // [`bar_response`] kept and the end accelerations (the same arithmetic, so the same
    // system).
    let (bars, end_acc) = (&ws.bars, &ws.end_acc);
    let assemble_again = |r: &mut Reactions| {
        assemble_kept(r, bars);
        r.set_rhs(end_acc);
    };
    if !ws.reactions.solve(assemble_again) {
        ws.dense_fallbacks += 1;
    }
    ws.reactions.add_to(&mut ws.end_force);
}

#[cfg(test)]
pub(crate) mod tests;
