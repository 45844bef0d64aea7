//! zig links the macOS binary without a macOS SDK, so with libSystem only: no crate under
//! the FMU binary may link an Apple framework for the apple targets. `cargo tree` (offline,
//! from the lock file) lists the crates, `cargo metadata` where their sources lie, and a
//! crate links a framework when its sources say `kind = "framework"` (`#[link]`) or
//! `framework=` (a build script's `rustc-link-lib`). The CLI's tree reaches one
//! (chrono's time zones, through core-foundation-sys), so the check can fail.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

fn cargo(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .args(["--offline", "--locked"])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// `name version` of every crate `package` depends on (normal edges) for `target`.
fn dependencies(package: &str, target: &str) -> BTreeSet<String> {
    let tree = ["tree", "-p", package, "--target", target, "-e", "normal"];
    cargo(&[&tree[..], &["--prefix", "none"]].concat())
        .lines()
        .filter_map(|l| {
            let mut words = l.split_whitespace();
            Some(format!("{} {}", words.next()?, words.next()?))
        })
        .collect()
}

/// Source folder of each package, by `name vversion`.
fn sources() -> BTreeMap<String, PathBuf> {
    let json: serde_json::Value =
        serde_json::from_str(&cargo(&["metadata", "--format-version", "1"])).expect("JSON");
    json["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .map(|p| {
            let key = format!(
                "{} v{}",
                p["name"].as_str().unwrap(),
                p["version"].as_str().unwrap()
            );
            let manifest = Path::new(p["manifest_path"].as_str().unwrap());
            (key, manifest.parent().unwrap().to_path_buf())
        })
        .collect()
}

/// Whether a Rust file at or below `path` links a framework.
fn links_a_framework(path: &Path) -> bool {
    if let Ok(entries) = std::fs::read_dir(path) {
        return entries.flatten().any(|e| links_a_framework(&e.path()));
    }
    path.extension().is_some_and(|x| x == "rs")
        && std::fs::read_to_string(path).is_ok_and(|text| {
            let text = text.replace(' ', "");
            text.contains("kind=\"framework\"") || text.contains("framework=")
        })
}

/// The crates under `package` for `target` that link a framework.
fn framework_crates(package: &str, target: &str) -> Vec<String> {
    let sources = sources();
    dependencies(package, target)
        .into_iter()
        .filter(|krate| {
            let dir = sources
                .get(krate)
                .unwrap_or_else(|| panic!("{krate}: no source"));
            // The library and the build script (not tests/ nor target/ of this workspace).
            ["src", "build.rs", "build"]
                .iter()
                .any(|part| links_a_framework(&dir.join(part)))
        })
        .collect()
}

#[test]
fn no_crate_under_the_fmu_binary_links_an_apple_framework() {
    for target in ["aarch64-apple-darwin", "x86_64-apple-darwin"] {
        let found = framework_crates("tensegrity-fmu-binary", target);
        assert!(found.is_empty(), "{target}: {found:?} link frameworks");
    }
}

#[test]
fn the_check_finds_the_framework_under_the_cli() {
    let found = framework_crates("tensegrity-fmu", "aarch64-apple-darwin");
    assert!(
        found.iter().any(|c| c.starts_with("core-foundation-sys ")),
        "{found:?}"
    );
}
