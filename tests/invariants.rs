//! Physics invariants: constraint residuals, energy, momentum, equilibrium, convergence.
//! Figures are printed (run with `--nocapture`) so that they can be reported.

use nalgebra::Vector3;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::model::coords::{ConstraintColumn, Coordinates};
use tensegrity_fmu::scene::{builtin, Scene};
use tensegrity_fmu::{Model, Simulation, StepError};

/// prism2 with elastic cables whose rest lengths are `factor` × their start lengths.
fn prism_elastic(factor: f64, gravity: Option<[f64; 3]>) -> Scene {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.solver.method = Method::Rk4;
    scene.prestress = None;
    scene.gravity = gravity;
    for c in &mut scene.cables {
        let [a, b] = c.nodes;
        let d = Vector3::from(scene.nodes[b - 1]) - Vector3::from(scene.nodes[a - 1]);
        c.rest_length = Some(factor * d.norm());
    }
    scene
}

/// Runs `steps` steps and returns the largest length and orthogonality errors seen.
fn run_tracking_errors(sim: &mut Simulation, steps: u64, h: f64) -> (f64, f64) {
    let (mut length, mut ortho) = (0.0f64, 0.0f64);
    for k in 0..steps {
        sim.step_to(k as f64 * h, (k + 1) as f64 * h).unwrap();
        sim.refresh();
        length = length.max(sim.length_error());
        ortho = ortho.max(sim.orthogonality_error());
    }
    (length, ortho)
}

fn node_positions(sim: &Simulation) -> Vec<Vector3<f64>> {
    (0..sim.model().n_nodes())
        .map(|n| sim.node_position(n))
        .collect()
}

fn max_distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

#[test]
fn correction_holds_constraints_over_100k_steps_and_its_absence_drifts() {
    let scene = prism_elastic(0.9, Some([0.0, 0.0, -9.81]));
    let mut on = Simulation::new(Model::new(&scene).unwrap());
    let (length, ortho) = run_tracking_errors(&mut on, 100_000, 1e-3);
    let mut off = Simulation::new(Model::new(&scene).unwrap());
    off.correction = false;
    let (length_off, ortho_off) = run_tracking_errors(&mut off, 100_000, 1e-3);
    println!("prism2 under gravity, 100k steps of 1 ms: correction on: length {length:.2e} m, orthogonality {ortho:.2e} m²/s; off: length {length_off:.2e} m, orthogonality {ortho_off:.2e} m²/s");
    assert!(length <= 1e-12, "length error {length}");
    assert!(ortho <= 1e-12, "orthogonality error {ortho}");
    assert!(
        length_off > 1e3 * length.max(1e-15),
        "no drift without correction: {length_off}"
    );
    assert!(
        length_off > 1e-10,
        "drift without correction too small to see: {length_off}"
    );
}

/// Relative energy drift `max |E − E₀| / |E₀|` over `time` at step `h`.
fn energy_drift(scene: &Scene, time: f64, h: f64) -> f64 {
    let mut sim = Simulation::new(Model::new(scene).unwrap());
    let e0 = sim.energy();
    let steps = (time / h).round() as u64;
    let mut drift = 0.0f64;
    for k in 0..steps {
        sim.step_to(k as f64 * h, (k + 1) as f64 * h).unwrap();
        if k % 10 == 9 {
            sim.refresh();
            drift = drift.max((sim.energy() - e0).abs() / e0.abs());
        }
    }
    drift
}

#[test]
fn energy_is_conserved_and_drift_shrinks_with_the_step() {
    let scene = prism_elastic(0.95, None);
    let coarse = energy_drift(&scene, 10.0, 1e-3);
    let fine = energy_drift(&scene, 10.0, 5e-4);
    println!(
        "prism2-elastic, 10 s: relative energy drift {coarse:.2e} at 1 ms, {fine:.2e} at 0.5 ms"
    );
    assert!(coarse <= 1e-6, "drift {coarse}");
    assert!(
        fine < coarse / 4.0,
        "drift does not shrink: {coarse} -> {fine}"
    );
}

fn free_spinning_icosahedron() -> Scene {
    let mut scene = builtin("icosahedron").unwrap();
    scene.solver.method = Method::Rk4;
    scene.fixed.clear();
    scene.force_inputs.clear();
    let omega = Vector3::new(0.3, -0.5, 2.0);
    let drift = Vector3::new(0.1, 0.05, -0.02);
    scene.velocities = Some(
        scene
            .nodes
            .iter()
            .map(|p| (omega.cross(&Vector3::from(*p)) + drift).into())
            .collect(),
    );
    scene
}

