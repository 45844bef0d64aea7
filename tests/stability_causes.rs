//! The stability guard names what limits the step (stiff cables, the ground penalty,
//! friction's regularisation) with the scene key and the value that fixes it, and the
//! fixes it prints do fix the scene; `build` and `simulate` say it once, up front.

mod cli_support;
use cli_support::{run, temp};

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, GroundSpec, Scene};
use tensegrity_fmu::{Model, Simulation};

/// prism2-elastic with cable `j` (1-based; all cables for `None`) at `stiffness`, run
/// with rk4 at 1 ms (the default, dopri5, has no stability limit to guard).
fn stiff_cables(which: Option<usize>, stiffness: f64) -> Scene {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.solver.method = Method::Rk4;
    for (j, c) in scene.cables.iter_mut().enumerate() {
        if which.is_none_or(|k| k == j + 1) {
            c.stiffness = Some(stiffness);
        }
    }
    scene
}

/// prism2 (rk4 at 1 ms), unpinned, standing under gravity on a ground (its bottom ring at the surface).
fn prism_on_ground(stiffness: f64, friction: f64) -> Scene {
    let mut scene = builtin("prism2").unwrap();
    scene.solver.method = Method::Rk4;
    scene.name = "prism-on-ground".into();
    scene.fixed.clear();
    scene.gravity = Some([0.0, 0.0, -9.81]);
    scene.ground = Some(GroundSpec {
        height: 0.0,
        normal: [0.0, 0.0, 1.0],
        stiffness,
        damping: 100.0,
        friction,
        slip_velocity: 0.01,
    });
    scene
}

fn problem(scene: &Scene) -> Option<String> {
    Simulation::new(Model::new(scene).unwrap()).stability_problem()
}

/// The number printed right after `key` in `message`.
fn value_after(message: &str, key: &str) -> f64 {
    let at = message
        .find(key)
        .unwrap_or_else(|| panic!("no `{key}` in: {message}"));
    let rest = &message[at + key.len()..];
    let end = rest.find([' ', ',', ')']).unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|e| panic!("`{}` after `{key}`: {e}", &rest[..end]))
}

/// The printed step fix works and the scene's step is 10 % inside the limit it names.
fn check_step_fix(scene: &Scene, why: &str) {
    let limit = value_after(why, "stability limit for this scene, h ≤ ");
    let step = value_after(why, "Fixes: solver.step_size ≤ ");
    assert!((step / limit - 0.9).abs() < 1e-3, "{why}");
    let mut fixed = scene.clone();
    fixed.solver.step_size = step;
    assert_eq!(problem(&fixed), None, "with solver.step_size = {step}");
}

#[test]
fn one_stiff_cable_is_named_with_the_stiffness_that_fits() {
    let scene = stiff_cables(Some(4), 1e8);
    let why = problem(&scene).expect("1 ms is above the limit of a 1e8 N/m cable");
    println!("{why}");
    assert!(why.contains("rk4's stability limit"), "{why}");
    assert!(
        why.contains("the stiffness of cables[4] (elastic, stiffness 1e8 N/m), alone"),
        "{why}"
    );
    assert!(why.contains("solver.method = \"dopri5\""), "{why}");
    check_step_fix(&scene, &why);
    let softer = value_after(&why, "soften cables[4] to stiffness ≤ ");
    assert!(softer > 1e6 && softer < 1e8, "{why}");
    let mut fixed = scene.clone();
    fixed.cables[3].stiffness = Some(softer);
    assert_eq!(problem(&fixed), None, "cables[4] at {softer} N/m");
    // Twice the printed stiffness is still refused: the value is near the real limit.
    fixed.cables[3].stiffness = Some(2.0 * softer);
    assert!(problem(&fixed).is_some_and(|w| w.contains("cables[4]")));
}

