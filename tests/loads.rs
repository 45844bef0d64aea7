//! Scripted loads (issue 6, item 2.6): constant, sinusoidal and step loads declared in the
//! scene, evaluated at the integrator's stage times.

use nalgebra::Vector3;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, LoadSpec, Scene};
use tensegrity_fmu::{Model, Simulation};

fn prism() -> Scene {
    builtin("prism2-elastic").unwrap()
}

fn positions(sim: &mut Simulation) -> Vec<Vector3<f64>> {
    sim.refresh();
    (0..sim.model().n_nodes())
        .map(|n| sim.node_position(n))
        .collect()
}

fn distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

#[test]
fn constant_load_equals_the_same_force_input() {
    let mut scene = prism();
    scene.loads = vec![LoadSpec::Constant {
        node: 7,
        force: [1.0, 0.0, -1.0],
    }];
    let mut scripted = Simulation::new(Model::new(&scene).unwrap());
    let mut input = Simulation::new(Model::new(&prism()).unwrap());
    input.inputs.node_force[0] = Vector3::new(1.0, 0.0, -1.0);
    scripted.advance_to(1.0).unwrap();
    input.advance_to(1.0).unwrap();
    let (a, b) = (positions(&mut scripted), positions(&mut input));
    assert_eq!(a, b, "bit-identical");
    assert!(
        distance(&a, &prism_at_rest()) > 1e-3,
        "the load moves the prism"
    );
}

fn prism_at_rest() -> Vec<Vector3<f64>> {
    prism().nodes.iter().map(|p| Vector3::from(*p)).collect()
}

#[test]
fn step_load_switches_on_at_its_time() {
    let mut scene = prism();
    scene.loads = vec![LoadSpec::Step {
        node: 8,
        force: [0.0, 5.0, 0.0],
        time: 0.2,
    }];
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    sim.advance_to(0.2).unwrap();
    assert!(
        distance(&positions(&mut sim), &prism_at_rest()) < 1e-12,
        "nothing before 0.2 s"
    );
    sim.advance_to(0.5).unwrap();
    let moved = positions(&mut sim)[7] - Vector3::from(scene.nodes[7]);
    assert!(
        moved.y > 1e-3,
        "node 8 moves along +y after the step: {moved:?}"
    );
}

/// The same sinusoid as a force input held over communication steps of `comm`, sampled
/// at each step's midpoint (second-order in `comm`), internal steps of `h`.
fn sampled_sinusoid(amplitude: f64, frequency: f64, comm: f64, h: f64) -> Vec<Vector3<f64>> {
    let mut scene = prism();
    scene.solver.step_size = h;
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    let n = (0.5 / comm).round() as usize;
    for k in 0..n {
        let mid = (k as f64 + 0.5) * comm;
        let f = amplitude * (2.0 * std::f64::consts::PI * frequency * mid).sin();
        sim.inputs.node_force[0] = Vector3::new(f, 0.0, 0.0);
        sim.advance_to((k + 1) as f64 * comm).unwrap();
    }
    positions(&mut sim)
}

#[test]
fn scripted_sinusoid_matches_inputs_extrapolated_to_zero_step() {
    let (amplitude, frequency, h) = (3.0, 2.0, 1.25e-4);
    let mut scene = prism();
    scene.solver.method = Method::Rk4;
    scene.solver.step_size = h;
    scene.loads = vec![LoadSpec::Sinusoidal {
        node: 7,
        amplitude: [amplitude, 0.0, 0.0],
        frequency,
        phase: 0.0,
    }];
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    sim.advance_to(0.5).unwrap();
    let scripted = positions(&mut sim);
    let coarse = sampled_sinusoid(amplitude, frequency, 2e-3, h);
    let fine = sampled_sinusoid(amplitude, frequency, 1e-3, h);
    // Richardson extrapolation of a second-order error to a zero communication step.
    let extrapolated: Vec<Vector3<f64>> = coarse
        .iter()
        .zip(&fine)
        .map(|(c, f)| (f * 4.0 - c) / 3.0)
        .collect();
    let (held, zero) = (
        distance(&scripted, &fine),
        distance(&scripted, &extrapolated),
    );
    println!("scripted vs held input at 1 ms: {held:.2e} m; vs extrapolated to 0: {zero:.2e} m");
    assert!(
        distance(&scripted, &prism_at_rest()) > 1e-3,
        "the load moves the prism"
    );
    assert!(zero <= 1e-9, "{zero}");
    assert!(
        held > 10.0 * zero,
        "the extrapolation is what closes the gap"
    );
}

#[test]
fn loads_are_validated() {
    let check = |load: LoadSpec, key: &str, reason: &str| {
        let mut scene = prism();
        scene.loads = vec![load];
        let err = Model::new(&scene).unwrap_err().to_string();
        assert!(err.starts_with(key) && err.contains(reason), "{err}");
    };
    check(
        LoadSpec::Constant {
            node: 1,
            force: [1.0; 3],
        },
        "loads[1].node",
        "pinned",
    );
    check(
        LoadSpec::Constant {
            node: 10,
            force: [1.0; 3],
        },
        "loads[1].node",
        "out of range",
    );
    check(
        LoadSpec::Sinusoidal {
            node: 7,
            amplitude: [1.0; 3],
            frequency: -1.0,
            phase: 0.0,
        },
        "loads[1].frequency",
        "≥ 0",
    );
    check(
        LoadSpec::Step {
            node: 7,
            force: [f64::NAN, 0.0, 0.0],
            time: 0.1,
        },
        "loads[1].force",
        "finite",
    );
    let text = prism().to_toml_string() + "\n[[loads]]\nkind = \"ramp\"\nnode = 7\n";
    let err = Scene::from_toml_str(&text).unwrap_err().to_string();
    assert!(err.contains("ramp"), "{err}");
}
