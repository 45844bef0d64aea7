//! Ground contact (penalty normal force + regularised Coulomb friction): a dropped
//! icosahedron comes to rest with every integrator, the penalty energy closes the energy
//! balance, invalid `[ground]` keys are named, and the fixed-step guard refuses a step above
//! the contact bound. Friction and the tilted plane are in `tests/ground_friction.rs`.
//! Figures are printed (run with `--nocapture`).

mod ground_support;

use ground_support::*;
use nalgebra::Vector3;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, GroundSpec, Scene};
use tensegrity_fmu::{Model, Simulation, StepError};

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
