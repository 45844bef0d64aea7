//! The step allocates nothing: a counting global allocator watches `advance`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    // Only the test's own thread is watched: the harness's threads allocate at will.
    static WATCHED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if WATCHED.with(std::cell::Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        }
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// One test, counting the allocations of its own thread.
#[test]
fn stepping_allocates_nothing() {
    WATCHED.with(|w| w.set(true));
    fixed_steps_allocate_nothing();
    every_method_advances_without_allocating();
}

fn every_method_advances_without_allocating() {
    use tensegrity_fmu::integrator::Method;
    for method in Method::ALL {
        let mut scene = builtin("tower20").unwrap();
        scene.solver.method = method;
        let mut sim = Simulation::new(Model::new(&scene).unwrap());
        sim.inputs.node_force[0].x = 1.0;
        sim.advance_to(0.002).unwrap();
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        // The path fmi2DoStep takes, communication step by communication step.
        for k in 3..=100 {
            sim.advance_to(k as f64 * 1e-3).unwrap();
        }
        let during = ALLOCATIONS.load(Ordering::SeqCst) - before;
        assert_eq!(during, 0, "{}: {during} allocations", method.name());
    }
}

fn fixed_steps_allocate_nothing() {
    for name in ["prism2", "icosahedron", "tower20"] {
        let mut sim = Simulation::new(Model::new(&builtin(name).unwrap()).unwrap());
        sim.inputs.node_force[0].x = 1.0;
        sim.advance(2, 1e-3).unwrap();
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        sim.advance(200, 1e-3).unwrap();
        sim.refresh();
        let _ = (
            sim.energy(),
            sim.length_error(),
            sim.bar_force(0),
            sim.cable_tension(0),
        );
        let during = ALLOCATIONS.load(Ordering::SeqCst) - before;
        assert_eq!(during, 0, "{name}: {during} allocations in 200 steps");
    }
}
