//! Both λ passes four bars at a time, one bar per lane of an AVX2 register.
//!
//! Lane by lane the arithmetic is the bar-by-bar code's ([`super::first_response`],
//! [`super::second_response`] and their [`super::response`]), in the same order and with no
//! fused multiply-add, so the results are the same bits. Groups are bars `4g..4g + 4`; a
//! group with a static bar, and a run's bars before its first whole group and after its
//! last, are taken bar by bar. `add_bar` (K's blocks) is still called bar by bar, in order.

use std::arch::x86_64::{
    __m256d, _mm256_add_pd, _mm256_div_pd, _mm256_loadu2_m128d, _mm256_loadu_pd, _mm256_mul_pd,
    _mm256_permute2f128_pd, _mm256_set1_pd, _mm256_set_pd, _mm256_storeu2_m128d, _mm256_storeu_pd,
    _mm256_sub_pd, _mm256_unpackhi_pd, _mm256_unpacklo_pd, _mm256_xor_pd,
};

use nalgebra::Vector3;

use crate::dynamics::BarKept;
use crate::model::inertia::InertiaLanes;
use crate::model::Model;

/// A bar's two ends, as the passes read them.
type Ends = [Vector3<f64>; 2];

/// A vector per lane.
#[derive(Clone, Copy)]
struct Lanes3 {
    x: __m256d,
    y: __m256d,
    z: __m256d,
}

/// The first pass over a run of bars from bar `first` on (as [`super::first_response`]),
/// four at a time where four moving bars make a group; `add_bar(i, b, 1/|b|²)` for each
/// moving bar, in order.
///
/// # Safety
/// The processor has AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn first_pass(
    model: &Model,
    (first, x, v, f): (usize, &[Ends], &[Ends], &[Ends]),
    (acc, lambda, kept): (&mut [Ends], &mut [f64], &mut [BarKept]),
    mut add_bar: impl FnMut(usize, &Vector3<f64>, f64),
) {
    let cut = aligned(first, x.len());
    let ([x0, x1, x2], [v0, v1, v2], [f0, f1, f2]) = (
        head_groups_tail(x, cut),
        head_groups_tail(v, cut),
        head_groups_tail(f, cut),
    );
    let [a0, a1, a2] = head_groups_tail_mut(acc, cut);
    let [l0, l1, l2] = head_groups_tail_mut(lambda, cut);
    let [k0, k1, k2] = head_groups_tail_mut(kept, cut);
    super::first_response(model, (first, x0, v0, f0), (a0, l0, k0), &mut add_bar);
    let given = x1
        .as_chunks::<4>()
        .0
        .iter()
        .zip(v1.as_chunks().0)
        .zip(f1.as_chunks().0);
    let out = a1.as_chunks_mut::<4>().0.iter_mut();
    let out = out.zip(l1.as_chunks_mut().0).zip(k1.as_chunks_mut().0);
    let start = first + cut[0];
    let groups = model.inertia_lanes[start / 4..].iter().zip(given.zip(out));
    for (g, (group, (((x, v), f), ((acc, lambda), kept)))) in groups.enumerate() {
        let bar = start + 4 * g;
        if group.moving {
            let inv_l2 = four_first(group, (x, v), f, (acc, lambda, kept));
            for (l, kept) in kept.iter().enumerate() {
                add_bar(bar + l, &kept.0, inv_l2[l]);
            }
        } else {
            let out = (&mut acc[..], &mut lambda[..], &mut kept[..]);
            super::first_response(model, (bar, x, v, f), out, &mut add_bar);
        }
    }
    let given = (first + cut[1], x2, v2, f2);
    super::first_response(model, given, (a2, l2, k2), &mut add_bar);
}

