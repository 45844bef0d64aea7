//! What a user reaches with one scene: parse → validate → build the model → a short
//! simulation, and for some inputs the FMU instance's path (instantiate, setup, enter and
//! exit initialization, DoStep, GetReal) through the library. `Err` names a broken
//! property; a panic is caught by the caller.

use std::path::Path;

use tensegrity_fmu::fmi::variables::BaseType;
use tensegrity_fmu::fmi::{guid_for, FmiResult, Instance};
use tensegrity_fmu::{analysis, outputs, Scene, SceneError, Simulation};

use super::generate::Input;

/// Internal steps one advance may take in the fuzzer: keeps every input cheap, whatever
/// `solver.max_steps` the scene asks for (it is still validated as written).
pub const MAX_STEPS: u64 = 200;
/// Advances of `solver.step_size` each.
const ADVANCES: u32 = 3;
/// Longest message accepted as one readable line, in characters.
const MAX_MESSAGE_CHARS: usize = 1500;

/// Every top-level key of a scene: an error must name one of them.
const KEYS: [&str; 18] = [
    "name",
    "description",
    "nodes",
    "fixed",
    "bars",
    "cables",
    "gravity",
    "force_inputs",
    "velocities",
    "outputs",
    "loads",
    "point_masses",
    "terrain",
    "collisions",
    "ground",
    "prestress",
    "start",
    "solver",
];

/// How far an input got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Refused with a message (parse, validation, model, step size or stability).
    Refused,
    /// Simulated; a step may have stopped it with a message.
    Simulated,
    /// Simulated, and the FMU instance path too.
    SimulatedFmu,
}

/// Runs the input through everything; `fmu_dir` is a scratch folder for `scene.toml`.
pub fn run(input: &Input, fmu_dir: &Path) -> Result<Outcome, String> {
    let parsed = if input.json {
        Scene::from_json_str(&input.text)
    } else {
        Scene::from_toml_str(&input.text)
    };
    let mut scene = match parsed {
        Ok(scene) => scene,
        Err(e) => return refused(&e),
    };
    scene.solver.max_steps = scene.solver.max_steps.min(MAX_STEPS);
    let model = match analysis::load(&scene) {
        Ok(model) => model,
        Err(e) => return refused(&e),
    };
    let mut sim = Simulation::new(model);
    for w in sim.warnings() {
        one_line("a model warning", w)?;
    }
    if let Some(why) = sim.step_size_problem() {
        one_line("the step size refusal", &why)?;
        show(&why);
        return Ok(Outcome::Refused);
    }
    if let Some(why) = sim.stability_problem() {
        one_line("the stability refusal", &why)?;
        show(&why);
        return Ok(Outcome::Refused);
    }
    if let Some(why) = sim.accuracy_problem() {
        one_line("the accuracy warning", &why)?;
    }
    let h = scene.solver.step_size;
    for k in 1..=ADVANCES {
        if let Err(e) = sim.advance_to(f64::from(k) * h) {
            one_line("a step error", &e.to_string())?;
            break;
        }
    }
    sim.refresh();
    finite_outputs(&sim)?;
    if !input.fmu {
        return Ok(Outcome::Simulated);
    }
    fmu(&scene, fmu_dir)?;
    Ok(Outcome::SimulatedFmu)
}

fn refused(e: &SceneError) -> Result<Outcome, String> {
    let text = e.to_string();
    one_line("the scene error", &text)?;
    show(&text);
    let named = match e {
        SceneError::Invalid { key, .. } => {
            let head = key.split(['.', '[']).next().unwrap_or_default();
            KEYS.contains(&head)
        }
        // A syntax error gives the line and column; a type error names the key.
        SceneError::Parse { message, .. } => {
            message.contains("line ") || KEYS.iter().any(|k| message.contains(k))
        }
        SceneError::Io { .. } => false,
    };
    if !named {
        return Err(format!("the scene error names no key (nor line): {text}"));
    }
    Ok(Outcome::Refused)
}

/// With `FUZZ_SHOW` set, prints every refusal (to see what the generators reach).
fn show(text: &str) {
    if std::env::var_os("FUZZ_SHOW").is_some() {
        eprintln!("refused: {text}");
    }
}

/// A message the user reads: one line, not empty, not a wall of text.
pub fn one_line(what: &str, text: &str) -> Result<(), String> {
    let chars = text.chars().count();
    if text.trim().is_empty() || text.contains('\n') || chars > MAX_MESSAGE_CHARS {
        return Err(format!(
            "{what} is not one readable line ({chars} characters): {text:?}"
        ));
    }
    Ok(())
}

fn finite_outputs(sim: &Simulation) -> Result<(), String> {
    if let Some(x) = sim.state().y.iter().find(|x| !x.is_finite()) {
        return Err(format!("the state holds {x} at t = {} s", sim.time()));
    }
    for o in outputs::outputs(sim) {
        let v = o.quantity.value(sim);
        if !v.is_finite() {
            return Err(format!(
                "output {} = {v} at t = {} s of an accepted scene",
                o.name,
                sim.time()
            ));
        }
    }
    Ok(())
}

/// fmi2Instantiate … fmi2DoStep twice, then fmi2GetReal of every Real variable.
fn fmu(scene: &Scene, dir: &Path) -> Result<(), String> {
    let text = scene.to_toml_string();
    std::fs::write(dir.join("scene.toml"), &text).map_err(|e| e.to_string())?;
    let mut fmu = match Instance::instantiate("fuzz", &guid_for(&text), dir, false) {
        Ok(fmu) => fmu,
        Err(e) => return one_line("the fmi2Instantiate error", &e),
    };
    let h = scene.solver.step_size;
    let calls: [&dyn Fn(&mut Instance) -> FmiResult; 5] = [
        &|f| f.setup_experiment(0.0, None),
        &|f| f.enter_initialization_mode(),
        &|f| f.exit_initialization_mode(),
        &|f| f.do_step(0.0, h),
        &|f| f.do_step(h, h),
    ];
    let mut stepped = true;
    for call in calls {
        if let Err(e) = call(&mut fmu) {
            one_line("an FMI error", &e.message)?;
            stepped = false;
            break;
        }
    }
    for m in fmu.drain_messages() {
        one_line("an FMI log message", &m.text)?;
    }
    if !stepped {
        return Ok(());
    }
    let vrs: Vec<u32> = fmu
        .table()
        .variables
        .iter()
        .filter(|v| v.base_type == BaseType::Real)
        .map(|v| v.value_reference)
        .collect();
    let mut values = vec![0.0; vrs.len()];
    if let Err(e) = fmu.get("fmi2GetReal", BaseType::Real, &vrs, &mut values) {
        return one_line("the fmi2GetReal error", &e.message);
    }
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        let name = &fmu.table().variables[vrs[k] as usize].name;
        return Err(format!("fmi2GetReal: {name} = {}", values[k]));
    }
    Ok(())
}
