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

mod halves;
mod handoff;
mod helper;

use nalgebra::Vector3;

pub use halves::Halves;
use halves::OTHER;
use handoff::Handoff;
pub use helper::{on_helper_thread, Helper};

use super::bar_response::{first_responses, pairs, pairs_mut};
use super::effects::{self, ForceSink};
use super::{Inputs, Workspace};
use crate::linalg::block_cholesky::BlockLdl;
use crate::model::Model;

/// Structures from this many bars up evaluate on two threads (`bench`, measured side by
/// side: see docs/benchmarks.md).
pub const MIN_BARS: usize = 4_000;

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
    fn shape_loads(&mut self) -> &mut [super::terrain::ShapeLoad] {
        unreachable!("terrain contact is applied after the halves")
    }
    fn collision(&mut self) -> &mut super::collisions::CollisionScratch {
        unreachable!("collisions are applied after the halves")
    }
    fn terrain_near(&mut self) -> &mut crate::contact::Proximity {
        unreachable!("terrain contact is applied after the halves")
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
                    shape_load: &mut ws.shape_load,
                    collision: &mut ws.collision,
                    terrain_near: &mut ws.terrain_near,
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
                    first_responses(model, given(0..b), (acc0, l0, k0), |i, bv, l2| {
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
                    first_responses(model, given(b..n), (acc1, l1, k1), |i, bv, l2| {
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
                    let (bv, inv_l2) = (bars[i].0, bars[i].3);
                    // SAFETY: both halves are done; one thread.
                    let closed = unsafe { r.add_bar(i, &bv, inv_l2, |c| !deferred[c]) };
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
                super::bar_response::assemble_kept(&mut ws.reactions, &ws.bars);
                super::add_reactions(ws);
            }
            // Stage 5: λ and the end accelerations again, and their scatter.
            let (acc0, acc1) = pairs_mut(&mut ws.end_acc).split_at_mut(b);
            let (l0, l1) = ws.lambda.split_at_mut(b);
            let (kept, forces) = (ws.bars.as_slice(), pairs(&ws.end_force));
            helper.join(
                || {
                    super::bar_response::second_responses(
                        model,
                        (0, &kept[..b], &forces[..b]),
                        (acc0, l0),
                    )
                },
                || {
                    super::bar_response::second_responses(
                        model,
                        (b, &kept[b..], &forces[b..]),
                        (acc1, l1),
                    )
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

#[cfg(test)]
mod tests;