/// The second pass over a run of bars from bar `first` on (as
/// [`super::second_response`]), four at a time where four moving bars make a group.
///
/// # Safety
/// The processor has AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn second_pass(
    model: &Model,
    (first, kept, f): (usize, &[BarKept], &[Ends]),
    (acc, lambda): (&mut [Ends], &mut [f64]),
) {
    let cut = aligned(first, kept.len());
    let ([k0, k1, k2], [f0, f1, f2]) = (head_groups_tail(kept, cut), head_groups_tail(f, cut));
    let ([a0, a1, a2], [l0, l1, l2]) = (
        head_groups_tail_mut(acc, cut),
        head_groups_tail_mut(lambda, cut),
    );
    super::second_response(model, (first, k0, f0), (a0, l0));
    let given = k1.as_chunks::<4>().0.iter().zip(f1.as_chunks().0);
    let out = a1.as_chunks_mut::<4>().0.iter_mut();
    let out = out.zip(l1.as_chunks_mut().0);
    let start = first + cut[0];
    let groups = model.inertia_lanes[start / 4..].iter().zip(given.zip(out));
    for (g, (group, ((kept, f), (acc, lambda)))) in groups.enumerate() {
        if group.moving {
            four_again(group, kept, f, (acc, lambda));
        } else {
            super::second_response(model, (start + 4 * g, kept, f), (acc, lambda));
        }
    }
    super::second_response(model, (first + cut[1], k2, f2), (a2, l2));
}

/// Where a run of `n` bars from bar `first` splits: the bars before the first whole group
/// of four (bar index a multiple of four), and the end of the last whole group.
fn aligned(first: usize, n: usize) -> [usize; 2] {
    let head = ((4 - first % 4) % 4).min(n);
    [head, head + (n - head) / 4 * 4]
}

/// A run's slice cut where [`aligned`] says: before, in and after its whole groups.
fn head_groups_tail<T>(s: &[T], [a, b]: [usize; 2]) -> [&[T]; 3] {
    let (s, tail) = s.split_at(b);
    let (head, middle) = s.split_at(a);
    [head, middle, tail]
}

fn head_groups_tail_mut<T>(s: &mut [T], [a, b]: [usize; 2]) -> [&mut [T]; 3] {
    let (s, tail) = s.split_at_mut(b);
    let (head, middle) = s.split_at_mut(a);
    [head, middle, tail]
}

/// λ and the end accelerations of the four bars of `inertia` for end forces `f`, with
/// `(b, −|ḃ|², 1/((β − α)|b|²))` given per bar in `kept` (the second pass).
#[inline]
#[target_feature(enable = "avx2")]
fn four_again(
    inertia: &InertiaLanes,
    kept: &[BarKept; 4],
    f: &[Ends; 4],
    (acc, lambda): (&mut [Ends; 4], &mut [f64; 4]),
) {
    let b = Lanes3 {
        x: gather(|l| kept[l].0.x),
        y: gather(|l| kept[l].0.y),
        z: gather(|l| kept[l].0.z),
    };
    let minus_bdot2 = gather(|l| kept[l].1);
    let inv_den = gather(|l| kept[l].2);
    respond(inertia, (b, minus_bdot2, inv_den), f, (acc, lambda));
}

/// The first pass for four moving bars: their `kept` values, λ and end accelerations;
/// returns `1/|b|²` per lane (for K).
#[inline]
#[target_feature(enable = "avx2")]
fn four_first(
    inertia: &InertiaLanes,
    (x, v): (&[Ends; 4], &[Ends; 4]),
    f: &[Ends; 4],
    (acc, lambda, kept): (&mut [Ends; 4], &mut [f64; 4], &mut [BarKept; 4]),
) -> [f64; 4] {
    let difference = |e: &[Ends; 4]| {
        let [a, b] = load_ends(e);
        Lanes3 {
            x: _mm256_sub_pd(b.x, a.x),
            y: _mm256_sub_pd(b.y, a.y),
            z: _mm256_sub_pd(b.z, a.z),
        }
    };
    let (b, bdot) = (difference(x), difference(v));
    // As nalgebra's `norm_squared` sums (`0 + ((x² + y²) + z²)`; adding 0 to a sum of
    // squares changes nothing).
    let norm_squared = |u: Lanes3| {
        let xy = _mm256_add_pd(_mm256_mul_pd(u.x, u.x), _mm256_mul_pd(u.y, u.y));
        _mm256_add_pd(xy, _mm256_mul_pd(u.z, u.z))
    };
    let inv_l2 = _mm256_div_pd(_mm256_set1_pd(1.0), norm_squared(b));
    // Negated by its sign bit, as `-x` is (`0 − x` would make −0 of 0).
    let minus_bdot2 = _mm256_xor_pd(norm_squared(bdot), _mm256_set1_pd(-0.0));
    let inv_den = _mm256_mul_pd(inv_l2, load(&inertia.inv_beta_minus_alpha));
    let (bx, by, bz, m, d, i) = (
        lanes(b.x),
        lanes(b.y),
        lanes(b.z),
        lanes(minus_bdot2),
        lanes(inv_den),
        lanes(inv_l2),
    );
    for (l, kept) in kept.iter_mut().enumerate() {
        *kept = (Vector3::new(bx[l], by[l], bz[l]), m[l], d[l], i[l]);
    }
    respond(inertia, (b, minus_bdot2, inv_den), f, (acc, lambda));
    lanes(inv_l2)
}

