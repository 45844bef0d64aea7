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
