//! Command-line front end. Each subcommand is a thin layer over the library.

mod analyze;
mod bench;
mod bench_contact;
mod bench_csv;
mod bench_effects;
mod bench_fmu;
mod bench_stiff;
mod bench_threads;
mod bench_work;
mod inputs;
pub mod interrupt;
mod progress;
mod render;
mod report;
mod simulate;
mod work;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use tensegrity_fmu::fmi;
use tensegrity_fmu::fmi::platforms::Binary;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{self, Scene, BUILTIN_DEFAULT};

/// Tensegrity dynamics (Cheong, Skelton & Cho 2014) as FMI 2.0 co-simulation FMUs.
#[derive(Parser, Debug)]
#[command(version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene and write a CSV whose columns are the FMU output names.
    Simulate {
        /// Scene file (.toml or .json) or built-in name; default: prism2.
        scene: Option<String>,
        /// Simulated time in s.
        #[arg(long, default_value_t = 1.0)]
        time: f64,
        /// Internal step in s (default: the scene's solver.step_size).
        #[arg(long)]
        step_size: Option<f64>,
        /// Write a row at every multiple of this many seconds and at --time (default: the step size).
        #[arg(long)]
        interval: Option<f64>,
        /// CSV of input values: header `time,<input names>` (e.g. `node[7].fx`,
        /// `cable[3].force_density`), applied as fmpy applies them (interpolated, held over
        /// each step; a time written twice is a step).
        #[arg(long, value_name = "FILE.csv")]
        inputs: Option<PathBuf>,
        /// Turn the constraint correction off.
        #[arg(long)]
        no_correction: bool,
        /// Take steps across cable slack/taut and ground contact switches whole instead of
        /// splitting them there (solver.locate_events = false).
        #[arg(long)]
        no_event_location: bool,
        /// Integration method: rk4, dopri5, rattle or sdirk3 (default: the scene's solver.method).
        #[arg(long)]
        method: Option<String>,
        /// Relative tolerance of dopri5 (default: the scene's solver.rtol).
        #[arg(long)]
        rtol: Option<f64>,
        /// Absolute tolerance of dopri5 (default: the scene's solver.atol).
        #[arg(long)]
        atol: Option<f64>,
        /// CSV file (default: <scene name>.csv).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Run even when the run is predicted to take more than 1e7 internal steps.
        #[arg(long)]
        force: bool,
    },
    /// Package a scene as an FMI 2.0 co-simulation FMU and print its path.
    Build {
        /// Scene file (.toml or .json) or built-in name; default: prism2.
        scene: Option<String>,
        /// Output file (default: <scene name>.fmu).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// The generic FMU binary (default: fmu/build-binary.sh's portable one when built from
        /// these sources, else libtensegrity_fmu_binary.so next to this program).
        #[arg(long)]
        binary: Option<PathBuf>,
        /// Platforms to package, comma-separated from linux64,win64,darwin64,aarch64-linux
        /// (default: every one that fmu/build-binary.sh built from these sources).
        #[arg(long)]
        platforms: Option<String>,
    },
    /// Regenerate the golden modelDescription.xml files of the shipped scenes.
    Golden {
        /// Folder to write `<scene>.xml` into.
        #[arg(long, default_value = "modelDescription")]
        dir: PathBuf,
    },
    /// Print a built-in scene as TOML (or list them with no name).
    Scene {
        /// Built-in name.
        name: Option<String>,
    },
    /// Print µs per step for towers of growing height, with the ratio to linear scaling
    /// (`bench effects`: what optional effects cost on tower20).
    #[command(args_conflicts_with_subcommands = true)]
    Bench {
        #[command(subcommand)]
        what: Option<BenchCommand>,
        /// Tower heights in stages.
        #[arg(long, value_delimiter = ',', default_value = "2,20,200,2000")]
        stages: Vec<usize>,
        /// Minimum wall time per measurement, s.
        #[arg(long, default_value_t = 1.0)]
        seconds: f64,
        /// Rounds over every height (the first measured again before each other one);
        /// each row gives the fastest round and the median ratio to the first.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..))]
        rounds: u64,
    },
    /// Draw a run: a PNG picture (at --at), a GIF animation (to --time, --fps frames per
    /// second); the format follows the extension of -o (.png, .gif, .html, .pvd).
    Render {
        /// Scene file (.toml or .json) or built-in name; default: prism2.
        scene: Option<String>,
        #[command(flatten)]
        request: render::Request,
    },
    /// Natural frequencies (Hz) and mode shapes about the scene's start state, which must be
    /// an equilibrium at rest (scene key `start = "equilibrium"` solves for one).
    Modes {
        /// Scene file (.toml or .json) or built-in name; default: prism2.
        scene: Option<String>,
        /// Print `{"frequencies_hz": [...], "damped_frequencies_hz": [...], "damping_ratios": [...], "kinds": [...], ...}` instead of a table.
        #[arg(long)]
        json: bool,
        /// Write the mode shapes (every node's displacement per mode) to this CSV.
        #[arg(short, long, value_name = "SHAPES.csv")]
        output: Option<PathBuf>,
    },
    /// The state-space model `ẋ = A x + B u, y = C x + D u` about the scene's start state
    /// (an equilibrium at rest), with the FMU's inputs and outputs; .json, .npz or .mat.
    Linearize {
        /// Scene file (.toml or .json) or built-in name; default: prism2.
        scene: Option<String>,
        /// Output file; its extension picks the format: .json, .npz or .mat.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Reports on the numerics (`report accuracy`: what accuracy costs in time).
    Report {
        #[command(subcommand)]
        what: report::ReportCommand,
    },
}

