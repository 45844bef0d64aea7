//! An evaluation on two threads, for large structures.
//!
//! Each stage's items are split in two halves, one run on the calling thread and one on
//! the workspace's [`Helper`]: ends, nodes and bars by index, forces by the ends they act
//! on, K's blocks by the bars that set them, the reactions' right-hand side and their
//! addition to the end forces by constraint columns at a seam across which no end is
//! shared, and the factor by the connected components of K (a tower's three chains of
//! joints), which factor independently (when the first thread has more columns and more
//! than one component, it hands its last one's backward substitution to the second). The halves run the baseline x86-64 build of the
//! stages (the one-thread evaluation picks AVX2 where it can; the bits are the same). An item's arithmetic is the one-thread evaluation's, and every sum
//! keeps its order: where both halves add to one value (a block of K at the seam, the
//! acceleration of a node the seam's two bars share), the second half's terms wait until
//! both halves are done and are added in order after them. So the results are the same
//! bits as on one thread.
//!
//! Why two threads pay: at these sizes an evaluation streams its arrays from memory, and on
//! this 2-core machine one core draws about half of what two draw together (two copies of
//! the 60,000-bar benchmark run side by side without slowing each other).

mod helper;

use std::sync::atomic::{AtomicU8, Ordering};

use nalgebra::Vector3;

pub use helper::{on_helper_thread, Helper};

use super::effects::{self, ForceEffect, ForceSink};
use super::{pairs, pairs_mut, response, BarKept, Inputs, Workspace};
use crate::model::block_cholesky::BlockLdl;
use crate::model::effects::CableLink;
use crate::model::Model;

/// Structures from this many bars up evaluate on two threads (`bench`, measured side by
/// side: see the README's performance section).
pub const MIN_BARS: usize = 4_000;

/// A cable whose force density the other thread records.
const OTHER: usize = usize::MAX;

/// How an evaluation's items are split between the two threads; built once per workspace.
#[derive(Debug, Clone)]
pub struct Halves {
    /// Bars `[0, bars)` are the first thread's, and their ends `[0, 2 bars)`.
    bars: usize,
    /// Nodes `[0, nodes)` are the first thread's.
    nodes: usize,
    /// Each thread's force effects: the items acting on its ends, the other thread's ends
    /// masked, each cable's force density recorded by one thread.
    forces: [Vec<ForceEffect>; 2],
    /// Effects applied after both halves', in order (ground contact, last in the pipeline).
    after: Vec<ForceEffect>,
    /// Per contribution to K: the second half's to a block the first half also sets.
    deferred: Vec<bool>,
    /// Those contributions' bars, in order.
    deferred_bars: Vec<usize>,
    /// Each thread's constraint columns to factor: whole components of K, in order.
    columns: [Vec<usize>; 2],
    /// The first thread's last columns (its last component) whose backward substitution
    /// the second thread runs, once the first has factored them (0 if none): the factor
    /// is bound by memory, so a thread with two of the tower's three chains hands the
    /// second one's backward pass to the thread with one.
    handed_columns: usize,
    /// Constraint columns `[0, even)` are the first thread's for the right-hand side and
    /// the addition of Ω to the end forces (half of them, acting on ends of their own).
    even: usize,
    /// Per end of the second half: its reduced node is also the first half's.
    late: Vec<bool>,
    /// Those ends, in order.
    late_ends: Vec<usize>,
}

