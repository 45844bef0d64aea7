//! Scene fuzzing: structured scenes with hostile values and real scenes with mutated
//! bytes, each run through parse → validate → model → a short simulation (and for some,
//! the FMU instance's calls). No input may panic, an error must be one line naming a key
//! (or the line of a syntax error), and an accepted scene's outputs must be finite.
//! Inputs over a second of CPU are printed as hangs.
//!
//! A long run (see docs/benchmarks.md):
//! `FUZZ_CASES=1000000 cargo test --release --test fuzz_scenes -- --nocapture`
//! (`FUZZ_SEED` picks another fixed sequence).

mod fuzz_support;

use proptest::strategy::Strategy;

use fuzz_support::generate::structured;
use fuzz_support::mutate::{corpus, mutated};
use fuzz_support::{describe, fuzz, settings};

/// Inputs in the test suite's run: a few seconds.
const CI_CASES: u64 = 3000;

#[test]
fn scenes_never_panic_and_errors_name_a_key() {
    let (cases, seed) = settings(CI_CASES);
    let strategies = [structured().boxed(), mutated(corpus()).boxed()];
    let report = fuzz(&strategies, cases, seed);
    println!("fuzz_scenes (seed {seed}): {}", report.summary());
    assert!(
        report.failures.is_empty() && report.panics == 0 && report.defects == 0,
        "{}{}",
        report.summary(),
        describe(&report)
    );
    if !report.hangs.is_empty() {
        println!("hangs:{}", describe(&report));
    }
    // The generators reach every stage: some inputs are refused, some simulated, some
    // also run through the FMU instance.
    assert!(report.refused > 0 && report.simulated > 0 && report.fmu > 0);
}

// Inputs the fuzzer found, shrunk by hand to what matters.

use fuzz_support::generate::Input;
use fuzz_support::pipeline::Outcome;
use tensegrity_fmu::{analysis, Scene};

/// A lone bar: two nodes, `top` (keys) and `tail` (tables) added.
fn lone_bar(top: &str, tail: &str) -> String {
    format!(
        "name = \"lone\"\n{top}\nnodes = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.5]]\n\n\
         [[bars]]\nnodes = [1, 2]\nmass = 0.1\n\n{tail}"
    )
}

