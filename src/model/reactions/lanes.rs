//! K assembled into the side-by-side chains ([`crate::linalg::block_lanes`]) several bars at
//! a time.
//!
//! A tower's stage has one strut per chain, and the struts' contributions go to the same
//! blocks of the lanes, one strut per lane. Such a run of consecutive bars (a bundle) adds
//! its contributions to all its lanes at once. Each lane's sums are the scalar ones in
//! bar order (bundles and single bars are taken in bar order, and a bundle has one bar per
//! lane), lane by lane the same arithmetic, so K is the same bits. A bundle leaves empty
//! only lanes without a part, which hold just 0 and 1: adding ±0 to them changes no bit, so
//! a bundle stores whole blocks (a masked store was 1.2× slower than one bar at a time).
// Bundles are assembled in AVX2 only: elsewhere their layout is built and left unused.
#![cfg_attr(
    not(target_arch = "x86_64"),
    allow(dead_code, unused_imports, unused_variables)
)]

use std::ops::Range;

use nalgebra::Vector3;

use super::Contribution;
use crate::linalg::block_lanes::{lanes, LaneGroups, Lanes, LANES};
use crate::linalg::symmetric::{LOWER, SYMMETRIC};

/// One contribution of each bar of a bundle to one block of the lanes.
#[derive(Debug, Clone)]
struct LaneContribution {
    /// The block of the lanes.
    block: usize,
    /// Per lane, as [`Contribution`]'s fields (zero in lanes without a bar).
    diagonal: Lanes,
    along: Lanes,
    /// Per lane, −1 where [`Contribution::first`] (a sign bit, as a blend reads it), else 0.
    first: Lanes,
}

/// A bar taken alone, or consecutive bars whose contributions go to the same blocks of the
/// lanes, one bar per lane.
#[derive(Debug, Clone)]
enum Unit {
    Bar(usize),
    Bundle {
        bar_of_lane: [Option<usize>; LANES],
        contributions: Range<usize>,
    },
}

/// The bars in bundles where they make one, in bar order.
#[derive(Debug, Clone)]
pub(super) struct LaneAssembly {
    units: Vec<Unit>,
    contributions: Vec<LaneContribution>,
}

impl LaneAssembly {
    /// The bundles of consecutive bars (each bar's contributions `of(bar)`) whose
    /// contributions go, in order, to the same blocks, each bar to a lane of its own
    /// (`position(slot)`: block and lane), with no part in a lane they leave empty
    /// (`used(block)`: lanes with a part); `None` when no bars make one.
    pub(super) fn new<'a>(
        bars: usize,
        of: impl Fn(usize) -> &'a [Contribution],
        position: impl Fn(usize) -> (usize, usize),
        used: impl Fn(usize) -> usize,
    ) -> Option<Self> {
        let lane = |bar: usize| {
            let (first, rest) = of(bar).split_first()?;
            let lane = position(first.slot).1;
            rest.iter()
                .all(|c| position(c.slot).1 == lane)
                .then_some(lane)
        };
        let blocks =
            |bar: usize| -> Vec<usize> { of(bar).iter().map(|c| position(c.slot).0).collect() };
        let mut assembly = Self {
            units: Vec::new(),
            contributions: Vec::new(),
        };
        let mut bar = 0;
        while bar < bars {
            let mut bar_of_lane = [None; LANES];
            let mut members = 1;
            let shared = blocks(bar);
            if let Some(l) = lane(bar) {
                bar_of_lane[l] = Some(bar);
                while members < LANES && bar + members < bars {
                    let next = bar + members;
                    match lane(next) {
                        Some(l) if bar_of_lane[l].is_none() && blocks(next) == shared => {
                            bar_of_lane[l] = Some(next);
                            members += 1;
                        }
                        _ => break,
                    }
                }
            }
            let empty_lane = bar_of_lane
                .iter()
                .position(Option::is_none)
                .unwrap_or(LANES);
            if members > 1 && shared.iter().all(|&block| used(block) <= empty_lane) {
                assembly.add_bundle(bar_of_lane, &shared, &of);
            } else {
                assembly.units.extend((bar..bar + members).map(Unit::Bar));
            }
            bar += members;
        }
        let bundled = assembly
            .units
            .iter()
            .any(|u| matches!(u, Unit::Bundle { .. }));
        bundled.then_some(assembly)
    }

    /// How many bundles there are.
    #[cfg(test)]
    pub(super) fn bundles(&self) -> usize {
        let bundle = |u: &&Unit| matches!(u, Unit::Bundle { .. });
        self.units.iter().filter(bundle).count()
    }

    /// A bundle of the bars in `bar_of_lane`, whose `k`-th contributions all go to the
    /// lanes' block `blocks[k]`.
    fn add_bundle<'a>(
        &mut self,
        bar_of_lane: [Option<usize>; LANES],
        blocks: &[usize],
        of: &impl Fn(usize) -> &'a [Contribution],
    ) {
        let start = self.contributions.len();
        for (k, &block) in blocks.iter().enumerate() {
            let per_lane: [Option<&Contribution>; LANES] =
                std::array::from_fn(|l| bar_of_lane[l].map(|bar| &of(bar)[k]));
            let value = |f: fn(&Contribution) -> f64| lanes(|l| per_lane[l].map_or(0.0, f));
            self.contributions.push(LaneContribution {
                block,
                diagonal: value(|c| c.diagonal),
                along: value(|c| c.along),
                first: lanes(|l| sign(per_lane[l].is_some_and(|c| c.first))),
            });
        }
        self.units.push(Unit::Bundle {
            bar_of_lane,
            contributions: start..self.contributions.len(),
        });
    }

    /// Assembles K (cleared) into `lanes` for the bar vectors `b(bar)`: a single bar's
    /// contributions one at a time (`add_bar`, with `1/|b|²` as its callers compute it), a
    /// bundle's in all its lanes at once with `avx2` (the processor has it), else bar by
    /// bar too.
    #[inline(always)]
    pub(super) fn assemble<'a>(
        &self,
        lanes_k: &mut LaneGroups,
        b: impl Fn(usize) -> (&'a Vector3<f64>, &'a f64),
        mut add_bar: impl FnMut(&mut LaneGroups, usize, &Vector3<f64>, f64),
        avx2: bool,
    ) {
        for unit in &self.units {
            match unit {
                Unit::Bar(bar) => {
                    let (bv, inv_l2) = b(*bar);
                    add_bar(lanes_k, *bar, bv, *inv_l2);
                }
                Unit::Bundle {
                    bar_of_lane,
                    contributions,
                } => {
                    let contributions = &self.contributions[contributions.clone()];
                    #[cfg(not(target_arch = "x86_64"))]
                    let _ = avx2;
                    #[cfg(target_arch = "x86_64")]
                    if avx2 {
                        // A lane without a bar adds ±0 (b = x̂, 1/|b|² = 1: no 0 · ∞).
                        let v = |l: usize| bar_of_lane[l].map_or((&NO_BAR.0, &NO_BAR.1), &b);
                        // SAFETY: the processor has AVX2.
                        unsafe {
                            assemble_bundle(lanes_k, contributions, [v(0), v(1), v(2), v(3)])
                        };
                        continue;
                    }
                    for &bar in bar_of_lane.iter().flatten() {
                        let (bv, inv_l2) = b(bar);
                        add_bar(lanes_k, bar, bv, *inv_l2);
                    }
                }
            }
        }
    }
}