/// Benchmarks beyond the default scaling one.
#[derive(Subcommand, Debug)]
enum BenchCommand {
    /// µs per CSV row of `simulate` next to µs per tower20 step, with the ratio (and a row
    /// of `{:e}` numbers, for comparison).
    Csv {
        /// Wall time per measured quantity, s, shared among its repeats.
        #[arg(long, default_value_t = 1.0)]
        seconds: f64,
        /// Measurements per quantity, interleaved; the best is printed.
        #[arg(long, default_value_t = 10)]
        repeats: usize,
    },
    /// µs per step of tower20 with only the base effects (elastic cables, pins, joints),
    /// with every optional effect declared at zero, and with them active.
    Effects {
        /// Minimum wall time per measurement, s.
        #[arg(long, default_value_t = 0.1)]
        seconds: f64,
        /// Measurements per case, interleaved; the best is printed (many short ones see
        /// through this machine's slow spells better than a few long ones).
        #[arg(long, default_value_t = 20)]
        repeats: usize,
    },
    /// What terrain contact and bar–bar collisions cost: per tower20 step, as ratios to
    /// the tower alone, and the collision stage alone on towers of growing size.
    Contact {
        /// Minimum wall time per measurement, s.
        #[arg(long, default_value_t = 0.2)]
        seconds: f64,
        /// Measurements per case, interleaved; the best is printed.
        #[arg(long, default_value_t = 10)]
        repeats: usize,
        /// Tower sizes in bars for the collision stage (multiples of 3).
        #[arg(long, value_delimiter = ',', default_value = "600,6000,60000")]
        bars: Vec<usize>,
    },
    /// Steel-stiff cables (κ = 1e7 N/m) over 2 s: sdirk3 at 1 ms against dopri5 at
    /// rtol 1e-6 and rk4 at its stability limit, each with its error and wall time.
    Stiff {
        /// Runs per method, interleaved; the fastest is printed.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
    },
    /// The internal steps and wall time predicted before a run against those it takes,
    /// for seven extreme scenes and the shipped ones (1 s, a row every step).
    Work,
    /// The FMU at scale, per tower size: variables, modelDescription.xml and .fmu sizes,
    /// build time, and through fmpy the read time and one doStep's.
    Fmu {
        /// Tower sizes in bars (multiples of 3).
        #[arg(long, value_delimiter = ',', default_value = "60,600,6000,60000")]
        bars: Vec<usize>,
        /// Keep the towers' three force inputs on the top ring.
        #[arg(long)]
        inputs: bool,
        /// The Python that has fmpy.
        #[arg(long, default_value = ".venv/bin/python")]
        python: PathBuf,
        /// The generic FMU binary (default: as for `build`).
        #[arg(long)]
        binary: Option<PathBuf>,
    },
    /// µs per step of large towers evaluated on one thread and on two, in alternation in
    /// one process, with the median ratio of the rounds.
    Threads {
        /// Tower heights in stages (from 1,334 stages, 4,002 bars, they take two threads).
        #[arg(long, value_delimiter = ',', default_value = "2000,6667,20000")]
        stages: Vec<usize>,
        /// Wall time per measurement, s.
        #[arg(long, default_value_t = 1.0)]
        seconds: f64,
        /// Rounds of one measurement each way.
        #[arg(long, default_value_t = 5)]
        rounds: usize,
    },
}

