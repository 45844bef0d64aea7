//! Kinks located: cable slack/taut transitions and ground contact on/off are found inside a
//! step and the step is split there, so rk4 keeps about fourth order where cables go slack
//! and where a node lands. Figures are printed (run with `--nocapture`).

use nalgebra::Vector3;
use std::time::Instant;
use tensegrity_fmu::integrator::Method;

use tensegrity_fmu::scene::{tower_scene, BarSpec, GroundSpec, Scene};
use tensegrity_fmu::{Model, Simulation};

const TIME: f64 = 1.0;

/// The 5-stage tower sagging under its own weight (cables go slack and taut).
fn sagging_tower(method: Method, h: f64) -> Scene {
    let mut scene = tower_scene(5, Some(500.0), "tower5");
    scene.gravity = Some([0.0, 0.0, -9.81]);
    scene.solver.method = method;
    scene.solver.step_size = h;
    scene
}

fn positions(sim: &Simulation) -> Vec<Vector3<f64>> {
    (0..sim.model().n_nodes())
        .map(|n| sim.node_position(n))
        .collect()
}

fn max_distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

/// Runs to `TIME` on the scene's grid (steps of `h`), counting slack/taut transitions of
/// the cables seen at the grid points.
fn run(scene: &Scene, locate: bool) -> (Vec<Vector3<f64>>, usize, Simulation) {
    run_for(scene, locate, TIME)
}

fn run_for(scene: &Scene, locate: bool, time: f64) -> (Vec<Vector3<f64>>, usize, Simulation) {
    let mut sim = Simulation::new(Model::new(scene).unwrap());
    sim.locate_events = locate;
    let h = scene.solver.step_size;
    let steps = (time / h).round() as u64;
    sim.refresh();
    let mut taut: Vec<bool> = sim.workspace().gamma.iter().map(|&g| g > 0.0).collect();
    let mut transitions = 0;
    for k in 0..steps {
        sim.step_to(k as f64 * h, (k + 1) as f64 * h).unwrap();
        sim.refresh();
        for (t, &g) in taut.iter_mut().zip(&sim.workspace().gamma) {
            if (g > 0.0) != *t {
                transitions += 1;
                *t = g > 0.0;
            }
        }
    }
    (positions(&sim), transitions, sim)
}

/// Observed orders between successive halvings of the step.
fn orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

const STEPS: [f64; 3] = [1e-3, 5e-4, 2.5e-4];

#[test]
fn slack_tower_keeps_rk4_fourth_order() {
    let (reference, transitions, r) = run(&sagging_tower(Method::Rk4, 1e-5), true);
    println!(
        "reference rk4 at 1e-5 s with location: {transitions} slack/taut transitions seen on \
         the grid, {} located events",
        r.stats().events
    );
    assert!(
        transitions >= 9,
        "only {transitions} transitions: nothing goes slack"
    );
    let mut by_locate = Vec::new();
    for locate in [false, true] {
        let mut errors = Vec::new();
        for h in STEPS {
            let (x, n, s) = run(&sagging_tower(Method::Rk4, h), locate);
            let e = max_distance(&x, &reference);
            println!(
                "rk4 {h:.2e} s, location {}: error {e:.3e} m, {n} transitions, {} events, \
                 {} steps, {} redone",
                if locate { "on " } else { "off" },
                s.stats().events,
                s.stats().steps,
                s.stats().rejected
            );
            errors.push(e);
        }
        let o = orders(&errors);
        println!(
            "  observed orders {:.2} (1 -> 0.5 ms), {:.2} (0.5 -> 0.25 ms)",
            o[0], o[1]
        );
        by_locate.push(o);
    }
    let located = &by_locate[1];
    assert!(
        located[1] >= 3.3,
        "order {:.2} between 0.5 and 0.25 ms",
        located[1]
    );
    assert!(
        located[0] >= 3.3,
        "order {:.2} between 1 and 0.5 ms",
        located[0]
    );
}

#[test]
fn dopri5_clips_its_steps_at_the_switches() {
    let (reference, _, _) = run(&sagging_tower(Method::Rk4, 1e-5), true);
    for locate in [false, true] {
        let mut scene = sagging_tower(Method::Dopri5, 1e-3);
        scene.solver.rtol = 1e-10;
        scene.solver.atol = 1e-12;
        let mut sim = Simulation::new(Model::new(&scene).unwrap());
        sim.locate_events = locate;
        sim.advance_to(TIME).unwrap();
        sim.refresh();
        let e = max_distance(&positions(&sim), &reference);
        let s = sim.stats();
        println!(
            "dopri5 rtol 1e-10, location {locate}: error {e:.3e} m, {} steps, {} rejected, \
             {} events, {} evaluations",
            s.steps,
            s.rejected,
            s.events,
            sim.integrator().rhs_evaluations()
        );
        if locate {
            assert!(s.events >= 9, "{} events", s.events);
            assert!(e < 1e-9, "error {e}");
        }
    }
}

