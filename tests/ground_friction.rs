//! Ground friction (regularised Coulomb): friction decelerates a slider at μ g, and a
//! tilted plane holds a body up to the regularisation's creep. Figures are printed (run
//! with `--nocapture`).

mod ground_support;

use ground_support::*;
use nalgebra::Vector3;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, BarSpec, Scene};
use tensegrity_fmu::{Model, Simulation};

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
        radius: 0.0,
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
