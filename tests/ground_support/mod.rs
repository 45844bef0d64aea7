//! Helpers of the ground-contact suites (`tests/ground.rs`, `tests/ground_friction.rs`):
//! the dropped icosahedron scene, solver and sampling helpers, the energy bound on the
//! penetration.

use nalgebra::{Rotation3, Vector3};
use tensegrity_fmu::dynamics::energy;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, GroundSpec, Scene};
use tensegrity_fmu::Simulation;

/// Gravity, m/s².
pub const G: f64 = 9.81;
/// Sampling interval of the runs on a 1e4 N/m ground, s. A contact's half period
/// π√(m/k) is 16–31 ms for a bar end of 0.25–1 kg at 1e4 N/m, so 1 ms sampling finds each
/// impact's deepest penetration to within 1 − cos(π/32) ≈ 0.5 %.
pub const SAMPLE: f64 = 1e-3;
/// Drop height of the lowest node above the ground, m.
#[allow(dead_code)] // used by tests/ground.rs only
pub const DROP: f64 = 0.3;
/// Penalty stiffness, N/m: static penetration W/(3k) ≈ 2 mm on three contacts.
pub const STIFFNESS: f64 = 1e4;
/// Penalty damping, N·s/m: a bar end of 0.25–1 kg on 1e4 N/m is critically damped at
/// 2√(k m) = 100–200 N·s/m, so 100 is a well-damped, barely bouncing contact.
pub const CONTACT_DAMPING: f64 = 100.0;
/// Cable damping for the settling runs, N·s/m. 10 leaves a slow (1.4 s period) mode ringing
/// at KE ≈ 1e-3 J after 8 s; 30 brings the KE to ≈ 1e-15 J in 16 s (80 and 200 overdamp
/// the cables and settle more slowly).
pub const CABLE_DAMPING: f64 = 30.0;

pub fn ground(normal: Vector3<f64>, stiffness: f64, damping: f64, friction: f64) -> GroundSpec {
    GroundSpec {
        height: 0.0,
        normal: normal.into(),
        stiffness,
        damping,
        friction,
        slip_velocity: 0.01,
    }
}

/// The built-in icosahedron (6 bars of 1 kg, prestressed elastic cables) without pins or
/// force inputs, under gravity, turned so that its cable face (nodes 1, 5, 9: centroid
/// direction (1,1,1)) faces the plane, its lowest nodes `gap` above it. Landing on a face
/// gives three symmetric contacts (the three-fold axis is along the normal), so the
/// resting load per contact is known: W/3 on a level ground.
pub fn icosahedron_over(ground: GroundSpec, gap: f64, cable_damping: Option<f64>) -> Scene {
    let mut scene = builtin("icosahedron").unwrap();
    scene.fixed.clear();
    scene.force_inputs.clear();
    scene.gravity = Some([0.0, 0.0, -G]);
    for c in &mut scene.cables {
        c.damping = cable_damping;
    }
    let n = Vector3::from(ground.normal).normalize();
    let face = Vector3::new(1.0, 1.0, 1.0).normalize();
    let turn = Rotation3::rotation_between(&face, &-n).unwrap();
    let turned: Vec<Vector3<f64>> = scene
        .nodes
        .iter()
        .map(|p| turn * Vector3::from(*p))
        .collect();
    let lowest = turned
        .iter()
        .map(|p| n.dot(p))
        .fold(f64::INFINITY, f64::min);
    let lift = n * (ground.height + gap - lowest);
    scene.nodes = turned.iter().map(|p| (p + lift).into()).collect();
    scene.ground = Some(ground);
    scene
}

pub fn with_solver(mut scene: Scene, method: Method, step: f64) -> Scene {
    scene.solver.method = method;
    scene.solver.step_size = step;
    scene
}

pub fn total_mass(scene: &Scene) -> f64 {
    scene.bars.iter().map(|b| b.mass).sum()
}

/// Sum of the contact forces of the last evaluation, N.
pub fn contact_sum(sim: &Simulation) -> Vector3<f64> {
    sim.workspace().contact_force.iter().sum()
}

