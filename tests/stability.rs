//! The explicit methods' stability limit: the estimated fastest mode predicts where RK4
//! stops being stable, and the FMU-facing check names the cause and the fixes.

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, Scene};
use tensegrity_fmu::sim::stability_limit;
use tensegrity_fmu::{Model, Simulation, StepError};

fn stiff_prism(stiffness: f64, method: Method, step: f64) -> Scene {
    let mut scene = builtin("prism2-elastic").unwrap();
    for c in &mut scene.cables {
        c.stiffness = Some(stiffness);
    }
    scene.solver.method = method;
    scene.solver.step_size = step;
    // Steps of h whole: split at the cables' switches they would not blow up as predicted.
    scene.solver.locate_events = false;
    scene
}

/// Runs 1 s under a 1 N load, without the stability guard; returns the outcome and the
/// final energy.
fn run(scene: &Scene) -> (Result<u64, StepError>, f64) {
    let mut sim = Simulation::new(Model::new(scene).unwrap());
    sim.guard_stability = false;
    sim.inputs.node_force[0].x = 1.0;
    let result = sim.advance_to(1.0);
    sim.refresh();
    (result, sim.energy())
}

#[test]
fn estimated_fastest_mode_predicts_rk4_blow_up() {
    let limit = stability_limit(Method::Rk4).unwrap();
    for stiffness in [1e5, 1e6] {
        let mut sim =
            Simulation::new(Model::new(&stiff_prism(stiffness, Method::Rk4, 1e-3)).unwrap());
        let omega = sim.max_frequency();
        let h_max = limit / omega;
        let (below, energy_below) = run(&stiff_prism(stiffness, Method::Rk4, 0.9 * h_max));
        let (above, _) = run(&stiff_prism(stiffness, Method::Rk4, 1.5 * h_max));
        println!("κ = {stiffness:e} N/m: ω ≈ {omega:.4e} rad/s, rk4 limit {h_max:.3e} s");
        assert!(below.is_ok() && energy_below.is_finite() && energy_below < 1.0);
        assert!(
            matches!(above, Err(StepError::NonFinite { .. })),
            "{above:?}"
        );
    }
}

#[test]
fn unstable_fixed_step_is_named_with_its_fixes() {
    let mut sim = Simulation::new(Model::new(&stiff_prism(1e7, Method::Rk4, 1e-3)).unwrap());
    let why = sim
        .stability_problem()
        .expect("1 ms is far above the limit at 1e7 N/m");
    assert!(
        why.contains("solver.step_size") && why.contains("dopri5"),
        "{why}"
    );
    // The guard refuses before any step is taken, so no broken state is ever accepted.
    let before = sim.state().clone();
    let refused = sim.advance_to(1e-3).unwrap_err();
    assert!(matches!(refused, StepError::Unstable { .. }), "{refused:?}");
    assert_eq!(sim.state(), &before);
    let mut ok = Simulation::new(Model::new(&stiff_prism(1e7, Method::Dopri5, 1e-3)).unwrap());
    assert!(
        ok.stability_problem().is_none(),
        "adaptive methods have no fixed-step limit"
    );
    let mut soft = Simulation::new(Model::new(&stiff_prism(500.0, Method::Rk4, 1e-3)).unwrap());
    assert!(soft.stability_problem().is_none());
}