impl Halves {
    /// The split of `model`'s evaluation, if it has at least `min_bars` bars and its layout
    /// allows one: the sparse joint/pin basis, K (if any) sparse with the scalar factor, and
    /// ground contact (which runs after both halves) last among the forces.
    ///
    /// Numberings: `columns` are in the reaction system's (K's), `even` in the
    /// coordinates'. The one-thread path adds Ω to the ends in the system's order and the
    /// halves in the coordinates'; they agree because the columns sharing an end share a
    /// bar, so lie in one component, whose order the system keeps.
    pub fn new(model: &Model, min_bars: usize) -> Option<Self> {
        let n_bars = model.bars.len();
        let single = model.coords.single.as_ref()?;
        if n_bars < min_bars.max(2) {
            return None;
        }
        let reactions = &model.reactions;
        let chol = match reactions.sparse() {
            Some(chol) if !chol.has_lanes() => Some(chol),
            None if reactions.size() == 0 => None,
            _ => return None,
        };
        let bars = n_bars / 2;
        let ends = 2 * bars;
        let owner = |e: usize| usize::from(e >= ends);
        let (forces, after) = split_forces(&model.pipeline.forces, owner)?;

        // K's blocks: the first half's, then the second half's on blocks of their own.
        let n_contributions = (0..n_bars)
            .map(|i| reactions.contributions_of(i).len())
            .sum();
        let mut deferred = vec![false; n_contributions];
        let mut deferred_bars = Vec::new();
        let mut columns = [Vec::new(), Vec::new()];
        let mut handed_columns = 0;
        let mut even = 0;
        if let Some(chol) = chol {
            let mut first_half = vec![false; chol.slots()];
            for i in (0..bars).flat_map(|b| reactions.contributions_of(b)) {
                first_half[reactions.contribution_slot(i)] = true;
            }
            for b in bars..n_bars {
                for i in reactions.contributions_of(b) {
                    deferred[i] = first_half[reactions.contribution_slot(i)];
                }
                if reactions.contributions_of(b).any(|i| deferred[i]) {
                    deferred_bars.push(b);
                }
            }
            (columns, handed_columns) = split_components(chol);
            even = seam(
                chol.size(),
                |c| reactions.column_terms(c),
                model.coords.n_ends(),
            );
        }

        // Accelerations of reduced nodes both halves' ends move.
        let mut first_half = vec![false; model.coords.r];
        for (g, _) in single[..ends].iter().flatten() {
            first_half[*g] = true;
        }
        let late: Vec<bool> = single[ends..]
            .iter()
            .map(|term| term.is_some_and(|(g, _)| first_half[g]))
            .collect();
        let late_ends = (0..late.len())
            .filter(|&k| late[k])
            .map(|k| ends + k)
            .collect();
        Some(Self {
            bars,
            nodes: model.n_nodes() / 2,
            forces,
            after,
            deferred,
            deferred_bars,
            columns,
            handed_columns,
            even,
            late,
            late_ends,
        })
    }
}

/// Each thread's force effects, and those applied after both (ground contact); `None` if
/// an effect that cannot be split comes before one that can.
fn split_forces(
    effects: &[ForceEffect],
    owner: impl Fn(usize) -> usize,
) -> Option<([Vec<ForceEffect>; 2], Vec<ForceEffect>)> {
    let serial_from = effects
        .iter()
        .position(|e| matches!(e, ForceEffect::GroundContact(_)))
        .unwrap_or(effects.len());
    let after = effects[serial_from..].to_vec();
    if after
        .iter()
        .any(|e| !matches!(e, ForceEffect::GroundContact(_)))
    {
        return None;
    }
    let part = |t: usize| -> Vec<ForceEffect> {
        let mine = |end: Option<usize>| end.filter(|&e| owner(e) == t);
        // A cable's force density is recorded by the thread of its first end (the first
        // thread for a cable between bar-less nodes).
        let link = |l: &CableLink| -> Option<CableLink> {
            let ends = l.ends.map(mine);
            let recorder = l.ends.iter().flatten().next().map_or(0, |&e| owner(e));
            let cable = if recorder == t { l.cable } else { OTHER };
            (ends.iter().any(Option::is_some) || cable != OTHER).then_some(CableLink {
                cable,
                nodes: l.nodes,
                ends,
            })
        };
        effects[..serial_from]
            .iter()
            .map(|effect| match effect {
                ForceEffect::ElasticCables(c) => ForceEffect::ElasticCables(
                    c.iter()
                        .filter_map(|(l, k, s)| Some((link(l)?, *k, *s)))
                        .collect(),
                ),
                ForceEffect::DampedCables(c) => ForceEffect::DampedCables(
                    c.iter()
                        .filter_map(|(l, k, s, d)| Some((link(l)?, *k, *s, *d)))
                        .collect(),
                ),
                ForceEffect::ForceDensityCables(c) => ForceEffect::ForceDensityCables(
                    c.iter().filter_map(|(l, i)| Some((link(l)?, *i))).collect(),
                ),
                ForceEffect::ReeledCables(c) => ForceEffect::ReeledCables(
                    c.iter()
                        .filter_map(|(l, k, d, i)| Some((link(l)?, *k, *d, *i)))
                        .collect(),
                ),
                ForceEffect::NodeForces(f) => ForceEffect::NodeForces(
                    f.iter()
                        .filter(|(_, e)| mine(*e).is_some())
                        .copied()
                        .collect(),
                ),
                ForceEffect::ScriptedLoads(l) => ForceEffect::ScriptedLoads(
                    l.iter()
                        .filter(|(e, _)| mine(*e).is_some())
                        .cloned()
                        .collect(),
                ),
                ForceEffect::Gravity(w) => ForceEffect::Gravity(
                    w.iter().filter(|(e, _)| owner(*e) == t).copied().collect(),
                ),
                ForceEffect::GroundContact(_) => unreachable!("applied after the halves"),
            })
            .collect()
    };
    Some(([part(0), part(1)], after))
}

