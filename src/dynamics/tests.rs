//! The evaluation's tests: side-by-side chains, the failure path, AVX2 vs baseline.

use super::*;
use crate::scene::builtin;

/// The `k`-th state of a sequence away from rest: `q0` moved by up to 1 cm, velocities
/// up to 0.1 m/s.
pub(super) fn moved(q0: &[f64], k: usize) -> (Vec<f64>, Vec<f64>) {
    let wave = |i: usize, f: f64| 1e-2 * ((i * 7 + k * 13) as f64 * f).sin();
    let q = q0
        .iter()
        .enumerate()
        .map(|(i, x)| x + wave(i, 0.37))
        .collect();
    let v = (0..q0.len()).map(|i| 10.0 * wave(i, 0.71)).collect();
    (q, v)
}

/// tower20's accelerations with its three chains of joints factored side by side are the
/// bits of the chains factored one after the other, at states away from rest.
#[test]
fn side_by_side_chains_give_the_same_accelerations() {
    let model = Model::new(&builtin("tower20").unwrap()).unwrap();
    let mut reference = model.clone();
    reference.reactions = reference.reactions.without_lanes();
    assert!(model.reactions.side_by_side() && !reference.reactions.side_by_side());
    let q0 = model.reduced_positions();
    let inputs = Inputs::start(&model);
    let (mut ws, mut ws_ref) = (Workspace::new(&model), Workspace::new(&reference));
    let (mut acc, mut acc_ref) = (vec![0.0; q0.len()], vec![0.0; q0.len()]);
    for k in 0..20 {
        let (q, v) = moved(&q0, k);
        accelerations(&model, &inputs, 0.0, &q, &v, &mut ws, &mut acc);
        accelerations(&reference, &inputs, 0.0, &q, &v, &mut ws_ref, &mut acc_ref);
        assert!(acc.iter().any(|a| a.abs() > 1e-3), "a state away from rest");
        for (a, b) in acc.iter().zip(&acc_ref) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        assert_eq!(ws.dense_fallbacks + ws_ref.dense_fallbacks, 0);
    }
}

/// A rigid frame: ten bars between five nodes, statically indeterminate, so K is
/// singular; `copies` of it side by side, 3 m apart.
pub(super) fn frames(copies: usize) -> crate::scene::Scene {
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.1],
        [0.4, 0.9, 0.0],
        [0.5, 0.3, 0.8],
        [0.9, 0.8, 0.7],
    ];
    let masses = [1.0, 2.0, 1.5, 1.0, 1.2, 0.8, 1.1, 0.9, 1.3, 1.4];
    let pairs = [
        (1, 2),
        (1, 3),
        (1, 4),
        (1, 5),
        (2, 3),
        (2, 4),
        (2, 5),
        (3, 4),
        (3, 5),
        (4, 5),
    ];
    let (mut nodes, mut bars) = (Vec::new(), Vec::new());
    for copy in 0..copies {
        let dx = 3.0 * copy as f64;
        nodes.extend(
            corners
                .iter()
                .map(|[x, y, z]| format!("[{}, {y}, {z}]", x + dx)),
        );
        for ((a, b), m) in pairs.iter().zip(masses) {
            let o = 5 * copy;
            bars.push(format!("{{ nodes = [{}, {}], mass = {m} }}", a + o, b + o));
        }
    }
    let text = format!(
        "name = \"frames\"\nnodes = [{}]\nbars = [{}]\ngravity = [0.0, 0.0, -9.81]\n",
        nodes.join(", "),
        bars.join(", ")
    );
    crate::scene::Scene::from_toml_str(&text).unwrap()
}

/// K singular in an evaluation (rigid frames, with the sparse solver forced on them) fails
/// the sparse factor there: the dense fallback must see K as assembled again from the bar
/// vectors, not as the failed factor left it, and so match the dense system's
/// accelerations. One frame fails the scalar factor, two identical ones the side-by-side
/// one (which overwrites its own K); the fallback's bits are those of the baseline code.
#[test]
fn a_failed_factor_in_an_evaluation_falls_back_on_k_as_assembled() {
    for copies in [1, 2] {
        let dense = Model::new(&frames(copies)).unwrap();
        let mut sparse = dense.clone();
        sparse.reactions = Reactions::new(&sparse.coords, &sparse.inertia, false);
        assert_eq!(sparse.reactions.side_by_side(), copies == 2);
        let q = dense.reduced_positions();
        // Moving ends (the bars' |ḃ|² terms), so that Ω is not zero as in a free fall.
        let v: Vec<f64> = (0..q.len()).map(|i| (i as f64 * 0.71).sin()).collect();
        let inputs = Inputs::start(&dense);
        let mut acc = [vec![0.0; q.len()], vec![0.0; q.len()], vec![0.0; q.len()]];
        let mut fallbacks = [0, 0, 0];
        for (k, model) in [&dense, &sparse, &sparse].into_iter().enumerate() {
            let mut ws = Workspace::new(model);
            if k < 2 {
                accelerations(model, &inputs, 0.0, &q, &v, &mut ws, &mut acc[k]);
            } else {
                evaluate(model, &inputs, 0.0, &q, &v, &mut ws, &mut acc[k]);
            }
            fallbacks[k] = ws.dense_fallbacks;
        }
        assert_eq!(
            fallbacks,
            [0, 1, 1],
            "the sparse factor fails, the dense never"
        );
        let scale = acc[0].iter().fold(0.0_f64, |m, a| m.max(a.abs()));
        assert!(scale > 1.0, "gravity accelerates the frame's free ends");
        for ((a, b), c) in acc[0].iter().zip(&acc[1]).zip(&acc[2]) {
            assert!((a - b).abs() <= 1e-9 * scale, "{copies} frames: {a} vs {b}");
            assert_eq!(
                b.to_bits(),
                c.to_bits(),
                "{copies} frames: AVX2 vs baseline"
            );
        }
    }
}