/// `(−|ḃ|² − b·(α f_a + β f_b)) / ((β − α)|b|²)` and `W g` per lane, as
/// [`super::response`] computes them.
#[inline]
#[target_feature(enable = "avx2")]
fn respond(
    inertia: &InertiaLanes,
    (b, minus_bdot2, inv_den): (Lanes3, __m256d, __m256d),
    f: &[Ends; 4],
    (acc, lambda): (&mut [Ends; 4], &mut [f64; 4]),
) {
    let [fa, fb] = load_ends(f);
    let (alpha, beta) = (load(&inertia.alpha), load(&inertia.beta));
    let weighted =
        |a: __m256d, b: __m256d| _mm256_add_pd(_mm256_mul_pd(a, alpha), _mm256_mul_pd(b, beta));
    let t = Lanes3 {
        x: weighted(fa.x, fb.x),
        y: weighted(fa.y, fb.y),
        z: weighted(fa.z, fb.z),
    };
    // nalgebra's 3-vector dot product: `(x + y) + z`.
    let dot = _mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(b.x, t.x), _mm256_mul_pd(b.y, t.y)),
        _mm256_mul_pd(b.z, t.z),
    );
    let l = _mm256_mul_pd(_mm256_sub_pd(minus_bdot2, dot), inv_den);
    let ga = |fa: __m256d, b: __m256d| _mm256_sub_pd(fa, _mm256_mul_pd(b, l));
    let gb = |fb: __m256d, b: __m256d| _mm256_add_pd(fb, _mm256_mul_pd(b, l));
    let (ga, gb) = (
        [ga(fa.x, b.x), ga(fa.y, b.y), ga(fa.z, b.z)],
        [gb(fb.x, b.x), gb(fb.y, b.y), gb(fb.z, b.z)],
    );
    let w = &inertia.w;
    let side = |wa: &[f64; 4], wb: &[f64; 4]| {
        let (wa, wb) = (load(wa), load(wb));
        let at =
            |axis: usize| _mm256_add_pd(_mm256_mul_pd(ga[axis], wa), _mm256_mul_pd(gb[axis], wb));
        Lanes3 {
            x: at(0),
            y: at(1),
            z: at(2),
        }
    };
    store_ends([side(&w[0], &w[1]), side(&w[2], &w[3])], acc);
    *lambda = lanes(l);
}

#[inline]
#[target_feature(enable = "avx2")]
fn gather(f: impl Fn(usize) -> f64) -> __m256d {
    _mm256_set_pd(f(3), f(2), f(1), f(0))
}

// `[Ends; 4]` is 24 f64 in a row: bar `l`'s `a.x, a.y, a.z, b.x, b.y, b.z` at `6l`.
const _: () = assert!(std::mem::size_of::<[Ends; 4]>() == 24 * 8);

/// Four bars' two ends, transposed into lanes: 4 × 4 (each bar's `a` and `b.x`) in
/// unpacks and 128-bit swaps, and 4 × 2 (`b.y`, `b.z`).
#[inline]
#[target_feature(enable = "avx2")]
fn load_ends(ends: &[Ends; 4]) -> [Lanes3; 2] {
    let p = ends.as_ptr().cast::<f64>();
    // SAFETY: 24 f64 from `p` (the assertion above); the reads end at `6l + 6`.
    let (r, s) = unsafe {
        (
            [0, 1, 2, 3].map(|l| _mm256_loadu_pd(p.add(6 * l))),
            [0, 1].map(|l| _mm256_loadu2_m128d(p.add(6 * l + 16), p.add(6 * l + 4))),
        )
    };
    let (t0, t1) = (
        _mm256_unpacklo_pd(r[0], r[1]),
        _mm256_unpackhi_pd(r[0], r[1]),
    );
    let (t2, t3) = (
        _mm256_unpacklo_pd(r[2], r[3]),
        _mm256_unpackhi_pd(r[2], r[3]),
    );
    [
        Lanes3 {
            x: _mm256_permute2f128_pd::<0x20>(t0, t2),
            y: _mm256_permute2f128_pd::<0x20>(t1, t3),
            z: _mm256_permute2f128_pd::<0x31>(t0, t2),
        },
        Lanes3 {
            x: _mm256_permute2f128_pd::<0x31>(t1, t3),
            y: _mm256_unpacklo_pd(s[0], s[1]),
            z: _mm256_unpackhi_pd(s[0], s[1]),
        },
    ]
}

