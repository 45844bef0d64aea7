//! How an evaluation is split between the two threads: the plan built once per workspace.

use crate::dynamics::effects::ForceEffect;
use crate::linalg::block_cholesky::BlockLdl;
use crate::model::effects::CableLink;
use crate::model::Model;

/// A cable whose force density the other thread records.
pub(super) const OTHER: usize = usize::MAX;

/// How an evaluation's items are split between the two threads; built once per workspace.
#[derive(Debug, Clone)]
pub struct Halves {
    /// Bars `[0, bars)` are the first thread's, and their ends `[0, 2 bars)`.
    pub(super) bars: usize,
    /// Nodes `[0, nodes)` are the first thread's.
    pub(super) nodes: usize,
    /// Each thread's force effects: the items acting on its ends, the other thread's ends
    /// masked, each cable's force density recorded by one thread.
    pub(super) forces: [Vec<ForceEffect>; 2],
    /// Effects applied after both halves', in order (ground contact, last in the pipeline).
    pub(super) after: Vec<ForceEffect>,
    /// Per contribution to K: the second half's to a block the first half also sets.
    pub(super) deferred: Vec<bool>,
    /// Those contributions' bars, in order.
    pub(super) deferred_bars: Vec<usize>,
    /// Each thread's constraint columns to factor: whole components of K, in order.
    pub(super) columns: [Vec<usize>; 2],
    /// The first thread's last columns (its last component) whose backward substitution
    /// the second thread runs, once the first has factored them (0 if none): the factor
    /// is bound by memory, so a thread with two of the tower's three chains hands the
    /// second one's backward pass to the thread with one.
    pub(super) handed_columns: usize,
    /// Constraint columns `[0, even)` are the first thread's for the right-hand side and
    /// the addition of Ω to the end forces (half of them, acting on ends of their own).
    pub(super) even: usize,
    /// Per end of the second half: its reduced node is also the first half's.
    pub(super) late: Vec<bool>,
    /// Those ends, in order.
    pub(super) late_ends: Vec<usize>,
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
        .position(|e| {
            matches!(
                e,
                ForceEffect::GroundContact(_)
                    | ForceEffect::Terrain(_)
                    | ForceEffect::Collisions(_)
            )
        })
        .unwrap_or(effects.len());
    let after = effects[serial_from..].to_vec();
    if after.iter().any(|e| {
        !matches!(
            e,
            ForceEffect::GroundContact(_) | ForceEffect::Terrain(_) | ForceEffect::Collisions(_)
        )
    }) {
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
                ForceEffect::GroundContact(_)
                | ForceEffect::Terrain(_)
                | ForceEffect::Collisions(_) => {
                    unreachable!("applied after the halves")
                }
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