/// The first column from the middle on at which the columns before it act on no end the
/// columns after it act on (`n` if there is none): the split of the right-hand side and of
/// the addition of Ω, which write by column and by end.
fn seam<'a>(n: usize, terms: impl Fn(usize) -> &'a [(usize, f64)], n_ends: usize) -> usize {
    let mut last = vec![0; n_ends];
    for c in 0..n {
        for &(e, _) in terms(c) {
            last[e] = c;
        }
    }
    // reach[c]: the last column acting on an end of columns 0..=c.
    let mut reach = 0;
    for c in 0..n {
        reach = terms(c).iter().fold(reach, |r, &(e, _)| r.max(last[e]));
        if c + 1 >= n / 2 && reach == c {
            return c + 1;
        }
    }
    n
}

/// K's components shared between the threads, the largest first to the thread with fewer
/// columns; each thread's columns in order. With the handoff: the number of the first
/// thread's last columns whose backward substitution the second runs (its last component,
/// if it has more columns than the second and more than one component).
fn split_components(chol: &BlockLdl) -> ([Vec<usize>; 2], usize) {
    let mut components = chol.components();
    components.sort_by_key(|c| std::cmp::Reverse(c.len()));
    let mut split = [Vec::new(), Vec::new()];
    for component in components {
        let sizes = split
            .each_ref()
            .map(|c: &Vec<Vec<usize>>| c.iter().map(Vec::len).sum::<usize>());
        split[usize::from(sizes[1] < sizes[0])].push(component);
    }
    for components in &mut split {
        components.sort_unstable_by_key(|c| c[0]);
    }
    let sizes = split
        .each_ref()
        .map(|c| c.iter().map(Vec::len).sum::<usize>());
    let handoff = match split[0].last() {
        Some(last) if split[0].len() > 1 && sizes[0] > sizes[1] => last.len(),
        _ => 0,
    };
    (split.map(|c| c.concat()), handoff)
}

/// The first thread's word that the columns it hands off are factored (and how).
#[derive(Default)]
struct Handoff(AtomicU8);

/// Sends its outcome once; a failure if dropped unsent (a panic), so the waiter ends.
struct Signal<'a>(Option<&'a Handoff>);

const PENDING: u8 = 0;
const FACTORED: u8 = 1;
const FAILED: u8 = 2;

impl Handoff {
    fn signal(&self) -> Signal<'_> {
        Signal(Some(self))
    }

    /// Waits for the outcome; true if the columns were factored. It spins (the other
    /// thread's factor is about a millisecond away at most), yielding its core after a
    /// while in case the other thread needs it.
    fn wait(&self) -> bool {
        let mut spins = 0u32;
        loop {
            match self.0.load(Ordering::Acquire) {
                PENDING if spins < 1 << 16 => {
                    spins += 1;
                    std::hint::spin_loop();
                }
                PENDING => std::thread::yield_now(),
                outcome => return outcome == FACTORED,
            }
        }
    }
}

impl Signal<'_> {
    fn send(&mut self, factored: bool) {
        if let Some(handoff) = self.0.take() {
            let outcome = if factored { FACTORED } else { FAILED };
            handoff.0.store(outcome, Ordering::Release);
        }
    }
}

impl Drop for Signal<'_> {
    fn drop(&mut self) {
        self.send(false);
    }
}

/// A slice two threads write at disjoint indices.
#[derive(Clone, Copy)]
struct Disjoint<T>(*mut T);

// SAFETY: the writers keep to disjoint indices (see each use).
unsafe impl<T: Send> Send for Disjoint<T> {}
unsafe impl<T: Send> Sync for Disjoint<T> {}

