//! A large structure steps on two threads (its evaluations, rk4's loops and the location
//! of switches) to the bits of one thread: every loop split between the threads is over
//! independent entries.

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::tower_scene;
use tensegrity_fmu::{Model, Simulation};

/// A 1,400-stage tower (4,200 bars, past the two-thread threshold) whose cables start at
/// rest lengths that leave some slack and some taut, so switches are located while it
/// moves.
fn tower() -> Model {
    let mut scene = tower_scene(1400, Some(500.0), "tall");
    scene.solver.method = Method::Rk4;
    scene.solver.step_size = 1e-3;
    scene.prestress = None;
    for (j, c) in scene.cables.iter_mut().enumerate() {
        let [a, b] = c.nodes;
        let d: f64 = (0..3)
            .map(|i| (scene.nodes[b - 1][i] - scene.nodes[a - 1][i]).powi(2))
            .sum::<f64>()
            .sqrt();
        c.rest_length = Some(d * [0.97, 1.0005, 0.99][j % 3]);
    }
    Model::new(&scene).unwrap()
}

#[test]
fn steps_on_two_threads_give_the_bits_of_one() {
    let model = tower();
    let mut runs = [false, true].map(|two| {
        let mut sim = Simulation::new(model.clone());
        sim.use_two_threads(two);
        assert_eq!(sim.workspace().two_threads(), two);
        sim
    });
    for sim in &mut runs {
        sim.advance(40, 1e-3).unwrap();
    }
    let [one, two] = &runs;
    assert!(
        one.stats().events > 0,
        "switches located: {:?}",
        one.stats()
    );
    assert_eq!(one.stats(), two.stats());
    let start = model.reduced_positions();
    assert_ne!(&one.state().y[..start.len()], &start[..], "the tower moved");
    for (a, b) in one.state().y.iter().zip(&two.state().y) {
        assert_eq!(a.to_bits(), b.to_bits());
    }
}
