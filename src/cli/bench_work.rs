//! `bench work`: the work predicted before a run against the work it takes, for the seven
//! extreme scenes ([`extreme_scenes`]) and the shipped ones, at `simulate`'s defaults (1 s,
//! a row every step). A run predicted past [`SAMPLE_STEPS`] is run only over the share of
//! its time that the prediction puts at that many steps, and its steps and wall time are
//! extrapolated to the whole run.

use std::time::Instant;

use tensegrity_fmu::scene::{builtin, builtin_names, extreme_scenes, Scene};
use tensegrity_fmu::sim::Pace;
use tensegrity_fmu::{analysis, Simulation};

use super::work::{self, duration};

/// Predicted steps a measured run is cut down to.
const SAMPLE_STEPS: f64 = 1e5;

/// `simulate`'s default simulated time, s.
const TIME: f64 = 1.0;

/// Prints one row per scene.
pub fn run() -> Result<(), String> {
    let mut shipped: Vec<Scene> = builtin_names().into_iter().filter_map(builtin).collect();
    let dropped = include_str!("../../fmu/scenes/icosahedron-dropped.toml");
    shipped.push(Scene::from_toml_str(dropped).map_err(|e| e.to_string())?);
    // The extreme scenes and the shipped ones at simulate's rows, then the shipped ones
    // with one row at the end, where dopri5 picks its own steps.
    let runs = extreme_scenes()
        .into_iter()
        .map(|e| (e.scene, None))
        .chain(shipped.clone().into_iter().map(|s| (s, None)))
        .chain(shipped.into_iter().map(|s| (s, Some(TIME))));
    println!(
        "{TIME} s, a row every solver.step_size (simulate's default) or at the end only; a run \
         predicted past {SAMPLE_STEPS:.0e} steps is run over the share of the time predicted \
         at that many steps (\"run over\") and extrapolated\n"
    );
    println!("| scene | method | rows every (s) | step held by | predicted steps | run over (s) | steps taken, extrapolated | taken / predicted | predicted time | time taken, extrapolated |");
    println!("|---|---|---:|---|---:|---:|---:|---:|---:|---:|");
    for (mut scene, rows_every) in runs {
        scene.solver.max_steps = u64::MAX;
        let model = analysis::load(&scene).map_err(|e| format!("{}: {e}", scene.name))?;
        let interval = rows_every.unwrap_or(model.solver.step_size);
        let mut sim = Simulation::new(model);
        let predicted = work::predict(&mut sim, TIME, interval, true, "")?;
        let steps = predicted.work.steps;
        let held = match predicted.work.pace {
            Pace::Fixed => "solver.step_size".to_string(),
            Pace::Rows => "the rows".to_string(),
            pace => {
                let kind = if pace == Pace::Stability {
                    "stability"
                } else {
                    "accuracy"
                };
                let cause = predicted.work.rate.as_ref().map_or(String::new(), |r| {
                    let text = r.describe(sim.model(), &sim.inputs);
                    text.split(" (").next().unwrap_or_default().to_string()
                });
                // A table cell: `|gravity|` must not end it.
                format!("{kind}: {}", cause.replace('|', "\\|"))
            }
        };
        let share = (SAMPLE_STEPS / steps).min(1.0);
        let stop = TIME * share;
        let rows = (stop / interval - 1e-9).ceil().max(1.0) as u64;
        let started = Instant::now();
        for k in 1..=rows {
            let t = (k as f64 * interval).min(stop);
            sim.advance_to(t)
                .map_err(|e| format!("{}: {e}", scene.name))?;
        }
        let wall = started.elapsed().as_secs_f64() / share;
        let stats = sim.stats();
        let taken = (stats.steps + stats.rejected) as f64 / share;
        println!(
            "| {} | {} | {interval} | {held} | {steps:.3e} | {stop:.3e} | {taken:.3e} | {} | {} | {} |",
            scene.name,
            scene.solver.method.name(),
            ratio(taken / steps),
            predicted.seconds.map_or("–".into(), duration),
            duration(wall),
        );
    }
    Ok(())
}

/// Two significant digits: "1.0", "0.33", "0.0028".
fn ratio(x: f64) -> String {
    let digits = (1.0 - x.log10().floor()).clamp(1.0, 6.0) as usize;
    format!("{x:.digits$}")
}
