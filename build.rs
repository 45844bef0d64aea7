//! Hashes what makes up the FMU binary (its sources, the locked dependency versions and
//! the compiler version) into `BUILD_ID`, so that an FMU's GUID changes whenever the
//! binary does, and records the git commit (`TENSEGRITY_GIT_COMMIT`) that
//! modelDescription.xml names in `generationTool`.

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

/// `git <args>` in the crate's folder, trimmed; `None` when git or the repository is absent.
/// `--no-optional-locks` keeps `git status` from rewriting the index, which would make
/// cargo rerun this script on every build.
fn git(root: &Path, args: &[&str]) -> Option<String> {
    let out = std::process::Command::new("git")
        .arg("--no-optional-locks")
        .arg("-C")
        .arg(root)
        .args(args)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// The short commit, with `-dirty` when tracked files differ from it; `unknown` without git.
fn git_commit(root: &Path) -> String {
    let Some(commit) = git(root, &["rev-parse", "--short", "HEAD"]).filter(|c| !c.is_empty())
    else {
        return "unknown".into();
    };
    // Rerun when the commit changes; edits to the sources rerun it anyway (watched in
    // `main`). The index is not watched: `git add` would rebuild the crate each time. The
    // paths come from git because a worktree keeps them outside `.git/`.
    let branch = git(root, &["symbolic-ref", "-q", "HEAD"]).unwrap_or_default();
    for path in ["HEAD", "packed-refs", branch.as_str()] {
        if path.is_empty() {
            continue;
        }
        if let Some(p) = git(root, &["rev-parse", "--git-path", path]) {
            let p = root.join(p);
            if p.exists() {
                println!("cargo:rerun-if-changed={}", p.display());
            }
        }
    }
    let dirty = git(root, &["status", "--porcelain", "--untracked-files=no"])
        .is_some_and(|s| !s.is_empty());
    if dirty {
        format!("{commit}-dirty")
    } else {
        commit
    }
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    // Read when the script runs, not when it was compiled: a copied target/ must not hash
    // another checkout's sources.
    let manifest_dir = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".into());
    let root_dir = Path::new(&manifest_dir);
    println!(
        "cargo:rustc-env=TENSEGRITY_GIT_COMMIT={}",
        git_commit(root_dir)
    );
    let root = root_dir;
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
