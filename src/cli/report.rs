//! `report accuracy`: the work-precision report of [`tensegrity_fmu::report`].

use std::path::PathBuf;
use std::time::Instant;

use clap::Subcommand;

use tensegrity_fmu::report::{self, Options};
use tensegrity_fmu::scene::{Scene, BUILTIN_DEFAULT};

/// Reports.
#[derive(Subcommand, Debug)]
pub enum ReportCommand {
    /// What accuracy costs in time: a reference solution, a sweep of methods and
    /// settings with the correction on and off, accuracy.csv, work_precision.png,
    /// constraint_error.png and a Markdown recommendation per error target.
    Accuracy {
        /// Scene file (.toml or .json) or built-in name; default: prism2.
        scene: Option<String>,
        /// Output folder (default: report-<scene name>).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Simulated time in s.
        #[arg(long, default_value_t = 2.0)]
        time: f64,
    },
}

/// Runs a report command.
pub fn run(command: ReportCommand) -> Result<(), String> {
    match command {
        ReportCommand::Accuracy {
            scene,
            output,
            time,
        } => {
            let scene = Scene::from_name_or_file(scene.as_deref().unwrap_or(BUILTIN_DEFAULT))
                .map_err(|e| e.to_string())?;
            if !(time.is_finite() && time > 0.0) {
                return Err(format!("--time must be positive and finite (got {time})"));
            }
            let dir = output.unwrap_or_else(|| PathBuf::from(format!("report-{}", scene.name)));
            let options = Options {
                horizon: time,
                progress: true,
                ..Options::default()
            };
            eprintln!("accuracy report for {} ({time} s):", scene.name);
            let started = Instant::now();
            let r = report::accuracy(&scene, &options, &dir)?;
            eprintln!("done in {:.1} s", started.elapsed().as_secs_f64());
            println!("{}", r.markdown);
            println!("Written:\n");
            let pictures = [&r.work_precision, &r.constraint_error];
            for p in [Some(&r.csv)]
                .into_iter()
                .chain(pictures.map(Option::as_ref))
                .flatten()
            {
                println!("- {}", p.display());
            }
            Ok(())
        }
    }
}
