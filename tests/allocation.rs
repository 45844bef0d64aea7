//! The step allocates nothing: a counting global allocator watches `advance`.

mod alloc_support;
use alloc_support::{allocations, watch_all_threads, watch_this_thread};

use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

/// One test, counting the allocations of its own thread.
#[test]
fn stepping_allocates_nothing() {
    watch_this_thread();
    fixed_steps_allocate_nothing();
    every_method_advances_without_allocating();
    contact_allocates_nothing();
    two_threads_allocate_nothing();
}

/// The icosahedron dropped across a box step (terrain with friction that sticks, and
/// collisions): from its first impact on, through contact onsets, grips that stick and
/// slip and located events, no step allocates.
fn contact_allocates_nothing() {
    use tensegrity_fmu::integrator::Method;
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fmu/scenes/icosahedron-step.toml");
    for method in [Method::Rk4, Method::Dopri5] {
        let mut scene = tensegrity_fmu::Scene::from_file(&path).unwrap();
        scene.solver.method = method;
        scene.solver.step_size = 2e-4;
        let mut sim = Simulation::new(Model::new(&scene).unwrap());
        // Past the first impact: every buffer has met a contact.
        sim.advance_to(0.3).unwrap();
        let before = allocations();
        for k in 1..=300 {
            sim.advance_to(0.3 + k as f64 * 2e-3).unwrap();
        }
        let during = allocations() - before;
        let events = sim.stats().events;
        assert!(
            events > 10,
            "{}: {events} events: the contact was never located",
            method.name()
        );
        assert_eq!(
            during,
            0,
            "{}: {during} allocations in contact",
            method.name()
        );
    }
}

/// A tower of 4,200 bars evaluates on two threads; neither allocates in a step (every
/// thread is watched: the second is the library's; this binary's one test runs alone).
fn two_threads_allocate_nothing() {
    use tensegrity_fmu::dynamics::parallel::{Halves, MIN_BARS};
    let mut scene = tensegrity_fmu::scene::tower_scene(1400, Some(500.0), "tower");
    scene.prestress = None;
    for c in &mut scene.cables {
        c.rest_length = Some(0.5);
    }
    let model = Model::new(&scene).unwrap();
    assert!(Halves::new(&model, MIN_BARS).is_some(), "on two threads");
    let mut sim = Simulation::new(model);
    sim.inputs.node_force[0].x = 1.0;
    sim.advance(2, 1e-3).unwrap();
    watch_all_threads(true);
    let before = allocations();
    sim.advance(20, 1e-3).unwrap();
    let during = allocations() - before;
    watch_all_threads(false);
    assert_eq!(during, 0, "{during} allocations in 20 steps on two threads");
}

fn every_method_advances_without_allocating() {
    use tensegrity_fmu::integrator::Method;
    // sdirk3 keeps its iteration matrix while Newton converges with it: rebuilding it (first
    // step, input changes, slow convergence) allocates, its steps do not.
    for method in Method::ALL {
        let mut scene = builtin("tower20").unwrap();
        scene.solver.method = method;
        let mut sim = Simulation::new(Model::new(&scene).unwrap());
        sim.inputs.node_force[0].x = 1.0;
        sim.advance_to(0.002).unwrap();
        let before = allocations();
        // The path fmi2DoStep takes, communication step by communication step.
        for k in 3..=100 {
            sim.advance_to(k as f64 * 1e-3).unwrap();
        }
        let during = allocations() - before;
        assert_eq!(during, 0, "{}: {during} allocations", method.name());
    }
}

fn fixed_steps_allocate_nothing() {
    for name in ["prism2", "icosahedron", "tower20"] {
        let mut sim = Simulation::new(Model::new(&builtin(name).unwrap()).unwrap());
        sim.inputs.node_force[0].x = 1.0;
        sim.advance(2, 1e-3).unwrap();
        let before = allocations();
        sim.advance(200, 1e-3).unwrap();
        sim.refresh();
        let _ = (
            sim.energy(),
            sim.length_error(),
            sim.bar_force(0),
            sim.cable_tension(0),
        );
        let during = allocations() - before;
        assert_eq!(during, 0, "{name}: {during} allocations in 200 steps");
    }
}