impl<T> Disjoint<T> {
    fn new(slice: &mut [T]) -> Self {
        Self(slice.as_mut_ptr())
    }

    fn ptr(self) -> *mut T {
        self.0
    }

    /// # Safety
    /// `i` is in bounds and no other thread touches it meanwhile.
    #[allow(clippy::mut_from_ref)]
    unsafe fn at(&self, i: usize) -> &mut T {
        &mut *self.0.add(i)
    }
}

/// One thread's outputs of the forces: its ends, the force densities it records and the
/// contact forces (written only after both halves).
struct HalfSink {
    end_force: Disjoint<Vector3<f64>>,
    gamma: Disjoint<f64>,
}

impl ForceSink for HalfSink {
    #[inline(always)]
    fn add(&mut self, end: usize, f: Vector3<f64>) {
        // SAFETY: this thread's effects act on its own ends only (`split_forces`).
        unsafe { *self.end_force.at(end) += f }
    }
    #[inline(always)]
    fn gamma(&mut self, cable: usize, gamma: f64) {
        if cable != OTHER {
            // SAFETY: one thread records each cable (`split_forces`).
            unsafe { *self.gamma.at(cable) = gamma }
        }
    }
    fn contact(&mut self, _: usize, _: Vector3<f64>) {
        unreachable!("ground contact is applied after the halves")
    }
}