/// Runs one command; errors come back as messages.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Simulate {
            scene,
            time,
            step_size,
            interval,
            inputs,
            no_correction,
            no_event_location,
            method,
            rtol,
            atol,
            output,
            force,
        } => {
            let mut scene = Scene::from_name_or_file(scene.as_deref().unwrap_or(BUILTIN_DEFAULT))
                .map_err(|e| e.to_string())?;
            let solver = &mut scene.solver;
            if let Some(m) = method {
                solver.method = Method::from_name(&m).ok_or_else(|| {
                    format!("--method {m}: unknown method (rk4, dopri5, rattle or sdirk3)")
                })?;
            }
            solver.step_size = step_size.unwrap_or(solver.step_size);
            solver.rtol = rtol.unwrap_or(solver.rtol);
            solver.atol = atol.unwrap_or(solver.atol);
            solver.correction &= !no_correction;
            solver.locate_events &= !no_event_location;
            let request = simulate::Request {
                time,
                interval,
                inputs,
                output,
                force,
            };
            simulate::simulate(scene, request)
        }
        Command::Scene { name: None } => {
            for n in scene::builtin_names() {
                println!("{n}");
            }
            Ok(())
        }
        Command::Scene { name: Some(name) } => {
            let s = scene::generate(&name).ok_or_else(|| scene::unknown_builtin(&name))?;
            print!("{}", s.to_toml_string());
            Ok(())
        }
        Command::Bench {
            what: Some(BenchCommand::Csv { seconds, repeats }),
            ..
        } => bench_csv::run(seconds, repeats),
        Command::Bench {
            what: Some(BenchCommand::Effects { seconds, repeats }),
            ..
        } => bench_effects::run(seconds, repeats),
        Command::Bench {
            what:
                Some(BenchCommand::Threads {
                    stages,
                    seconds,
                    rounds,
                }),
            ..
        } => bench_threads::run(&stages, seconds, rounds),
        Command::Bench {
            what:
                Some(BenchCommand::Fmu {
                    bars,
                    inputs,
                    python,
                    binary,
                }),
            ..
        } => {
            bench_fmu::check_bars(&bars)?;
            bench_fmu::run(&bars, inputs, &python, &fmu_binary(binary)?)
        }
        Command::Bench {
            what:
                Some(BenchCommand::Contact {
                    seconds,
                    repeats,
                    bars,
                }),
            ..
        } => bench_contact::run(seconds, repeats, &bars),
        Command::Bench {
            what: Some(BenchCommand::Stiff { repeats }),
            ..
        } => bench_stiff::run(repeats),
        Command::Bench {
            what: Some(BenchCommand::Work),
            ..
        } => bench_work::run(),
        Command::Bench {
            what: None,
            stages,
            seconds,
            rounds,
        } => bench::scaling(&stages, seconds, rounds as usize),
        Command::Report { what } => report::run(what),
        Command::Modes {
            scene,
            json,
            output,
        } => analyze::modes(&load_scene(scene)?, json, output.as_deref()),
        Command::Linearize { scene, output } => analyze::linearize(&load_scene(scene)?, &output),
        Command::Render { scene, request } => {
            let scene = Scene::from_name_or_file(scene.as_deref().unwrap_or(BUILTIN_DEFAULT))
                .map_err(|e| e.to_string())?;
            render::render(scene, request)
        }
        Command::Golden { dir } => {
            for name in scene::builtin_names() {
                let s = scene::builtin(name).expect("built-in");
                let xml = fmi::package::golden_model_description(&s)?;
                let path = dir.join(format!("{name}.xml"));
                tensegrity_fmu::partial::write(&path, xml.as_bytes())?;
                println!("{}", path.display());
            }
            Ok(())
        }
        Command::Build {
            scene,
            output,
            binary,
            platforms,
        } => {
            let binaries = fmu_binaries(binary, platforms.as_deref())?;
            build(
                scene.as_deref().unwrap_or(BUILTIN_DEFAULT),
                output,
                &binaries,
            )
        }
    }
}

