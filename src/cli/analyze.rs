//! `modes` and `linearize`: the analyses of [`tensegrity_fmu::analysis`] about a scene's
//! start state, named with the FMU's variable names.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::json;
use tensegrity_fmu::analysis::modes::{ModeKind, Spectrum};
use tensegrity_fmu::analysis::{self, damped, export, linear, Tangent};
use tensegrity_fmu::fmi::variables::VariableTable;
use tensegrity_fmu::{numbers, outputs, partial, Scene, Simulation};

/// The scene's start state as a simulation, refused unless it is an equilibrium at rest.
fn at_rest(scene: &Scene, what: &str) -> Result<Simulation, String> {
    let model = analysis::load(scene).map_err(|e| e.to_string())?;
    if let Some(start) = model.start {
        eprintln!("{start}");
    }
    let mut sim = Simulation::new(model);
    analysis::require_rest(&sim, what)?;
    sim.refresh();
    Ok(sim)
}

/// `tensegrity-fmu modes`: frequencies on standard output (a table, or JSON), shapes to CSV.
pub fn modes(scene: &Scene, json: bool, shapes: Option<&Path>) -> Result<(), String> {
    let sim = at_rest(scene, "modes")?;
    let y = &sim.state().y;
    let q = &y[..y.len() / 2];
    let tangent = Tangent::new(sim.model(), &sim.inputs, sim.time(), q, &vec![0.0; q.len()]);
    let spectrum = Spectrum::of(sim.model(), &tangent);
    let damping = damped::damping(&tangent, &spectrum);
    if let Some(path) = shapes {
        partial::write(path, shapes_csv(&sim, &spectrum).as_bytes())?;
        eprintln!("mode shapes: {}", path.display());
    }
    if json {
        let modes = &spectrum.modes;
        let value = json!({
            "scene": scene.name,
            "frequencies_hz": spectrum.frequencies_hz(),
            "damped_frequencies_hz": damping.iter().map(|d| d.frequency_hz).collect::<Vec<_>>(),
            "damping_ratios": damping.iter().map(|d| d.ratio).collect::<Vec<_>>(),
            "kinds": modes.iter().map(|m| m.kind.name()).collect::<Vec<_>>(),
            "omega_squared": modes.iter().map(|m| m.omega_squared).collect::<Vec<_>>(),
            "growth_rates_per_s": modes.iter().map(|m| m.growth_rate()).collect::<Vec<_>>(),
            "rigid_body_modes": spectrum.count(ModeKind::RigidBody),
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&value).expect("plain values")
        );
        return Ok(());
    }
    print!("{}", table(scene, &spectrum, &damping));
    Ok(())
}

fn table(scene: &Scene, spectrum: &Spectrum, damping: &[damped::Damping]) -> String {
    let mut out = format!(
        "{}: {} modes about the start state (constrained coordinates, with the geometric \
         stiffness of the prestress)\n\
         f_n: undamped natural frequency; f_d and zeta: damped frequency and damping ratio \
         from the eigenvalue pair of the linear model's A that moves the mode most\n\
         {:>5}  {:>12}  {:>12}  {:>10}  kind\n",
        scene.name,
        spectrum.modes.len(),
        "mode",
        "f_n (Hz)",
        "f_d (Hz)",
        "zeta"
    );
    for (k, (mode, damping)) in spectrum.modes.iter().zip(damping).enumerate() {
        let note = match mode.kind {
            ModeKind::Unstable => format!("unstable (grows at {:.4e} 1/s)", mode.growth_rate()),
            kind => kind.name().to_string(),
        };
        // A round-off ζ of −1e-16 reads as 0.0000, not −0.0000.
        let ratio = damping.ratio.map_or_else(
            || "-".to_string(),
            |z| format!("{:.4}", if z.abs() < 5e-5 { 0.0 } else { z }),
        );
        let _ = writeln!(
            out,
            "{:>5}  {:>12.6}  {:>12.6}  {ratio:>10}  {note}",
            k + 1,
            mode.frequency_hz(),
            damping.frequency_hz
        );
    }
    out
}

/// One row per mode: number, frequency, kind, then every node's displacement (the shape,
/// scaled so the largest node moves 1 m).
fn shapes_csv(sim: &Simulation, spectrum: &Spectrum) -> String {
    let mut out = String::from("mode,frequency_hz,kind");
    for n in 1..=sim.model().n_nodes() {
        for axis in ["x", "y", "z"] {
            let _ = write!(out, ",node[{n}].d{axis}");
        }
    }
    out.push('\n');
    let mut digits = zmij::Buffer::new();
    for (k, mode) in spectrum.modes.iter().enumerate() {
        let f = numbers::number(&mut digits, mode.frequency_hz());
        let _ = write!(out, "{},{f},{}", k + 1, mode.kind.name());
        for d in &mode.shape {
            for x in [d.x, d.y, d.z] {
                let _ = write!(out, ",{}", numbers::number(&mut digits, x));
            }
        }
        out.push('\n');
    }
    out
}

/// `tensegrity-fmu linearize`: the state-space model about the start state, to `output`.
pub fn linearize(scene: &Scene, output: &Path) -> Result<(), String> {
    let sim = at_rest(scene, "linearize")?;
    let channels = VariableTable::new(&sim).input_channels();
    let outputs = outputs::outputs(&sim);
    let model = linear::linearize(&sim, &channels, &outputs);
    export::write(output, &model, &scene.name)?;
    eprintln!(
        "linear model: {} states, {} inputs, {} outputs",
        model.states.len(),
        model.inputs.len(),
        model.outputs.len()
    );
    println!("{}", output.display());
    Ok(())
}
