//! Damped frequencies and damping ratios (`analysis::damped`, `modes`) held to closed forms:
//! the bar of `tests/point_mass_frequencies.rs` held at its tip by two damped cables is a
//! mass on a damped spring along the cables (ω_n² = 2κ/I, ζ = 2c/(2√(2κ I)), I = m/3 + p)
//! and undamped across them; an undamped structure has ζ = 0 and f_d = f_n.
//! Figures are printed: `cargo test --release --test analysis_damping -- --nocapture`.

mod cli_support;
#[allow(dead_code)] // only part of it is used here
mod point_mass_support;

use std::f64::consts::PI;

use nalgebra::{Complex, DMatrix, DVector};
use point_mass_support::{cable_held_bar, CABLE_BAR};
use tensegrity_fmu::analysis::damped::{self, Damping, ModalMatrices};
use tensegrity_fmu::analysis::modes::{ModeKind, Spectrum};
use tensegrity_fmu::analysis::{self, Tangent};
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Scene, Simulation};

/// The cable-held bar with damping `c` (N·s/m) on both cables and a tip payload `p`.
fn damped_bar(c: f64, p: f64) -> Scene {
    let mut scene = cable_held_bar((p > 0.0).then_some(p), [0.0; 3]);
    for cable in &mut scene.cables {
        cable.damping = Some(c);
    }
    scene
}

/// The scene's start state, its tangent, spectrum and damping.
fn analyze(scene: &Scene) -> (Tangent, Spectrum, Vec<Damping>) {
    let sim = Simulation::new(analysis::load(scene).expect("scene loads"));
    analysis::require_rest(&sim, "test").expect("the start is at rest");
    let y = &sim.state().y;
    let q = &y[..y.len() / 2];
    let tangent = Tangent::new(sim.model(), &sim.inputs, sim.time(), q, &vec![0.0; q.len()]);
    let spectrum = Spectrum::of(sim.model(), &tangent);
    let damping = damped::damping(&tangent, &spectrum);
    (tangent, spectrum, damping)
}