/// [`super::evaluate`] on two threads (the sparse basis, see [`Halves::new`]): this one and
/// `helper`'s.
#[allow(clippy::too_many_arguments)]
pub(super) fn evaluate(
    model: &Model,
    (halves, helper): (&Halves, &Helper),
    inputs: &Inputs,
    t: f64,
    q: &[f64],
    v: &[f64],
    ws: &mut Workspace,
    acc: &mut [f64],
) {
    let coords = &model.coords;
    let single = coords.single.as_deref().expect("the sparse basis");
    let (b, e) = (halves.bars, 2 * halves.bars);
    // The halves write through raw pointers: the lengths they index are checked here once.
    assert_eq!(
        acc.len(),
        3 * coords.r,
        "accelerations of every reduced node"
    );
    assert_eq!(ws.end_force.len(), coords.n_ends(), "a force per end");
    assert_eq!(
        ws.gamma.len(),
        model.cables.len(),
        "a force density per cable"
    );
    {
        // Stage 1: kinematics (and the zeroing of the end forces and accelerations).
        {
            let (p0, p1) = ws.end_pos.split_at_mut(e);
            let (v0, v1) = ws.end_vel.split_at_mut(e);
            let (f0, f1) = ws.end_force.split_at_mut(e);
            let (a0, a1) = acc.split_at_mut(acc.len() / 2);
            let (s0, s1) = single.split_at(e);
            let (c0, c1) = coords.fixed.split_at(e);
            helper.join(
                || ends_half((s0, c0), (q, v), (p0, v0, f0), a0),
                || ends_half((s1, c1), (q, v), (p1, v1, f1), a1),
            );
        }
        {
            let n = halves.nodes;
            let ends = (ws.end_pos.as_slice(), ws.end_vel.as_slice());
            let (x0, x1) = ws.node_pos.split_at_mut(n);
            let (xd0, xd1) = ws.node_vel.split_at_mut(n);
            helper.join(
                || super::node_states(&coords.node_end[..n], ends, (x0, xd0)),
                || super::node_states(&coords.node_end[n..], ends, (x1, xd1)),
            );
        }
        // Stage 2: forces.
        {
            let nodes = (ws.node_pos.as_slice(), ws.node_vel.as_slice());
            let end_force = Disjoint::new(&mut ws.end_force);
            let gamma = Disjoint::new(&mut ws.gamma);
            let half = |side: usize| {
                let mut sink = HalfSink { end_force, gamma };
                effects::apply(&halves.forces[side], inputs, t, nodes, &mut sink);
            };
            helper.join(|| half(0), || half(1));
            if !halves.after.is_empty() {
                let mut sink = effects::Slices {
                    end_force: &mut ws.end_force,
                    gamma: &mut ws.gamma,
                    contact_force: &mut ws.contact_force,
                };
                effects::apply(&halves.after, inputs, t, nodes, &mut sink);
            }
        }
        let with_reactions = !model.pipeline.constraints.is_empty();
        // Stage 3: λ, the end accelerations and K.
        let mut scale: f64;
        {
            if with_reactions {
                ws.reactions.clear();
            }
            let Workspace {
                end_pos,
                end_vel,
                end_force,
                end_acc,
                lambda,
                bars,
                reactions,
                ..
            } = &mut *ws;
            let shared = reactions.shared();
            let (acc0, acc1) = pairs_mut(end_acc).split_at_mut(b);
            let (l0, l1) = lambda.split_at_mut(b);
            let (k0, k1) = bars.split_at_mut(b);
            let given = |range: std::ops::Range<usize>| {
                (
                    range.start,
                    &pairs(end_pos)[range.clone()],
                    &pairs(end_vel)[range.clone()],
                    &pairs(end_force)[range],
                )
            };
            let shared = &shared;
            let deferred = &halves.deferred;
            // Each part also gathers the largest diagonal magnitude of the pivot blocks it
            // closes: the scale of the singularity threshold.
            let (amax0, amax1) = helper.join(
                || {
                    let mut amax: f64 = 0.0;
                    first_response(model, given(0..b), (acc0, l0, k0), |i, bv, l2| {
                        if let Some(r) = shared {
                            // SAFETY: the first half's blocks; the second half's terms
                            // on them wait (`deferred`).
                            amax = amax.max(unsafe { r.add_bar(i, bv, l2, |_| false) });
                        }
                    });
                    amax
                },
                || {
                    let mut amax: f64 = 0.0;
                    let n = model.bars.len();
                    first_response(model, given(b..n), (acc1, l1, k1), |i, bv, l2| {
                        if let Some(r) = shared {
                            // SAFETY: the second half's own blocks.
                            amax = amax.max(unsafe { r.add_bar(i, bv, l2, |c| deferred[c]) });
                        }
                    });
                    amax
                },
            );
            scale = amax0.max(amax1);
            if let Some(r) = shared {
                for &i in &halves.deferred_bars {
                    let bv = bars[i].0;
                    // SAFETY: both halves are done; one thread.
                    let closed =
                        unsafe { r.add_bar(i, &bv, 1.0 / bv.norm_squared(), |c| !deferred[c]) };
                    scale = scale.max(closed);
                }
            }
        }
        // Stage 4: reactions, each thread factoring and solving its components.
        if with_reactions {
            let solved = {
                let n = ws.reactions.size() / 3;
                let end_acc = ws.end_acc.as_slice();
                let shared = ws.reactions.shared().expect("the scalar factor");
                let halves_of = |side: usize| [0..halves.even, halves.even..n][side].clone();
                // SAFETY: each thread sets the right-hand side of its own columns.
                let rhs = |side: usize| unsafe { shared.set_rhs(halves_of(side), end_acc) };
                helper.join(|| rhs(0), || rhs(1));
                let tiny = BlockLdl::singular_below(scale);
                let (own, handed) =
                    halves.columns[0].split_at(halves.columns[0].len() - halves.handed_columns);
                let factored = Handoff::default();
                // The waiter is `join`'s second closure: a join without the helper runs
                // the first, which always sends, before it.
                // SAFETY: components share no slot, pivot or right-hand side entry; the
                // handed-off columns' backward substitution waits for their factor.
                let (ok0, ok1) = helper.join(
                    || unsafe {
                        let mut signal = factored.signal();
                        let ok = shared.factor(&halves.columns[0], tiny);
                        signal.send(ok);
                        if ok {
                            shared.solve_back(own);
                        }
                        ok
                    },
                    || unsafe {
                        let ok = shared.factor(&halves.columns[1], tiny);
                        if ok {
                            shared.solve_back(&halves.columns[1]);
                        }
                        if !handed.is_empty() && factored.wait() {
                            shared.solve_back(handed);
                        }
                        ok
                    },
                );
                if ok0 && ok1 {
                    let end_force = Disjoint::new(&mut ws.end_force);
                    // SAFETY: the two threads' columns act on different ends (`Halves::new`).
                    let add =
                        |side: usize| unsafe { shared.add_to(halves_of(side), end_force.ptr()) };
                    helper.join(|| add(0), || add(1));
                }
                ok0 && ok1
            };
            if !solved {
                // A self-stressed frame: K again from the kept bar vectors (the factor
                // may have overwritten it), then the one-thread path, which fails the same way and
                // takes the dense solve.
                super::assemble_kept(&mut ws.reactions, &ws.bars);
                super::add_reactions(ws);
            }
            // Stage 5: λ and the end accelerations again, and their scatter.
            let per_bar = (&coords.static_bar, &model.inertia);
            let (acc0, acc1) = pairs_mut(&mut ws.end_acc).split_at_mut(b);
            let (l0, l1) = ws.lambda.split_at_mut(b);
            let (kept, forces) = (ws.bars.as_slice(), pairs(&ws.end_force));
            helper.join(
                || {
                    let given = (&kept[..b], &forces[..b]);
                    super::second_response((&per_bar.0[..b], &per_bar.1[..b]), given, (acc0, l0))
                },
                || {
                    let given = (&kept[b..], &forces[b..]);
                    super::second_response((&per_bar.0[b..], &per_bar.1[b..]), given, (acc1, l1))
                },
            );
        }
        // The accelerations of the reduced nodes; the second half skips those the first
        // half moves, and adds to them after it, in order.
        let out = Disjoint::new(acc.as_chunks_mut::<3>().0);
        let end_acc = ws.end_acc.as_slice();
        let scatter = |ends: std::ops::Range<usize>, second: bool| {
            for k in ends {
                if let Some((g, c)) = single[k] {
                    if !(second && halves.late[k - e]) {
                        // SAFETY: the halves' reduced nodes are disjoint but for the late
                        // ones, which the second half skips.
                        super::add_scaled(unsafe { out.at(g) }, c, &end_acc[k]);
                    }
                }
            }
        };
        helper.join(|| scatter(0..e, false), || scatter(e..single.len(), true));
        for &k in &halves.late_ends {
            if let Some((g, c)) = single[k] {
                // SAFETY: both halves are done; one thread.
                super::add_scaled(unsafe { out.at(g) }, c, &end_acc[k]);
            }
        }
    }
}