#[test]
fn uniformly_stiff_cables_are_named_together() {
    let scene = stiff_cables(None, 1e8);
    let why = problem(&scene).expect("1 ms is above the limit of 1e8 N/m cables");
    println!("{why}");
    assert!(why.contains("the stiffness of cables["), "{why}");
    assert!(
        why.contains("(elastic, stiffness 1e8 N/m), together"),
        "{why}"
    );
    check_step_fix(&scene, &why);
    let softer = value_after(
        &why,
        "soften the 15 cables of stiffness ≥ 1e8 N/m to stiffness ≤ ",
    );
    let fixed = stiff_cables(None, softer);
    assert_eq!(problem(&fixed), None, "all cables at {softer} N/m");
}

#[test]
fn a_stiff_ground_is_named_with_the_stiffness_that_fits() {
    let scene = prism_on_ground(1e8, 0.0);
    let why = problem(&scene).expect("1 ms is above the contact bound of a 1e8 N/m ground");
    println!("{why}");
    assert!(
        why.contains("comes from the ground penalty, ground.stiffness = 1e8 N/m with ground.damping = 100 N·s/m"),
        "{why}"
    );
    assert!(why.contains("end compliance w = 4 1/kg of node 1"), "{why}");
    check_step_fix(&scene, &why);
    let softer = value_after(&why, "or ground.stiffness ≤ ");
    let mut fixed = scene.clone();
    fixed.ground.as_mut().unwrap().stiffness = softer;
    assert_eq!(problem(&fixed), None, "ground.stiffness = {softer}");
}

#[test]
fn friction_names_its_slip_velocity_and_the_one_that_fits() {
    // The case: a free prism on the ground with μ = 0.6, refused at its own 1 ms.
    let scene = prism_on_ground(1e4, 0.6);
    let why = problem(&scene).expect("1 ms is above friction's viscous rate");
    println!("{why}");
    assert!(
        why.contains(
            "comes from ground friction, ground.friction = 0.6 with ground.slip_velocity = 0.01 m/s"
        ),
        "{why}"
    );
    // μ W w / v_s with W = 6 kg · 9.81 m/s² and w = 4/(1 kg): 1.413e4 1/s.
    assert!(why.contains("ω ≈ 1.413e4 1/s"), "{why}");
    assert!(why.contains("the weight W = 58.86 N"), "{why}");
    check_step_fix(&scene, &why);
    let slip = value_after(&why, "raise ground.slip_velocity to ≥ ");
    assert_eq!(slip, 0.056, "{why}");
    assert!(why.contains("÷ 5.6"), "{why}");
    let mut fixed = scene.clone();
    fixed.ground.as_mut().unwrap().slip_velocity = slip;
    assert_eq!(problem(&fixed), None, "ground.slip_velocity = {slip}");
    // The same cause is named when the step is absurdly small instead.
    let mut tiny = scene.clone();
    tiny.solver.step_size = 1e-12;
    let why = Simulation::new(Model::new(&tiny).unwrap())
        .step_size_problem()
        .expect("1e-12 s is absurd");
    assert!(why.contains("set by ground friction"), "{why}");
}

