//! `bench effects`: what optional effects cost on tower20. The step runs the list of
//! contributions built from the declared effects (`Model::pipeline`), so a scene without an
//! effect should not pay for it. Three cases, each timed as µs per RK4 step (1 ms, with
//! correction):
//!
//! - `base`: tower20 as shipped minus its force inputs, so only the base effects remain:
//!   prestressed elastic cables, the pins and the class-2 joints.
//! - `declared-zero`: every optional effect declared with zero magnitude (gravity 0, cable
//!   damping 0, force inputs left at 0, a sinusoidal load of amplitude 0, 0 kg point
//!   masses, a ground 100 m below, one reeled and one force-density cable whose prestress
//!   start values hold the shipped equilibrium): the same motion as `base` (none), at the
//!   cost of running each contribution.
//! - `active`: the same effects with real values, the controlled cables driven between
//!   communication steps.
//!
//! A second figure times the force stage alone (`dynamics::applied_forces`, which runs the
//! pipeline's force contributions; an rk4 step evaluates it 4 times besides the joint,
//! pin and bar-length work that every case shares) at the window's end state.
//!
//! Timing: every measurement replays the same window (the first [`WINDOW`] steps from the
//! scene's start) until at least `seconds` of wall time have been spent stepping; copying
//! the start state is not timed. The cases are interleaved, each measured `repeats` times,
//! and the best is printed (this machine has slow spells, which only ever add time).

use std::f64::consts::PI;
use std::time::{Duration, Instant};

use nalgebra::Vector3;

use tensegrity_fmu::dynamics::effects::{ConstraintEffect, ForceEffect, Pipeline};
use tensegrity_fmu::dynamics::{applied_forces, Workspace};
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{
    builtin, CableControl, CableSpec, GroundSpec, LoadSpec, PointMassSpec, Scene, SolverSpec,
};
use tensegrity_fmu::{Model, Simulation};

/// Steps between two input updates (a 10 ms communication step at h = 1 ms).
const CHUNK: u64 = 10;
/// Steps of the replayed window (1 s of simulated time).
const WINDOW: u64 = 1000;
/// Step size, s.
const STEP: f64 = 1e-3;
/// Cable (0-based) turned into a rest-length controlled one: the first top-ring cable.
const REELED: usize = 60;
/// Cable (0-based) turned into a force-density controlled one: a top-stage diagonal.
const CONTROLLED: usize = 120;
/// Active values.
const GRAVITY: f64 = -9.81;
const DAMPING: f64 = 0.5;
const NODE_FORCE: f64 = 5.0;
const LOAD_AMPLITUDE: f64 = 2.0;
const LOAD_FREQUENCY: f64 = 2.0;
const POINT_MASS: f64 = 0.5;
/// Relative swing of the controlled force density (the rest length swings 1/20 of it), and
/// its frequency (Hz). Below the doubling that re-runs the stability check.
const DRIVE_SWING: f64 = 0.2;
const DRIVE_FREQUENCY: f64 = 1.0;
/// Active ground: this far below the lowest free ring, m (pinned nodes take no contact).
const GROUND_GAP: f64 = 0.005;
/// Force-stage evaluations per measurement of it.
const FORCE_EVALS: u32 = 20_000;
/// Ground penalty stiffness (N/m), damping (N·s/m), friction and slip velocity (m/s): inside
/// rk4's stability limit at 1 ms under the active case's weight.
const GROUND: [f64; 4] = [1e5, 100.0, 0.3, 0.5];

/// One benchmarked case.
struct Case {
    name: &'static str,
    /// The start state, its stability verdict cached, the inputs at their start values.
    start: Simulation,
    /// Drive the inputs between chunks (force inputs, reeled and controlled cables).
    drive: Option<Drive>,
    /// Best µs per step and the steps timed in that measurement.
    best: Option<(f64, u64)>,
    /// Best µs per evaluation of the force stage alone.
    best_forces: Option<f64>,
}

