//! `start = "equilibrium"`: a sagging prism under gravity, a tower, and a free prism
//! standing on the ground start at rest and stay there over 2 s of simulation; a
//! mechanism, a load the structure cannot carry, and a prestress it cannot hold are
//! refused with the reason. Figures are printed (run with `--nocapture`).

use nalgebra::Vector3;
use tensegrity_fmu::analysis;
use tensegrity_fmu::analysis::modes::{ModeKind, Spectrum};
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, tower_scene, GroundSpec, PrestressSpec, Scene, Start};
use tensegrity_fmu::Simulation;

const GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

fn settled(mut scene: Scene) -> Scene {
    scene.start = Start::Equilibrium;
    scene.solver.method = Method::Rk4;
    scene
}

/// Runs 2 s from the start and returns (largest node move from the start, largest sag
/// of the start from the scene's geometry), m.
fn drift_over_two_seconds(scene: &Scene) -> (f64, f64) {
    let model = analysis::load(scene).expect("the scene settles");
    let report = model.start.expect("an equilibrium start reports its solve");
    println!("{}: {report}", scene.name);
    let given: Vec<Vector3<f64>> = scene.nodes.iter().map(|p| Vector3::from(*p)).collect();
    let sag = (0..given.len())
        .map(|n| (model.positions[n] - given[n]).norm())
        .fold(0.0, f64::max);
    let start = model.positions.clone();
    let mut sim = Simulation::new(model);
    assert!(
        sim.stability_problem().is_none(),
        "{}: step refused",
        scene.name
    );
    sim.advance_to(2.0).expect("2 s run");
    sim.refresh();
    let drift = (0..start.len())
        .map(|n| (sim.node_position(n) - start[n]).norm())
        .fold(0.0, f64::max);
    println!(
        "{}: sag from the given geometry {sag:.4e} m, drift over 2 s {drift:.3e} m",
        scene.name
    );
    (drift, sag)
}

#[test]
fn sagging_prism_starts_at_rest_and_stays_there() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.gravity = Some(GRAVITY);
    let (drift, sag) = drift_over_two_seconds(&settled(scene.clone()));
    assert!(drift <= 1e-9, "drift {drift:e} m");
    // It really sagged: gravity moves the top by millimetres against 500 N/m cables.
    assert!(sag > 1e-3, "sag {sag:e} m");
    // Started as given, the same prism swings by about its sag.
    let model = analysis::load(&scene).unwrap();
    let start = model.positions.clone();
    let mut sim = Simulation::new(model);
    sim.advance_to(0.2).unwrap();
    sim.refresh();
    let swing = (0..start.len())
        .map(|n| (sim.node_position(n) - start[n]).norm())
        .fold(0.0, f64::max);
    println!("as given: moves {swing:.4e} m in 0.2 s");
    assert!(swing > 0.1 * sag, "as given it should move ({swing:e} m)");
}

#[test]
fn tower_under_gravity_starts_at_rest() {
    // Five stages of 500 N/m cables at 10 N prestress fold under their own weight (the
    // solve says so); 5000 N/m at 100 N stands.
    let mut scene = tower_scene(5, Some(5000.0), "tower5");
    scene.prestress = Some(PrestressSpec { min_tension: 100.0 });
    scene.gravity = Some(GRAVITY);
    let (drift, sag) = drift_over_two_seconds(&settled(scene));
    assert!(drift <= 1e-9, "drift {drift:e} m");
    assert!(sag > 1e-3, "sag {sag:e} m");
}

/// The prism with nothing pinned, standing on a frictionless or rough ground.
fn free_prism_on_ground(friction: f64) -> Scene {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.name = format!("free-prism-mu{friction}");
    scene.fixed.clear();
    scene.gravity = Some(GRAVITY);
    scene.ground = Some(GroundSpec {
        height: 0.0,
        normal: [0.0, 0.0, 1.0],
        stiffness: 1e4,
        damping: 0.0,
        friction,
        slip_velocity: 1.0,
    });
    scene
}

#[test]
fn free_prism_stands_on_the_ground_at_rest() {
    for friction in [0.0, 0.3] {
        let scene = free_prism_on_ground(friction);
        let (drift, sag) = drift_over_two_seconds(&settled(scene.clone()));
        assert!(drift <= 1e-9, "μ = {friction}: drift {drift:e} m");
        assert!(sag > 1e-3, "sag {sag:e} m");
        // Six bars of 1 kg on three feet of 1e4 N/m sink 59 N / 3e4 N/m ≈ 2 mm each.
        let model = analysis::load(&settled(scene)).unwrap();
        for n in 0..3 {
            let z = model.positions[n].z;
            assert!(
                (z + 9.81 * 6.0 / 3.0e4).abs() < 2e-4,
                "foot {} at z = {z}",
                n + 1
            );
        }
    }
}

#[test]
fn a_prism_without_prestress_is_a_mechanism() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.prestress = None;
    for cable in &mut scene.cables {
        let [a, b] = cable.nodes;
        let s = Vector3::from(scene.nodes[b - 1]) - Vector3::from(scene.nodes[a - 1]);
        cable.rest_length = Some(s.norm());
    }
    let err = analysis::load(&settled(scene)).unwrap_err().to_string();
    println!("{err}");
    assert!(err.starts_with("start:"), "{err}");
    assert!(
        err.contains("mechanism") && err.contains("prestress"),
        "{err}"
    );
}

