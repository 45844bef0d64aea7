//! What an importer pays to read outputs every step (issue 14, item 2): tower20 through
//! the packaged FMU and the `fmi` crate, the raw `fmi2DoStep` / `fmi2GetReal` calls a C
//! importer makes, with preallocated arrays. A benchmark that prints figures, not a timed
//! test: `cargo test --release --test fmu_bench -- --ignored --nocapture`.
//!
//! tower20 as shipped but stepped by rk4 at 1 ms (the case; the shipped default is
//! the adaptive dopri5, whose steps would differ between the cases). Timed over the same 2 s of simulated time (2,000 internal steps of 1 ms), interleaved
//! and the best of each kept (this shared machine's slow spells only ever add time):
//! - one `fmi2DoStep` over the whole span;
//! - 2,000 `fmi2DoStep`s of 1 ms, each followed by `fmi2GetReal` of every node position;
//! - the same with one cable tension read too (an output that needs an evaluation).

use std::time::Instant;

mod fmu_support;
use fmu_support::{build_fmu, started};

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common};
use fmi::traits::FmiImport;

const SCENE: &str = "tower20";
const H: f64 = 1e-3;
const STEPS: usize = 2_000;
const REPEATS: usize = 7;

/// Seconds for the span: one doStep (`reads` None), or a doStep per 1 ms each followed by
/// a get of `reads`.
fn run(import: &Fmi2Import, reads: Option<&[u32]>) -> f64 {
    let mut inst = started(import, "bench");
    let mut values = vec![0.0; reads.map_or(0, <[u32]>::len)];
    let start = Instant::now();
    match reads {
        None => {
            inst.do_step(0.0, STEPS as f64 * H, true)
                .expect("fmi2DoStep");
        }
        Some(vrs) => {
            for k in 0..STEPS {
                inst.do_step(k as f64 * H, H, true).expect("fmi2DoStep");
                inst.get_real(vrs, &mut values).expect("fmi2GetReal");
            }
        }
    }
    let elapsed = start.elapsed().as_secs_f64();
    assert!(values.iter().all(|v| v.is_finite()));
    Common::terminate(&mut inst).expect("fmi2Terminate");
    elapsed
}

/// The shipped tower20 with `method = "rk4"` in its `[solver]` table, written into `dir`.
fn rk4_scene(dir: &std::path::Path) -> String {
    let shipped = concat!(env!("CARGO_MANIFEST_DIR"), "/fmu/scenes/tower20.toml");
    let text = std::fs::read_to_string(shipped).expect("read the shipped tower20");
    assert!(
        text.contains("\n[solver]\n"),
        "tower20.toml has a [solver] table"
    );
    let text = text.replace("\n[solver]\n", "\n[solver]\nmethod = \"rk4\"\n");
    std::fs::create_dir_all(dir).expect("create the temporary directory");
    let path = dir.join("tower20-rk4.toml");
    std::fs::write(&path, text).expect("write the rk4 scene");
    path.to_str().expect("a UTF-8 path").to_owned()
}

#[test]
#[ignore = "a benchmark: run with --ignored --nocapture"]
fn stepping_and_reading_every_position_costs_the_steps() {
    let dir = std::env::temp_dir().join(format!("tensegrity-fmu-bench-{}", std::process::id()));
    let fmu = build_fmu(&dir, &rk4_scene(&dir));
    let import: Fmi2Import = fmi::import::from_path(&fmu).expect("import the FMU");
    let md = import.model_description();
    let vr = |name: &str| {
        md.model_variable_by_name(name)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .value_reference
    };
    let nodes = (1..)
        .take_while(|n| md.model_variable_by_name(&format!("node[{n}].x")).is_ok())
        .count();
    let positions: Vec<u32> = (1..=nodes)
        .flat_map(|n| ["x", "y", "z"].map(|a| format!("node[{n}].{a}")))
        .map(|name| vr(&name))
        .collect();
    let mut with_tension = positions.clone();
    with_tension.push(vr("cable[1].tension"));
    let cases: [(&str, Option<&[u32]>); 3] = [
        ("one fmi2DoStep over the span", None),
        (
            "fmi2DoStep of 1 ms + fmi2GetReal of every node position",
            Some(&positions),
        ),
        (
            "the same + one cable tension (needs an evaluation)",
            Some(&with_tension),
        ),
    ];
    let mut best = [f64::INFINITY; 3];
    run(&import, Some(&positions));
    for _ in 0..REPEATS {
        for (b, (_, reads)) in best.iter_mut().zip(&cases) {
            *b = b.min(run(&import, *reads));
        }
    }
    println!(
        "\n{SCENE}, {STEPS} internal steps of {H} s, {} positions per read, best of {REPEATS} \
         interleaved runs:\n",
        positions.len()
    );
    println!("| what | ms | µs per 1 ms | ratio to one doStep |");
    println!("|---|---:|---:|---:|");
    for ((what, _), t) in cases.iter().zip(best) {
        println!(
            "| {what} | {:.1} | {:.2} | {:.3} |",
            t * 1e3,
            t * 1e6 / STEPS as f64,
            t / best[0]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
