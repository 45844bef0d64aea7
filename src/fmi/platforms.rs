//! The platforms an FMU carries a binary for: the folder under `binaries/`, and where
//! `fmu/build-binary.sh` (cargo-zigbuild) leaves each binary under `target/`.

use std::path::{Path, PathBuf};

use super::BUILD_ID;

/// One platform of the FMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Platform {
    /// The name `--platforms` takes, also the folder under `binaries/`.
    pub folder: &'static str,
    /// The folder under `target/` that cargo-zigbuild builds into.
    pub target: &'static str,
    /// The file name cargo gives the library there.
    pub file: &'static str,
    /// The extension of `<model identifier>.<extension>` in the FMU.
    pub extension: &'static str,
}

/// Every platform, in the order `build` packages them. `aarch64-linux` is the FMI 3.0
/// platform tuple (FMI 2.0 names no folder for Linux on ARM), which FMPy uses too.
pub const PLATFORMS: [Platform; 4] = [
    Platform {
        folder: "linux64",
        target: "x86_64-unknown-linux-gnu",
        file: "libtensegrity_fmu_binary.so",
        extension: "so",
    },
    Platform {
        folder: "win64",
        target: "x86_64-pc-windows-gnu",
        file: "tensegrity_fmu_binary.dll",
        extension: "dll",
    },
    Platform {
        folder: "darwin64",
        target: "universal2-apple-darwin",
        file: "libtensegrity_fmu_binary.dylib",
        extension: "dylib",
    },
    Platform {
        folder: "aarch64-linux",
        target: "aarch64-unknown-linux-gnu",
        file: "libtensegrity_fmu_binary.so",
        extension: "so",
    },
];

/// linux64, the platform `--binary` stands for.
pub const LINUX64: Platform = PLATFORMS[0];

/// A binary to package: its platform and file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Binary {
    /// The platform it runs on.
    pub platform: Platform,
    /// The library file.
    pub path: PathBuf,
}

/// Whether `bytes` (a library) was built from these sources: it carries their [`BUILD_ID`].
pub fn from_these_sources(bytes: &[u8]) -> bool {
    bytes
        .windows(BUILD_ID.len())
        .any(|w| w == BUILD_ID.as_bytes())
}

/// The platforms named in `list` (comma-separated folder names).
pub fn parse(list: &str) -> Result<Vec<Platform>, String> {
    let mut chosen = Vec::new();
    for name in list.split(',').map(str::trim) {
        let Some(p) = PLATFORMS.iter().find(|p| p.folder == name) else {
            let known: Vec<_> = PLATFORMS.iter().map(|p| p.folder).collect();
            return Err(format!(
                "--platforms: unknown platform '{name}': choose from {}",
                known.join(",")
            ));
        };
        if !chosen.contains(p) {
            chosen.push(*p);
        }
    }
    Ok(chosen)
}

/// Where `fmu/build-binary.sh` leaves `platform`'s binary, for a program in
/// `target/<profile>/`.
pub fn built_path(program_dir: &Path, platform: &Platform) -> Option<PathBuf> {
    let (target, profile) = (program_dir.parent()?, program_dir.file_name()?);
    Some(
        target
            .join(platform.target)
            .join(profile)
            .join(platform.file),
    )
}

/// The binary of `platform` that `fmu/build-binary.sh` built from these sources, or why
/// there is none.
pub fn built(program_dir: &Path, platform: &Platform) -> Result<Binary, String> {
    let path = built_path(program_dir, platform)
        .ok_or_else(|| format!("cannot locate target/ from {}", program_dir.display()))?;
    let bytes = std::fs::read(&path).map_err(|_| format!("{} is missing", path.display()))?;
    if !from_these_sources(&bytes) {
        return Err(format!("{} is from other sources", path.display()));
    }
    Ok(Binary {
        platform: *platform,
        path,
    })
}
