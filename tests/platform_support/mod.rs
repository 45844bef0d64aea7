//! The binaries `fmu/build-binary.sh` builds for each platform, an FMU that carries them
//! all, and the C importer of tests/importer/ built for each platform that runs here.

#![allow(dead_code)] // each suite uses part of it

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Mutex, OnceLock};

pub const REPO: &str = env!("CARGO_MANIFEST_DIR");

/// `target/`, above the CLI this test was built with.
pub fn target_dir() -> PathBuf {
    Path::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>/tensegrity-fmu")
        .to_path_buf()
}

/// The binary `fmu/build-binary.sh` built for `target` (cargo-zigbuild's folder), which
/// must exist.
pub fn built(target: &str, file: &str) -> PathBuf {
    let path = target_dir().join(target).join("release").join(file);
    assert!(
        path.is_file(),
        "{} is missing: run `bash tests/setup.sh` and `bash fmu/build-binary.sh`",
        path.display()
    );
    path
}

/// Runs `cmd`, which must succeed; its output.
pub fn run(cmd: &mut Command) -> Output {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    assert!(
        out.status.success(),
        "{cmd:?} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The stdout of `cmd`, which must succeed.
pub fn stdout(cmd: &mut Command) -> String {
    String::from_utf8_lossy(&run(cmd).stdout).into_owned()
}

/// A scratch folder under target/, emptied.
pub fn scratch(name: &str) -> PathBuf {
    let dir = target_dir().join("platform-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create the scratch folder");
    dir
}

/// An FMU of `scene` with every platform (`build`'s default), extracted into a folder.
pub struct Extracted {
    pub dir: PathBuf,
    pub guid: String,
    /// Value references of the node positions (outputs `node[i].x|y|z`).
    pub positions: Vec<u32>,
    /// The force input along x on the last node, pushed during the runs.
    pub push: u32,
}

impl Extracted {
    pub fn library(&self, folder: &str, extension: &str) -> PathBuf {
        let id = self.dir.file_name().unwrap().to_string_lossy();
        self.dir
            .join("binaries")
            .join(folder)
            .join(format!("{id}.{extension}"))
    }
}

/// Builds `scene` with `tensegrity-fmu build` (all platforms) and extracts it, once per
/// test binary.
pub fn extracted(scene: &str) -> &'static Extracted {
    static BUILT: Mutex<BTreeMap<String, &'static Extracted>> = Mutex::new(BTreeMap::new());
    let mut built = BUILT.lock().unwrap_or_else(|e| e.into_inner());
    built
        .entry(scene.to_string())
        .or_insert_with(|| Box::leak(Box::new(extract(scene))))
}

fn extract(scene: &str) -> Extracted {
    let root = scratch(&format!("fmu-{scene}"));
    let fmu = root.join(format!("{scene}.fmu"));
    let out = run(Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args(["build", scene, "-o"])
        .arg(&fmu));
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(
        log.contains("platforms linux64,win64,darwin64,aarch64-linux)"),
        "not every platform was packaged (run `bash fmu/build-binary.sh`): {log}"
    );
    let dir = root.join(scene);
    let file = std::fs::File::open(&fmu).expect("open the FMU");
    zip::ZipArchive::new(file)
        .expect("read the FMU")
        .extract(&dir)
        .expect("extract the FMU");
    let xml = std::fs::read_to_string(dir.join("modelDescription.xml")).expect("read it");
    let attr = |text: &str, name: &str| -> Option<String> {
        let start = text.find(&format!(" {name}=\""))? + name.len() + 3;
        Some(text[start..start + text[start..].find('"')?].to_string())
    };
    let guid = attr(&xml, "guid").expect("guid");
    let variables: Vec<(String, String, u32)> = xml
        .split("<ScalarVariable ")
        .skip(1)
        .map(|v| format!(" {}", &v[..v.find('>').unwrap()]))
        .map(|v| {
            let vr = attr(&v, "valueReference").unwrap().parse().unwrap();
            (
                attr(&v, "name").unwrap(),
                attr(&v, "causality").unwrap_or_default(),
                vr,
            )
        })
        .collect();
    let positions = variables
        .iter()
        .filter(|(name, causality, _)| {
            causality == "output"
                && name.starts_with("node[")
                && [".x", ".y", ".z"].iter().any(|e| name.ends_with(e))
        })
        .map(|v| v.2)
        .collect();
    let push = variables
        .iter()
        .filter(|(name, causality, _)| causality == "input" && name.ends_with(".fx"))
        .map(|v| v.2)
        .next_back()
        .expect("a force input");
    Extracted {
        dir,
        guid,
        positions,
        push,
    }
}

/// The importers, compiled once: (linux64, win64 .exe beside the Wine shim, aarch64).
pub fn importers() -> &'static (PathBuf, PathBuf, PathBuf) {
    static BUILT: OnceLock<(PathBuf, PathBuf, PathBuf)> = OnceLock::new();
    BUILT.get_or_init(|| {
        let dir = scratch("importer");
        let source = Path::new(REPO).join("tests/importer/importer.c");
        let linux = dir.join("importer");
        run(Command::new("cc")
            .args(["-O2", "-o"])
            .arg(&linux)
            .arg(&source)
            .arg("-ldl"));
        let win = dir.join("importer.exe");
        run(Command::new("x86_64-w64-mingw32-gcc")
            .args(["-O2", "-static", "-o"])
            .arg(&win)
            .arg(&source));
        run(Command::new("x86_64-w64-mingw32-gcc")
            .args(["-O2", "-shared", "-o"])
            .arg(dir.join("bcryptprimitives.dll"))
            .arg(Path::new(REPO).join("tests/importer/prng_shim.c"))
            .arg("-ladvapi32"));
        let arm = dir.join("importer-aarch64");
        run(Command::new(Path::new(REPO).join(".venv/bin/python"))
            .args([
                "-m",
                "ziglang",
                "cc",
                "-target",
                "aarch64-linux-gnu.2.28",
                "-O2",
                "-o",
            ])
            .arg(&arm)
            .arg(&source));
        // Creates the Wine prefix now, not in tests running side by side (a usage error).
        let _ = wine().arg(&win).output();
        (linux, win, arm)
    })
}

