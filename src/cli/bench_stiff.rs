//! `bench stiff`: what steel-stiff cables cost each method. The steel prism
//! ([`steel_prism_scene`]: κ = 1e7 N/m, settled under gravity, swayed by a slow 0.5 Hz
//! load) over 2 s with sdirk3 at a 1 ms controller step, dopri5 at rtol = atol = 1e-6 and
//! rk4 at 90 % of its stability limit, each with its largest node-position error against
//! dopri5 at 1e-11 (sampled every 10 ms) and its wall time, the best of interleaved
//! repeats, as ratios to sdirk3's.

use std::time::Instant;

use nalgebra::Vector3;

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{steel_prism_scene, Scene};
use tensegrity_fmu::sim::stability_limit;
use tensegrity_fmu::{analysis, Simulation};

/// Simulated time, s.
const HORIZON: f64 = 2.0;
/// Sampling interval of the error, s.
const SAMPLE: f64 = 0.01;

/// Node positions at each sample time.
type Samples = Vec<Vec<Vector3<f64>>>;

struct Run {
    label: String,
    scene: Scene,
    best: f64,
    error: f64,
}

/// Runs the benchmark and prints one row per method.
pub fn run(repeats: usize) -> Result<(), String> {
    if repeats == 0 {
        return Err("--repeats must be at least 1".to_string());
    }
    let scene = steel_prism_scene();
    let model = analysis::load(&scene).map_err(|e| e.to_string())?;
    let omega = Simulation::new(model).max_frequency();
    let limit = stability_limit(Method::Rk4).expect("rk4 has a limit");
    let h_rk4 = 0.9 * limit / omega;
    let (reference, _) = simulate(&with(&scene, Method::Dopri5, 1e-4, 1e-11))?;
    let mut runs = [
        (
            "sdirk3, h = 1 ms".to_string(),
            with(&scene, Method::Sdirk3, 1e-3, 1e-6),
        ),
        (
            "dopri5, rtol = atol = 1e-6".to_string(),
            with(&scene, Method::Dopri5, 1e-3, 1e-6),
        ),
        (
            format!("rk4 at 90 % of its limit, h = {:.3} ms", h_rk4 * 1e3),
            with(&scene, Method::Rk4, h_rk4, 1e-6),
        ),
    ]
    .map(|(label, scene)| Run {
        label,
        scene,
        best: f64::INFINITY,
        error: f64::NAN,
    });
    for _ in 0..repeats {
        for r in &mut runs {
            let (samples, seconds) = simulate(&r.scene)?;
            r.best = r.best.min(seconds);
            r.error = max_distance(&samples, &reference);
        }
    }
    println!(
        "steel prism (κ = 1e7 N/m, fastest mode ω = {omega:.4e} 1/s), {HORIZON} s under a 0.5 Hz \
         load; error: largest node distance to dopri5 at 1e-11 every {} ms; wall time: best of \
         {repeats} interleaved runs\n",
        SAMPLE * 1e3
    );
    println!("| method | error (m) | wall time (s) | time / sdirk3's |");
    println!("|---|---:|---:|---:|");
    let base = runs[0].best;
    for r in &runs {
        println!(
            "| {} | {:.2e} | {:.4} | {:.2} |",
            r.label,
            r.error,
            r.best,
            r.best / base
        );
    }
    Ok(())
}

fn with(scene: &Scene, method: Method, step: f64, tol: f64) -> Scene {
    let mut s = scene.clone();
    s.solver.method = method;
    s.solver.step_size = step;
    s.solver.rtol = tol;
    s.solver.atol = tol;
    s.solver.max_steps = 10_000_000;
    s
}

/// Node positions every [`SAMPLE`] and the wall time of the integration, s.
fn simulate(scene: &Scene) -> Result<(Samples, f64), String> {
    let mut sim = Simulation::new(analysis::load(scene).map_err(|e| e.to_string())?);
    let mut samples = Vec::new();
    let mut seconds = 0.0;
    for k in 1..=(HORIZON / SAMPLE).round() as usize {
        let started = Instant::now();
        sim.advance_to(k as f64 * SAMPLE)
            .map_err(|e| e.to_string())?;
        seconds += started.elapsed().as_secs_f64();
        samples.push(
            (0..sim.model().n_nodes())
                .map(|n| sim.node_position(n))
                .collect(),
        );
    }
    Ok((samples, seconds))
}

fn max_distance(a: &Samples, b: &Samples) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).norm()))
        .fold(0.0, f64::max)
}
