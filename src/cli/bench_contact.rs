//! `bench contact`: what terrain contact and bar–bar collisions cost.
//!
//! - Per step on tower20 (rk4, 0.5 ms, correction on, gravity, 2 cm bar capsules): the tower
//!   alone, with terrain (the ground plane under it and a box pressing on the bars of one
//!   side of its lower half), with collisions, and with both, each as a ratio to the tower
//!   alone. Timed as `bench effects` times: the same window replayed, cases interleaved,
//!   the best of the repeats.
//! - The collision stage alone (broad phase, closest points, forces) on towers of 600 to
//!   60,000 bars at their start state: µs per bar, as a ratio to the smallest tower's.

use std::time::{Duration, Instant};

use nalgebra::Vector3;

use tensegrity_fmu::contact::segments::{capsule_bounds, overlapping_pairs};
use tensegrity_fmu::dynamics::collisions::{self, CollisionScratch};
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{
    builtin, tower_with_rest_lengths, CollisionSpec, FrictionModel, Scene, SolverSpec, TerrainKind,
    TerrainSpec,
};
use tensegrity_fmu::{Model, Simulation};

/// Steps of the replayed window (0.2 s).
const WINDOW: u64 = 400;
/// Step size, s.
const STEP: f64 = 5e-4;
/// Bar radius, m.
const RADIUS: f64 = 0.02;
/// Contact law: stiffness (N/m), damping (N·s/m), friction.
const LAW: [f64; 3] = [1e4, 50.0, 0.5];

/// Runs both parts and prints their tables.
pub fn run(seconds: f64, repeats: usize, bars: &[usize]) -> Result<(), String> {
    if !(seconds.is_finite() && seconds > 0.0) || repeats == 0 {
        return Err("--seconds must be positive and --repeats at least 1".into());
    }
    if let Some(b) = bars.iter().find(|&&b| b == 0 || b % 3 != 0) {
        return Err(format!(
            "--bars: {b} is not a positive multiple of 3 (a tower has 3 bars per stage)"
        ));
    }
    per_step(seconds, repeats)?;
    scaling(bars, repeats)
}

fn per_step(seconds: f64, repeats: usize) -> Result<(), String> {
    let base = tower(builtin("tower20").ok_or("the built-in tower20 is missing")?);
    let terrain = with_terrain(&base);
    let collide = with_collisions(&base);
    let both = with_collisions(&terrain);
    let mut cases: Vec<(&str, Simulation, f64, (u32, u64))> = Vec::new();
    for (name, scene) in [
        ("tower20", &base),
        ("+ terrain", &terrain),
        ("+ collisions", &collide),
        ("+ both", &both),
    ] {
        let mut sim = Simulation::new(Model::new(scene).map_err(|e| e.to_string())?);
        // A run checks its step's stability once; the replayed windows share that check.
        if let Some(problem) = sim.check_stability() {
            return Err(format!("{name}: {problem}"));
        }
        cases.push((name, sim, f64::INFINITY, (0, 0)));
    }
    for _ in 0..repeats {
        for case in &mut cases {
            let (us, contacts) = measure(&case.1, seconds)?;
            case.2 = case.2.min(us);
            case.3 = contacts;
        }
    }
    println!(
        "tower20 (60 bars, radius {RADIUS} m), gravity, rk4, h = 0.5 ms (inside the limit the collisions' friction sets), correction on; the first \
         {} s replayed; best of {repeats} interleaved measurements of ≥ {seconds} s each\n",
        WINDOW as f64 * STEP
    );
    println!(
        "| case | µs/step | ratio to tower20 | contact points at the window's end | events located in the window |"
    );
    println!("|---|---:|---:|---:|---:|");
    let base_us = cases[0].2;
    for (name, _, us, (contacts, events)) in &cases {
        println!(
            "| {name} | {us:.1} | {:.3} | {contacts} | {events} |",
            us / base_us
        );
    }
    println!();
    Ok(())
}

/// Best µs per step over windows replayed for at least `seconds`, the contact points
/// (terrain and collisions) at the window's end and the events located in a window.
fn measure(start: &Simulation, seconds: f64) -> Result<(f64, (u32, u64)), String> {
    let (mut spent, mut steps, mut contacts, mut events) = (Duration::ZERO, 0u64, 0, 0);
    while spent.as_secs_f64() < seconds {
        let mut sim = start.clone();
        let t0 = Instant::now();
        for k in 0..WINDOW {
            sim.step_to(k as f64 * STEP, (k + 1) as f64 * STEP)
                .map_err(|e| e.to_string())?;
        }
        spent += t0.elapsed();
        steps += WINDOW;
        sim.refresh();
        let ws = sim.workspace();
        contacts = ws.shape_load.iter().map(|l| l.contacts).sum::<u32>() + ws.collision.contacts;
        events = sim.stats().events - start.stats().events;
    }
    Ok((spent.as_secs_f64() * 1e6 / steps as f64, (contacts, events)))
}

