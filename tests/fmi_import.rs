//! The packaged FMU seen through an independent FMI 2.0 importer (the `fmi` crate):
//! archive loading, co-simulation instantiation, value references looked up by name in the
//! parsed model description, and agreement with the library it wraps.

use std::path::Path;
use std::sync::OnceLock;

mod fmu_support;
use fmu_support::{build_fmu, started};

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common};
use fmi::traits::FmiImport;
use tensegrity_fmu::{Model, Simulation};

const SCENE: &str = "prism2-elastic";
const H: f64 = 1e-3;
const STEPS: usize = 500;
const FORCE: f64 = 5.0;

/// What the FMU reported for node 7 and the bar-length residual, and every node position
/// after 1 ms doSteps with and without a cable tension read after each.
#[derive(Debug, Clone)]
struct FmuRun {
    x_start: f64,
    x_end: f64,
    length_error: f64,
    positions_reading_tensions: Vec<f64>,
    positions_not_reading: Vec<f64>,
}

fn vr(import: &Fmi2Import, name: &str) -> u32 {
    import
        .model_description()
        .model_variable_by_name(name)
        .unwrap_or_else(|e| panic!("{name} is not in the model description: {e}"))
        .value_reference
}

/// Loads the FMU with the `fmi` crate and runs the experiment through the C API.
fn run_fmu(fmu: &Path) -> FmuRun {
    let import: Fmi2Import = fmi::import::from_path(fmu).expect("import the FMU");
    let md = import.model_description();
    assert_eq!(md.fmi_version, "2.0");
    assert_eq!(md.model_name, SCENE);
    let cs = md.co_simulation.as_ref().expect("a CoSimulation element");
    assert_eq!(cs.model_identifier, "prism2_elastic");
    let (fx, x, len_err) = (
        vr(&import, "node[7].fx"),
        vr(&import, "node[7].x"),
        vr(&import, "constraint.length_error"),
    );

    let mut inst = import
        .instantiate_cs("fmi_import", false, false)
        .expect("fmi2Instantiate (NULL on a GUID mismatch: .so and CLI from other sources)");
    assert_eq!(Common::get_version(&inst), "2.0");
    assert_eq!(inst.get_types_platform(), "default");
    Common::setup_experiment(&mut inst, None, 0.0, None).expect("fmi2SetupExperiment");
    Common::enter_initialization_mode(&mut inst).expect("fmi2EnterInitializationMode");
    Common::exit_initialization_mode(&mut inst).expect("fmi2ExitInitializationMode");

    let mut v = [0.0];
    inst.get_real(&[x], &mut v).expect("fmi2GetReal node[7].x");
    let x_start = v[0];
    inst.set_real(&[fx], &[FORCE])
        .expect("fmi2SetReal node[7].fx");
    inst.get_real(&[fx], &mut v)
        .expect("fmi2GetReal node[7].fx");
    assert_eq!(v[0], FORCE, "the input reads back as set");

    for k in 0..STEPS {
        inst.do_step(k as f64 * H, H, true)
            .unwrap_or_else(|e| panic!("fmi2DoStep {k}: {e}"));
    }
    let mut out = [0.0; 2];
    inst.get_real(&[x, len_err], &mut out)
        .expect("fmi2GetReal outputs");
    Common::terminate(&mut inst).expect("fmi2Terminate");
    FmuRun {
        x_start,
        x_end: out[0],
        length_error: out[1],
        positions_reading_tensions: positions_after_steps(&import, true),
        positions_not_reading: positions_after_steps(&import, false),
    }
}

/// Every node position after `STEPS` doSteps of `H` under the load, with `cable[1].tension`
/// (an output that needs an evaluation) read after each step if `read_tension`.
fn positions_after_steps(import: &Fmi2Import, read_tension: bool) -> Vec<f64> {
    let nodes: Vec<u32> = (1..=9)
        .flat_map(|n| ["x", "y", "z"].map(|axis| vr(import, &format!("node[{n}].{axis}"))))
        .collect();
    let (fx, tension) = (vr(import, "node[7].fx"), vr(import, "cable[1].tension"));
    let mut inst = started(import, "reads");
    inst.set_real(&[fx], &[FORCE]).expect("fmi2SetReal");
    let mut t = [0.0];
    for k in 0..STEPS {
        inst.do_step(k as f64 * H, H, true).expect("fmi2DoStep");
        if read_tension {
            inst.get_real(&[tension], &mut t)
                .expect("fmi2GetReal tension");
            assert!(t[0] > 0.0, "cable 1 is taut: {}", t[0]);
        }
    }
    let mut positions = vec![0.0; nodes.len()];
    inst.get_real(&nodes, &mut positions).expect("fmi2GetReal");
    Common::terminate(&mut inst).expect("fmi2Terminate");
    positions
}

/// Builds and runs the FMU once for all tests in this file.
fn fmu_run() -> FmuRun {
    static RUN: OnceLock<FmuRun> = OnceLock::new();
    RUN.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!(
            "tensegrity-fmi-import-{}-{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos())
        ));
        let fmu = build_fmu(&dir, SCENE);
        let run = run_fmu(&fmu);
        let _ = std::fs::remove_dir_all(&dir);
        run
    })
    .clone()
}

#[test]
fn fmi_crate_imports_and_steps_the_fmu() {
    let run = fmu_run();
    eprintln!("{run:?}");
    assert!(run.x_start.is_finite() && run.x_end.is_finite());
    assert!(
        run.x_end - run.x_start > 1e-3,
        "node 7 moved {} m in +x under +{FORCE} N",
        run.x_end - run.x_start
    );
    assert!(
        run.length_error.abs() <= 1e-12,
        "bar-length error {}",
        run.length_error
    );
}

#[test]
fn fmu_matches_the_library() {
    let run = fmu_run();
    let scene = tensegrity_fmu::scene::builtin(SCENE).expect("built-in scene");
    let model = Model::new(&scene).expect("valid scene");
    assert_eq!(model.force_inputs[0], 6, "node 7 is the first force input");
    let mut sim = Simulation::new(model);
    let x_start = sim.node_position(6).x;
    sim.inputs.node_force[0].x = FORCE;
    // `step_to` steps by `(k+1)h - kh`, the FMU by exactly h: they agree to round-off.
    for k in 0..STEPS {
        sim.step_to(k as f64 * H, (k + 1) as f64 * H)
            .unwrap_or_else(|e| panic!("library step {k}: {e}"));
    }
    sim.refresh();
    let x_end = sim.node_position(6).x;
    let diff = (run.x_end - x_end).abs();
    eprintln!(
        "node[7].x: FMU {:.17e}, library {x_end:.17e}, |diff| {diff:e}",
        run.x_end
    );
    assert_eq!(run.x_start, x_start, "same start geometry");
    assert!(diff <= 1e-12, "FMU and library differ by {diff:e} m");
    assert!((run.length_error - sim.length_error()).abs() <= 1e-12);
}

#[test]
fn outputs_read_between_steps_change_no_bit() {
    // The read evaluates at the step's end, and the next step takes that evaluation as its
    // first stage: the motion must be the same bits as without the reads.
    let run = fmu_run();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        bits(&run.positions_reading_tensions),
        bits(&run.positions_not_reading)
    );
    let moved = (run.positions_not_reading[18] - run.x_start).abs();
    assert!(moved > 1e-3, "node 7 moved {moved} m");
}
