//! Natural frequencies and modes (`analysis::modes`) held to computations made without the
//! library's reduced coordinates: the finite-difference linearization of a dense KKT model
//! in bar-end coordinates (bars, joints and pins all multipliers; `tests/analysis_support`),
//! and the hand linearization of a bar on two prestressed cables. Also the `modes` command.
//! Figures are printed: `cargo test --release --test analysis_modes -- --nocapture`.

mod analysis_support;
mod cli_support;
#[allow(dead_code)] // only part of it is used here
mod point_mass_support;

use analysis_support::kkt_spectrum;
use point_mass_support::{cable_held_bar, CABLE_BAR};
use tensegrity_fmu::analysis::modes::{ModeKind, Spectrum};
use tensegrity_fmu::analysis::{self, equilibrium};
use tensegrity_fmu::scene::{builtin, tower_scene, Start};
use tensegrity_fmu::{Scene, Simulation};

/// The scene's start state (as the CLI loads it) and its spectrum.
fn start(scene: &Scene) -> (Simulation, Spectrum) {
    let sim = Simulation::new(analysis::load(scene).expect("scene loads"));
    analysis::require_rest(&sim, "test").expect("the start is at rest");
    let y = &sim.state().y;
    let spectrum = Spectrum::new(sim.model(), &sim.inputs, sim.time(), &y[..y.len() / 2]);
    (sim, spectrum)
}

/// Compares the spectrum's vibration frequencies with the KKT linearization's, after
/// `rigid` zero eigenvalues (rigid-body motions) are set aside; returns the largest
/// relative frequency error.
fn check_against_kkt(scene: &Scene, rigid: usize) -> f64 {
    let name = &scene.name;
    let (sim, spectrum) = start(scene);
    let kkt = kkt_spectrum(&sim);
    let largest = kkt.omega_squared.last().copied().unwrap();
    println!(
        "{name}: KKT in {} end coordinates, tangent space of dimension {}; range leak \
         {:.1e}, velocity coupling {:.1e}, |Im λ| {:.1e} (relative)",
        kkt.full_dim, kkt.tangent_dim, kkt.range_leak, kkt.velocity_coupling, kkt.imaginary
    );
    assert!(kkt.range_leak <= 1e-9, "{name}: J leaves the tangent space");
    assert!(kkt.velocity_coupling <= 1e-9, "{name}: undamped at rest");
    assert!(kkt.imaginary <= 1e-9, "{name}: complex ω²");
    assert_eq!(spectrum.modes.len(), kkt.tangent_dim, "{name}: mode count");
    assert_eq!(
        spectrum.count(ModeKind::RigidBody),
        rigid,
        "{name}: rigid modes"
    );
    assert_eq!(spectrum.count(ModeKind::Vibration), kkt.tangent_dim - rigid);
    let (zeros, vibrations) = kkt.omega_squared.split_at(rigid);
    let zero = zeros.iter().fold(0.0f64, |m, w| m.max(w.abs())) / largest;
    println!("{name}: {rigid} rigid-body eigenvalues, largest |ω²| {zero:.1e} of the largest");
    assert!(zero <= 1e-9, "{name}: rigid-body eigenvalues are not zero");
    assert!(
        vibrations[0] > 1e-3 * largest,
        "{name}: a zero beyond the rigid ones"
    );
    let mine: Vec<f64> = spectrum
        .modes
        .iter()
        .filter(|m| m.kind == ModeKind::Vibration)
        .map(|m| m.omega_squared)
        .collect();
    let mut worst = 0.0f64;
    for (k, (a, b)) in mine.iter().zip(vibrations).enumerate() {
        let rel = (a / b).sqrt() - 1.0;
        worst = worst.max(rel.abs());
        assert!(
            rel.abs() <= 1e-6,
            "{name}: mode {k}: ω {} vs KKT {} (rel. {rel:.2e})",
            a.sqrt(),
            b.sqrt()
        );
    }
    let hz = |w2: f64| w2.sqrt() / (2.0 * std::f64::consts::PI);
    println!(
        "{name}: {} frequencies {:.4}–{:.4} Hz match the KKT linearization, max rel. error \
         {worst:.2e}",
        mine.len(),
        hz(mine[0]),
        hz(*mine.last().unwrap())
    );
    worst
}

