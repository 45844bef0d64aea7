//! Every advance ends in bounded work (issue 10, item 1): `solver.max_steps` caps the
//! internal steps of one call, a time too coarse for the step is refused, and a refusal
//! leaves the simulation exactly where it was.

use tensegrity_fmu::error::StepError;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

fn sim(method: Method, max_steps: u64) -> Simulation {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.solver.method = method;
    scene.solver.max_steps = max_steps;
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    sim.inputs.node_force[0].x = 1.0;
    sim
}

#[test]
fn fixed_step_advance_beyond_max_steps_is_refused_before_any_step() {
    for method in [Method::Rk4, Method::Rattle] {
        let mut s = sim(method, 50);
        let before = s.state().clone();
        let err = s.advance_to(0.051).unwrap_err();
        assert!(
            matches!(err, StepError::TooManySteps { max: 50, .. }),
            "{err}"
        );
        assert!(err.changed_nothing());
        assert!(err.to_string().contains("solver.max_steps = 50"), "{err}");
        assert_eq!(s.state(), &before);
        assert_eq!(s.stats().steps, 0);
        // exactly the cap is allowed
        assert_eq!(s.advance_to(0.050).unwrap(), 50);
    }
}

#[test]
fn adaptive_advance_stops_at_max_steps_and_restores_the_state() {
    let mut s = sim(Method::Dopri5, 20);
    let before = s.state().clone();
    let err = s.advance_to(1e6).unwrap_err();
    assert!(
        matches!(err, StepError::TooManySteps { max: 20, .. }),
        "{err}"
    );
    assert_eq!(s.state(), &before, "the state is where the advance began");
    let stats = s.stats();
    assert_eq!(
        stats.steps + stats.rejected,
        20,
        "it took exactly the cap of attempts"
    );
    // a reachable target still works afterwards
    s.advance_to(0.01).unwrap();
    assert!((s.time() - 0.01).abs() < 1e-15);
}

#[test]
fn a_time_too_coarse_for_the_step_is_refused() {
    let mut s = sim(Method::Rk4, 100_000);
    s.set_time(1e16);
    let err = s.advance_to(1e16 + 1.0).unwrap_err();
    assert!(
        matches!(err, StepError::TimeResolution { step, .. } if step == 1e-3),
        "{err}"
    );
    assert!(
        err.to_string().contains("solver.step_size = 0.001"),
        "{err}"
    );
    // 1e3 s is fine for 1 ms steps: its doubles are 1.1e-13 s apart
    s.set_time(1e3);
    assert_eq!(s.advance_to(1e3 + 0.002).unwrap(), 2);
}

#[test]
fn a_step_size_far_below_the_time_scale_is_reported() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.solver.step_size = 1e-12;
    let mut s = Simulation::new(Model::new(&scene).unwrap());
    let why = s.step_size_problem().expect("1e-12 s is refused");
    assert!(
        why.starts_with("solver.step_size = 1e-12 s is below 1e-6"),
        "{why}"
    );
    // the floor is 1e-6/ω: prism2-elastic's fastest mode (ω ≈ 11 rad/s) allows 1e-7 s
    scene.solver.step_size = 1e-6;
    let mut s = Simulation::new(Model::new(&scene).unwrap());
    assert_eq!(s.step_size_problem(), None);
}

/// The FMU's refusal past `solver.max_steps` under dopri5 names the element that keeps
/// its steps short and suggests sdirk3.
#[test]
fn the_fmu_names_the_stiff_element_when_max_steps_runs_out() {
    use tensegrity_fmu::fmi::{guid_for, Instance};
    let scene = tensegrity_fmu::scene::extreme_scenes().remove(0).scene;
    assert_eq!(scene.name, "stiff-cable");
    let dir = std::env::temp_dir().join(format!("bounded-work-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = scene.to_toml_string();
    std::fs::write(dir.join("scene.toml"), &text).unwrap();
    let mut fmu = Instance::instantiate("stiff", &guid_for(&text), &dir, true).unwrap();
    fmu.setup_experiment(0.0, None).unwrap();
    fmu.enter_initialization_mode().unwrap();
    fmu.exit_initialization_mode().unwrap();
    fmu.drain_messages();
    let message = fmu.do_step(0.0, 1.0).unwrap_err().message;
    println!("{message}");
    assert!(
        message.starts_with(
            "fmi2DoStep: this advance with dopri5 takes more than solver.max_steps = 100000"
        ),
        "{message}"
    );
    assert!(
        message.contains("the stiffness of cables[4] (elastic, stiffness 5e14 N/m)"),
        "{message}"
    );
    assert!(message.contains("solver.method = \"sdirk3\""), "{message}");
    // The instance carries on: a step it can afford goes through.
    fmu.do_step(0.0, 1e-6).unwrap();
    assert!((fmu.simulation().time() - 1e-6).abs() < 1e-18);
}
