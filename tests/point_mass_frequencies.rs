//! Point masses (payloads) at nodes: small-oscillation frequencies held to hand
//! linearizations, made independently of the code: a compound pendulum under gravity and a
//! bar held by two prestressed cables (an axial and a purely geometric-stiffness mode),
//! each with and without payloads, and the ratio ω(p)/ω(0). The KKT, conservation and
//! validation tests of payloads are in tests/point_masses.rs.
//!
//! Scenes are written as JSON text and parsed by `Scene::from_json_str`, so the scene key
//! `point_masses` itself is exercised. Figures are printed (run with `--nocapture`).

#[allow(dead_code)] // only the step `H` is used here
mod kkt_support;
mod point_mass_support;

use kkt_support::H;
use point_mass_support::{cable_held_bar, scene_from, CABLE_BAR};
use serde_json::json;
use std::f64::consts::PI;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::{Model, Scene, Simulation};

/// Mean period of a sampled signal `(t, y)` oscillating about 0, from its zero crossings
/// (linearly interpolated between samples). Returns the period and the crossing count.
///
/// Linear interpolation of `A sin ωt` around a root is exact to second order (the second
/// derivative vanishes there): with the root δ₁ after one sample and δ₂ before the next,
/// the crossing time is off by `ω² δ₁ δ₂ (δ₂ − δ₁) / 6 ≤ ω² h³ / 62`, i.e. 3e-10 s at
/// ω = 4 rad/s and 5e-8 s at ω = 55 rad/s for h = 1 ms. The period comes from the span
/// between the first and last of ≥ 10 crossings, which divides that by ≥ 5 periods.
fn mean_period(samples: &[(f64, f64)]) -> (f64, usize) {
    let mut crossings = Vec::new();
    for w in samples.windows(2) {
        let ((t0, y0), (t1, y1)) = (w[0], w[1]);
        if (y0 < 0.0 && y1 >= 0.0) || (y0 > 0.0 && y1 <= 0.0) {
            crossings.push(t0 + (t1 - t0) * y0 / (y0 - y1));
        }
    }
    let n = crossings.len();
    assert!(n >= 10, "only {n} zero crossings");
    (2.0 * (crossings[n - 1] - crossings[0]) / (n - 1) as f64, n)
}

/// Runs `scene` for `time` at step `H` (RK4 with the correction) and samples `probe`
/// after every step.
fn sample(scene: &Scene, time: f64, probe: impl Fn(&Simulation) -> f64) -> Vec<(f64, f64)> {
    let mut scene = scene.clone();
    scene.solver.method = Method::Rk4;
    let mut sim = Simulation::new(Model::new(&scene).expect("scene builds"));
    assert!(
        !sim.warnings().iter().any(|w| w.contains("projected")),
        "the start velocities must satisfy the constraints: {:?}",
        sim.warnings()
    );
    let steps = (time / H).ceil() as u64;
    let mut out = Vec::with_capacity(steps as usize + 1);
    out.push((0.0, probe(&sim)));
    for k in 0..steps {
        let (t, t_next) = (k as f64 * H, (k + 1) as f64 * H);
        sim.step_to(t, t_next).expect("step");
        sim.refresh();
        out.push((t_next, probe(&sim)));
    }
    out
}

/// Arithmetic-geometric mean.
fn agm(mut a: f64, mut b: f64) -> f64 {
    for _ in 0..64 {
        let (a1, b1) = ((a + b) / 2.0, (a * b).sqrt());
        a = a1;
        b = b1;
        if (a - b).abs() <= 1e-16 * a {
            break;
        }
    }
    a
}

/// One bar (length `L`, mass `m`) pinned at node 1, released at rest at `theta0` from the
/// downward vertical in the x–z plane, gravity −g ẑ, payload `p` at the free end (node 2);
/// `p = None` writes no `point_masses` key at all.
fn pendulum(l: f64, m: f64, g: f64, theta0: f64, p: Option<f64>) -> Scene {
    let mut s = json!({
        "name": "compound-pendulum",
        "nodes": [[0.0, 0.0, 0.0], [l * theta0.sin(), 0.0, -l * theta0.cos()]],
        "fixed": [1],
        "gravity": [0.0, 0.0, -g],
        "bars": [{ "nodes": [1, 2], "mass": m }],
    });
    if let Some(p) = p {
        s["point_masses"] = json!([{ "node": 2, "mass": p }]);
    }
    scene_from(&s)
}