/// Closed form of the axial mode: (f_n, ζ) for cable damping `c` and payload `p`.
fn axial(c: f64, p: f64) -> (f64, f64) {
    let (_, m, _, k, _) = CABLE_BAR;
    let inertia = m / 3.0 + p;
    let omega = (2.0 * k / inertia).sqrt();
    (
        omega / (2.0 * PI),
        2.0 * c / (2.0 * (2.0 * k * inertia).sqrt()),
    )
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

#[test]
fn underdamped_bar_matches_the_damped_oscillator() {
    for (c, p) in [(1.0, 0.0), (5.0, 0.5), (20.0, 2.0)] {
        let (_, spectrum, damping) = analyze(&damped_bar(c, p));
        let (f_n, zeta) = axial(c, p);
        let f_d = f_n * (1.0 - zeta * zeta).sqrt();
        // Mode order: the lateral (geometric) mode is the lower one.
        let (lateral, axial_mode) = (&spectrum.modes[0], &spectrum.modes[1]);
        assert!(axial_mode.shape[1].z.abs() > 0.99 && lateral.shape[1].y.abs() > 0.99);
        let d = damping[1];
        println!(
            "c = {c}, p = {p}: f_n {:.9} (closed {f_n:.9}), f_d {:.9} (closed {f_d:.9}), ζ {:.9} \
             (closed {zeta:.9}); lateral ζ {:?}",
            axial_mode.frequency_hz(),
            d.frequency_hz,
            d.ratio.unwrap(),
            damping[0].ratio
        );
        assert!(close(axial_mode.frequency_hz(), f_n, 1e-10));
        assert!(close(d.ratio.unwrap(), zeta, 1e-9), "ζ {:?}", d.ratio);
        assert!(close(d.frequency_hz, f_d, 1e-9), "f_d {}", d.frequency_hz);
        // Across the cables their damping does not act (to first order): ζ = 0, f_d = f_n.
        assert!(damping[0].ratio.unwrap().abs() <= 1e-12);
        assert!(close(
            damping[0].frequency_hz,
            lateral.frequency_hz(),
            1e-10
        ));
    }
}

#[test]
fn overdamped_bar_has_two_real_eigenvalues() {
    let p = 0.5;
    let (_, m, _, k, _) = CABLE_BAR;
    let inertia = m / 3.0 + p;
    let zeta = 2.5;
    // ζ = c/√(2κI) ⇒ c = ζ √(2κI).
    let c = zeta * (2.0 * k * inertia).sqrt();
    let (_, spectrum, damping) = analyze(&damped_bar(c, p));
    let (f_n, closed_zeta) = axial(c, p);
    assert!(close(closed_zeta, zeta, 1e-12));
    let d = damping[1];
    let omega = 2.0 * PI * f_n;
    let mut expected = [
        -omega * (zeta - (zeta * zeta - 1.0).sqrt()),
        -omega * (zeta + (zeta * zeta - 1.0).sqrt()),
    ];
    expected.sort_by(f64::total_cmp);
    let mut got = [d.eigenvalues[0].re, d.eigenvalues[1].re];
    got.sort_by(f64::total_cmp);
    println!(
        "overdamped: ζ {:?} (closed {zeta}), f_d {}, eigenvalues {got:?} (closed {expected:?})",
        d.ratio, d.frequency_hz
    );
    assert_eq!(d.frequency_hz, 0.0);
    assert!(d.eigenvalues.iter().all(|l| l.im == 0.0));
    for (a, b) in got.iter().zip(expected) {
        assert!(close(*a, b, 1e-9), "{a} vs {b}");
    }
    assert!(close(d.ratio.unwrap(), zeta, 1e-9));
    assert!(close(spectrum.modes[1].frequency_hz(), f_n, 1e-10));
    assert!(damping[0].ratio.unwrap().abs() <= 1e-12);
}

#[test]
fn undamped_structures_have_zero_damping_ratios() {
    for name in ["prism2", "prism2-elastic", "icosahedron"] {
        let (tangent, spectrum, damping) = analyze(&builtin(name).unwrap());
        assert!(
            tangent.damping.iter().all(|&c| c == 0.0),
            "{name} is undamped"
        );
        for (mode, d) in spectrum.modes.iter().zip(&damping) {
            assert_eq!(d.ratio, Some(0.0), "{name}");
            assert_eq!(d.frequency_hz, mode.frequency_hz(), "{name}");
        }
        // The general path (eigenvalues of A, paired by shape) agrees up to round-off,
        // degenerate pairs of equal frequency included.
        let (a, mass, kinds) = state_matrix(&tangent, &spectrum);
        let general = damped::of_state_matrix(&a, &mass, &kinds);
        let mut worst = (0.0f64, 0.0f64);
        for (mode, d) in spectrum.modes.iter().zip(&general) {
            worst.0 = worst.0.max(d.ratio.unwrap().abs());
            worst.1 = worst
                .1
                .max((d.frequency_hz / mode.frequency_hz() - 1.0).abs());
        }
        println!(
            "{name}: through A's eigenvalues, |ζ| ≤ {:.1e}, |f_d/f_n − 1| ≤ {:.1e}",
            worst.0, worst.1
        );
        assert!(worst.0 <= 1e-9 && worst.1 <= 1e-9, "{name}: {worst:?}");
    }
}

fn state_matrix(
    tangent: &Tangent,
    spectrum: &Spectrum,
) -> (DMatrix<f64>, DVector<f64>, Vec<ModeKind>) {
    let phi = spectrum.shapes();
    let matrices = ModalMatrices::new(tangent, &phi);
    let kinds = spectrum.modes.iter().map(|m| m.kind).collect();
    (matrices.state_matrix(), matrices.mass.diagonal(), kinds)
}

/// Three decoupled oscillators, two of them at the same frequency with different damping
/// and one overdamped: pairing by nearest frequency could not tell the first two apart;
/// pairing by shape gives each its own ζ = c/(2√(km)).
#[test]
fn pairing_follows_the_shapes() {
    let mass = [2.0, 0.5, 1.0];
    let stiffness = [8.0, 2.0, 3.0]; // ω² = 4, 4, 3
    let damping = [0.4, 0.6, 10.0]; // ζ = 0.05, 0.3, 2.89
    let m = 3;
    let mut a = DMatrix::zeros(2 * m, 2 * m);
    for k in 0..m {
        a[(k, m + k)] = 1.0;
        a[(m + k, k)] = -stiffness[k] / mass[k];
        a[(m + k, m + k)] = -damping[k] / mass[k];
    }
    let kinds = [ModeKind::Vibration; 3];
    let result = damped::of_state_matrix(&a, &DVector::from_column_slice(&mass), &kinds);
    for k in 0..m {
        let omega = (stiffness[k] / mass[k]).sqrt();
        let zeta = damping[k] / (2.0 * (stiffness[k] * mass[k]).sqrt());
        let f_d = if zeta < 1.0 {
            omega * (1.0 - zeta * zeta).sqrt() / (2.0 * PI)
        } else {
            0.0
        };
        println!(
            "oscillator {k}: ζ {:?} (closed {zeta}), f_d {} (closed {f_d})",
            result[k].ratio, result[k].frequency_hz
        );
        assert!(close(result[k].ratio.unwrap(), zeta, 1e-12), "mode {k}");
        assert!(
            (result[k].frequency_hz - f_d).abs() <= 1e-12 * omega,
            "mode {k}"
        );
    }
}

/// Every eigenvalue of A is attributed to exactly one mode, on a structure with
/// non-proportional damping (every cable of prism2-elastic damped).
#[test]
fn every_eigenvalue_of_a_goes_to_one_mode() {
    let mut scene = builtin("prism2-elastic").unwrap();
    for cable in &mut scene.cables {
        cable.damping = Some(2.0);
    }
    let (tangent, spectrum, damping) = analyze(&scene);
    let (a, _, _) = state_matrix(&tangent, &spectrum);
    let mut all: Vec<Complex<f64>> = a.complex_eigenvalues().iter().copied().collect();
    let mut attributed: Vec<Complex<f64>> = damping.iter().flat_map(|d| d.eigenvalues).collect();
    let order =
        |x: &Complex<f64>, y: &Complex<f64>| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im));
    all.sort_by(order);
    attributed.sort_by(order);
    let scale = all.iter().map(|l| l.norm()).fold(0.0, f64::max);
    assert_eq!(all.len(), attributed.len());
    for (x, y) in all.iter().zip(&attributed) {
        assert!((x - y).norm() <= 1e-9 * scale, "{x} vs {y}");
    }
    for (k, (mode, d)) in spectrum.modes.iter().zip(&damping).enumerate() {
        let zeta = d.ratio.unwrap();
        println!(
            "prism2-elastic, c = 2: mode {}: f_n {:.6}, f_d {:.6}, ζ {zeta:.6}",
            k + 1,
            mode.frequency_hz(),
            d.frequency_hz
        );
        assert!((0.0..1.0).contains(&zeta), "mode {k}: ζ {zeta}");
        // Light damping: each mode's pair lies near its own undamped frequency.
        assert!(close(d.frequency_hz, mode.frequency_hz(), 0.2), "mode {k}");
    }
}

