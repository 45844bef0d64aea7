//! The evaluation on two threads gives the one-thread bits.

use super::super::tests::moved;
use super::super::{accelerations, Inputs, Workspace};
use super::Halves;
use crate::model::reactions::Reactions;
use crate::model::Model;
use crate::scene::builtin;

/// What [`same_bits_on_two_threads`] saw: the split, the evaluations that fell back on the
/// dense solve, and the contacts that pushed.
struct Seen {
    halves: Halves,
    fallbacks: u64,
    pushing: usize,
}

/// Evaluates `model` on one thread and on two at 6 states away from rest and compares
/// every output bit for bit.
fn same_bits_on_two_threads(model: &Model, inputs: &Inputs) -> Seen {
    let halves = Halves::new(model, 2).expect("a layout two threads can share");
    let (mut one, mut two) = (
        Workspace::two_threads_from(model, usize::MAX),
        Workspace::two_threads_from(model, 2),
    );
    assert!(!one.two_threads() && two.two_threads());
    let q0 = model.reduced_positions();
    let (mut acc_one, mut acc_two) = (vec![0.0; q0.len()], vec![f64::NAN; q0.len()]);
    let name = &model.scene.name;
    for k in 0..6 {
        let (q, v) = moved(&q0, k);
        accelerations(model, inputs, 0.1, &q, &v, &mut one, &mut acc_one);
        accelerations(model, inputs, 0.1, &q, &v, &mut two, &mut acc_two);
        assert!(
            acc_one.iter().any(|a| a.abs() > 1e-3),
            "a state away from rest"
        );
        let bits = |x: &[f64]| x.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&acc_one), bits(&acc_two), "{name}: accelerations");
        assert_eq!(bits(&one.gamma), bits(&two.gamma), "{name}: γ");
        assert_eq!(bits(&one.lambda), bits(&two.lambda), "{name}: λ");
        let vectors =
            |x: &[nalgebra::Vector3<f64>]| bits(&x.iter().flatten().copied().collect::<Vec<_>>());
        assert_eq!(
            vectors(&one.end_force),
            vectors(&two.end_force),
            "{name}: end forces with Ω"
        );
        assert_eq!(
            vectors(&one.contact_force),
            vectors(&two.contact_force),
            "{name}: contacts"
        );
        let omega = |ws: &Workspace| -> Vec<_> {
            let columns = 0..model.coords.constraints.len();
            columns.map(|c| ws.reaction_solution(c)).collect()
        };
        assert_eq!(vectors(&omega(&one)), vectors(&omega(&two)), "{name}: Ω");
        assert_eq!(one.dense_fallbacks, two.dense_fallbacks, "{name}");
    }
    Seen {
        halves,
        fallbacks: two.dense_fallbacks,
        pushing: two.contact_force.iter().filter(|f| f.z > 0.0).count(),
    }
}

/// A 30-stage tower (its chains factored one after the other, as beyond the lanes' size)
/// with elastic cables and force inputs: the seam between the halves
/// crosses K's blocks and the reduced nodes the two halves' bars share, and each thread
/// factors whole chains.
#[test]
fn a_tower_gives_the_same_bits_on_two_threads() {
    let mut scene = crate::scene::tower_scene(30, Some(500.0), "tower");
    scene.prestress = None;
    for (j, c) in scene.cables.iter_mut().enumerate() {
        c.rest_length = Some(0.4 + 0.01 * (j % 7) as f64);
    }
    let mut model = Model::new(&scene).unwrap();
    model.reactions = model.reactions.without_lanes();
    let mut inputs = Inputs::start(&model);
    for (k, f) in inputs.node_force.iter_mut().enumerate() {
        f.x = 0.5 + k as f64;
    }
    let halves = same_bits_on_two_threads(&model, &inputs).halves;
    assert!(!halves.deferred_bars.is_empty(), "K's blocks at the seam");
    let columns = model.coords.constraints.len();
    assert!(
        halves.even > 0 && halves.even < columns,
        "Ω split at {}",
        halves.even
    );
    assert!(!halves.late_ends.is_empty(), "nodes at the seam");
    assert_eq!(
        halves.columns.map(|c| c.len()),
        [60, 30],
        "two chains and one"
    );
    assert_eq!(
        halves.handed_columns, 30,
        "the second chain's backward substitution handed to the other thread"
    );
}

/// Every other kind of effect: controlled cables (prism2), a reeled cable and a scripted
/// load (prism2-elastic), damped cables, payloads, gravity and ground contact
/// (icosahedron-dropped, pressed into its ground, applied after both halves).
#[test]
fn every_effect_gives_the_same_bits_on_two_threads() {
    let [reeled, dropped] = super::super::tests::reeled_and_dropped();
    for scene in [builtin("prism2").unwrap(), reeled, dropped] {
        let mut model = Model::new(&scene).unwrap();
        // Side by side the chains keep one thread.
        model.reactions = model.reactions.without_lanes();
        let mut inputs = Inputs::start(&model);
        inputs.force_density.iter_mut().for_each(|g| *g += 3.0);
        inputs.rest_length.iter_mut().for_each(|s| *s *= 0.9);
        let seen = same_bits_on_two_threads(&model, &inputs);
        if model.ground.is_some() {
            assert_eq!(seen.halves.after.len(), 1, "contact after the halves");
            assert!(seen.pushing > 0, "contacts that push");
        }
    }
}

/// Rigid frames (K singular) with the sparse solver forced on them: the factor fails on a
/// thread, and the evaluation falls back on the dense solve of K assembled again.
#[test]
fn a_failed_factor_on_two_threads_falls_back_as_on_one() {
    let mut model = Model::new(&super::super::tests::frames(3)).unwrap();
    model.reactions = Reactions::new(&model.coords, &model.inertia, false).without_lanes();
    let seen = same_bits_on_two_threads(&model, &Inputs::start(&model));
    assert!(seen.halves.columns.iter().all(|c| !c.is_empty()));
    assert!(
        seen.halves.handed_columns > 0,
        "a failed factor with a handoff waiting on it"
    );
    assert_eq!(
        seen.fallbacks, 6,
        "the sparse factor fails in every evaluation"
    );
}

/// The dense basis and the side-by-side chains keep one thread.
#[test]
fn layouts_two_threads_cannot_share_keep_one() {
    let prism = builtin("prism2").unwrap();
    let dense = Model::with_basis(&prism, crate::model::BasisKind::Dense).unwrap();
    assert!(Halves::new(&dense, 2).is_none());
    let tower = Model::new(&builtin("tower20").unwrap()).unwrap();
    assert!(Halves::new(&tower, 2).is_none(), "the lanes hold K");
    assert!(Halves::new(&Model::new(&prism).unwrap(), usize::MAX).is_none());
}

/// The handoff's word carries the outcome, and a signal dropped unsent (a panic unwinding
/// the first thread) reads as a failure, so the waiting thread always ends.
#[test]
fn the_handoff_carries_the_outcome_and_a_dropped_signal_fails() {
    let sent = super::Handoff::default();
    sent.signal().send(true);
    assert!(sent.wait());
    let failed = super::Handoff::default();
    failed.signal().send(false);
    assert!(!failed.wait());
    let dropped = super::Handoff::default();
    drop(dropped.signal());
    assert!(!dropped.wait());
    let first_only = super::Handoff::default();
    let mut signal = first_only.signal();
    signal.send(true);
    drop(signal);
    assert!(first_only.wait(), "a signal sends once");
}