/// prism2-elastic with a reeled cable and a scripted sinusoidal load, and the dropped
/// icosahedron lowered from 0.3 m to 5 mm into its ground, so that its contacts push.
pub(super) fn reeled_and_dropped() -> [crate::scene::Scene; 2] {
    let mut reeled = crate::scene::Scene::from_toml_str(
        &(builtin("prism2-elastic").unwrap().to_toml_string()
            + "\n[[loads]]\nkind = \"sinusoidal\"\nnode = 7\namplitude = [1.0, 0.0, 0.0]\n\
               frequency = 2.0\nphase = 0.5\n"),
    )
    .unwrap();
    reeled.cables[9].control = Some(crate::scene::CableControl::RestLength);
    let mut dropped = crate::scene::Scene::from_toml_str(include_str!(
        "../../fmu/scenes/icosahedron-dropped.toml"
    ))
    .unwrap();
    dropped.nodes.iter_mut().for_each(|x| x[2] -= 0.305);
    [reeled, dropped]
}

/// The evaluation compiled for AVX2 (used where the processor has it) gives the bits of
/// the baseline x86-64 one (whose lanes' factor, λ passes and K's bundles still pick AVX2
/// themselves: those are compared in `block_cholesky`, `bar_response::lanes` and `reactions`), for
/// every kind of effect: joints side by side and force
/// inputs (tower20), controlled cables in the sparse and the dense basis (prism2), a reeled
/// cable and a scripted sinusoidal load (prism2-elastic), and damped cables, payloads,
/// gravity and ground contact with friction (icosahedron-dropped), at states away from rest.
#[test]
fn the_avx2_evaluation_gives_the_portable_bits() {
    if !crate::simd::has_avx2() {
        eprintln!("no AVX2 here: the baseline evaluation is compared with itself");
    }
    let [reeled, dropped] = reeled_and_dropped();
    let models = [
        Model::new(&builtin("tower20").unwrap()).unwrap(),
        Model::new(&builtin("prism2").unwrap()).unwrap(),
        Model::with_basis(&builtin("prism2").unwrap(), crate::model::BasisKind::Dense).unwrap(),
        Model::new(&reeled).unwrap(),
        Model::new(&dropped).unwrap(),
    ];
    assert_eq!(
        Inputs::start(&models[3]).rest_length.len(),
        1,
        "a reeled cable"
    );
    assert_eq!(models[3].scene.loads.len(), 1, "a scripted load");
    for model in &models {
        let q0 = model.reduced_positions();
        let mut inputs = Inputs::start(model);
        inputs.force_density.iter_mut().for_each(|g| *g += 3.0);
        inputs.rest_length.iter_mut().for_each(|s| *s *= 0.9);
        for (k, f) in inputs.node_force.iter_mut().enumerate() {
            *f = Vector3::new(0.5, -0.3 * k as f64, 0.2);
        }
        let (mut ws, mut ws_portable) = (Workspace::new(model), Workspace::new(model));
        let (mut acc, mut acc_portable) = (vec![0.0; q0.len()], vec![0.0; q0.len()]);
        let mut pushed = 0;
        for k in 0..10 {
            let (q, v) = moved(&q0, k);
            accelerations(model, &inputs, 0.1, &q, &v, &mut ws, &mut acc);
            evaluate(
                model,
                &inputs,
                0.1,
                &q,
                &v,
                &mut ws_portable,
                &mut acc_portable,
            );
            assert!(acc.iter().any(|a| a.abs() > 1e-3), "a state away from rest");
            for (a, b) in acc.iter().zip(&acc_portable) {
                assert_eq!(a.to_bits(), b.to_bits(), "{}", model.scene.name);
            }
            for (a, b) in ws.gamma.iter().zip(&ws_portable.gamma) {
                assert_eq!(a.to_bits(), b.to_bits(), "{}: γ", model.scene.name);
            }
            pushed += ws.contact_force.iter().filter(|f| f.z > 0.0).count();
        }
        assert_eq!(pushed > 0, model.ground.is_some(), "{}", model.scene.name);
    }
}