#[test]
fn modes_json_and_table_report_damping() {
    let (c, p) = (5.0, 0.5);
    let path = cli_support::temp("damped-bar.toml");
    std::fs::write(&path, damped_bar(c, p).to_toml_string()).unwrap();
    let (ok, out, err) = cli_support::run(&["modes", path.to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON on stdout");
    let list = |key: &str| -> Vec<f64> {
        v[key]
            .as_array()
            .unwrap_or_else(|| panic!("{key}"))
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let (f_n, zeta) = axial(c, p);
    let (hz, damped_hz, ratios) = (
        list("frequencies_hz"),
        list("damped_frequencies_hz"),
        list("damping_ratios"),
    );
    assert_eq!((hz.len(), damped_hz.len(), ratios.len()), (2, 2, 2));
    assert!(close(hz[1], f_n, 1e-10));
    assert!(close(ratios[1], zeta, 1e-9));
    assert!(close(damped_hz[1], f_n * (1.0 - zeta * zeta).sqrt(), 1e-9));
    assert!(ratios[0].abs() <= 1e-12 && close(damped_hz[0], hz[0], 1e-10));
    let (ok, out, err) = cli_support::run(&["modes", path.to_str().unwrap()]);
    assert!(ok, "{err}");
    println!("{out}");
    assert!(out.contains("f_n (Hz)") && out.contains("f_d (Hz)") && out.contains("zeta"));
    let row: Vec<&str> = out.lines().last().unwrap().split_whitespace().collect();
    assert_eq!(row[0], "2");
    let parse = |s: &str| s.parse::<f64>().unwrap();
    assert!((parse(row[1]) - f_n).abs() <= 1e-6);
    assert!((parse(row[2]) - f_n * (1.0 - zeta * zeta).sqrt()).abs() <= 1e-6);
    assert!((parse(row[3]) - zeta).abs() <= 1e-4);
}

/// A free structure's rigid-body modes have no damping ratio (null in JSON).
#[test]
fn rigid_body_modes_have_no_damping_ratio() {
    let mut scene = builtin("icosahedron").unwrap();
    scene.fixed.clear();
    scene.force_inputs.clear();
    for cable in &mut scene.cables {
        cable.damping = Some(1.0);
    }
    let (_, spectrum, damping) = analyze(&scene);
    assert_eq!(spectrum.count(ModeKind::RigidBody), 6);
    for (mode, d) in spectrum.modes.iter().zip(&damping) {
        match mode.kind {
            ModeKind::RigidBody => assert_eq!((d.ratio, d.frequency_hz), (None, 0.0)),
            // Modes that stretch no cable (to first order) are undamped.
            _ => assert!((-1e-12..1.0).contains(&d.ratio.unwrap()), "{d:?}"),
        }
    }
}