/// [`load_ends`] reversed.
#[inline]
#[target_feature(enable = "avx2")]
fn store_ends([a, b]: [Lanes3; 2], ends: &mut [Ends; 4]) {
    let (t0, t1) = (_mm256_unpacklo_pd(a.x, a.y), _mm256_unpackhi_pd(a.x, a.y));
    let (t2, t3) = (_mm256_unpacklo_pd(a.z, b.x), _mm256_unpackhi_pd(a.z, b.x));
    let r = [
        _mm256_permute2f128_pd::<0x20>(t0, t2),
        _mm256_permute2f128_pd::<0x20>(t1, t3),
        _mm256_permute2f128_pd::<0x31>(t0, t2),
        _mm256_permute2f128_pd::<0x31>(t1, t3),
    ];
    let s = [_mm256_unpacklo_pd(b.y, b.z), _mm256_unpackhi_pd(b.y, b.z)];
    let p = ends.as_mut_ptr().cast::<f64>();
    // SAFETY: as in `load_ends`.
    unsafe {
        for (l, r) in r.into_iter().enumerate() {
            _mm256_storeu_pd(p.add(6 * l), r);
        }
        for (l, s) in s.into_iter().enumerate() {
            _mm256_storeu2_m128d(p.add(6 * l + 16), p.add(6 * l + 4), s);
        }
    }
}

#[inline]
#[target_feature(enable = "avx2")]
fn load(x: &[f64; 4]) -> __m256d {
    // SAFETY: four f64.
    unsafe { _mm256_loadu_pd(x.as_ptr()) }
}