/// A compound pendulum is `I θ̈ = −(m L/2 + p L) g sin θ` with `I = m L²/3 + p L²` about
/// the pin (the rod's weight acts at its centre, the payload's at the tip), so
/// `ω₀² = g (m L/2 + p L) / (m L²/3 + p L²)` for small swings. At amplitude θ₀ the exact
/// period is `T = 2π / (ω₀ AGM(1, cos(θ₀/2)))` (complete elliptic integral), i.e.
/// `T/T_lin − 1 = θ₀²/16 + 11 θ₀⁴/3072 + …`.
#[test]
fn pendulum_frequency_matches_linearization_with_payloads() {
    let (l, m, g, theta0) = (0.8, 1.2, 9.81, 0.02);
    let amplitude_correction = theta0 * theta0 / 16.0; // 2.5e-5
    let omega_lin = |p: f64| (g * (m * l / 2.0 + p * l) / (m * l * l / 3.0 + p * l * l)).sqrt();
    let mut omega_measured = Vec::new();
    for p in [0.0, 0.25, 1.0, 4.0] {
        let scene = pendulum(l, m, g, theta0, (p > 0.0).then_some(p));
        let t_lin = 2.0 * PI / omega_lin(p);
        let t_exact = t_lin / agm(1.0, (theta0 / 2.0).cos());
        let samples = sample(&scene, 6.3 * t_lin, |sim| {
            let x = sim.node_position(1);
            x.x.atan2(-x.z)
        });
        let (period, crossings) = mean_period(&samples);
        let vs_exact = period / t_exact - 1.0;
        let vs_lin = period / t_lin - 1.0;
        println!(
            "pendulum p = {p} kg: T = {period:.9} s over {crossings} crossings; linearized \
             {t_lin:.9} s (T/T_lin − 1 = {vs_lin:.4e}, θ₀²/16 = {amplitude_correction:.4e}); \
             exact finite-amplitude {t_exact:.9} s (rel. error {vs_exact:.2e})"
        );
        // Against the exact finite-amplitude period nothing is left but RK4's phase error,
        // ≈ (ωh)⁴/120 ≈ 2e-12 per period, and the interpolation error (≲ 1e-9 relative;
        // measured ≤ 5e-11 in all): 1e-8 is 2,500× below the amplitude effect θ₀²/16.
        assert!(
            vs_exact.abs() <= 1e-8,
            "p = {p}: period off by {vs_exact:e}"
        );
        // Against the linearization the measured excess is the amplitude correction
        // θ₀²/16 (the θ₀⁴ term is 6e-10): within 1 % of it.
        assert!(
            (vs_lin - amplitude_correction).abs() <= 0.01 * amplitude_correction,
            "p = {p}: T/T_lin − 1 = {vs_lin:e}, expected θ₀²/16 = {amplitude_correction:e}"
        );
        omega_measured.push((p, 2.0 * PI / period));
    }
    let (_, w0) = omega_measured[0];
    for &(p, w) in &omega_measured[1..] {
        let predicted = omega_lin(p) / omega_lin(0.0);
        let rel = (w / w0) / predicted - 1.0;
        println!(
            "pendulum p = {p} kg: ω(p)/ω(0) = {:.9}, predicted {predicted:.9} (rel. error {rel:.2e})",
            w / w0
        );
        // The same θ₀ scales every period by the same elliptic factor, so it cancels in
        // the ratio; what remains is the ≲ 1e-9 timing error (measured ≤ 9e-11). The
        // payload effect is ≥ 6 % (p = 0.25 kg), so 1e-8 is far below it.
        assert!(rel.abs() <= 1e-8, "p = {p}: ratio off by {rel:e}");
        assert!(1.0 - predicted > 0.03, "the payload must change ω visibly");
    }
}