/// Writes `scene` as TOML into this test's temporary folder.
fn scene_file(scene: &Scene, name: &str) -> String {
    let path = temp(name);
    std::fs::write(&path, scene.to_toml_string()).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn simulate_refuses_once_up_front() {
    let file = scene_file(&prism_on_ground(1e4, 0.6), "friction.toml");
    let csv = temp("friction.csv");
    let (ok, _, err) = run(&[
        "simulate",
        &file,
        "--time",
        "0.01",
        "-o",
        csv.to_str().unwrap(),
    ]);
    println!("{err}");
    assert!(!ok);
    assert_eq!(err.matches("stability limit").count(), 1, "{err}");
    assert!(err.contains("ground.slip_velocity"), "{err}");
    assert!(!err.contains("warning"), "{err}");
    assert!(!csv.exists());
    // With an input table the inputs may change the stiffness first: warned once, and the
    // refusal at the first step points back to the warning instead of repeating it.
    let inputs = temp("friction_inputs.csv");
    std::fs::write(&inputs, "time,node[7].fx\n0,0\n0.01,0\n").unwrap();
    let (ok, _, err) = run(&[
        "simulate",
        &file,
        "--time",
        "0.01",
        "--inputs",
        inputs.to_str().unwrap(),
        "-o",
        csv.to_str().unwrap(),
    ]);
    println!("{err}");
    assert!(!ok);
    assert_eq!(
        err.matches("ground.slip_velocity = 0.01").count(),
        1,
        "{err}"
    );
    assert!(err.contains("the warning above names the cause"), "{err}");
}

#[test]
fn build_warns_once_that_the_fmu_will_refuse_its_own_settings() {
    // A stand-in binary with this program's build id: enough for the packaging.
    let binary = temp("fake_binary.so");
    std::fs::write(&binary, tensegrity_fmu::fmi::BUILD_ID.as_bytes()).unwrap();
    let fmu = temp("stiff.fmu");
    let build = |scene: &Scene, name: &str| {
        let file = scene_file(scene, name);
        let args = ["build", &file, "--binary", binary.to_str().unwrap()];
        run(&[&args[..], &["-o", fmu.to_str().unwrap()]].concat())
    };
    let (ok, _, err) = build(&stiff_cables(Some(4), 1e8), "stiff.toml");
    println!("{err}");
    assert!(ok, "{err}");
    assert!(fmu.is_file());
    assert_eq!(err.matches("stability limit").count(), 1, "{err}");
    assert!(
        err.contains("warning: at the scene's own settings"),
        "{err}"
    );
    assert!(err.contains("soften cables[4] to stiffness ≤"), "{err}");
    // A scene within its limit, and the stiff one at the default method (dopri5, adaptive:
    // nothing to refuse), build without the warning.
    let mut adaptive = stiff_cables(Some(4), 1e8);
    adaptive.solver = Default::default();
    for (scene, name) in [
        (stiff_cables(Some(4), 1e5), "soft.toml"),
        (adaptive, "stiff-default.toml"),
    ] {
        let (ok, _, err) = build(&scene, name);
        assert!(ok, "{err}");
        assert!(!err.contains("stability limit"), "{err}");
    }
}

/// A stable but too long rk4 step on steel-stiff cables is named as inaccurate, with the
/// cables and the fixes; the step it names fixes it; a soft scene and the default (dopri5)
/// say nothing; `simulate` warns once.
#[test]
fn a_stable_but_unresolving_step_is_named_with_its_fix() {
    let mut scene = stiff_cables(None, 1e6);
    scene.prestress = Some(tensegrity_fmu::scene::PrestressSpec { min_tension: 100.0 });
    let inaccurate = |s: &Scene| Simulation::new(Model::new(s).unwrap()).accuracy_problem();
    assert_eq!(problem(&scene), None, "1 ms is stable for 1e6 N/m cables");
    let why = inaccurate(&scene).expect("1 ms cannot follow the cable mode");
    println!("{why}");
    assert!(
        why.contains("stiffness 1e6 N/m") && why.contains("cables["),
        "{why}"
    );
    assert!(why.contains("solver.method = \"dopri5\""), "{why}");
    let mut fixed = scene.clone();
    fixed.solver.step_size = value_after(&why, "or solver.step_size ≤ ");
    assert_eq!(inaccurate(&fixed), None);
    assert_eq!(inaccurate(&stiff_cables(None, 500.0)), None);
    let mut adaptive = scene.clone();
    adaptive.solver = Default::default();
    assert_eq!(inaccurate(&adaptive), None);
    let file = scene_file(&scene, "unresolved.toml");
    let csv = temp("unresolved.csv");
    let (ok, _, err) = run(&[
        "simulate",
        &file,
        "--time",
        "0.01",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert_eq!(err.matches("too long to follow").count(), 1, "{err}");
}