fn load_scene(scene: Option<String>) -> Result<Scene, String> {
    Scene::from_name_or_file(scene.as_deref().unwrap_or(BUILTIN_DEFAULT)).map_err(|e| e.to_string())
}

fn build(scene_arg: &str, output: Option<PathBuf>, binaries: &[Binary]) -> Result<(), String> {
    let scene = Scene::from_name_or_file(scene_arg).map_err(|e| e.to_string())?;
    let out = output.unwrap_or_else(|| PathBuf::from(format!("{}.fmu", scene.name)));
    let built = fmi::package::build_fmu_for(&scene, binaries, &out)?;
    if let Some(start) = built.start {
        eprintln!("{start}");
    }
    if let Some(why) = &built.inaccurate {
        eprintln!("warning: {why}");
    }
    if let Some(why) = &built.unstable {
        eprintln!(
            "warning: at the scene's own settings and start inputs the FMU refuses fmi2DoStep \
             (an importer may set other solver parameters or inputs first): {why}"
        );
    }
    let folders: Vec<_> = binaries.iter().map(|b| b.platform.folder).collect();
    eprintln!(
        "built {} ({} variables, model identifier {}, GUID {}, platforms {})",
        scene.name,
        built.variables,
        built.model_identifier,
        built.guid,
        folders.join(",")
    );
    println!("{}", out.display());
    Ok(())
}

/// The binaries `build` packages: linux64 from `binary` or as [`fmu_binary`] finds it, and
/// the other platforms' as `fmu/build-binary.sh` left them. Without `platforms`, every
/// platform built from these sources; a platform named there must have its binary.
fn fmu_binaries(binary: Option<PathBuf>, platforms: Option<&str>) -> Result<Vec<Binary>, String> {
    let chosen = match platforms {
        Some(list) => fmi::platforms::parse(list)?,
        None => fmi::platforms::PLATFORMS.to_vec(),
    };
    if binary.is_some() && !chosen.contains(&fmi::platforms::LINUX64) {
        return Err(
            "--binary is the linux64 binary: add linux64 to --platforms or drop --binary".into(),
        );
    }
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let dir = exe.parent().ok_or("cannot locate this program's folder")?;
    let mut binaries = Vec::new();
    for platform in chosen {
        if platform == fmi::platforms::LINUX64 {
            let path = fmu_binary(binary.clone())?;
            binaries.push(Binary { platform, path });
            continue;
        }
        match fmi::platforms::built(dir, &platform) {
            Ok(b) => binaries.push(b),
            Err(why) if platforms.is_some() => {
                return Err(format!(
                    "--platforms {}: {why}: build it with `bash fmu/build-binary.sh`",
                    platform.folder
                ))
            }
            Err(_) => {}
        }
    }
    Ok(binaries)
}

/// `binary`, or the default one; either must exist.
fn fmu_binary(binary: Option<PathBuf>) -> Result<PathBuf, String> {
    let binary = match binary {
        Some(b) => b,
        None => {
            let exe = std::env::current_exe().map_err(|e| e.to_string())?;
            let dir = exe.parent().ok_or("cannot locate this program's folder")?;
            default_binary(dir)
        }
    };
    if !binary.is_file() {
        return Err(format!(
            "the FMU binary {} is missing: build it with `cargo build --release --workspace`, or pass --binary",
            binary.display()
        ));
    }
    Ok(binary)
}

/// The FMU binary for `build` without `--binary`. `cargo build` puts the program in
/// target/<profile>/ and the library beside it; `fmu/build-binary.sh` (cargo-zigbuild, glibc
/// 2.28) puts a portable one in target/x86_64-unknown-linux-gnu/<profile>/, preferred
/// whenever it was built from this program's sources (cargo may rebuild either one later).
fn default_binary(dir: &std::path::Path) -> PathBuf {
    let linux64 = &fmi::platforms::LINUX64;
    let native = dir.join(linux64.file);
    let Some(portable) = fmi::platforms::built_path(dir, linux64) else {
        return native;
    };
    let Ok(so) = std::fs::read(&portable) else {
        return native;
    };
    if fmi::platforms::from_these_sources(&so) {
        return portable;
    }
    eprintln!(
        "note: {} is from other sources, packaging {} (run fmu/build-binary.sh for the portable one)",
        portable.display(),
        native.display()
    );
    native
}
