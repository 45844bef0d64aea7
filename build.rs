//! Hashes what makes up the FMU binary (its sources, the locked dependency versions and
//! the compiler version) into `BUILD_ID`, so that an FMU's GUID changes whenever the
//! binary does.

use std::path::Path;

use sha2::{Digest, Sha256};

fn hash_dir(dir: &Path, hasher: &mut Sha256) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut paths: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    paths.sort();
    for path in paths {
        if path.is_dir() {
            hash_dir(&path, hasher);
        } else if path.extension().is_some_and(|e| e == "rs" || e == "toml") {
            hasher.update(path.file_name().unwrap_or_default().as_encoded_bytes());
            hasher.update(std::fs::read(&path).unwrap_or_default());
        }
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut hasher = Sha256::new();
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    for dir in ["src", "fmu/src", "modelDescription/src"] {
        hash_dir(&root.join(dir), &mut hasher);
        println!("cargo:rerun-if-changed={dir}");
    }
    hasher.update(std::fs::read(root.join("Cargo.lock")).unwrap_or_default());
    println!("cargo:rerun-if-changed=Cargo.lock");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    if let Ok(out) = std::process::Command::new(rustc).arg("--version").output() {
        hasher.update(out.stdout);
    }
    let digest = hasher.finalize();
    let hex: String = digest.iter().take(16).map(|b| format!("{b:02x}")).collect();
    println!("cargo:rustc-env=TENSEGRITY_BUILD_ID={hex}");
}