#[test]
fn frequencies_match_kkt_linearization_prism2_elastic() {
    check_against_kkt(&builtin("prism2-elastic").unwrap(), 0);
}

#[test]
fn frequencies_match_kkt_linearization_pinned_icosahedron() {
    check_against_kkt(&builtin("icosahedron").unwrap(), 0);
}

#[test]
fn frequencies_match_kkt_linearization_class2_tower() {
    // Three stages: the two middle rings are class-2 joints; the bottom ring is pinned.
    check_against_kkt(&tower_scene(3, Some(500.0), "tower3"), 0);
}

#[test]
fn frequencies_match_kkt_linearization_force_density_prism2() {
    check_against_kkt(&builtin("prism2").unwrap(), 0);
}

/// The free icosahedron (no pins, no gravity): six rigid-body modes at zero frequency whose
/// shapes are rigid motions, and vibrations matching the KKT linearization (which has six
/// zero eigenvalues of its own).
#[test]
fn free_icosahedron_has_six_rigid_body_modes() {
    let mut scene = builtin("icosahedron").unwrap();
    scene.fixed.clear();
    scene.force_inputs.clear();
    scene.name = "free icosahedron".into();
    check_against_kkt(&scene, 6);
    let (sim, spectrum) = start(&scene);
    let model = sim.model();
    let x: Vec<_> = (0..model.n_nodes()).map(|n| sim.node_position(n)).collect();
    let members = model
        .bars
        .iter()
        .map(|b| b.nodes)
        .chain(model.cables.iter().map(|c| c.nodes));
    let members: Vec<[usize; 2]> = members.collect();
    let mut strain = 0.0f64;
    for (k, mode) in spectrum.modes.iter().enumerate() {
        if k < 6 {
            assert_eq!(mode.kind, ModeKind::RigidBody, "mode {k}");
            assert_eq!(mode.frequency_hz(), 0.0);
            // A rigid motion stretches no member to first order: (d_b − d_a)·(x_b − x_a) = 0.
            for &[a, b] in &members {
                let d = mode.shape[b] - mode.shape[a];
                strain = strain.max(d.dot(&(x[b] - x[a])).abs());
            }
        } else {
            assert_eq!(mode.kind, ModeKind::Vibration, "mode {k}");
            assert!(mode.frequency_hz() > 0.5);
        }
    }
    println!("free icosahedron: largest member stretch rate in a rigid-body mode {strain:.1e}");
    assert!(strain <= 1e-9);
    // The vibrations are not those of the pinned structure.
    let (_, pinned) = start(&builtin("icosahedron").unwrap());
    assert_eq!(pinned.modes.len() + 9, spectrum.modes.len());
}