/// Penetrations `h − n·x` of every contact point at the last evaluation, m.
#[allow(dead_code)] // used by tests/ground.rs only
pub fn penetrations(sim: &Simulation) -> Vec<f64> {
    let ground = sim.model().ground.as_ref().unwrap();
    let ws = sim.workspace();
    ground
        .nodes
        .iter()
        .map(|&(n, _)| ground.penetration(&ws.node_pos[n], 0.0))
        .collect()
}

#[allow(dead_code)] // used by tests/ground.rs only
pub fn kinetic(sim: &Simulation) -> f64 {
    energy::kinetic(sim.model(), sim.workspace())
}

pub fn max_speed(sim: &Simulation) -> f64 {
    (0..sim.model().n_nodes())
        .map(|n| sim.node_velocity(n).norm())
        .fold(0.0, f64::max)
}

/// Penalty energy `Σ ½ k d²` at the last evaluation, J.
#[allow(dead_code)] // used by tests/ground.rs only
pub fn penalty_energy(sim: &Simulation) -> f64 {
    let ground = sim.model().ground.as_ref().unwrap();
    let ws = sim.workspace();
    ground
        .nodes
        .iter()
        .map(|&(n, _)| ground.energy(&ws.node_pos[n], 0.0))
        .sum()
}

/// What a run saw at its samples.
#[derive(Debug, Default)]
#[allow(dead_code)] // used by tests/ground.rs only
pub struct Trace {
    /// Energy at the start, J.
    pub e0: f64,
    /// Deepest penetration, m (the lowest node is this far below the ground).
    pub max_penetration: f64,
    /// Largest `max |‖b‖ − l|`, m.
    pub max_length_error: f64,
    /// Largest energy increase between successive samples, J.
    pub max_energy_rise: f64,
    /// Largest energy change between successive samples, either sign, J.
    pub max_energy_step: f64,
    /// Largest `|E − E₀|`, J.
    pub max_energy_error: f64,
    /// Largest penalty energy, J.
    pub max_penalty_energy: f64,
    /// Times the structure went from no contact to contact.
    pub touchdowns: usize,
}

/// Runs `sim` to `time`, sampling every `sample` s.
#[allow(dead_code)] // used by tests/ground.rs only
pub fn track(sim: &mut Simulation, time: f64, sample: f64) -> Trace {
    let mut trace = Trace {
        e0: sim.energy(),
        ..Trace::default()
    };
    let mut previous = trace.e0;
    let mut touching = false;
    let t0 = sim.time();
    let samples = (time / sample).round() as usize;
    for k in 1..=samples {
        sim.advance_to(t0 + k as f64 * sample).unwrap();
        sim.refresh();
        let deepest = penetrations(sim).into_iter().fold(f64::MIN, f64::max);
        trace.max_penetration = trace.max_penetration.max(deepest);
        if deepest > 0.0 && !touching {
            trace.touchdowns += 1;
        }
        touching = deepest > 0.0;
        trace.max_length_error = trace.max_length_error.max(sim.length_error());
        let e = sim.energy();
        trace.max_energy_rise = trace.max_energy_rise.max(e - previous);
        trace.max_energy_step = trace.max_energy_step.max((e - previous).abs());
        trace.max_energy_error = trace.max_energy_error.max((e - trace.e0).abs());
        trace.max_penalty_energy = trace.max_penalty_energy.max(penalty_energy(sim));
        previous = e;
    }
    trace
}

/// Deepest penetration the energy allows. The contact law dissipates (`dE/dt = −c (n·v)²`
/// while `k d > c n·v`, `−k d n·v < 0` while the clamp holds) as do cable damping and
/// friction, so `E(t) ≤ E₀` (E includes ½ k d², with gravity measured from the ground
/// plane). Kinetic and cable energies are ≥ 0, and the centre of mass, a convex
/// combination of the nodes, is no lower than the deepest node, so with `W = M g`:
/// `½ k d² − W d ≤ E₀`, i.e. `d ≤ (W + √(W² + 2 k E₀)) / k`.
#[allow(dead_code)] // used by tests/ground.rs only
pub fn penetration_bound(weight: f64, stiffness: f64, e0: f64) -> f64 {
    (weight + (weight * weight + 2.0 * stiffness * e0).sqrt()) / stiffness
}
