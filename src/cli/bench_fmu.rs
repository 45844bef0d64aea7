//! The FMU at scale: for towers of given bar counts (no inputs, or with the three force
//! inputs on the top ring), the variables, the sizes of
//! modelDescription.xml and of the .fmu, the build time, and through fmpy (the helper
//! fmu/sweep/fmu_timing.py) the time to read the model description, to instantiate and
//! initialize, and of the first two doSteps.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use tensegrity_fmu::fmi::package::build_fmu;

use super::bench::tower;

/// Times fmpy on the FMU given as its one argument; prints one JSON line.
const FMPY_TIMING: &str = include_str!("../../fmu/sweep/fmu_timing.py");

/// What fmpy took on one FMU, s.
#[derive(serde::Deserialize)]
struct FmpyTiming {
    read: f64,
    initialize: f64,
    /// The first two doSteps.
    do_step: [f64; 2],
    step: f64,
}

/// Checks the bar counts: each a positive multiple of 3 (a tower stage has 3 bars).
pub fn check_bars(bars: &[usize]) -> Result<(), String> {
    match bars.iter().find(|&&b| b == 0 || b % 3 != 0) {
        Some(b) => Err(format!(
            "--bars {b}: a tower has 3 bars per stage; give positive multiples of 3 (e.g. --bars 60,600)"
        )),
        None => Ok(()),
    }
}

/// Prints one row per bar count (as each completes); `bars` passed [`check_bars`].
pub fn run(bars: &[usize], inputs: bool, python: &Path, binary: &Path) -> Result<(), String> {
    if !python.is_file() {
        return Err(format!(
            "--python {}: no such program; pass the Python that has fmpy (bash tests/setup.sh makes .venv)",
            python.display()
        ));
    }
    let dir = tempfile::Builder::new()
        .prefix("tensegrity-bench-fmu")
        .tempdir()
        .map_err(|e| format!("cannot create a temporary folder: {e}"))?;
    rows(bars, inputs, python, binary, dir.path())
}

fn rows(
    bars: &[usize],
    inputs: bool,
    python: &Path,
    binary: &Path,
    dir: &Path,
) -> Result<(), String> {
    let kind = if inputs {
        "force inputs on the top ring"
    } else {
        "no inputs"
    };
    println!(
        "Towers of elastic cables with explicit rest lengths (rk4 at 1 ms, {kind}); fmpy {}:",
        fmpy_version(python)
    );
    println!();
    println!("| bars | variables | modelDescription.xml (MB) | .fmu (MB) | build (s) | fmpy read (s) | fmpy instantiate + initialize (s) | first doStep (s) | second doStep (s) |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for &b in bars {
        let mut scene = tower(b / 3);
        if !inputs {
            scene.force_inputs.clear();
        }
        let fmu: PathBuf = dir.join(format!("tower{b}.fmu"));
        let started = Instant::now();
        let built = build_fmu(&scene, binary, &fmu)?;
        let build = started.elapsed().as_secs_f64();
        let fmu_bytes = std::fs::metadata(&fmu)
            .map_err(|e| format!("{}: {e}", fmu.display()))?
            .len();
        let xml_bytes = entry_size(&fmu, "modelDescription.xml")?;
        let fmpy = fmpy_timing(python, &fmu)?;
        let _ = std::fs::remove_file(&fmu);
        let mb = |bytes: u64| bytes as f64 / 1e6;
        println!(
            "| {b} | {} | {:.2} | {:.2} | {build:.2} | {:.2} | {:.2} | {:.3} | {:.3} (step {} s) |",
            built.variables,
            mb(xml_bytes),
            mb(fmu_bytes),
            fmpy.read,
            fmpy.initialize,
            fmpy.do_step[0],
            fmpy.do_step[1],
            fmpy.step
        );
        let _ = std::io::stdout().flush();
    }
    Ok(())
}

/// The uncompressed size of `entry` in the archive `fmu`.
fn entry_size(fmu: &Path, entry: &str) -> Result<u64, String> {
    let file = std::fs::File::open(fmu).map_err(|e| format!("{}: {e}", fmu.display()))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| format!("{}: {e}", fmu.display()))?;
    let size = zip
        .by_name(entry)
        .map_err(|e| format!("{}: {entry}: {e}", fmu.display()))?
        .size();
    Ok(size)
}

fn fmpy_version(python: &Path) -> String {
    Command::new(python)
        .args(["-c", "import fmpy; print(fmpy.__version__)"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map_or_else(
            || "(version unknown)".into(),
            |o| String::from_utf8_lossy(&o.stdout).trim().to_string(),
        )
}

fn fmpy_timing(python: &Path, fmu: &Path) -> Result<FmpyTiming, String> {
    let out = Command::new(python)
        .arg("-c")
        .arg(FMPY_TIMING)
        .arg(fmu)
        .output()
        .map_err(|e| format!("--python {}: cannot run it: {e}", python.display()))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        let last = stderr.lines().last().unwrap_or("no message");
        return Err(format!("fmpy on {}: {last}", fmu.display()));
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.lines().last().unwrap_or("");
    serde_json::from_str(line)
        .map_err(|e| format!("fmpy on {}: unreadable timing {line:?}: {e}", fmu.display()))
}