/// A free 1 m bar, tilted, its lower end `drop` above a frictionless, undamped ground.
fn dropped_bar(h: f64, drop: f64) -> Scene {
    let mut scene = tower_scene(1, Some(500.0), "dropped-bar");
    scene.description = None;
    scene.nodes = vec![[0.0, 0.0, drop], [0.6, 0.0, drop + 0.8]];
    scene.fixed = Vec::new();
    scene.bars = vec![BarSpec {
        nodes: [1, 2],
        mass: 1.0,
        radius: 0.0,
    }];
    scene.cables = Vec::new();
    scene.force_inputs = Vec::new();
    scene.prestress = None;
    scene.gravity = Some([0.0, 0.0, -9.81]);
    scene.ground = Some(GroundSpec {
        height: 0.0,
        normal: [0.0, 0.0, 1.0],
        stiffness: 1e4,
        damping: 0.0,
        friction: 0.0,
        slip_velocity: 1e-2,
    });
    scene.solver.method = Method::Rk4;
    scene.solver.step_size = h;
    scene
}

#[test]
fn a_landing_node_keeps_rk4_fourth_order() {
    // Lands after about 0.1 s, bounces off after about 20 ms in contact, flies on.
    let time = 0.25;
    let (reference, _, r) = run_for(&dropped_bar(1e-5, 0.05), true, time);
    let landings = r.stats().events;
    println!("reference: {landings} located contact events");
    assert!(
        landings >= 2,
        "{landings} events: the node never landed and left"
    );
    let mut by_locate = Vec::new();
    for locate in [false, true] {
        let mut errors = Vec::new();
        for h in STEPS {
            let (x, _, s) = run_for(&dropped_bar(h, 0.05), locate, time);
            let e = max_distance(&x, &reference);
            println!(
                "rk4 {h:.2e} s, location {}: error {e:.3e} m, {} events",
                if locate { "on " } else { "off" },
                s.stats().events
            );
            errors.push(e);
        }
        let o = orders(&errors);
        println!("  observed orders {:.2}, {:.2}", o[0], o[1]);
        by_locate.push(o);
    }
    // At these steps (ω h ≤ 0.14 in contact) the located runs converge at or a little
    // above fourth order on their way to it; without location the order collapses.
    for o in &by_locate[1] {
        assert!((3.5..5.0).contains(o), "order {o:.2}");
    }
}

/// Not a timed assertion: the cost of locating, per located event, on the sagging tower.
#[test]
fn cost_per_located_event() {
    let h = 2.5e-4;
    let mut times = Vec::new();
    let mut events = 0;
    let mut evaluations = Vec::new();
    for locate in [false, true] {
        let scene = sagging_tower(Method::Rk4, h);
        let mut best = f64::INFINITY;
        for _ in 0..3 {
            let mut sim = Simulation::new(Model::new(&scene).unwrap());
            sim.locate_events = locate;
            let started = Instant::now();
            sim.advance_to(TIME).unwrap();
            best = best.min(started.elapsed().as_secs_f64());
            events = sim.stats().events;
            if evaluations.len() < 2 && (locate || evaluations.is_empty()) {
                evaluations.push(sim.integrator().rhs_evaluations());
            }
        }
        times.push(best);
    }
    let steps = TIME / h;
    let step_time = times[0] / steps;
    let per_evaluation = times[0] / evaluations[0] as f64;
    let events = events.max(1) as f64;
    // Redoing: the extra evaluations (a discarded trial, 2 evaluations of 4 per part);
    // the rest of the extra time is the sign check every step pays.
    let redo = (evaluations[1] - evaluations[0]) as f64 * per_evaluation;
    let check = (times[1] - times[0] - redo).max(0.0) / steps;
    println!(
        "tower5 sagging, rk4 {h:.2e} s, {steps} steps: {:.3} ms without location, {:.3} ms \
         with ({events} events, {} -> {} evaluations)\n  {:.2} us per step without, {:.2} us \
         with; per located event {:.1} us redone ({:.1} steps' worth); sign check {:.2} us \
         per step ({:.1}% of a step); all extra time per event {:.1} us",
        times[0] * 1e3,
        times[1] * 1e3,
        evaluations[0],
        evaluations[1],
        step_time * 1e6,
        times[1] / steps * 1e6,
        redo / events * 1e6,
        redo / events / step_time,
        check * 1e6,
        100.0 * check / step_time,
        (times[1] - times[0]) / events * 1e6,
    );
}
