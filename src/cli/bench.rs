//! Scaling benchmark: µs per RK4 step (with correction) for towers of growing height.

use std::time::Instant;

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, tower_with_rest_lengths, Scene};
use tensegrity_fmu::{Model, Simulation};

/// Step size of every measured run, s.
const STEP: f64 = 1e-3;

/// `scene` stepped by rk4 at [`STEP`], the method and step these benchmarks time (the
/// scenes' own default is the adaptive dopri5).
pub fn with_rk4(mut scene: Scene) -> Scene {
    scene.solver.method = Method::Rk4;
    scene.solver.step_size = STEP;
    scene
}

/// µs per step of `sim` at [`STEP`] over at least `seconds` (and 20 steps), after 10 steps
/// of warm-up.
pub fn us_per_step(sim: &mut Simulation, seconds: f64) -> Result<f64, String> {
    sim.advance(10, STEP).map_err(|e| e.to_string())?;
    let started = Instant::now();
    let mut steps = 0u64;
    while started.elapsed().as_secs_f64() < seconds || steps < 20 {
        sim.advance(10, STEP).map_err(|e| e.to_string())?;
        steps += 10;
    }
    Ok(started.elapsed().as_secs_f64() * 1e6 / steps as f64)
}

/// A tower of `k` stages with explicit rest lengths (the dense prestress solve is not what
/// is measured), stepped by rk4 at [`STEP`].
pub fn tower(k: usize) -> Scene {
    with_rk4(tower_with_rest_lengths(k, &format!("tower{k}")))
}

/// Prints one row per tower height: the fastest round's µs per step, and the ratio of µs
/// per bar-step to the first height's. This machine's speed drifts, so in each round the
/// first height is measured again right before each other one, and the row gives the
/// median of the rounds' ratios (the upper middle one for an even count) and their range.
pub fn scaling(stages: &[usize], seconds: f64, rounds: usize) -> Result<(), String> {
    let mut towers = Vec::with_capacity(stages.len());
    for &k in stages {
        let scene = tower(k);
        let started = Instant::now();
        let model = Model::new(&scene).map_err(|e| e.to_string())?;
        let build_ms = started.elapsed().as_secs_f64() * 1e3;
        towers.push((k, model.bars.len(), build_ms, Simulation::new(model)));
    }
    let n = towers.len();
    let (mut best, mut ratios) = (vec![f64::INFINITY; n], vec![Vec::new(); n]);
    for _ in 0..rounds {
        for i in 0..n {
            let base = us_per_step(&mut towers[0].3, seconds)?;
            let us = if i == 0 {
                base
            } else {
                us_per_step(&mut towers[i].3, seconds)?
            };
            best[0] = best[0].min(base);
            best[i] = best[i].min(us);
            ratios[i].push((us / towers[i].1 as f64) / (base / towers[0].1 as f64));
        }
    }
    println!("| stages | bars | build (ms) | µs/step | µs/(step·bar) | ratio to linear | rounds' range |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for ((&(k, bars, build_ms, _), us), ratios) in towers.iter().zip(&best).zip(&mut ratios) {
        ratios.sort_by(f64::total_cmp);
        let (low, median, high) = (
            ratios[0],
            ratios[ratios.len() / 2],
            ratios[ratios.len() - 1],
        );
        let per_bar = us / bars as f64;
        println!(
            "| {k} | {bars} | {build_ms:.1} | {us:.1} | {per_bar:.3} | {median:.2} | {low:.2}–{high:.2} |"
        );
    }
    // The paper's "more than an hour in Matlab" case, as shipped (prestressed, loaded).
    let started = Instant::now();
    let scene = with_rk4(builtin("tower20").expect("built-in"));
    let model = Model::new(&scene).map_err(|e| e.to_string())?;
    let mut sim = Simulation::new(model);
    for f in &mut sim.inputs.node_force {
        f.x = 1.0;
    }
    sim.advance(10_000, STEP).map_err(|e| e.to_string())?;
    println!(
        "\ntower20 (60 bars, shipped scene, 1 N top loads, rk4): 10 s at 1 ms in {:.3} s wall time, including the prestress solve",
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
