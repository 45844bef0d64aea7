//! Stages 3 and 5 of the evaluation: each moving bar's force density λ in closed form and
//! its end accelerations, first for the applied forces (keeping what the second pass and
//! K need), then again with the reactions. Four bars at a time in AVX2 where the
//! processor has it ([`lanes`]).

#[cfg(target_arch = "x86_64")]
mod lanes;

use nalgebra::Vector3;

use super::{BarKept, Workspace};
use crate::model::reactions::Reactions;
use crate::model::Model;

/// Stage 3: λ in closed form and the end accelerations of every moving bar; also K of the
/// reactions for the bar directions, and what the second pass needs.
#[inline(always)]
pub fn bar_response(model: &Model, ws: &mut Workspace) {
    let with_reactions = !model.pipeline.constraints.is_empty();
    // K from the bar vectors the pass keeps, after it, where bars are assembled several at
    // a time; else bar by bar inside it.
    let bundled = with_reactions && ws.reactions.assembles_in_bundles();
    let bar_by_bar = with_reactions && !bundled;
    if bar_by_bar {
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
    } = ws;
    let add_bar = |i: usize, bv: &Vector3<f64>, inv_l2: f64| {
        if bar_by_bar {
            reactions.add_bar(i, bv, inv_l2);
        }
    };
    let given = (0, pairs(end_pos), pairs(end_vel), pairs(end_force));
    let out = (
        pairs_mut(end_acc),
        lambda.as_mut_slice(),
        bars.as_mut_slice(),
    );
    first_responses(model, given, out, add_bar);
    if bundled {
        assemble_kept(reactions, bars);
    }
}

/// The first λ pass over a run of bars, four at a time in AVX2 lanes where the processor
/// has it ([`lanes`]), else [`first_response`].
#[inline(always)]
#[allow(clippy::type_complexity)]
pub(super) fn first_responses(
    model: &Model,
    given: (
        usize,
        &[[Vector3<f64>; 2]],
        &[[Vector3<f64>; 2]],
        &[[Vector3<f64>; 2]],
    ),
    out: (&mut [[Vector3<f64>; 2]], &mut [f64], &mut [BarKept]),
    add_bar: impl FnMut(usize, &Vector3<f64>, f64),
) {
    crate::simd::dispatch!(avx2 = lanes::first_pass, portable = first_response;
        model, given, out, add_bar)
}

/// The first λ pass over a run of bars from bar `first` on (given their end positions,
/// velocities and forces), with `add_bar(i, b, 1/|b|²)` for each moving bar `i`.
#[inline(always)]
#[allow(clippy::type_complexity)]
pub(super) fn first_response(
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
        // One division per bar: 1/|b|² serves K's u uᵀ and λ's denominator.
        let inv_l2 = 1.0 / bv.norm_squared();
        *kept = (
            bv,
            -bdot.norm_squared(),
            inv_l2 * inertia.inv_beta_minus_alpha,
            inv_l2,
        );
        add_bar(first + i, &bv, inv_l2);
        (*lambda, *acc) = response(inertia, kept, f);
    }
}

/// Stage 5: λ and the end accelerations again, for the end forces with the reactions,
/// from what [`bar_response`] kept.
#[inline(always)]
pub(super) fn bar_response_again(model: &Model, ws: &mut Workspace) {
    let given = (0, ws.bars.as_slice(), pairs(&ws.end_force));
    second_responses(model, given, (pairs_mut(&mut ws.end_acc), &mut ws.lambda));
}

/// The second λ pass over a run of bars, four at a time in AVX2 lanes where the processor
/// has it ([`lanes`]), else [`second_response`].
#[inline(always)]
pub(super) fn second_responses(
    model: &Model,
    given: (usize, &[BarKept], &[[Vector3<f64>; 2]]),
    out: (&mut [[Vector3<f64>; 2]], &mut [f64]),
) {
    crate::simd::dispatch!(avx2 = lanes::second_pass, portable = second_response;
        model, given, out)
}

/// The second λ pass over a run of bars from bar `first` on, bar by bar.
#[inline(always)]
pub(super) fn second_response(
    model: &Model,
    (first, bars, end_force): (usize, &[BarKept], &[[Vector3<f64>; 2]]),
    (end_acc, lambda): (&mut [[Vector3<f64>; 2]], &mut [f64]),
) {
    let range = first..first + bars.len();
    let per_bar = model.coords.static_bar[range.clone()]
        .iter()
        .zip(&model.inertia[range]);
    let out = end_acc.iter_mut().zip(lambda);
    let inputs = bars.iter().zip(end_force);
    for (((&fixed, inertia), (cached, f)), (acc, lambda)) in per_bar.zip(inputs).zip(out) {
        if !fixed {
            (*lambda, *acc) = response(inertia, cached, f);
        }
    }
}

/// λ of a bar (compression positive), `(−|ḃ|² − b·(α f_a + β f_b)) / ((β − α)|b|²)` with
/// `b`, `−|ḃ|²` and the reciprocal of the denominator given, for its end forces `f`, and
/// its end accelerations.
#[inline(always)]
pub(super) fn response(
    inertia: &crate::model::inertia::BarInertia,
    &(bv, minus_bdot2, inv_den, _): &BarKept,
    [fa, fb]: &[Vector3<f64>; 2],
) -> (f64, [Vector3<f64>; 2]) {
    let lambda = (minus_bdot2 - bv.dot(&(fa * inertia.alpha + fb * inertia.beta))) * inv_den;
    let (ga, gb) = (fa - bv * lambda, fb + bv * lambda);
    let w = &inertia.w;
    (
        lambda,
        [ga * w[0][0] + gb * w[0][1], ga * w[1][0] + gb * w[1][1]],
    )
}

/// A bar's two ends at a time.
#[inline(always)]
pub(super) fn pairs(ends: &[Vector3<f64>]) -> &[[Vector3<f64>; 2]] {
    ends.as_chunks::<2>().0
}

#[inline(always)]
pub(super) fn pairs_mut(ends: &mut [Vector3<f64>]) -> &mut [[Vector3<f64>; 2]] {
    ends.as_chunks_mut::<2>().0
}

/// K assembled again from the bar vectors [`bar_response`] kept (the same arithmetic, so
/// the same K), after a factor may have overwritten it. A static bar's entry is never set, but it has
/// no blocks either: `add_bar` returns.
#[inline(always)]
pub(super) fn assemble_kept(r: &mut Reactions, bars: &[BarKept]) {
    r.assemble_bars(|i| (&bars[i].0, &bars[i].3));
}
