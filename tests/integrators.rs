//! Measured orders of accuracy of the integrators on prism2 with elastic cables, in a
//! range where no cable goes slack, against a tight-tolerance adaptive reference.

use nalgebra::Vector3;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, Scene};
use tensegrity_fmu::{Model, Simulation};

fn scene(method: Method, h: f64, tol: f64) -> Scene {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.prestress = None;
    for c in &mut scene.cables {
        let [a, b] = c.nodes;
        let d = Vector3::from(scene.nodes[b - 1]) - Vector3::from(scene.nodes[a - 1]);
        c.rest_length = Some(0.9 * d.norm());
    }
    scene.solver.method = method;
    scene.solver.step_size = h;
    scene.solver.rtol = tol;
    scene.solver.atol = tol;
    scene
}

/// Node positions after 1 s under a constant top load; asserts taut cables throughout and
/// exact constraints at the end.
fn run(method: Method, h: f64, tol: f64) -> (Vec<Vector3<f64>>, u64) {
    let mut sim = Simulation::new(Model::new(&scene(method, h, tol)).unwrap());
    for f in &mut sim.inputs.node_force {
        *f = Vector3::new(0.5, 0.0, 0.0);
    }
    for k in 1..=100 {
        sim.advance_to(k as f64 * 0.01).unwrap();
        sim.refresh();
        assert!(
            sim.workspace().gamma.iter().all(|&g| g > 0.0),
            "a cable went slack"
        );
    }
    assert!(sim.length_error() <= 1e-12 && sim.orthogonality_error() <= 1e-12);
    let x = (0..sim.model().n_nodes())
        .map(|n| sim.node_position(n))
        .collect();
    (x, sim.integrator().rhs_evaluations())
}

fn distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

fn reference() -> Vec<Vector3<f64>> {
    let (tight, _) = run(Method::Dopri5, 1e-3, 1e-13);
    let (looser, _) = run(Method::Dopri5, 1e-3, 1e-12);
    let converged = distance(&tight, &looser);
    println!("reference: dopri5 at 1e-13 differs from 1e-12 by {converged:.1e} m");
    assert!(converged < 1e-11, "reference not converged: {converged}");
    tight
}

fn observed_orders(method: Method, steps: &[f64], reference: &[Vector3<f64>]) -> Vec<f64> {
    let errors: Vec<f64> = steps
        .iter()
        .map(|&h| distance(&run(method, h, 1e-6).0, reference))
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    let shown: Vec<String> = errors.iter().map(|e| format!("{e:.2e}")).collect();
    println!("{}: errors {shown:?} m, orders {orders:.2?}", method.name());
    orders
}

#[test]
fn rk4_is_fourth_order_and_rattle_second_order() {
    let reference = reference();
    for order in observed_orders(Method::Rk4, &[2e-3, 1e-3, 5e-4, 2.5e-4], &reference) {
        assert!((3.7..4.3).contains(&order), "rk4 order {order}");
    }
    for order in observed_orders(Method::Rattle, &[4e-3, 2e-3, 1e-3, 5e-4], &reference) {
        assert!((1.8..2.2).contains(&order), "rattle order {order}");
    }
}

#[test]
fn adaptive_error_tracks_its_tolerance() {
    let reference = reference();
    let mut last_evals = 0;
    for tol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9] {
        let (x, evals) = run(Method::Dopri5, 1e-3, tol);
        let error = distance(&x, &reference);
        println!("dopri5 tol {tol:.0e}: error {error:.2e} m, {evals} evaluations");
        assert!(
            error <= 10.0 * tol && error >= tol / 10.0,
            "tol {tol}: error {error}"
        );
        assert!(evals > last_evals, "tighter tolerance must cost more");
        last_evals = evals;
    }
}

/// Largest relative energy error in each 100 s block of a 1,000 s undamped run of the
/// icosahedron (one face pinned, started with a velocity disturbance).
fn energy_error_per_block(method: Method) -> Vec<f64> {
    let mut scene = builtin("icosahedron").unwrap();
    scene.solver.method = method;
    scene.velocities = Some(
        (0..scene.nodes.len())
            .map(|i| {
                let s = i as f64;
                [
                    0.3 * (1.7 * s).sin(),
                    0.3 * (2.3 * s).cos(),
                    0.3 * (0.7 * s).sin(),
                ]
            })
            .collect(),
    );
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    let e0 = sim.energy();
    (0..10)
        .map(|block| {
            let mut worst = 0.0f64;
            for k in 1..=1000 {
                sim.advance_to((block * 1000 + k) as f64 * 0.1).unwrap();
                sim.refresh();
                worst = worst.max(((sim.energy() - e0) / e0).abs());
            }
            worst
        })
        .collect()
}

#[test]
fn rattle_keeps_energy_bounded_over_1000_s() {
    let mut growth = Vec::new();
    // The explicit methods and rattle (sdirk3 is for stiff runs; it damps, see tests/stiff.rs).
    for method in [Method::Rk4, Method::Dopri5, Method::Rattle] {
        let blocks = energy_error_per_block(method);
        let shown: Vec<String> = blocks.iter().map(|e| format!("{e:.1e}")).collect();
        println!(
            "{}: worst relative energy error per 100 s: {shown:?}",
            method.name()
        );
        growth.push(blocks[9] / blocks[0]);
    }
    let [rk4, dopri5, rattle] = growth[..] else {
        unreachable!()
    };
    // The one-step RK methods drift linearly; RATTLE's error oscillates at its level.
    assert!(rk4 > 5.0 && dopri5 > 5.0, "rk4 {rk4}, dopri5 {dopri5}");
    assert!(rattle < 1.5, "rattle's energy error grew by {rattle}");
}