#[test]
fn free_floating_icosahedron_conserves_momentum() {
    let mut sim = Simulation::new(Model::new(&free_spinning_icosahedron()).unwrap());
    assert!(
        sim.warnings().is_empty(),
        "rigid spin needs no projection: {:?}",
        sim.warnings()
    );
    let (p0, l0) = (sim.linear_momentum(), sim.angular_momentum());
    let x0 = node_positions(&sim);
    sim.advance(10_000, 1e-3).unwrap();
    sim.refresh();
    let dp = (sim.linear_momentum() - p0).norm() / p0.norm();
    let dl = (sim.angular_momentum() - l0).norm() / l0.norm();
    let moved = max_distance(&x0, &node_positions(&sim));
    println!("free icosahedron, 10 s: linear momentum drift {dp:.2e}, angular {dl:.2e} (relative); nodes moved {moved:.2} m");
    assert!(moved > 0.5, "the structure should drift and spin");
    assert!(dp <= 1e-12, "linear momentum drift {dp}");
    assert!(dl <= 1e-6, "angular momentum drift {dl}");
}

#[test]
fn prestressed_builtins_stay_at_rest() {
    for name in ["prism2", "prism2-elastic", "icosahedron", "tower20"] {
        let mut sim = Simulation::new(Model::new(&builtin(name).unwrap()).unwrap());
        let x0 = node_positions(&sim);
        sim.advance(10_000, 1e-3).unwrap();
        sim.refresh();
        let moved = max_distance(&x0, &node_positions(&sim));
        println!("{name}: nodes moved {moved:.2e} m over 10 s");
        assert!(moved <= 1e-10, "{name} moved {moved} m");
    }
}

/// Node positions after `time` with step `h` under a constant top load; asserts that no
/// cable goes slack, since a slack kink would cap the observed order.
fn loaded_prism_positions(h: f64, time: f64) -> Vec<Vector3<f64>> {
    let mut sim = Simulation::new(Model::new(&prism_elastic(0.9, None)).unwrap());
    for f in &mut sim.inputs.node_force {
        *f = Vector3::new(0.5, 0.0, 0.0);
    }
    let steps = (time / h).round() as u64;
    for k in 0..steps {
        sim.step_to(k as f64 * h, (k + 1) as f64 * h).unwrap();
        sim.refresh();
        assert!(
            sim.workspace().gamma.iter().all(|&g| g > 0.0),
            "a cable went slack"
        );
    }
    node_positions(&sim)
}

#[test]
fn rk4_converges_at_fourth_order() {
    let steps = [2e-3, 1e-3, 5e-4];
    let errors: Vec<f64> = steps
        .iter()
        .map(|&h| {
            max_distance(
                &loaded_prism_positions(h, 1.0),
                &loaded_prism_positions(h / 4.0, 1.0),
            )
        })
        .collect();
    for w in errors.windows(2) {
        let order = (w[0] / w[1]).log2();
        println!(
            "error {:.3e} -> {:.3e}: observed order {order:.2}",
            w[0], w[1]
        );
        assert!((3.7..4.3).contains(&order), "order {order}");
    }
}

#[test]
fn nan_input_is_rejected_and_state_kept() {
    let mut sim = Simulation::new(Model::new(&builtin("prism2").unwrap()).unwrap());
    sim.advance(5, 1e-3).unwrap();
    let before = sim.state().clone();
    sim.inputs.force_density[3] = f64::NAN;
    let err = sim.advance(1, 1e-3).unwrap_err();
    assert!(matches!(err, StepError::NonFiniteInput { .. }));
    assert!(err.to_string().contains("cable[4].force_density"), "{err}");
    assert_eq!(sim.state(), &before);
    sim.inputs.force_density[3] = 1.0;
    sim.inputs.node_force[0].x = f64::INFINITY;
    assert!(sim
        .advance(1, 1e-3)
        .unwrap_err()
        .to_string()
        .contains("node[7].fx"));
    assert_eq!(sim.state(), &before);
}

#[test]
fn non_finite_state_restores_last_good_point() {
    let mut scene = builtin("prism2").unwrap();
    scene.solver.method = Method::Rk4;
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    sim.advance(3, 1e-3).unwrap();
    let before = sim.state().clone();
    // A force so large that the RK4 stages overflow to infinity.
    sim.inputs.node_force[0] = Vector3::new(1e307, 1e307, 0.0);
    let err = sim.advance(1, 1e-3).unwrap_err();
    assert!(matches!(err, StepError::NonFinite { .. }), "{err}");
    assert_eq!(sim.state(), &before);
    assert!(sim.length_error() < 1e-12);
}

#[test]
fn contradictory_constraints_are_an_error_and_redundant_ones_are_ranked_out() {
    let bars = [(0, 1)];
    let pin = |e: usize| ConstraintColumn {
        terms: vec![(e, 1.0)],
    };
    let at = |x: f64| Vector3::new(x, 0.0, 0.0);
    // The same end pinned twice at the same place: redundant, rank 1.
    let coords =
        Coordinates::general(&bars, 2, vec![pin(0), pin(0)], vec![at(0.0), at(0.0)]).unwrap();
    assert_eq!(coords.r, 1);
    assert!(coords.fixed[0].norm() < 1e-15);
    // The same end pinned at two places: contradictory.
    let err =
        Coordinates::general(&bars, 2, vec![pin(0), pin(0)], vec![at(0.0), at(1.0)]).unwrap_err();
    assert!(err.to_string().contains("contradictory"), "{err}");
}