/// The bar of `tests/point_mass_frequencies.rs` on two prestressed cables: ω² = 2κ/(m/3 + p)
/// (axial) and 2T₀/(H (m/3 + p)) (purely geometric), the hand linearization written there,
/// with and without a tip payload. The bar's only two motions are these two modes.
#[test]
fn cable_held_bar_matches_hand_linearization() {
    let (_, m, h, k, s0) = CABLE_BAR;
    let t0 = k * (h - s0);
    for p in [0.0, 0.5, 2.0] {
        let scene = cable_held_bar((p > 0.0).then_some(p), [0.0; 3]);
        let (_, spectrum) = start(&scene);
        assert_eq!(spectrum.modes.len(), 2);
        let inertia = m / 3.0 + p;
        let mut hand = [2.0 * t0 / h / inertia, 2.0 * k / inertia];
        hand.sort_by(f64::total_cmp);
        for (mode, w2) in spectrum.modes.iter().zip(hand) {
            let rel = mode.omega_squared / w2 - 1.0;
            println!(
                "cable-held bar, p = {p} kg: ω² = {:.12} 1/s², hand {w2:.12} (rel. {rel:.1e})",
                mode.omega_squared
            );
            assert_eq!(mode.kind, ModeKind::Vibration);
            assert!(rel.abs() <= 1e-12, "p = {p}: ω² off by {rel:e}");
        }
        // The geometric mode moves the tip along y only, the axial one along z only.
        let (lateral, axial) = (&spectrum.modes[0].shape[1], &spectrum.modes[1].shape[1]);
        assert!((lateral.y.abs() - 1.0).abs() <= 1e-12 && lateral.z.abs() <= 1e-12);
        assert!((axial.z.abs() - 1.0).abs() <= 1e-12 && axial.y.abs() <= 1e-12);
    }
}

// ------------------------------------------------------------------------------ CLI

#[test]
fn modes_json_lists_every_mode() {
    let (ok, out, err) = cli_support::run(&["modes", "prism2-elastic", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON on stdout");
    let hz: Vec<f64> = v["frequencies_hz"]
        .as_array()
        .expect("frequencies_hz")
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(hz.len(), 12, "6 free nodes × 3 − 6 bars");
    let (_, spectrum) = start(&builtin("prism2-elastic").unwrap());
    let mine = spectrum.frequencies_hz();
    for (a, b) in hz.iter().zip(&mine) {
        assert!((a - b).abs() <= 1e-12 * b, "{a} vs {b}");
    }
    // Degenerate pairs (the three-fold symmetry) are listed twice.
    let repeated = hz.windows(2).filter(|w| (w[1] - w[0]).abs() <= 1e-9 * w[1]);
    assert!(repeated.count() >= 3, "{hz:?}");
    assert_eq!(v["kinds"].as_array().unwrap().len(), 12);
    assert_eq!(v["rigid_body_modes"], 0);
}

/// prism2-elastic under gravity, written to a file, `start` as given or `"equilibrium"`.
fn heavy_prism(start: Start, file: &str) -> std::path::PathBuf {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.gravity = Some([0.0, 0.0, -9.81]);
    scene.start = start;
    let path = cli_support::temp(file);
    std::fs::write(&path, scene.to_toml_string()).unwrap();
    path
}

#[test]
fn modes_refuses_a_start_that_is_not_an_equilibrium() {
    let path = heavy_prism(Start::AsGiven, "heavy-as-given.toml");
    let (ok, out, err) = cli_support::run(&["modes", path.to_str().unwrap()]);
    println!("{err}");
    assert!(!ok, "modes ran on a state out of equilibrium: {out}");
    assert!(err.contains("start = \"equilibrium\""), "{err}");
    assert!(err.contains("not an equilibrium"), "{err}");
    // With the key, it settles first and then lists the modes.
    let path = heavy_prism(Start::Equilibrium, "heavy-equilibrium.toml");
    let (ok, out, err) = cli_support::run(&["modes", path.to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    assert!(err.contains("static equilibrium"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["frequencies_hz"].as_array().unwrap().len(), 12);
    // The settled state is an equilibrium of the same model to the solver's tolerance.
    let scene = Scene::from_name_or_file(path.to_str().unwrap()).unwrap();
    let model = analysis::load(&scene).unwrap();
    let q = equilibrium::reduced_positions(&model);
    let inputs = tensegrity_fmu::dynamics::Inputs::start(&model);
    let (residual, scale, _) = equilibrium::unbalanced(&model, &inputs, &q);
    println!("heavy prism2-elastic settled: unbalanced {residual:.1e} N of {scale:.1e} N");
    assert!(residual <= analysis::REST_TOLERANCE * scale);
}
