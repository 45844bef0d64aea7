//! Ground contact (penalty normal force + regularised Coulomb friction): a dropped
//! icosahedron comes to rest with every integrator, the penalty energy closes the energy
//! balance, friction decelerates a slider at μ g, a tilted plane holds a body up to the
//! regularisation's creep, invalid `[ground]` keys are named, and the fixed-step guard
//! refuses a step above the contact bound. Figures are printed (run with `--nocapture`).

use nalgebra::{Rotation3, Vector3};
use tensegrity_fmu::dynamics::energy;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, BarSpec, GroundSpec, Scene};
use tensegrity_fmu::{Model, Simulation, StepError};

/// Gravity, m/s².
const G: f64 = 9.81;
/// Sampling interval of the runs on a 1e4 N/m ground, s. A contact's half period
/// π√(m/k) is 16–31 ms for a bar end of 0.25–1 kg at 1e4 N/m, so 1 ms sampling finds each
/// impact's deepest penetration to within 1 − cos(π/32) ≈ 0.5 %.
const SAMPLE: f64 = 1e-3;
/// Drop height of the lowest node above the ground, m.
const DROP: f64 = 0.3;
/// Penalty stiffness, N/m: static penetration W/(3k) ≈ 2 mm on three contacts.
const STIFFNESS: f64 = 1e4;
/// Penalty damping, N·s/m: a bar end of 0.25–1 kg on 1e4 N/m is critically damped at
/// 2√(k m) = 100–200 N·s/m, so 100 is a well-damped, barely bouncing contact.
const CONTACT_DAMPING: f64 = 100.0;
/// Cable damping for the settling runs, N·s/m. 10 leaves a slow (1.4 s period) mode ringing
/// at KE ≈ 1e-3 J after 8 s; 30 brings the KE to ≈ 1e-15 J in 16 s (80 and 200 overdamp
/// the cables and settle more slowly).
const CABLE_DAMPING: f64 = 30.0;