/// Runs the benchmark and prints one row per case.
pub fn run(seconds: f64, repeats: usize) -> Result<(), String> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!(
            "--seconds must be positive and finite (got {seconds})"
        ));
    }
    if repeats == 0 {
        return Err("--repeats must be at least 1".to_string());
    }
    let base = base_scene()?;
    let mut cases = [
        case("base", &base, false)?,
        case("declared-zero", &with_effects(&base, false)?, false)?,
        case("active", &with_effects(&base, true)?, true)?,
    ];
    // Warm-up (caches, branch predictors): one untimed window each, which also gives what
    // the window does.
    let mut windows = cases.iter().map(replay).collect::<Result<Vec<_>, _>>()?;
    for _ in 0..repeats {
        for (c, w) in cases.iter_mut().zip(&mut windows) {
            let (us, steps) = measure(c, seconds)?;
            if c.best.is_none_or(|(b, _)| us < b) {
                c.best = Some((us, steps));
            }
            let us = measure_forces(c, &mut w.workspace);
            if c.best_forces.is_none_or(|b| us < b) {
                c.best_forces = Some(us);
            }
        }
    }
    println!(
        "tower20 ({} bars), rk4, h = {} ms, correction on; the first {} s replayed; best of \
         {repeats} interleaved measurements of ≥ {seconds} s each\n",
        cases[0].start.model().bars.len(),
        STEP * 1e3,
        WINDOW as f64 * STEP,
    );
    println!(
        "| case | µs/step | ratio to base | steps timed | force stage (µs/eval) | max node \
         displacement (m) | pipeline |"
    );
    println!("|---|---:|---:|---:|---:|---:|---|");
    let base_us = cases[0].best.map_or(f64::NAN, |b| b.0);
    for (c, w) in cases.iter().zip(&windows) {
        let (us, steps) = c.best.expect("measured at least once");
        let forces = c.best_forces.expect("measured at least once");
        println!(
            "| {} | {us:.1} | {:.2} | {steps} | {forces:.2} | {:.2e} | {} |",
            c.name,
            us / base_us,
            w.displacement,
            pipeline_names(&c.start.model().pipeline)
        );
    }
    let active = &windows[2];
    println!(
        "\nbase: tower20 without its force inputs (prestressed elastic cables, pins, class-2 \
         joints).\ndeclared-zero: gravity 0, damping 0 on every cable, force inputs on nodes \
         61–63 left at 0, a 0 N sinusoid on node 61, 0 kg on nodes 61–63, a ground 100 m \
         below, cable {} reeled and cable {} force-density controlled at their prestress start \
         values (the shipped equilibrium).\nactive: gravity {GRAVITY} m/s², damping {DAMPING} \
         N·s/m, {NODE_FORCE} N along x on nodes 61–63, a {LOAD_AMPLITUDE} N {LOAD_FREQUENCY} \
         Hz sinusoid on node 61, {POINT_MASS} kg on nodes 61–63, the ground {GROUND_GAP} m \
         below ring 1 (k = {:e} N/m), the controlled force density ±{:.0} % and rest length \
         ±{:.0} % at {DRIVE_FREQUENCY} Hz. The tower sags and topples under its weight: up to \
         {} nodes touch the ground at once and up to {} of {} cables are slack during the window.",
        REELED + 1,
        CONTROLLED + 1,
        GROUND[0],
        DRIVE_SWING * 100.0,
        DRIVE_SWING * 5.0,
        active.touching,
        active.slack,
        cases[2].start.model().cables.len(),
    );
    Ok(())
}

/// Builds a case's start: the model, the stability check (cached in the simulation, so no
/// timed step runs it) and, when driven, the force inputs.
fn case(name: &'static str, scene: &Scene, drive: bool) -> Result<Case, String> {
    let model = Model::new(scene).map_err(|e| format!("{name}: {e}"))?;
    let mut start = Simulation::new(model);
    if let Some(problem) = start.check_stability() {
        return Err(format!("{name}: {problem}"));
    }
    let drive = drive.then(|| {
        for f in &mut start.inputs.node_force {
            *f = Vector3::new(NODE_FORCE, 0.0, 0.0);
        }
        Drive::new(&start)
    });
    Ok(Case {
        name,
        start,
        drive,
        best: None,
        best_forces: None,
    })
}