/// Hand linearization of [`cable_held_bar`]. The tip moves on the sphere |x| = L; the bar's
/// kinetic energy about the pin is `½ I θ̇²` with `I = m L²/3 + p L²`. Each cable stores
/// `½ κ (|s| − s₀)²`, so `V'' = κ (|s|')² + T₀ |s|''` per cable at the equilibrium:
/// - vertical mode (rotation about ŷ, tip z = L sin θ): `|s_up|² = L²(1−cos θ)² +
///   (H − L sin θ)² = (H − Lθ)² + O(θ³)`, so `|s|' = ∓L`, `|s|'' = 0`: `V'' = 2 κ L²`,
///   `ω² = 2κ / (m/3 + p)` (the prestress drops out);
/// - lateral mode (rotation about ẑ, tip y = L sin φ): `|s| = √(H² + L² φ²) + O(φ⁴)`, so
///   `|s|' = 0`, `|s|'' = L²/H`: `V'' = 2 T₀ L²/H`, `ω² = 2 T₀ / (H (m/3 + p))`, a pure
///   geometric (prestress) stiffness.
fn cable_bar_omega(p: f64, lateral: bool) -> f64 {
    let (_, m, h, k, s0) = CABLE_BAR;
    let t0 = k * (h - s0);
    let stiffness = if lateral { 2.0 * t0 / h } else { 2.0 * k };
    (stiffness / (m / 3.0 + p)).sqrt()
}

#[test]
fn cable_held_bar_frequencies_match_linearization_with_payloads() {
    // Tip speed 5 mm/s. Axial mode: amplitudes 0.09–0.24 mm (θ ≤ 2.4e-4 rad); the neglected
    // terms are relative O(θ² (L/H)²) ≤ 2.4e-7 and RK4's phase error (ωh)⁴/120 ≤ 8e-8
    // (ω ≤ 55 rad/s): tolerance 1e-6 (measured ≤ 4e-8). Geometric mode: amplitudes
    // A = 0.29–0.77 mm; the tension change κ A²/(2H) at the amplitude is a relative
    // ≤ 1.2e-5 of T₀, and the frequency shift is of that order: tolerance 5e-5 (measured
    // ≤ 4e-6, growing with A as expected). Both are ≥ 7,000× below the smallest payload
    // effect (1 − ω(p)/ω(0) = 37 %).
    let speed = 5e-3;
    for (lateral, mode, tol) in [(false, "axial (z)", 1e-6), (true, "geometric (y)", 5e-5)] {
        let velocity = if lateral {
            [0.0, speed, 0.0]
        } else {
            [0.0, 0.0, speed]
        };
        let mut w0 = 0.0;
        for p in [0.0, 0.5, 2.0] {
            let scene = cable_held_bar((p > 0.0).then_some(p), velocity);
            let predicted = cable_bar_omega(p, lateral);
            let samples = sample(&scene, 12.0 * 2.0 * PI / predicted, |sim| {
                let x = sim.node_position(1);
                if lateral {
                    x.y
                } else {
                    x.z
                }
            });
            let (period, crossings) = mean_period(&samples);
            let w = 2.0 * PI / period;
            let rel = w / predicted - 1.0;
            println!(
                "cable-held bar, {mode} mode, p = {p} kg: ω = {w:.6} rad/s over {crossings} \
                 crossings, predicted {predicted:.6} (rel. error {rel:.2e})"
            );
            assert!(rel.abs() <= tol, "{mode}, p = {p}: ω off by {rel:e}");
            if p == 0.0 {
                w0 = w;
            } else {
                let ratio = cable_bar_omega(p, lateral) / cable_bar_omega(0.0, lateral);
                let rel = (w / w0) / ratio - 1.0;
                println!(
                    "cable-held bar, {mode} mode, p = {p} kg: ω(p)/ω(0) = {:.6}, predicted \
                     √((m/3)/(m/3 + p)) = {ratio:.6} (rel. error {rel:.2e})",
                    w / w0
                );
                assert!(rel.abs() <= tol, "{mode}, p = {p}: ratio off by {rel:e}");
                assert!(1.0 - ratio > 0.3, "the payload must change ω visibly");
            }
        }
    }
}