#[inline]
#[target_feature(enable = "avx2")]
fn lanes(v: __m256d) -> [f64; 4] {
    let mut out = [0.0; 4];
    // SAFETY: four f64.
    unsafe { _mm256_storeu_pd(out.as_mut_ptr(), v) };
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// A value per call, spread over magnitudes and signs, with exact zeros of both signs.
    fn values() -> impl FnMut() -> f64 {
        let mut k = 0u32;
        move || {
            k += 1;
            match k % 23 {
                0 => 0.0,
                11 => -0.0,
                _ => (f64::from(k) * 0.61).sin() * 10f64.powi((k % 5) as i32 - 2),
            }
        }
    }

    fn vectors(n: usize, next: &mut impl FnMut() -> f64) -> Vec<Ends> {
        (0..n)
            .map(|_| [(); 2].map(|_| Vector3::new(next(), next(), next())))
            .collect()
    }

    /// Both passes four bars at a time give the bar-by-bar bits, and K's additions in the
    /// same order with the same arguments: tower20 (fifteen groups) with static bars in two
    /// groups and an inertia of its own per bar, and prism2 (a group and two bars after it), over all bars and over runs
    /// that start and end inside a group (as the two threads' halves), with zero velocities
    /// (`−|ḃ|²` of −0), zero forces and forces of both signs.
    #[test]
    fn four_at_a_time_gives_the_bits_of_one_at_a_time() {
        if !crate::simd::has_avx2() {
            eprintln!("no AVX2 here: nothing to compare");
            return;
        }
        let mut tower = Model::new(&builtin("tower20").unwrap()).unwrap();
        for bar in [5, 42, 43] {
            tower.coords.static_bar[bar] = true;
        }
        // A mass and payloads per bar, so that a lane given another bar's constants shows.
        for (i, inertia) in tower.inertia.iter_mut().enumerate() {
            let i = i as f64;
            *inertia = crate::model::inertia::BarInertia::new(1.0 + 0.1 * i, [0.01 * i, 0.3]);
        }
        tower.inertia_lanes = InertiaLanes::groups(&tower.inertia, &tower.coords.static_bar);
        let prism = Model::new(&builtin("prism2").unwrap()).unwrap();
        assert_eq!(tower.inertia_lanes.iter().filter(|g| g.moving).count(), 13);
        assert!(prism.inertia_lanes[0].moving && prism.bars.len() == 6);
        let mut next = values();
        let runs = [
            (&tower, 0..60),
            (&tower, 0..29),
            (&tower, 29..60),
            (&tower, 13..15),
        ];
        let runs = runs.into_iter().chain([(&prism, 0..6), (&prism, 1..6)]);
        for (model, bars) in runs {
            let (first, n) = (bars.start, bars.len());
            for round in 0..3 {
                let x = vectors(n, &mut next);
                let mut v = vectors(n, &mut next);
                let mut f = vectors(n, &mut next);
                if round == 1 {
                    v.iter_mut()
                        .take(7)
                        .for_each(|v| *v = [Vector3::zeros(); 2]);
                    f.iter_mut()
                        .skip(1)
                        .take(5)
                        .for_each(|f| *f = [Vector3::zeros(); 2]);
                }
                let mut added = [Vec::new(), Vec::new()];
                let mut outputs = [0, 1].map(|_| {
                    let acc = vectors(n, &mut next);
                    (
                        acc,
                        vec![7.0; n],
                        vec![(Vector3::zeros(), 0.0, 1.0, 1.0); n],
                    )
                });
                let [(acc, lambda, kept), (acc_ref, lambda_ref, kept_ref)] = &mut outputs;
                let [add, add_ref] = &mut added;
                let given = (first, &x[..], &v[..], &f[..]);
                // SAFETY: the processor has AVX2.
                unsafe { first_pass(model, given, (acc, lambda, kept), record(add)) };
                let out = (&mut acc_ref[..], &mut lambda_ref[..], &mut kept_ref[..]);
                super::super::first_response(model, given, out, record(add_ref));
                let what = format!("{} bars {bars:?}", model.scene.name);
                assert_eq!(add, add_ref, "{what}: K's additions");
                assert_eq!(
                    add.len(),
                    bars.clone()
                        .filter(|&i| !model.coords.static_bar[i])
                        .count()
                );
                assert_same(&outputs, &what);
                // The second pass with other forces.
                let f = vectors(n, &mut next);
                let [(acc, lambda, kept), (acc_ref, lambda_ref, kept_ref)] = &mut outputs;
                // SAFETY: the processor has AVX2.
                unsafe { second_pass(model, (first, kept, &f), (acc, lambda)) };
                super::super::second_response(model, (first, kept_ref, &f), (acc_ref, lambda_ref));
                assert_same(&outputs, &what);
            }
        }
    }

    /// `add_bar` that records its arguments' bits.
    fn record(to: &mut Vec<(usize, [u64; 4])>) -> impl FnMut(usize, &Vector3<f64>, f64) + '_ {
        move |i, b, inv_l2| {
            to.push((i, [b.x, b.y, b.z, inv_l2].map(f64::to_bits)));
        }
    }

    type Outputs = (Vec<Ends>, Vec<f64>, Vec<BarKept>);

    fn assert_same(
        [(acc, lambda, kept), (acc_ref, lambda_ref, kept_ref)]: &[Outputs; 2],
        name: &str,
    ) {
        let bits = |v: &Vector3<f64>| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        for (i, (a, b)) in acc.iter().zip(acc_ref).enumerate() {
            assert_eq!(
                a.map(|e| bits(&e)),
                b.map(|e| bits(&e)),
                "{name}: bar {i}'s accelerations"
            );
        }
        for (i, (a, b)) in lambda.iter().zip(lambda_ref).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "{name}: bar {i}'s λ");
        }
        for (i, (a, b)) in kept.iter().zip(kept_ref).enumerate() {
            // What K's assembly reads: a moving bar's 1/|b|² (a static one keeps b = 0).
            if a.0 != Vector3::zeros() {
                let inv_l2 = 1.0 / a.0.norm_squared();
                assert_eq!(a.3.to_bits(), inv_l2.to_bits(), "{name}: bar {i}'s 1/|b|²");
            }
            let (a, b) = (
                (bits(&a.0), a.1.to_bits(), a.2.to_bits(), a.3.to_bits()),
                (bits(&b.0), b.1.to_bits(), b.2.to_bits(), b.3.to_bits()),
            );
            assert_eq!(a, b, "{name}: bar {i}'s kept values");
        }
    }
}