/// Start values of the controlled cables' inputs, to swing them around.
struct Drive {
    force_density: Vec<f64>,
    rest_length: Vec<f64>,
}

impl Drive {
    fn new(sim: &Simulation) -> Self {
        Self {
            force_density: sim.inputs.force_density.clone(),
            rest_length: sim.inputs.rest_length.clone(),
        }
    }

    /// The controlled cables' inputs at the current time.
    fn set(&self, sim: &mut Simulation) {
        let s = (2.0 * PI * DRIVE_FREQUENCY * sim.time()).sin();
        for (input, start) in sim.inputs.force_density.iter_mut().zip(&self.force_density) {
            *input = start * (1.0 + DRIVE_SWING * s);
        }
        for (input, start) in sim.inputs.rest_length.iter_mut().zip(&self.rest_length) {
            *input = start * (1.0 + 0.05 * DRIVE_SWING * s);
        }
    }
}

/// Steps one window from a copy of the start: `each` runs after every chunk.
fn window(c: &Case, mut each: impl FnMut(&mut Simulation)) -> Result<Simulation, String> {
    let mut sim = c.start.clone();
    for _ in 0..WINDOW / CHUNK {
        if let Some(d) = &c.drive {
            d.set(&mut sim);
        }
        sim.advance(CHUNK, STEP)
            .map_err(|e| format!("{}: {e}", c.name))?;
        each(&mut sim);
    }
    Ok(sim)
}

/// µs per step over at least `seconds` of stepping, whole windows from the start.
fn measure(c: &Case, seconds: f64) -> Result<(f64, u64), String> {
    let mut spent = Duration::ZERO;
    let mut steps = 0u64;
    while spent.as_secs_f64() < seconds {
        let mut sim = c.start.clone();
        let started = Instant::now();
        for _ in 0..WINDOW / CHUNK {
            if let Some(d) = &c.drive {
                d.set(&mut sim);
            }
            sim.advance(CHUNK, STEP)
                .map_err(|e| format!("{}: {e}", c.name))?;
        }
        spent += started.elapsed();
        steps += WINDOW;
    }
    Ok((spent.as_secs_f64() * 1e6 / steps as f64, steps))
}

/// µs per evaluation of the force stage (every contribution of the pipeline, the step's
/// stage 2) at the window's end state; 4 per rk4 step.
fn measure_forces(c: &Case, ws: &mut Workspace) -> f64 {
    let model = c.start.model();
    let inputs = &c.start.inputs;
    let started = Instant::now();
    for k in 0..FORCE_EVALS {
        applied_forces(model, inputs, f64::from(k) * STEP, ws);
    }
    started.elapsed().as_secs_f64() * 1e6 / f64::from(FORCE_EVALS)
}

/// What a window does, sampled after every chunk.
struct Window {
    /// Largest distance of a node from its start position, m.
    displacement: f64,
    /// Most nodes touching the ground at once.
    touching: usize,
    /// Most slack cables at once.
    slack: usize,
    /// The workspace at the window's end (positions, velocities: what the forces read).
    workspace: Workspace,
}

/// One untimed window, watched.
fn replay(c: &Case) -> Result<Window, String> {
    let (mut displacement, mut touching, mut slack) = (0.0, 0, 0);
    let end = window(c, |sim| {
        sim.refresh();
        let model = sim.model();
        let ws = sim.workspace();
        for n in 0..model.n_nodes() {
            displacement = f64::max(
                displacement,
                (sim.node_position(n) - model.positions[n]).norm(),
            );
        }
        let now = ws.contact_force.iter().filter(|f| f.norm() > 0.0).count();
        touching = touching.max(now);
        slack = slack.max(ws.gamma.iter().filter(|&&g| g == 0.0).count());
    })?;
    Ok(Window {
        displacement,
        touching,
        slack,
        workspace: end.workspace().clone(),
    })
}

