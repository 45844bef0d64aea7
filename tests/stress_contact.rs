//! Stress suite, library half: the contact cases (terrain and collisions). As in
//! tests/stress.rs, every test appends one JSON line per (case, method) to
//! `$STRESS_RESULTS` before asserting; `tests/stress.sh` runs both files.

// Shared with tests/stress.rs, which uses the rest of it.
#[allow(dead_code)]
mod stress_support;
mod terrain_support;

use nalgebra::Vector3;
use stress_support::*;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{BarSpec, FrictionModel, Scene, TerrainKind, TerrainSpec};
use terrain_support::{prism_scene, G};

/// Check: the icosahedron with 2 cm capsules dropped across the edge of a 15 cm box step
/// onto the ground (fmu/scenes/icosahedron-step.toml), 2 s, with rk4 at 0.1 ms (inside
/// the limit the collisions' friction sets), dopri5 at 1e-8 and sdirk3 at 0.5 ms (at 1 ms
/// its Newton iteration fails where an end lands on the ground at 1.9 m/s): no step
/// error, finite, exact constraints; no capsule sinks through the ground (the lowest node
/// stays above the radius less 3 W / k, three times the whole weight on one contact); it
/// lands on the step (a box contact); its energy at 2 s is below the start's (damped
/// contacts and friction only take energy away).
#[test]
fn six_bar_dropped_onto_a_box_step() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fmu/scenes/icosahedron-step.toml"
    );
    let scene = Scene::from_file(std::path::Path::new(path)).expect("the shipped scene");
    let weight = 6.0 * 9.81;
    let floor = 0.02 - 3.0 * weight / 1e4;
    let mut rows = Vec::new();
    for (method, h, tol) in [
        (Method::Rk4, 1e-4, 1e-6),
        (Method::Dopri5, 1e-3, 1e-8),
        (Method::Sdirk3, 5e-4, 1e-6),
    ] {
        let mut sim = build(&with_solver(scene.clone(), method, h, tol));
        sim.refresh();
        let start_energy = sim.energy();
        let mut t = Tracker::new(&mut sim);
        let (mut lowest, mut on_step) = (f64::INFINITY, 0u32);
        let _ = t.run(&mut sim, 2.0, 1e-2, |sim, _| {
            lowest = (0..12)
                .map(|n| sim.node_position(n).z)
                .fold(lowest, f64::min);
            on_step = on_step.max(sim.shape_load(1).contacts);
        });
        sim.refresh();
        let spent = 1.0 - sim.energy() / start_energy;
        let mut o =
            Outcome::from_tracker("six_bar_dropped_onto_a_box_step", method.name(), &t, false);
        o.check_exact()
            .check(t.error.is_none(), "no step error")
            .check(lowest > floor, "lowest node above r - 3 W/k")
            .check(on_step > 0, "it lands on the step")
            .check(spent > 0.0, "energy at 2 s below the start's");
        o.note(format!(
            "lowest node {} m (floor {}), energy spent by 2 s {:.1} %, {} steps",
            sci(lowest),
            sci(floor),
            100.0 * spent,
            sim.stats().steps
        ));
        rows.push(o);
    }
    report(&rows);
}

