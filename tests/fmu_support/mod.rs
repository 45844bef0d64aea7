//! Building the packaged FMU from the tests that load it through the `fmi` crate.

use std::path::{Path, PathBuf};
use std::process::Command;

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{Common, InstanceCS};

/// `target/<profile>`, the directory holding the CLI this test was built with.
fn profile_dir() -> PathBuf {
    Path::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .parent()
        .expect("the CLI binary has a parent directory")
        .to_path_buf()
}

/// The generic FMU binary, (re)built with cargo: it must come from the same sources as the
/// CLI, whose build id goes into the GUID that `fmi2Instantiate` checks. The build is a
/// no-op after `cargo build --workspace`; it builds the whole workspace, not `-p` the FMU
/// crate alone, so that the library's features (the `cli` feature, which a build of the FMU
/// crate alone leaves out) are the same and the next workspace build has nothing to redo.
fn fmu_binary() -> PathBuf {
    let dir = profile_dir();
    let target_dir = dir.parent().expect("target directory");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["build", "--workspace", "--target-dir"])
        .arg(target_dir);
    if dir.file_name().is_some_and(|n| n == "release") {
        cmd.arg("--release");
    }
    let status = cmd.status().expect("run cargo build for the FMU binary");
    assert!(
        status.success(),
        "cargo build --workspace (for the FMU binary) failed"
    );
    let so = dir.join("libtensegrity_fmu_binary.so");
    assert!(so.is_file(), "{} is missing after the build", so.display());
    so
}

/// Packages `scene` with the CLI into `dir`.
pub fn build_fmu(dir: &Path, scene: &str) -> PathBuf {
    std::fs::create_dir_all(dir).expect("create the temporary directory");
    let fmu = dir.join(format!("{scene}.fmu"));
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args(["build", scene, "-o"])
        .arg(&fmu)
        .arg("--binary")
        .arg(fmu_binary())
        .output()
        .expect("run tensegrity-fmu build");
    assert!(
        out.status.success(),
        "tensegrity-fmu build failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(fmu.is_file(), "{} was not written", fmu.display());
    fmu
}

/// A co-simulation instance named `name`, initialized at time 0: instantiated, set up,
/// and through initialization mode, ready for its first `fmi2DoStep`.
pub fn started(import: &Fmi2Import, name: &str) -> InstanceCS {
    let mut inst = import
        .instantiate_cs(name, false, false)
        .expect("fmi2Instantiate");
    Common::setup_experiment(&mut inst, None, 0.0, None).expect("fmi2SetupExperiment");
    Common::enter_initialization_mode(&mut inst).expect("fmi2EnterInitializationMode");
    Common::exit_initialization_mode(&mut inst).expect("fmi2ExitInitializationMode");
    inst
}