#[test]
fn a_free_prism_in_free_fall_is_refused() {
    let mut scene = free_prism_on_ground(0.0);
    scene.ground = None;
    let err = analysis::load(&settled(scene)).unwrap_err().to_string();
    println!("{err}");
    assert!(err.contains("a load it cannot carry"), "{err}");
    assert!(err.contains("pin it") && err.contains("ground"), "{err}");
}

#[test]
fn a_load_far_beyond_what_the_prism_carries_is_refused() {
    let mut scene = builtin("prism2-elastic").unwrap();
    // 4905 m/s²: the weight pulls the prism through itself; no stable equilibrium near.
    scene.gravity = Some([0.0, 0.0, -981.0 * 5.0]);
    let err = analysis::load(&settled(scene)).unwrap_err().to_string();
    println!("{err}");
    assert!(
        err.starts_with("start: no stable static equilibrium"),
        "{err}"
    );
}

#[test]
fn an_equilibrium_given_as_is_needs_no_iteration() {
    let scene = settled(builtin("prism2-elastic").unwrap());
    let model = analysis::load(&scene).unwrap();
    let report = model.start.unwrap();
    println!("prism2-elastic: {report}");
    assert_eq!(report.iterations, 0);
    let given: Vec<Vector3<f64>> = scene.nodes.iter().map(|p| Vector3::from(*p)).collect();
    for (n, x) in model.positions.iter().enumerate() {
        assert!((x - given[n]).norm() < 1e-15, "node {} moved", n + 1);
    }
}

#[test]
fn a_structure_too_large_for_the_dense_solve_is_refused_up_front() {
    // 167 stages: 3 · 3 · 167 = 1503 reduced coordinates, just over the limit.
    // Rest lengths written out: the prestress solve of so tall a tower takes longer
    // than the check under test.
    let mut scene = settled(tower_scene(167, Some(500.0), "tower167"));
    scene.prestress = None;
    for cable in &mut scene.cables {
        let [a, b] = cable.nodes;
        let s = Vector3::from(scene.nodes[b - 1]) - Vector3::from(scene.nodes[a - 1]);
        cable.rest_length = Some(0.99 * s.norm());
    }
    let started = std::time::Instant::now();
    let err = analysis::load(&scene).unwrap_err().to_string();
    println!("{err} ({:.2} s)", started.elapsed().as_secs_f64());
    assert!(
        err.starts_with(
            "start: start = \"equilibrium\": the structure has 1503 reduced coordinates"
        ),
        "{err}"
    );
    assert!(err.contains("start it \"as_given\""), "{err}");
    let mut given = scene;
    given.start = Start::AsGiven;
    assert!(analysis::load(&given).is_ok());
}

#[test]
fn a_single_pin_leaves_three_rigid_rotations_not_a_mechanism() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.fixed = vec![1];
    let model = analysis::load(&settled(scene)).expect("a prism on one pin has an equilibrium");
    let sim = Simulation::new(model);
    let y = &sim.state().y;
    let spectrum = Spectrum::new(sim.model(), &sim.inputs, 0.0, &y[..y.len() / 2]);
    println!("one pin: {:?}", &spectrum.frequencies_hz()[..5]);
    assert_eq!(spectrum.count(ModeKind::RigidBody), 3);
    assert_eq!(spectrum.count(ModeKind::Mechanism), 0);
    assert_eq!(
        spectrum.count(ModeKind::Vibration),
        spectrum.modes.len() - 3
    );
}

#[test]
fn a_steel_stiff_prism_with_little_prestress_is_stable_not_a_mechanism() {
    // κ = 1e7 N/m and 0.01 N of prestress: the prestress mode is 1e-11 of the stiffest.
    let mut scene = builtin("prism2-elastic").unwrap();
    for cable in &mut scene.cables {
        cable.stiffness = Some(1e7);
    }
    scene.prestress = Some(PrestressSpec { min_tension: 0.01 });
    let model = analysis::load(&settled(scene)).expect("at its own equilibrium already");
    println!("steel prism: {}", model.start.unwrap());
    let sim = Simulation::new(model);
    let y = &sim.state().y;
    let spectrum = Spectrum::new(sim.model(), &sim.inputs, 0.0, &y[..y.len() / 2]);
    let f = spectrum.frequencies_hz();
    println!(
        "steel prism: lowest {:.4} Hz, highest {:.1} Hz",
        f[0],
        f[f.len() - 1]
    );
    assert_eq!(spectrum.count(ModeKind::Vibration), 12);
    assert!(f[0] > 0.01 && f[0] < 0.05, "prestress mode {} Hz", f[0]);
}

#[test]
fn a_structure_above_its_ground_is_told_to_stand_on_it() {
    let mut scene = free_prism_on_ground(0.0);
    for node in &mut scene.nodes {
        node[2] += 0.01;
    }
    let err = analysis::load(&settled(scene)).unwrap_err().to_string();
    println!("{err}");
    assert!(
        err.contains("no node touches the ground (the lowest is 1.000e-2 m above it)"),
        "{err}"
    );
    assert!(err.contains("place it on the ground"), "{err}");
}

#[test]
fn analyses_of_a_moving_start_ask_to_remove_the_velocities() {
    let mut scene = settled(builtin("prism2-elastic").unwrap());
    scene.velocities = Some(
        vec![[0.0, 0.0, 0.0]; 6]
            .into_iter()
            .chain([[0.1, 0.0, 0.0]; 3])
            .collect(),
    );
    let sim = Simulation::new(analysis::load(&scene).unwrap());
    let err = analysis::require_rest(&sim, "modes").unwrap_err();
    println!("{err}");
    assert!(err.starts_with("modes: the start state is moving"), "{err}");
    assert!(err.ends_with("remove `velocities` from the scene"), "{err}");
}