/// Check: a 2 kg bar with 5 cm capsule across two boxes, its ends overhanging both, 10 s
/// with each method: from 1 s on, both ends stay at box top + radius − m g / (4 k) (the
/// four edges it crosses share the weight) to 1e-7 m; exact constraints.
#[test]
fn bar_resting_on_two_supports() {
    let (k, m, r) = (1e5, 2.0, 0.05);
    let shape = |x: f64| TerrainSpec {
        kind: TerrainKind::Box,
        point: None,
        normal: None,
        center: Some([x, 0.0, 0.25]),
        size: Some([0.4, 1.0, 0.5]),
        yaw: None,
        file: None,
        heights: None,
        origin: None,
        spacing: None,
        stiffness: k,
        damping: 400.0,
        friction: 0.5,
        slip_velocity: 0.01,
        friction_model: FrictionModel::default(),
    };
    let mut scene = bare(
        "bar_on_two_supports",
        vec![[-1.0, 0.0, 0.55], [1.0, 0.0, 0.55]],
        vec![],
    );
    scene.bars = vec![BarSpec {
        nodes: [1, 2],
        mass: m,
        radius: r,
    }];
    scene.gravity = Some([0.0, 0.0, -9.81]);
    scene.terrain = vec![shape(-0.6), shape(0.6)];
    let expected = 0.5 + r - m * 9.81 / (4.0 * k);
    let mut rows = Vec::new();
    for (method, h, tol) in methods(1e-9) {
        let mut sim = build(&with_solver(scene.clone(), method, h, tol));
        let mut t = Tracker::new(&mut sim);
        let mut off = 0.0f64;
        let _ = t.run(&mut sim, 10.0, 1e-2, |sim, time| {
            if time >= 1.0 {
                off = (0..2)
                    .map(|n| (sim.node_position(n).z - expected).abs())
                    .fold(off, f64::max);
            }
        });
        let mut o = Outcome::from_tracker("bar_resting_on_two_supports", method.name(), &t, false);
        o.check_exact()
            .check(t.error.is_none(), "no step error")
            .check(off <= 1e-7, "ends at top + r - m g/(4k) to 1e-7 m");
        o.note(format!(
            "ends off top + r - m g/(4k) by at most {} m from 1 s to 10 s",
            sci(off)
        ));
        rows.push(o);
    }
    report(&rows);
}

/// Check: the damped prism (3 × 1 kg bars, stick–slip friction μ 0.5, k 1e5 N/m) on a
/// plane just below its friction angle (tan θ = 0.95 μ) and just above it (1.05 μ), 20 s
/// and 4 s with each method (rk4 at 0.25 ms and rattle at 0.1 ms: at 1 ms, ten steps per
/// period of the sticking springs, the prism below the angle ratchets down the slope by
/// centimetres in 10 s; rattle at 0.25 ms creeps 17 µm): below, its centre moves less than 1e-6 m from 10 s to 20 s; above, it
/// accelerates at g (sin θ − μ cos θ) within 2 % between 2 s and 4 s; exact constraints.
#[test]
fn prism_at_the_friction_angle() {
    let mu: f64 = 0.5;
    let mut rows = Vec::new();
    for (ratio, case) in [
        (0.95, "prism_just_below_the_friction_angle"),
        (1.05, "prism_just_above_the_friction_angle"),
    ] {
        let theta = (ratio * mu).atan();
        let downhill = Vector3::new(-theta.cos(), 0.0, -theta.sin());
        let scene = prism_scene(theta, mu, false, "", 300.0);
        for (method, h, tol) in methods(1e-9) {
            let h = match method {
                Method::Rk4 => 2.5e-4,
                Method::Rattle => 1e-4,
                _ => h,
            };
            let mut sim = build(&with_solver(scene.clone(), method, h, tol));
            let mut t = Tracker::new(&mut sim);
            let (mut at10, mut v2) = (Vector3::zeros(), 0.0);
            let end = if ratio < 1.0 { 20.0 } else { 4.0 };
            let _ = t.run(&mut sim, end, 1e-2, |sim, time| {
                if (time - 10.0).abs() < 1e-9 {
                    at10 = centre(sim);
                }
                if (time - 2.0).abs() < 1e-9 {
                    sim.refresh();
                    v2 = sim.linear_momentum().dot(&downhill) / 3.0;
                }
            });
            let mut o = Outcome::from_tracker(case, method.name(), &t, false);
            o.check_exact().check(t.error.is_none(), "no step error");
            if ratio < 1.0 {
                let moved = (centre(&sim) - at10).norm();
                o.check(moved < 1e-6, "moves < 1e-6 m from 10 s to 20 s");
                o.note(format!("centre moves {} m from 10 s to 20 s", sci(moved)));
            } else {
                sim.refresh();
                let v4 = sim.linear_momentum().dot(&downhill) / 3.0;
                let a = (v4 - v2) / 2.0;
                let expected = G * (theta.sin() - mu * theta.cos());
                let off = (a - expected) / expected;
                o.check(off.abs() < 0.02, "a = g (sin θ − μ cos θ) within 2 %");
                o.note(format!(
                    "a = {a:.5} m/s², g (sin θ − μ cos θ) = {expected:.5} ({:+.2} %)",
                    100.0 * off
                ));
            }
            rows.push(o);
        }
    }
    report(&rows);
}