/// wine64 (Debian keeps it in /usr/lib/wine), quiet, in a prefix under target/.
fn wine() -> Command {
    let wine = ["/usr/lib/wine/wine64", "/usr/bin/wine64"]
        .into_iter()
        .find(|w| Path::new(w).is_file())
        .unwrap_or("wine");
    let mut c = Command::new(wine);
    c.env("WINEPREFIX", target_dir().join("wineprefix"))
        .env("WINEDEBUG", "-all")
        .env("WINEDLLOVERRIDES", "mscoree,mshtml=");
    c
}

/// Where a platform runs here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Runner {
    Native,
    Wine,
    Qemu,
}

/// What the importer printed: the node positions in value-reference order, and its log.
pub struct Run {
    pub positions: Vec<f64>,
    pub log: String,
}

/// Runs the importer of `runner` on `fmu` for `stop` s at 10 ms steps, with `env` set,
/// pushing the last node along x with 5 N.
pub fn simulate(fmu: &Extracted, runner: Runner, stop: &str, env: &[(&str, &str)]) -> Output {
    let (linux, win, arm) = importers();
    let resources = fmu.dir.join("resources");
    let mut cmd = match runner {
        Runner::Native => {
            let mut c = Command::new(linux);
            c.arg(fmu.library("linux64", "so"))
                .arg(format!("file://{}", resources.display()));
            c
        }
        Runner::Wine => {
            let windows = |p: &Path| format!("Z:{}", p.display()).replace('/', "\\");
            let mut c = wine();
            c.arg(win)
                .arg(windows(&fmu.library("win64", "dll")))
                .arg(format!("file:///Z:{}", resources.display()));
            c
        }
        Runner::Qemu => {
            let mut c = Command::new("qemu-aarch64");
            c.args(["-L", "/usr/aarch64-linux-gnu"])
                .arg(arm)
                .arg(fmu.library("aarch64-linux", "so"))
                .arg(format!("file://{}", resources.display()));
            c
        }
    };
    cmd.arg(&fmu.guid).args([stop, "0.01"]);
    cmd.arg(format!("{}=5", fmu.push));
    cmd.args(fmu.positions.iter().map(u32::to_string));
    cmd.env_remove("TENSEGRITY_SIMD").envs(env.iter().copied());
    cmd.output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"))
}

/// [`simulate`] for 1 s, which must succeed and print every position.
pub fn positions(fmu: &Extracted, runner: Runner, env: &[(&str, &str)]) -> Run {
    positions_at(fmu, runner, "1", env)
}

/// [`simulate`], which must succeed and print every position.
pub fn positions_at(fmu: &Extracted, runner: Runner, stop: &str, env: &[(&str, &str)]) -> Run {
    let out = simulate(fmu, runner, stop, env);
    let log = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{runner:?} importer failed: {log}");
    let text = String::from_utf8_lossy(&out.stdout);
    let mut positions = Vec::new();
    for (line, vr) in text.lines().zip(&fmu.positions) {
        let (r, value) = line.split_once(' ').expect("`vr value`");
        assert_eq!(r.parse::<u32>().unwrap(), *vr, "{line}");
        positions.push(value.parse().expect("a number"));
    }
    assert_eq!(positions.len(), fmu.positions.len(), "{text}");
    Run { positions, log }
}

/// The largest difference between two runs' positions, m.
pub fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}