fn run(text: &str, json: bool) -> Result<Outcome, String> {
    let dir = std::env::temp_dir().join(format!("tensegrity-fuzz-pin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let input = Input {
        json,
        text: text.to_string(),
        fmu: true,
    };
    fuzz_support::check(&input, &dir).0
}

fn refusal(text: &str) -> String {
    let scene = Scene::from_toml_str(text).expect("parses");
    analysis::load(&scene).expect_err("refused").to_string()
}

#[test]
fn an_equilibrium_start_with_only_rigid_motions_keeps_the_geometry() {
    // Every mode of a lone free bar is rigid: the eigenproblem of the rest was 0 × 0 and
    // nalgebra panicked on it. Nothing acts on the bar, so it is at rest as given.
    let text = lone_bar("start = \"equilibrium\"", "");
    assert_eq!(run(&text, false), Ok(Outcome::SimulatedFmu));
    let model = analysis::load(&Scene::from_toml_str(&text).unwrap()).unwrap();
    assert_eq!(model.positions[1].z, 0.5);
    // Pinned at both ends, nothing can move at all: no coordinates, nothing to solve.
    let pinned = lone_bar("start = \"equilibrium\"\nfixed = [1, 2]", "");
    assert_eq!(run(&pinned, false), Ok(Outcome::SimulatedFmu));
}

#[test]
fn numbers_beyond_1e30_are_refused_naming_the_key() {
    // f64::MAX as a stiffness, a load or gravity gave ∞ or NaN bar forces at t = 0 in an
    // accepted scene.
    let cases = [
        (
            lone_bar(
                "fixed = [1]",
                "[[cables]]\nnodes = [1, 2]\nstiffness = 1.7976931348623157e308\nrest_length = 0.4\n",
            ),
            "cables[1].stiffness: 1.7976931348623157e308 is beyond ±1e30",
        ),
        (
            lone_bar(
                "",
                "[[loads]]\nkind = \"constant\"\nnode = 2\nforce = [1e300, 0.0, 0.0]\n",
            ),
            "loads[1].force: 1e300 is beyond ±1e30",
        ),
        (
            lone_bar("gravity = [0.0, 0.0, -1e31]", ""),
            "gravity: -1e31 is beyond ±1e30",
        ),
    ];
    for (text, expected) in cases {
        let message = refusal(&text);
        assert!(message.starts_with(expected), "{message}");
        assert_eq!(run(&text, false), Ok(Outcome::Refused));
    }
    // At the bound itself the scene runs, and every output stays finite.
    let heavy = lone_bar("fixed = [1]\ngravity = [0.0, 1e30, -1e30]", "");
    assert_eq!(run(&heavy, false), Ok(Outcome::SimulatedFmu));
}

#[test]
fn an_unknown_key_as_long_as_the_file_is_cut_in_the_message() {
    // A byte flip turned `"nodes":` into a 4000-character key; the message quoted all of it.
    let key = format!("nodes#:{}", "[0.5,0.25,0.125],".repeat(200));
    let text = format!("{{\"name\": \"x\", \"{key}\": 1}}");
    let message = Scene::from_json_str(&text).unwrap_err().to_string();
    assert!(message.chars().count() < 500, "{message}");
    assert!(message.contains("unknown field"), "{message}");
    assert!(
        message.starts_with("malformed JSON scene: nodes#:[0.5,0.25"),
        "{message}"
    );
    assert_eq!(run(&text, true), Ok(Outcome::Refused));
}

#[test]
fn a_state_that_blows_up_stops_before_its_forces_overflow() {
    // A bar spinning at 1e15 m/s under rk4 at 0.1 ms (h·ω ≈ 1e11) grows its speed by many
    // orders of magnitude per step: the state stayed finite while the bar force, m v²/L,
    // overflowed to -∞. The speed is set on the state, past what a scene may start with.
    let text = r#"name = "spun"
nodes = [[0.0, 0.0, 0.9210475351814649], [0.8535097982834869, 0.0, 0.0], [0.0, 0.0, 0.9210475351814649]]
fixed = [3]
velocities = [[1e8, -0.144728004956339e-7, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
bars = [{ nodes = [1, 2], mass = 1.8859505750897774 }]
point_masses = [{ node = 2, mass = 0.1 }]
cables = [{ nodes = [3, 2], rest_length = 0.05, stiffness = 10.0 }]
solver = { method = "rk4", step_size = 1e-4, locate_events = false }
"#;
    let model = analysis::load(&Scene::from_toml_str(text).unwrap()).unwrap();
    let mut sim = tensegrity_fmu::Simulation::new(model);
    let mut state = sim.state().clone();
    let half = state.y.len() / 2;
    state.y[half..].iter_mut().for_each(|v| *v *= 1e7);
    sim.set_state(state);
    let stop = (1..=40)
        .find_map(|k| sim.advance_to(f64::from(k) * 1e-4).err())
        .expect("the run stops");
    assert!(stop.to_string().contains("past ±1e100"), "{stop}");
    sim.refresh();
    let speed = sim.node_velocity(0).norm();
    assert!(speed > 1e14 && speed <= 1e100, "{speed}");
    assert!(sim.bar_force(0).is_finite() && sim.energy().is_finite());
}

#[test]
fn a_key_with_a_line_break_is_quoted_on_one_line() {
    // A byte flip made `"stiffness"` the JSON string "stif\ness"; the unknown-key error
    // quoted its line break raw, twice.
    let json = r#"{"name": "x", "nodes": [[0, 0, 0], [1, 0, 0]], "bars": [{"nodes": [1, 2], "mass": 1}], "cables": [{"nodes": [1, 2], "stif\ness": 5.0}]}"#;
    let message = Scene::from_json_str(json).unwrap_err().to_string();
    assert!(
        message
            .starts_with("malformed JSON scene: cables[1].stif\\ness: unknown field `stif\\ness`"),
        "{message}"
    );
    assert!(!message.contains('\n'));
    // The same in TOML, with a quoted key.
    let toml = "name = \"x\"\n\"a\\tb\\r\" = 1\n";
    let message = Scene::from_toml_str(toml).unwrap_err().to_string();
    assert!(
        message.starts_with("malformed TOML scene: a\\tb\\r: unknown field"),
        "{message}"
    );
    assert!(!message.contains(['\t', '\r']), "{message}");
}
