//! The tests of [`super`].

use super::*;
use crate::model::Model;
use crate::scene::Scene;

/// Ten bars between five nodes are a rigid frame with a self-stress: K is singular, the
/// sparse factorization fails (overwriting K and the right-hand side) and the dense
/// fallback must still see both as assembled, so its Ω is the dense solver's.
#[test]
fn a_failed_factorization_falls_back_on_k_as_assembled() {
    let scene = Scene::from_toml_str(
        r#"
        name = "frame"
        nodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.1], [0.4, 0.9, 0.0], [0.5, 0.3, 0.8], [0.9, 0.8, 0.7]]
        bars = [
            { nodes = [1, 2], mass = 1.0 },
            { nodes = [1, 3], mass = 2.0 },
            { nodes = [1, 4], mass = 1.5 },
            { nodes = [1, 5], mass = 1.0 },
            { nodes = [2, 3], mass = 1.2 },
            { nodes = [2, 4], mass = 0.8 },
            { nodes = [2, 5], mass = 1.1 },
            { nodes = [3, 4], mass = 0.9 },
            { nodes = [3, 5], mass = 1.3 },
            { nodes = [4, 5], mass = 1.4 },
        ]
        "#,
    )
    .unwrap();
    let model = Model::new(&scene).unwrap();
    let units: Vec<Vector3<f64>> = model
        .bars
        .iter()
        .map(|b| (model.positions[b.nodes[1]] - model.positions[b.nodes[0]]) / b.length)
        .collect();
    let mut sparse = Reactions::new(&model.coords, &model.inertia, false);
    let mut dense = Reactions::new(&model.coords, &model.inertia, true);
    let rhs = DVector::from_fn(sparse.size(), |i, _| (i as f64 + 1.0).sin());
    for r in [&mut sparse, &mut dense] {
        r.assemble(&units);
        r.rhs.copy_from(&rhs);
    }
    let again = |r: &mut Reactions| {
        r.assemble(&units);
        r.rhs.copy_from(&rhs);
    };
    assert!(
        !sparse.solve(again),
        "the sparse factorization fails on a rigid frame"
    );
    assert!(dense.solve(|_| unreachable!("a dense K is kept")));
    let diff = (&sparse.rhs - &dense.rhs).amax();
    assert!(diff <= 1e-12 * dense.rhs.amax(), "differ by {diff:e}");
}

/// The scale of the singularity threshold that two threads gather as they close each
/// pivot block of K is the one the one-thread factor finds by a pass over K.
#[test]
fn the_gathered_scale_is_the_factors() {
    let mut scene = crate::scene::tower_scene(30, Some(500.0), "tower");
    scene.prestress = None;
    for (i, bar) in scene.bars.iter_mut().enumerate() {
        bar.mass = 1.0 + 0.1 * (i % 7) as f64;
    }
    for c in &mut scene.cables {
        c.rest_length = Some(0.5);
    }
    let model = Model::new(&scene).unwrap();
    let mut r = Reactions::new(&model.coords, &model.inertia, false).without_lanes();
    r.clear();
    let mut gathered: f64 = 0.0;
    let shared = r.shared().expect("the scalar factor");
    for (i, b) in model.bars.iter().enumerate() {
        let bv = model.positions[b.nodes[1]] - model.positions[b.nodes[0]];
        let bv = bv + Vector3::new(0.01, -0.02, 0.03) * (i as f64).sin();
        // SAFETY: one thread.
        let closed = unsafe { shared.add_bar(i, &bv, 1.0 / bv.norm_squared(), |_| false) };
        gathered = gathered.max(closed);
    }
    let pass = r.sparse().unwrap().diagonal_scale();
    assert!(pass > 0.0);
    assert_eq!(gathered.to_bits(), pass.to_bits());
}

/// The tower's three chains of joints (one per strut of a stage) are factored side by
/// side while the lanes' K and factor fit in 2 MiB (700 stages), not beyond (2,000).
#[test]
fn the_towers_chains_go_side_by_side() {
    for (stages, expected) in [(2, true), (20, true), (700, true), (2000, false)] {
        let mut scene = crate::scene::tower_scene(stages, Some(500.0), "tower");
        // Rest lengths given (as `bench` does): no dense prestress solve.
        scene.prestress = None;
        for c in &mut scene.cables {
            c.rest_length = Some(0.5);
        }
        let model = Model::new(&scene).unwrap();
        let reactions = Reactions::new(&model.coords, &model.inertia, false);
        assert_eq!(reactions.side_by_side(), expected, "{stages} stages");
    }
}

/// K assembled several bars at a time into the side-by-side chains is the bits of K
/// assembled bar by bar: tower20 with an inertia of its own per bar, at bar vectors of
/// every sign and magnitude, twice in a row (the second assembly sets and adds to blocks
/// the first left), through the AVX2 code and the bar-by-bar fallback.
#[test]
fn bundled_assembly_gives_the_bits_of_bar_by_bar() {
    if !crate::simd::has_avx2() {
        eprintln!("no AVX2 here: only the fallback is compared");
    }
    let model = Model::new(&crate::scene::builtin("tower20").unwrap()).unwrap();
    let inertia: Vec<BarInertia> = (0..model.inertia.len())
        .map(|i| BarInertia::new(1.0 + 0.1 * i as f64, [0.02 * i as f64, 0.3]))
        .collect();
    let mut bundled = Reactions::new(&model.coords, &inertia, false);
    let mut bar_by_bar = bundled.clone();
    assert!(bundled.assembles_in_bundles());
    let bundles = bundled.lane_assembly.as_ref().unwrap().bundles();
    assert_eq!(bundles, 20, "a bundle per stage");
    let slots = match &bundled.solver {
        Solver::Sparse(chol) => chol.slots(),
        Solver::Dense(_) => unreachable!(),
    };
    let block = |r: &Reactions, slot: usize| match &r.solver {
        Solver::Sparse(chol) => chol.block(slot),
        Solver::Dense(_) => unreachable!(),
    };
    for (round, avx2) in [(0, true), (1, true), (2, false)] {
        let b = |bar: usize| {
            let f = (bar * 3 + round * 7) as f64;
            Vector3::new(
                (f * 0.7).sin() * 2.0,
                (f * 1.3).cos() * 0.01,
                -(f * 0.3).sin(),
            )
        };
        let avx2 = avx2 && crate::simd::has_avx2();
        let kept: Vec<_> = (0..model.bars.len())
            .map(|bar| (b(bar), 1.0 / b(bar).norm_squared()))
            .collect();
        bundled.assemble_bars_with(|bar| (&kept[bar].0, &kept[bar].1), avx2);
        bar_by_bar.clear();
        for bar in 0..model.bars.len() {
            let bv = b(bar);
            bar_by_bar.add_bar(bar, &bv, 1.0 / bv.norm_squared());
        }
        for slot in 0..slots {
            let (x, y) = (block(&bundled, slot), block(&bar_by_bar, slot));
            for (x, y) in x.iter().zip(y.iter()) {
                assert_eq!(x.to_bits(), y.to_bits(), "round {round}, slot {slot}");
            }
        }
        // The lanes without a part (identity pivots, zero blocks) are kept too.
        let lane_bits = |r: &mut Reactions| match &mut r.solver {
            Solver::Sparse(chol) => chol.lanes_mut().unwrap().k_bits(),
            Solver::Dense(_) => unreachable!(),
        };
        assert!(
            lane_bits(&mut bundled) == lane_bits(&mut bar_by_bar),
            "round {round}"
        );
    }
}
