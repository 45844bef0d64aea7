//! The step allocates nothing: a counting global allocator watches `advance`.

mod alloc_support;
use alloc_support::{allocations, watch_this_thread};

use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

/// One test, counting the allocations of its own thread.
#[test]
fn stepping_allocates_nothing() {
    watch_this_thread();
    fixed_steps_allocate_nothing();
    every_method_advances_without_allocating();
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