/// What a lane without a bar takes: `b = x̂` and its `1/|b|²` (read from memory, as a bar's
/// are: built on the stack, its parts were stored piecewise and loaded whole, and each load
/// waited for the stores to retire).
static NO_BAR: (Vector3<f64>, f64) = (Vector3::new(1.0, 0.0, 0.0), 1.0);

/// −1 (sign bit set) for `true`, 0 for `false`.
fn sign(set: bool) -> f64 {
    if set {
        -1.0
    } else {
        0.0
    }
}

/// A bundle's contributions for its bars' vectors and their `1/|b|²`, `v` (one per lane),
/// each lane's sums as [`super::Reactions::add_bar`]'s: `outer_lower`'s products,
/// `Contribution::block`, and the sums of `summed` (old plus new, or new where first),
/// stored whole.
///
/// # Safety
/// The processor has AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn assemble_bundle(
    lanes_k: &mut LaneGroups,
    contributions: &[LaneContribution],
    v: [(&Vector3<f64>, &f64); LANES],
) {
    use std::arch::x86_64::{
        _mm256_add_pd, _mm256_blendv_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd,
        _mm256_set_pd, _mm256_storeu_pd, _mm256_xor_pd,
    };
    let load = |a: &Lanes| unsafe { _mm256_loadu_pd(a.as_ptr()) };
    let x = _mm256_set_pd(v[3].0.x, v[2].0.x, v[1].0.x, v[0].0.x);
    let y = _mm256_set_pd(v[3].0.y, v[2].0.y, v[1].0.y, v[0].0.y);
    let z = _mm256_set_pd(v[3].0.z, v[2].0.z, v[1].0.z, v[0].0.z);
    let inv_l2 = _mm256_set_pd(*v[3].1, *v[2].1, *v[1].1, *v[0].1);
    let bb = [
        _mm256_mul_pd(x, x),
        _mm256_mul_pd(y, x),
        _mm256_mul_pd(z, x),
        _mm256_mul_pd(y, y),
        _mm256_mul_pd(z, y),
        _mm256_mul_pd(z, z),
    ];
    for c in contributions {
        // `−along · 1/|b|²`, the negation by the sign bit as `-x` is.
        let s = _mm256_mul_pd(_mm256_xor_pd(load(&c.along), _mm256_set1_pd(-0.0)), inv_l2);
        let d = load(&c.diagonal);
        let block = [
            _mm256_add_pd(_mm256_mul_pd(bb[0], s), d),
            _mm256_mul_pd(bb[1], s),
            _mm256_mul_pd(bb[2], s),
            _mm256_add_pd(_mm256_mul_pd(bb[3], s), d),
            _mm256_mul_pd(bb[4], s),
            _mm256_add_pd(_mm256_mul_pd(bb[5], s), d),
        ];
        let at = lanes_k.block_mut(c.block);
        // The lower triangle's six entries before the sums.
        let old = |i: usize| load(&at[LOWER[i]]);
        let old = [old(0), old(1), old(2), old(3), old(4), old(5)];
        let first = load(&c.first);
        let sum = |i: usize| {
            let added = _mm256_add_pd(old[i], block[i]);
            _mm256_blendv_pd(added, block[i], first)
        };
        let sum = [sum(0), sum(1), sum(2), sum(3), sum(4), sum(5)];
        for (e, at) in at.iter_mut().enumerate() {
            // SAFETY: four f64.
            unsafe { _mm256_storeu_pd(at.as_mut_ptr(), sum[SYMMETRIC[e]]) };
        }
    }
}