/// Stage 1 for one half of the ends: positions and velocities, and the end forces and
/// this half of the accelerations zeroed.
#[allow(clippy::type_complexity)]
fn ends_half(
    basis: (&[Option<(usize, f64)>], &[Vector3<f64>]),
    (q, v): (&[f64], &[f64]),
    (x, xdot, f): (
        &mut [Vector3<f64>],
        &mut [Vector3<f64>],
        &mut [Vector3<f64>],
    ),
    acc: &mut [f64],
) {
    super::end_states(basis.0, basis.1, q, v, (x, xdot));
    f.iter_mut().for_each(|f| *f = Vector3::zeros());
    acc.iter_mut().for_each(|a| *a = 0.0);
}

/// The first λ pass over a run of bars from bar `first` on (given their end positions,
/// velocities and forces), with `add_bar(i, b, 1/|b|²)` for each moving bar `i`: the
/// arithmetic of [`super::bar_response`], which keeps its own loop (through this function
/// and a closure, tower20 took 3% more instructions).
#[inline(always)]
#[allow(clippy::type_complexity)]
fn first_response(
    model: &Model,
    (first, xs, vs, fs): (
        usize,
        &[[Vector3<f64>; 2]],
        &[[Vector3<f64>; 2]],
        &[[Vector3<f64>; 2]],
    ),
    (end_acc, lambda, bars): (&mut [[Vector3<f64>; 2]], &mut [f64], &mut [BarKept]),
    mut add_bar: impl FnMut(usize, &Vector3<f64>, f64),
) {
    let range = first..first + xs.len();
    let per_bar = model.coords.static_bar[range.clone()]
        .iter()
        .zip(&model.inertia[range]);
    let ends = xs.iter().zip(vs).zip(fs);
    let out = end_acc.iter_mut().zip(lambda).zip(bars);
    for (i, ((&fixed, inertia), (((x, v), f), ((acc, lambda), kept)))) in
        per_bar.zip(ends.zip(out)).enumerate()
    {
        if fixed {
            *lambda = 0.0;
            *acc = [Vector3::zeros(); 2];
            continue;
        }
        let bv = x[1] - x[0];
        let bdot = v[1] - v[0];
        let inv_l2 = 1.0 / bv.norm_squared();
        *kept = (
            bv,
            -bdot.norm_squared(),
            inv_l2 * inertia.inv_beta_minus_alpha,
        );
        add_bar(first + i, &bv, inv_l2);
        (*lambda, *acc) = response(inertia, *kept, f);
    }
}

#[cfg(test)]
mod tests;
