//! The FMU binary (`fmu/`, crate `tensegrity-fmu-binary`) links only what runs inside an
//! FMU: the library without its default `cli` feature. `cargo tree` (offline, from the
//! lock file) must show none of the CLI's crates under it, while the CLI's own tree still
//! has them (so the names below are the crates' real names, and the check can fail).

use std::collections::BTreeSet;
use std::process::Command;

/// Crates that only the command line, pictures, plots, exports and packaging use.
const CLI_ONLY: [&str; 18] = [
    "clap",
    "libc",
    "zip",
    "image",
    "plotters",
    "humantime",
    "quick-xml",
    "base64",
    "npyz",
    "matrw",
    "chrono",
    "png",
    "tempfile",
    "signal-hook",
    "gif",
    "binrw",
    "indicatif",
    "console",
];

/// The names of the crates `package` depends on (normal edges only), from `cargo tree`.
fn dependencies(package: &str) -> BTreeSet<String> {
    let out = Command::new(env!("CARGO"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "tree",
            "--offline",
            "--locked",
            "-e",
            "normal",
            "--prefix",
            "none",
        ])
        .args(["-p", package])
        .output()
        .expect("cargo tree runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    text.lines()
        .filter_map(|line| line.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

#[test]
fn the_fmu_binary_depends_on_none_of_the_cli_crates() {
    let fmu = dependencies("tensegrity-fmu-binary");
    assert!(
        fmu.contains("tensegrity-fmu") && fmu.contains("nalgebra") && fmu.contains("fmi-sys"),
        "{fmu:?}"
    );
    let linked: Vec<&str> = CLI_ONLY
        .into_iter()
        .filter(|name| fmu.contains(*name))
        .collect();
    assert!(linked.is_empty(), "the FMU binary links {linked:?}");
}

#[test]
fn the_cli_still_depends_on_its_crates() {
    let cli = dependencies("tensegrity-fmu");
    let missing: Vec<&str> = CLI_ONLY
        .into_iter()
        .filter(|name| !cli.contains(*name))
        .collect();
    assert!(missing.is_empty(), "the CLI lacks {missing:?}");
    // vtkio pulled nom 3 and quick-xml 0.22, which a future Rust rejects.
    assert!(!cli.contains("vtkio") && !cli.contains("nom"), "{cli:?}");
}