/// A tower as the benchmark runs it: no inputs, gravity, capsules, rk4 at 0.5 ms.
fn tower(mut scene: Scene) -> Scene {
    scene.force_inputs.clear();
    scene.gravity = Some([0.0, 0.0, -9.81]);
    scene.bars.iter_mut().for_each(|b| b.radius = RADIUS);
    scene.solver = SolverSpec {
        step_size: STEP,
        method: Method::Rk4,
        ..SolverSpec::default()
    };
    scene
}

fn shape(kind: TerrainKind) -> TerrainSpec {
    TerrainSpec {
        kind,
        point: None,
        normal: None,
        center: None,
        size: None,
        yaw: None,
        file: None,
        heights: None,
        origin: None,
        spacing: None,
        stiffness: LAW[0],
        damping: LAW[1],
        friction: LAW[2],
        slip_velocity: 0.5,
        friction_model: FrictionModel::default(),
    }
}

/// The ground under the pinned ring, and a box whose face presses 2 mm into the capsules
/// on the +x side of the tower's lower half.
fn with_terrain(base: &Scene) -> Scene {
    let mut scene = base.clone();
    let top = base.nodes.iter().map(|p| p[2]).fold(f64::MIN, f64::max);
    let reach = base.nodes.iter().map(|p| p[0]).fold(f64::MIN, f64::max);
    let ground = TerrainSpec {
        point: Some([0.0, 0.0, -RADIUS]),
        ..shape(TerrainKind::Plane)
    };
    let wall = TerrainSpec {
        center: Some([reach + RADIUS - 0.002 + 0.5, 0.0, 0.25 * top]),
        size: Some([1.0, 4.0, 0.5 * top]),
        ..shape(TerrainKind::Box)
    };
    scene.terrain = vec![ground, wall];
    scene
}

fn with_collisions(base: &Scene) -> Scene {
    let mut scene = base.clone();
    scene.collisions = Some(CollisionSpec {
        stiffness: LAW[0],
        damping: LAW[1],
        friction: LAW[2],
        slip_velocity: 0.5,
    });
    scene
}

/// The collision stage alone on towers of `bars` bars, at their start state: with the
/// broad phase each time, and between broad phases.
fn scaling(bars: &[usize], repeats: usize) -> Result<(), String> {
    println!(
        "the collision stage alone on towers at their start state, radius {RADIUS} m, best of \
         {repeats}: an evaluation that runs the broad phase (sweep and prune, closest points of \
         the pairs whose boxes overlap) and one between broad phases (a check of how far the \
         nodes moved, then the pairs kept)\n"
    );
    println!(
        "| bars | broad phase (µs) | µs per bar | ratio to linear | between (µs) | pairs in overlapping boxes | pairs kept |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    let mut first: Option<f64> = None;
    for &n in bars {
        let scene = with_collisions(&tower(tower_with_rest_lengths(n / 3, "tower")));
        let model = Model::new(&scene).map_err(|e| e.to_string())?;
        let c = model.collisions.as_ref().expect("declared");
        let x = model.positions.clone();
        let v = vec![Vector3::zeros(); x.len()];
        let mut scratch = CollisionScratch::new(c.capsules.len());
        let mut force = vec![Vector3::zeros(); model.coords.n_ends()];
        // Warm-up: the first sort starts from the bar order.
        collisions::apply(c, (&x, &v), &mut scratch, |e, f| force[e] += f);
        let (mut broad, mut between) = (f64::INFINITY, f64::INFINITY);
        let rounds = (2_000_000 / n).max(3);
        for _ in 0..repeats {
            let t0 = Instant::now();
            for _ in 0..rounds {
                scratch.forget();
                collisions::apply(c, (&x, &v), &mut scratch, |e, f| force[e] += f);
            }
            broad = broad.min(t0.elapsed().as_secs_f64() * 1e6 / rounds as f64);
            let t0 = Instant::now();
            for _ in 0..rounds {
                collisions::apply(c, (&x, &v), &mut scratch, |e, f| force[e] += f);
            }
            between = between.min(t0.elapsed().as_secs_f64() * 1e6 / rounds as f64);
        }
        let boxes: Vec<_> = c
            .capsules
            .iter()
            .map(|cap| {
                capsule_bounds(
                    &x[cap.nodes[0]],
                    &x[cap.nodes[1]],
                    cap.radius + 0.5 * c.margin,
                )
            })
            .collect();
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut pairs = 0u64;
        overlapping_pairs(&boxes, &mut order, |_, _| pairs += 1);
        let per_bar = broad / n as f64;
        let ratio = per_bar / *first.get_or_insert(per_bar);
        println!(
            "| {n} | {broad:.1} | {per_bar:.4} | {ratio:.2} | {between:.1} | {pairs} | {} |",
            scratch.kept()
        );
    }
    Ok(())
}