fn ground(normal: Vector3<f64>, stiffness: f64, damping: f64, friction: f64) -> GroundSpec {
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
fn icosahedron_over(ground: GroundSpec, gap: f64, cable_damping: Option<f64>) -> Scene {
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

fn with_solver(mut scene: Scene, method: Method, step: f64) -> Scene {
    scene.solver.method = method;
    scene.solver.step_size = step;
    scene
}

fn total_mass(scene: &Scene) -> f64 {
    scene.bars.iter().map(|b| b.mass).sum()
}

/// Sum of the contact forces of the last evaluation, N.
fn contact_sum(sim: &Simulation) -> Vector3<f64> {
    sim.workspace().contact_force.iter().sum()
}

/// Penetrations `h − n·x` of every contact point at the last evaluation, m.
fn penetrations(sim: &Simulation) -> Vec<f64> {
    let ground = sim.model().ground.as_ref().unwrap();
    let ws = sim.workspace();
    ground
        .nodes
        .iter()
        .map(|&(n, _)| ground.penetration(&ws.node_pos[n]))
        .collect()
}

fn kinetic(sim: &Simulation) -> f64 {
    energy::kinetic(sim.model(), sim.workspace())
}

fn max_speed(sim: &Simulation) -> f64 {
    (0..sim.model().n_nodes())
        .map(|n| sim.node_velocity(n).norm())
        .fold(0.0, f64::max)
}

/// Penalty energy `Σ ½ k d²` at the last evaluation, J.
fn penalty_energy(sim: &Simulation) -> f64 {
    let ground = sim.model().ground.as_ref().unwrap();
    let ws = sim.workspace();
    ground
        .nodes
        .iter()
        .map(|&(n, _)| ground.energy(&ws.node_pos[n]))
        .sum()
}

/// What a run saw at its samples.
#[derive(Debug, Default)]
struct Trace {
    /// Energy at the start, J.
    e0: f64,
    /// Deepest penetration, m (the lowest node is this far below the ground).
    max_penetration: f64,
    /// Largest `max |‖b‖ − l|`, m.
    max_length_error: f64,
    /// Largest energy increase between successive samples, J.
    max_energy_rise: f64,
    /// Largest energy change between successive samples, either sign, J.
    max_energy_step: f64,
    /// Largest `|E − E₀|`, J.
    max_energy_error: f64,
    /// Largest penalty energy, J.
    max_penalty_energy: f64,
    /// Times the structure went from no contact to contact.
    touchdowns: usize,
}

/// Runs `sim` to `time`, sampling every `sample` s.
fn track(sim: &mut Simulation, time: f64, sample: f64) -> Trace {
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
fn penetration_bound(weight: f64, stiffness: f64, e0: f64) -> f64 {
    (weight + (weight * weight + 2.0 * stiffness * e0).sqrt()) / stiffness
}

// ------------------------------------------------------------------ 1. dropped icosahedron

#[test]
fn dropped_icosahedron_comes_to_rest_on_the_ground() {
    let scene = icosahedron_over(
        ground(Vector3::z(), STIFFNESS, CONTACT_DAMPING, 0.5),
        DROP,
        Some(CABLE_DAMPING),
    );
    let weight = total_mass(&scene) * G;
    let impact_speed = (2.0 * G * DROP).sqrt();
    let time = 16.0;
    // Fixed steps the guard accepts: its contact bound is the viscous friction rate
    // μ W w / v_s = 0.5 · 58.86 N · 4 kg⁻¹ / 0.01 m/s ≈ 1.2e4 s⁻¹, so rk4 needs h ≤ 2.4e-4 s
    // and rattle h ≤ 1.7e-4 s.
    let mut deepest = Vec::new();
    for (method, step) in [
        (Method::Rk4, 2e-4),
        (Method::Dopri5, 1e-3),
        (Method::Rattle, 1e-4),
    ] {
        let mut sim =
            Simulation::new(Model::new(&with_solver(scene.clone(), method, step)).unwrap());
        assert!(
            sim.stability_problem().is_none(),
            "{}: the guard refuses {step} s",
            method.name()
        );
        let trace = track(&mut sim, time, SAMPLE);
        let bound = penetration_bound(weight, STIFFNESS, trace.e0);
        let ke = kinetic(&sim);
        let speed = max_speed(&sim);
        let sum = contact_sum(&sim);
        let vertical_error = (sum.z - weight).abs() / weight;
        let tangential = sum.xy().norm() / weight;
        let d: Vec<f64> = penetrations(&sim)
            .into_iter()
            .filter(|&d| d > 0.0)
            .collect();
        let d_static = weight / 3.0 / STIFFNESS;
        let share_error = d
            .iter()
            .map(|x| (x - d_static).abs() / d_static)
            .fold(0.0, f64::max);
        println!(
            "drop {DROP} m, {}: deepest penetration {:.3e} m (energy bound {bound:.3e} m), \
             largest energy rise between samples {:.1e} J, length error ≤ {:.1e} m; at {time} s: KE {ke:.1e} J, max speed {speed:.1e} m/s, \
             Σf = ({:.1e}, {:.1e}, {:.6}) N vs W = {weight:.2} N (vertical {vertical_error:.1e}, \
             tangential {tangential:.1e} relative), {} contacts at d/(W/3k) − 1 ≤ {share_error:.1e}, \
             {} steps, {} rejected",
            method.name(),
            trace.max_penetration,
            trace.max_energy_rise,
            trace.max_length_error,
            sum.x,
            sum.y,
            sum.z,
            d.len(),
            sim.stats().steps,
            sim.stats().rejected,
        );
        // The lowest node never sinks deeper than the energy allows.
        assert!(trace.max_penetration <= bound, "{}", trace.max_penetration);
        // Friction, contact and cable damping only dissipate, so E never rises beyond the
        // integrator's error: a step across the kink at d = 0 errs by about the penalty
        // energy of one step's travel, ½ k (v h)², v = √(2 g h_drop) the impact speed
        // (1.2e-3 J at 0.2 ms, 0.03 J at 1 ms; measured rises are round-off, ~5e-14 J).
        let allowance = 0.5 * STIFFNESS * (impact_speed * step).powi(2);
        assert!(
            trace.max_energy_rise <= allowance,
            "energy rose by {} J",
            trace.max_energy_rise
        );
        // The correction holds the bars at round-off through every impact.
        assert!(
            trace.max_length_error <= 1e-12,
            "{}",
            trace.max_length_error
        );
        // At rest: 17.7 J of kinetic energy at impact, 1.6e-15 J left after 16 s with every
        // method (the slowest mode, ~1.4 s period, decays by ~e⁻¹ per second); 1e-10 J and
        // 1e-5 m/s leave margin for a slightly slower decay.
        assert!(ke <= 1e-10, "kinetic energy {ke}");
        assert!(speed <= 1e-5, "max speed {speed}");
        // Newton for the whole structure (cable and bar forces are internal):
        // Σf_contact − W ẑ = M a_com, which vanishes at rest (measured 4.5e-9 W).
        assert!(vertical_error <= 1e-6, "vertical balance {vertical_error}");
        // Friction is viscous below v_s, μ f_n v_t / v_s, so at rest it vanishes with the
        // speed: |Σ f_t| ≤ μ W max|v| / v_s (2e-6 W at 3.5e-8 m/s; rk4 keeps the symmetric
        // state and measures round-off, dopri5 leaves 1e-9 m/s of tangential noise).
        assert!(
            tangential <= 0.5 * speed / 0.01,
            "tangential sum {tangential} at speed {speed}"
        );
        // Three-fold symmetry: the three face nodes carry W/3 each at d = W/(3k).
        assert_eq!(d.len(), 3, "contacts at rest: {d:?}");
        assert!(
            share_error <= 1e-6,
            "resting penetrations {d:?} vs {d_static}"
        );
        deepest.push(trace.max_penetration);
    }
    // The three methods integrate the same impacts: their deepest penetrations (8.5–8.6 mm,
    // sampled every ms) agree to 1 %, so none of them is thrown off by the non-smooth force.
    let (lo, hi) = (
        deepest.iter().copied().fold(f64::INFINITY, f64::min),
        deepest.iter().copied().fold(0.0, f64::max),
    );
    assert!(hi - lo <= 0.01 * hi, "deepest penetrations {deepest:?}");
}

// ------------------------------------------------------------------ 2. energy

#[test]
fn contact_energy_is_conserved_without_damping_and_dissipated_with_it() {
    // Frictionless elastic penalty, undamped cables: E = KE + cable strain + gravity + ½ k d²
    // is a first integral, so its error is the integrator's. One second holds 12
    // touchdowns (the first impact, rebounds and the rocking nodes' re-contacts); longer
    // undamped runs are chaotic, so runs at different steps stop being comparable.
    let elastic = icosahedron_over(ground(Vector3::z(), STIFFNESS, 0.0, 0.0), DROP, None);
    let time = 1.0;
    let runs = [
        (Method::Rk4, 1e-3),
        (Method::Rk4, 5e-4),
        (Method::Rk4, 2.5e-4),
        (Method::Rk4, 1.25e-4),
        (Method::Rattle, 1e-4),
        (Method::Dopri5, 1e-3),
    ];
    let mut errors = Vec::new();
    let mut reference = None;
    for (method, step) in runs {
        let scene = with_solver(elastic.clone(), method, step);
        let mut sim = Simulation::new(Model::new(&scene).unwrap());
        let trace = track(&mut sim, time, SAMPLE);
        let relative = trace.max_energy_error / trace.e0;
        println!(
            "elastic bounces, {} at {step} s: {} touchdowns in {time} s, peak penalty energy \
             {:.2} J, max |E − E₀|/E₀ = {relative:.2e}, length error ≤ {:.1e} m",
            method.name(),
            trace.touchdowns,
            trace.max_penalty_energy,
            trace.max_length_error
        );
        // It bounces, and the penalty term is a large part of the balance: leaving ½ k d²
        // out would be an error of this size (4.4 J), not of the integrator's.
        assert!(trace.touchdowns >= 10, "{} touchdowns", trace.touchdowns);
        assert!(trace.max_penalty_energy >= 100.0 * trace.max_energy_error);
        assert!(trace.max_length_error <= 1e-12);
        errors.push(relative);
        reference.get_or_insert(trace);
    }
    // rk4 at 1 ms: a step across the kink at d = 0 errs by at most about the penalty energy
    // of one step's travel, ½ k (v h)² ≈ 0.03 J ≈ 6e-4 E₀ at the impact speed 2.4 m/s;
    // the crossings' errors partly cancel (measured 2.3e-4).
    assert!(errors[0] <= 1e-3, "rk4 1 ms: {}", errors[0]);
    // The force is continuous with a kink, so a crossing step's local error is O(h³) and
    // the energy error second order: 1 ms → 0.125 ms should gain 64. Where the kink falls
    // within a step changes with h, so the ratio scatters (measured 42); ≥ 16 (order ≥ 4/3)
    // still tells integrator error from a modelling error, which would not shrink.
    assert!(
        errors[0] >= 16.0 * errors[3],
        "rk4 energy error does not converge: {errors:?}"
    );
    // Velocity Verlet's energy error is O((h ω)²) of the contact mode's energy, with
    // ω = √(k · 4/m) = 200 rad/s: (1e-4 · 200)² = 4e-4 of ≤ 4.4 J, i.e. ≤ 4e-5 E₀.
    assert!(errors[4] <= 4e-5, "rattle: {}", errors[4]);
    // dopri5 at rtol 1e-6 (steps rejected at the kinks until they meet it): ≤ 100 rtol.
    assert!(errors[5] <= 1e-4, "dopri5: {}", errors[5]);

    // The same drop with contact damping only: the energy never rises between samples by
    // more than the elastic run's integrator error over one sample at the same step (its
    // largest |ΔE| between samples), and the bounces die out.
    let reference = reference.unwrap();
    let damped = icosahedron_over(
        ground(Vector3::z(), STIFFNESS, CONTACT_DAMPING, 0.0),
        DROP,
        None,
    );
    let scene = with_solver(damped.clone(), Method::Rk4, 1e-3);
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    let time = 3.0;
    let trace = track(&mut sim, time, SAMPLE);
    let lost = trace.e0 - sim.energy();
    let drop_energy = total_mass(&damped) * G * DROP;
    println!(
        "contact damping {CONTACT_DAMPING} N·s/m, rk4 at 1 ms: largest rise between samples \
         {:.1e} J (elastic run's largest |ΔE| per sample {:.1e} J), {lost:.2} J dissipated in \
         {time} s (drop energy M g h = {drop_energy:.2} J), {} touchdowns",
        trace.max_energy_rise, reference.max_energy_step, trace.touchdowns
    );
    assert!(
        trace.max_energy_rise <= reference.max_energy_step,
        "energy rose by {}",
        trace.max_energy_rise
    );
    // Most of the impact energy goes: a well-damped contact barely rebounds.
    assert!(
        lost >= 0.5 * drop_energy,
        "dissipated {lost} of {drop_energy}"
    );
}

// ------------------------------------------------------------------ 3. friction

/// One horizontal 1 kg bar of 1 m along x, resting at its static penetration W/(2k) on each
/// end (so it starts in vertical equilibrium), both ends moving with `velocity`.
fn sliding_bar(friction: f64, velocity: [f64; 3]) -> Scene {
    let z = -G / 2.0 / STIFFNESS;
    let mut scene = builtin("icosahedron").unwrap();
    scene.nodes = vec![[-0.5, 0.0, z], [0.5, 0.0, z]];
    scene.bars = vec![BarSpec {
        nodes: [1, 2],
        mass: 1.0,
    }];
    scene.cables.clear();
    scene.fixed.clear();
    scene.force_inputs.clear();
    scene.prestress = None;
    scene.gravity = Some([0.0, 0.0, -G]);
    scene.velocities = Some(vec![velocity; 2]);
    scene.ground = Some(ground(Vector3::z(), STIFFNESS, CONTACT_DAMPING, friction));
    with_solver(scene, Method::Rk4, 5e-4)
}

#[test]
fn friction_decelerates_a_slider_at_mu_g() {
    let mu = 0.5;
    let slip = 0.01;
    let v0 = Vector3::new(0.6, 0.8, 0.0); // 1 m/s, along and across the bar at once
    let mut sim = Simulation::new(Model::new(&sliding_bar(mu, v0.into())).unwrap());
    assert!(sim.stability_problem().is_none());
    let mass = 1.0;
    // Both ends slide faster than v_s until t = (|v₀| − v_s)/(μ g) ≈ 0.202 s; the
    // friction resultant μ Σ f_n = μ W acts at ground level through the bar's line, so no
    // moment shifts the load and the deceleration is exactly μ g in that window.
    let (t1, t2) = (0.05, 0.15);
    sim.advance_to(t1).unwrap();
    sim.refresh();
    let p1 = sim.linear_momentum();
    sim.advance_to(t2).unwrap();
    sim.refresh();
    let p2 = sim.linear_momentum();
    let deceleration = (p1 - p2).xy() / (mass * (t2 - t1));
    let direction_error = deceleration.normalize().dot(&v0.xy().normalize()) - 1.0;
    let relative = (deceleration.norm() - mu * G).abs() / (mu * G);
    // Stopping distance: (|v₀|² − v_s²)/(2 μ g) while sliding, then the viscous tail
    // v̇ = −(μ g / v_s) v covers v_s / (μ g / v_s): (|v₀|² + v_s²)/(2 μ g) in all.
    sim.advance_to(1.0).unwrap();
    sim.refresh();
    let centre = (sim.node_position(0) + sim.node_position(1)) / 2.0;
    let travelled = centre.xy().norm();
    let predicted = (v0.norm_squared() + slip * slip) / (2.0 * mu * G);
    let speed = max_speed(&sim);
    println!(
        "bar sliding at 1 m/s, μ = {mu}: deceleration {:.9} m/s² vs μ g = {:.9} (relative \
         {relative:.1e}, direction {direction_error:.1e}); stopped after {travelled:.9} m vs \
         (v₀² + v_s²)/(2 μ g) = {predicted:.9} m, speed at 1 s {speed:.1e} m/s",
        deceleration.norm(),
        mu * G
    );
    // Constant force, so rk4 integrates the sliding phase exactly up to round-off.
    assert!(relative <= 1e-9, "deceleration {deceleration:?}");
    assert!(direction_error.abs() <= 1e-12);
    // The kink at |v_t| = v_s costs rk4 O(h²)-small errors in the distance.
    assert!(
        (travelled - predicted).abs() <= 1e-4 * predicted,
        "{travelled} vs {predicted}"
    );
    // The viscous tail decays at μ g / v_s ≈ 490 s⁻¹: at rest long before 1 s.
    assert!(speed <= 1e-9, "{speed}");

    // Frictionless: only normal (vertical) forces, so the horizontal momentum is kept.
    let mut sim = Simulation::new(Model::new(&sliding_bar(0.0, v0.into())).unwrap());
    let p0 = sim.linear_momentum();
    sim.advance_to(1.0).unwrap();
    sim.refresh();
    let drift = (sim.linear_momentum() - p0).xy().norm() / p0.xy().norm();
    println!("frictionless bar: horizontal momentum drift {drift:.1e} over 1 s");
    assert!(drift <= 1e-13, "{drift}");

    // The icosahedron on a face, pushed at 1 m/s: every contact point that slides faster
    // than v_s carries exactly |f_t| = μ f_n against its own tangential velocity. The
    // body's deceleration is not μ g here: it settles onto its contacts while it slides
    // (Σ f_n ≠ W over the window) and the landing spreads the contact nodes radially, so
    // their friction forces are not parallel (|Σ f_t| < Σ |f_t|); both are printed.
    let mu = 0.1;
    let mut scene = icosahedron_over(
        ground(Vector3::z(), STIFFNESS, CONTACT_DAMPING, mu),
        0.0,
        Some(CABLE_DAMPING),
    );
    scene.velocities = Some(vec![v0.into(); scene.nodes.len()]);
    let mut sim = Simulation::new(Model::new(&with_solver(scene, Method::Rk4, 2e-4)).unwrap());
    let (mut normal, mut sum_of_norms, mut sliding, mut worst) = (0.0, 0.0, 0usize, 0.0f64);
    let mut norm_of_sum = 0.0;
    for k in 1..=900 {
        sim.advance_to(k as f64 * SAMPLE).unwrap();
        sim.refresh();
        let ground = sim.model().ground.as_ref().unwrap();
        let ws = sim.workspace();
        for (f, &(n, _)) in ws.contact_force.iter().zip(&ground.nodes) {
            let v = ws.node_vel[n];
            let vt = v - ground.normal * ground.normal.dot(&v);
            let (f_n, f_t) = (
                f.dot(&ground.normal),
                f - ground.normal * f.dot(&ground.normal),
            );
            if f_n > 0.0 && vt.norm() > slip {
                sliding += 1;
                let expected = -vt.normalize() * mu * f_n;
                worst = worst.max((f_t - expected).norm() / f_n);
            }
            normal += f_n;
            sum_of_norms += f_t.norm();
        }
        norm_of_sum += contact_sum(&sim).xy().norm();
    }
    println!(
        "icosahedron sliding at 1 m/s, μ = {mu}, 0.9 s: {sliding} sliding contact samples, \
         largest |f_t + μ f_n v_t/|v_t||/f_n = {worst:.1e}; over the samples μ Σ f_n = \
         {:.1} N, Σ |f_t| = {sum_of_norms:.1} N, |Σ f_t| = {norm_of_sum:.1} N",
        mu * normal
    );
    assert!(sliding >= 1000, "{sliding}");
    assert!(worst <= 1e-12, "{worst}");
    assert!(norm_of_sum <= sum_of_norms * (1.0 + 1e-12));
}

// ------------------------------------------------------------------ 4. tilted plane

/// Centre of mass, m.
fn centre_of_mass(sim: &Simulation) -> Vector3<f64> {
    let model = sim.model();
    let mass: f64 = model.bars.iter().map(|b| b.mass).sum();
    model
        .bars
        .iter()
        .map(|b| (sim.node_position(b.nodes[0]) + sim.node_position(b.nodes[1])) * (b.mass / 2.0))
        .sum::<Vector3<f64>>()
        / mass
}

/// A 10° slope, normal (0, sin 10°, cos 10°). With μ = 0.5 > tan 10° ≈ 0.176 Coulomb
/// friction would hold the icosahedron still; the regularised law has no sticking, so the
/// body creeps at the speed where the viscous friction μ f_n v / v_s of all contacts, each
/// creeping at v < v_s, carries the downhill weight: μ W cos θ v / v_s = W sin θ, i.e.
/// v = v_s tan θ / μ = 3.5 mm/s (0.35 mm/s with v_s = 1 mm/s). With μ = 0.1 < tan 10° it
/// slides at g (sin θ − μ cos θ).
#[test]
fn tilted_plane_holds_the_icosahedron_up_to_the_regularised_creep() {
    let theta = 10f64.to_radians();
    let normal = Vector3::new(0.0, theta.sin(), theta.cos());
    let downhill = Vector3::new(0.0, theta.cos(), -theta.sin());
    let slip = 0.01;
    for mu in [0.5, 0.1] {
        let scene = icosahedron_over(
            ground(normal, STIFFNESS, CONTACT_DAMPING, mu),
            0.01,
            Some(CABLE_DAMPING),
        );
        let weight = total_mass(&scene) * G;
        let mass = total_mass(&scene);
        let scene = with_solver(scene, Method::Rk4, 2e-4);
        let mut sim = Simulation::new(Model::new(&scene).unwrap());
        assert!(sim.stability_problem().is_none());
        // Settled after 10 s (the level drop's KE is ~1e-10 J by then); measure over 2 s.
        let (t1, t2) = (10.0, 12.0);
        sim.advance_to(t1).unwrap();
        sim.refresh();
        let (x1, p1) = (centre_of_mass(&sim), sim.linear_momentum());
        sim.advance_to(t2).unwrap();
        sim.refresh();
        let (x2, p2) = (centre_of_mass(&sim), sim.linear_momentum());
        let velocity = (x2 - x1) / (t2 - t1);
        let along = velocity.dot(&downhill);
        let across = (velocity - downhill * along).norm();
        let acceleration = (p2 - p1).dot(&downhill) / (mass * (t2 - t1));
        let balance = (contact_sum(&sim) - Vector3::new(0.0, 0.0, weight)).norm() / weight;
        let creep = slip * theta.tan() / mu;
        let sliding = G * (theta.sin() - mu * theta.cos());
        println!(
            "10° slope, μ = {mu}: from {t1} to {t2} s mean speed down the slope {along:.6e} m/s \
             (v_s tan θ / μ = {creep:.6e}), across {across:.1e} m/s, acceleration \
             {acceleration:.6e} m/s² (g (sin θ − μ cos θ) = {sliding:.6e}), |Σf + M g|/W = \
             {balance:.1e}, largest node speed {:.3e} m/s",
            max_speed(&sim)
        );
        if mu > theta.tan() {
            // Steady creep at the predicted speed (the last 5e-4 is residual settling), in
            // the viscous regime (every node slower than v_s), straight down the slope.
            assert!(
                (along - creep).abs() <= 1e-2 * creep,
                "creep {along} vs {creep}"
            );
            assert!(max_speed(&sim) < slip);
            assert!(across <= 1e-2 * creep, "sideways {across}");
            // Uniform motion: the contact forces carry the weight, Σf = −M g, to the
            // settled state's residual acceleration (measured 4e-8 W).
            assert!(balance <= 1e-6, "{balance}");
        } else {
            // Every contact slides faster than v_s the same way, so Σ f_t = μ Σ f_n and
            // Σ f_n = W cos θ once settled: Coulomb's sliding block, to 1e-4.
            assert!(
                (acceleration - sliding).abs() <= 1e-4 * sliding,
                "{acceleration} vs {sliding}"
            );
            assert!(across <= 1e-3 * along, "sideways {across}");
        }
    }
}

// ------------------------------------------------------------------ 5. validation

/// Makes one `[ground]` key invalid.
type Spoil = fn(&mut GroundSpec);

#[test]
fn invalid_ground_keys_are_named() {
    let base = icosahedron_over(ground(Vector3::z(), STIFFNESS, 0.0, 0.5), DROP, None);
    let cases: [(&str, Spoil); 9] = [
        ("ground.stiffness", |g| g.stiffness = 0.0),
        ("ground.stiffness", |g| g.stiffness = -1e4),
        ("ground.stiffness", |g| g.stiffness = f64::INFINITY),
        ("ground.normal", |g| g.normal = [0.0; 3]),
        ("ground.normal", |g| g.normal = [0.0, f64::NAN, 1.0]),
        ("ground.height", |g| g.height = f64::NAN),
        ("ground.friction", |g| g.friction = -0.1),
        ("ground.damping", |g| g.damping = -1.0),
        ("ground.slip_velocity", |g| g.slip_velocity = 0.0),
    ];
    for (key, spoil) in cases {
        let mut scene = base.clone();
        spoil(scene.ground.as_mut().unwrap());
        let err = Model::new(&scene).expect_err(key).to_string();
        println!("{err}");
        assert!(err.starts_with(key), "expected {key}: {err}");
    }
    // The defaults (normal +z, slip velocity 1 cm/s) fill in from a scene file.
    let mut text = builtin("icosahedron").unwrap().to_toml_string();
    text.push_str("\n[ground]\nheight = -1.0\nstiffness = 1e4\n");
    let scene = Scene::from_toml_str(&text).unwrap();
    let model = Model::new(&scene).unwrap();
    let g = model.ground.as_ref().unwrap();
    assert_eq!(
        (g.normal, g.slip_velocity, g.friction),
        (Vector3::z(), 0.01, 0.0)
    );
    // Contact points: the free bar ends only (the built-in pins nodes 1, 5, 9).
    assert_eq!(g.nodes.len(), 12 - 3);
}

// ------------------------------------------------------------------ 6. stability guard

#[test]
fn stiff_contact_refuses_a_large_rk4_step_and_dopri5_runs_it() {
    let stiffness = 1e8;
    let scene = icosahedron_over(
        ground(Vector3::z(), stiffness, CONTACT_DAMPING, 0.5),
        DROP,
        Some(CABLE_DAMPING),
    );
    let weight = total_mass(&scene) * G;
    // The contact bound: √(k w) + c w with the end compliance w = 4/m = 4 kg⁻¹ is
    // 2e4 + 400 s⁻¹, so rk4 needs h ≤ 2√2 / 2.04e4 ≈ 1.4e-4 s; 1 ms is 7× too large. The
    // power iteration cannot see it: the structure is in the air when the check runs.
    let mut sim =
        Simulation::new(Model::new(&with_solver(scene.clone(), Method::Rk4, 1e-3)).unwrap());
    let why = sim
        .stability_problem()
        .expect("1 ms is above the contact bound");
    println!("rk4 at 1 ms on a 1e8 N/m ground: {why}");
    assert!(
        why.contains("solver.step_size") && why.contains("dopri5"),
        "{why}"
    );
    let before = sim.state().clone();
    let refused = sim.advance_to(0.5).unwrap_err();
    assert!(matches!(refused, StepError::Unstable { .. }), "{refused:?}");
    assert!(
        refused.to_string().contains("solver.step_size"),
        "{refused}"
    );
    assert_eq!(sim.state(), &before);
    // Without the guard the same run does blow up (or the drop would not need it).
    let mut unguarded =
        Simulation::new(Model::new(&with_solver(scene.clone(), Method::Rk4, 1e-3)).unwrap());
    unguarded.guard_stability = false;
    let e0 = unguarded.energy();
    let outcome = unguarded.advance_to(0.5);
    unguarded.refresh();
    let e = unguarded.energy();
    println!(
        "unguarded rk4 at 1 ms: {:?}, energy {e0:.2} J → {e:.3e} J",
        outcome.as_ref().map_err(|e| e.to_string())
    );
    // Nothing may add energy to this drop; the unstable penalty oscillator does (h ω ≈ 20).
    assert!(
        outcome.is_err() || !e.is_finite() || e > 2.0 * e0,
        "{outcome:?}, {e}"
    );
    // Rattle's bound (h ω ≤ 2) refuses the same step.
    let rattle = with_solver(sim.model().scene.clone(), Method::Rattle, 1e-3);
    let mut sim = Simulation::new(Model::new(&rattle).unwrap());
    assert!(matches!(
        sim.advance_to(0.5),
        Err(StepError::Unstable { .. })
    ));

    // dopri5 takes its own steps through the same drop and impact.
    let mut sim = Simulation::new(Model::new(&with_solver(scene, Method::Dopri5, 1e-3)).unwrap());
    assert!(sim.stability_problem().is_none());
    // Contact on 1e8 N/m lasts π√(0.25/1e8) ≈ 0.16 ms: sample every 10 µs.
    let trace = track(&mut sim, 0.5, 1e-5);
    let bound = penetration_bound(weight, stiffness, trace.e0);
    println!(
        "dopri5 on a 1e8 N/m ground: deepest penetration {:.3e} m (energy bound {bound:.3e} m), \
         largest energy rise between samples {:.1e} J, length error ≤ {:.1e} m, {} steps, {} \
         rejected",
        trace.max_penetration,
        trace.max_energy_rise,
        trace.max_length_error,
        sim.stats().steps,
        sim.stats().rejected
    );
    assert!(trace.touchdowns >= 1);
    assert!(trace.max_penetration <= bound);
    assert!(trace.max_length_error <= 1e-12);
}