/// tower20 with only the base effects: its force inputs dropped, rk4 at 1 ms with
/// correction.
fn base_scene() -> Result<Scene, String> {
    let mut scene = builtin("tower20").ok_or("the built-in tower20 is missing")?;
    scene.force_inputs.clear();
    scene.solver = SolverSpec {
        step_size: STEP,
        correction: true,
        method: Method::Rk4,
        ..SolverSpec::default()
    };
    Ok(scene)
}

/// `base` with every optional effect declared: zero magnitudes, or the active values.
fn with_effects(base: &Scene, active: bool) -> Result<Scene, String> {
    let mut scene = base.clone();
    let value = |v: f64| if active { v } else { 0.0 };
    let n = scene.nodes.len();
    let top: Vec<usize> = (n - 2..=n).collect();
    scene.gravity = Some([0.0, 0.0, value(GRAVITY)]);
    for cable in &mut scene.cables {
        cable.damping = Some(value(DAMPING));
    }
    // With `prestress` both derive their start value from the shipped self-stress: the
    // reeled cable its rest length, the controlled one its force density.
    let reeled = scene
        .cables
        .get_mut(REELED)
        .ok_or("tower20 has too few cables")?;
    reeled.control = Some(CableControl::RestLength);
    let nodes = scene
        .cables
        .get(CONTROLLED)
        .ok_or("tower20 has too few cables")?
        .nodes;
    scene.cables[CONTROLLED] = CableSpec {
        nodes,
        control: Some(CableControl::ForceDensity),
        ..CableSpec::default()
    };
    scene.force_inputs = top.clone();
    scene.loads = vec![LoadSpec::Sinusoidal {
        node: top[0],
        amplitude: [0.0, value(LOAD_AMPLITUDE), 0.0],
        frequency: LOAD_FREQUENCY,
        phase: 0.0,
    }];
    scene.point_masses = top
        .iter()
        .map(|&node| PointMassSpec {
            node,
            mass: value(POINT_MASS),
        })
        .collect();
    // The lowest free ring (ring 1): pinned nodes take no contact.
    let lowest_free = (0..n)
        .filter(|&i| !scene.fixed.contains(&(i + 1)))
        .map(|i| scene.nodes[i][2])
        .fold(f64::INFINITY, f64::min);
    let [stiffness, damping, friction, slip_velocity] = GROUND;
    scene.ground = Some(GroundSpec {
        height: if active {
            lowest_free - GROUND_GAP
        } else {
            -100.0
        },
        normal: [0.0, 0.0, 1.0],
        stiffness,
        damping,
        friction,
        slip_velocity,
    });
    scene.name = format!("tower20-{}", if active { "active" } else { "zero" });
    Ok(scene)
}

/// `ElasticCables(123), JointsAndPins`: the force effects with their sizes, then the
/// constraint effects.
fn pipeline_names(pipeline: &Pipeline) -> String {
    let forces = pipeline.forces.iter().map(|f| match f {
        ForceEffect::Gravity(v) => format!("Gravity({})", v.len()),
        ForceEffect::ElasticCables(v) => format!("ElasticCables({})", v.len()),
        ForceEffect::DampedCables(v) => format!("DampedCables({})", v.len()),
        ForceEffect::ForceDensityCables(v) => format!("ForceDensityCables({})", v.len()),
        ForceEffect::ReeledCables(v) => format!("ReeledCables({})", v.len()),
        ForceEffect::NodeForces(v) => format!("NodeForces({})", v.len()),
        ForceEffect::ScriptedLoads(v) => format!("ScriptedLoads({})", v.len()),
        ForceEffect::GroundContact(g) => format!("GroundContact({})", g.nodes.len()),
        ForceEffect::Terrain(t) => format!("Terrain({}×{})", t.capsules.len(), t.shapes.len()),
        ForceEffect::Collisions(c) => format!("Collisions({})", c.capsules.len()),
    });
    let constraints = pipeline.constraints.iter().map(|c| match c {
        ConstraintEffect::JointsAndPins => "JointsAndPins".to_string(),
    });
    forces.chain(constraints).collect::<Vec<_>>().join(", ")
}
