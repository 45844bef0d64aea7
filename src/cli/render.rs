//! `render`: draw a scene's run as a PNG picture, a GIF animation, an interactive HTML page
//! or a ParaView series. The run is simulated here with the scene's own solver settings,
//! or read back from a CSV of `simulate` or fmpy, or is one mode shape moving about the
//! start equilibrium (`--mode`, built in [`tensegrity_fmu::render::mode`]).

use std::path::{Path, PathBuf};

use clap::Args;
use tensegrity_fmu::dynamics::contact_points::has_contacts;
use tensegrity_fmu::render::{animation, mode, picture, view, Frames};
use tensegrity_fmu::Scene;

/// What `render` was asked for, beyond the scene.
#[derive(Args, Debug)]
pub struct Request {
    /// Picture to write; its extension picks the format: .png, .gif, .html or .pvd.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Time of a still picture, s (default: --time, or 0).
    #[arg(long, allow_negative_numbers = true)]
    pub at: Option<f64>,
    /// Simulated time, s (default: --at for a picture, 2 for an animation).
    #[arg(long)]
    pub time: Option<f64>,
    /// Draw a recorded run instead: a CSV of `simulate` or fmpy for this scene (every
    /// node position column; tensions and velocities read as 0 when absent).
    #[arg(long, value_name = "RESULT.csv")]
    pub csv: Option<PathBuf>,
    /// Animation frames per second; the run is recorded every 1/fps s.
    #[arg(long, default_value_t = 10.0)]
    pub fps: f64,
    /// Camera azimuth, degrees about +z from +x.
    #[arg(long, default_value_t = view::DEFAULT_AZIMUTH, allow_negative_numbers = true)]
    pub azimuth: f64,
    /// Camera elevation, degrees above the x-y plane.
    #[arg(long, default_value_t = view::DEFAULT_ELEVATION, allow_negative_numbers = true)]
    pub elevation: f64,
    /// Number the nodes, bars (b1, ...) and cables (c1, ...).
    #[arg(long)]
    pub labels: bool,
    /// Draw every contact point (terrain, collisions, [ground]) and its force as an arrow,
    /// the largest force of the run 15 % of the structure's size (needs a simulated run).
    #[arg(long)]
    pub contacts: bool,
    /// Instead of simulating, animate mode K (1-based, as `modes` numbers them) about the
    /// start equilibrium: x* + A·φ·sin(2π f t) over one period (a zero-frequency mode
    /// moves linearly there and back over 2 s), bar lengths restored; a .png shows the
    /// peak. Cables are coloured by the tensions of each displaced geometry (at rest).
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    pub mode: Option<i64>,
    /// Largest node displacement of --mode, m (default: 10 % of the structure's size).
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub amplitude: Option<f64>,
    /// Run even when the run is predicted to take more than 1e7 internal steps.
    #[arg(long)]
    pub force: bool,
}

/// Default simulated time of an animation, s.
pub const ANIMATION_TIME: f64 = 2.0;

enum Format {
    Png,
    Gif,
    Html,
    Pvd,
}

fn format_of(path: &Path) -> Result<Format, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png") => Ok(Format::Png),
        Some("gif") => Ok(Format::Gif),
        Some("html") => Ok(Format::Html),
        Some("pvd") => Ok(Format::Pvd),
        _ => Err(format!(
            "-o {}: unknown picture format; name the file with one of .png, .gif, .html, .pvd",
            path.display()
        )),
    }
}

fn check(name: &str, v: f64, example: &str) -> Result<f64, String> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!(
            "{name} must be a finite number (got {v}); pass e.g. {name} {example}"
        ))
    }
}

/// Renders and prints the written path.
pub fn render(scene: Scene, r: Request) -> Result<(), String> {
    let format = format_of(&r.output)?;
    let azimuth = check("--azimuth", r.azimuth, "30")?;
    let elevation = check("--elevation", r.elevation, "20")?;
    if let Some(time) = r.time {
        if !(time >= 0.0 && time.is_finite()) {
            return Err(format!(
                "--time must be zero or positive and finite (got {time}); pass e.g. --time 2"
            ));
        }
    }
    if let Some(at) = r.at {
        check("--at", at, "0.5")?;
    }
    if !(r.fps > 0.0 && r.fps <= 100.0) {
        return Err(format!(
            "--fps must be above 0 and at most 100 (got {}); pass e.g. --fps 10",
            r.fps
        ));
    }
    if r.amplitude.is_some() && r.mode.is_none() {
        return Err("--amplitude is the size of a --mode animation; add --mode K (`tensegrity-fmu modes SCENE` lists them) or drop --amplitude".into());
    }
    if r.csv.is_some() && r.time.is_some() {
        return Err("--time and --csv exclude each other: the CSV's rows are the run; drop --time (or --csv to simulate)".into());
    }
    if r.contacts && r.csv.is_some() {
        return Err("--contacts needs a simulated run: a CSV holds no contact points or forces; drop --csv to simulate the scene instead (or drop --contacts)".into());
    }
    if r.contacts && r.mode.is_some() {
        return Err("--contacts and --mode exclude each other: a mode moves about the start equilibrium, where nothing is simulated to touch; drop one".into());
    }
    let style = picture::Style::new(azimuth, elevation, r.labels);
    let (frames, k) = match (r.mode, &format) {
        (Some(number), _) => mode_loop(&scene, &r, number)?,
        (None, Format::Png) => still(&scene, &r)?,
        (None, _) => (series(&scene, &r)?, 0),
    };
    match format {
        Format::Png => picture::write_png(&frames, k, &style, &r.output)?,
        Format::Gif => animation::write_gif(&frames, r.fps, &style, &r.output)?,
        Format::Html => {
            let page = tensegrity_fmu::render::html::page(&frames);
            tensegrity_fmu::partial::write(&r.output, page.as_bytes())?;
        }
        Format::Pvd => tensegrity_fmu::render::vtk::write_pvd(&frames, &r.output)?,
    }
    println!("{}", r.output.display());
    Ok(())
}

/// One loop of mode `number` and the index of its peak (the frame of a still picture).
fn mode_loop(scene: &Scene, r: &Request, number: i64) -> Result<(Frames, usize), String> {
    let excluded = [
        (r.csv.is_some(), "--csv", "a mode moves about the scene's start equilibrium, not a recorded run; drop --csv (or --mode to draw the CSV)"),
        (r.time.is_some(), "--time", "a mode animation lasts one period (2 s without a frequency); drop --time"),
        (r.at.is_some(), "--at", "a mode's still picture shows its peak, a quarter period in; drop --at"),
    ];
    if let Some((_, flag, why)) = excluded.iter().find(|e| e.0) {
        return Err(format!("--mode and {flag} exclude each other: {why}"));
    }
    let animation = mode::animate(scene, number, r.amplitude, r.fps)?;
    eprintln!(
        "{}: {} frames over {:.4} s, amplitude {:.4} m",
        animation.title,
        animation.frames.len(),
        animation.period,
        animation.amplitude
    );
    Ok((animation.frames, animation.peak))
}

/// The run of a still picture and the index of the frame to draw.
fn still(scene: &Scene, r: &Request) -> Result<(Frames, usize), String> {
    if let Some(path) = &r.csv {
        let frames = Frames::from_csv(scene, path)?;
        let (t0, t1) = (frames.times[0], frames.times[frames.len() - 1]);
        let at = r.at.unwrap_or(t0);
        if at < t0 || at > t1 {
            return Err(format!(
                "--at {at} is outside the run in {}, which spans {t0} to {t1} s; pass --at between them",
                path.display()
            ));
        }
        let k = frames.nearest(at).unwrap_or(0);
        return Ok((frames, k));
    }
    let at = r.at.unwrap_or(r.time.unwrap_or(0.0));
    let time = r.time.unwrap_or(at.max(0.0));
    if !(0.0..=time).contains(&at) {
        return Err(format!(
            "--at {at} is outside the run, which spans 0 to {time} s (--time); pass --at between them or a longer --time"
        ));
    }
    Ok((simulate(scene, &[at], r)?, 0))
}

/// The run of an animation: recorded every 1/fps s from 0 to --time (and at --time), or
/// the CSV's rows thinned to 1/fps s.
fn series(scene: &Scene, r: &Request) -> Result<Frames, String> {
    if r.at.is_some() {
        return Err("--at is for still pictures (.png); an animation shows the whole run: drop --at, or set its length with --time".into());
    }
    let interval = 1.0 / r.fps;
    if let Some(path) = &r.csv {
        let frames = Frames::from_csv(scene, path)?;
        return Ok(frames.select(&frames.every(interval)));
    }
    let time = r.time.unwrap_or(ANIMATION_TIME);
    let frames = (time / interval + 1e-9).floor() as u64;
    if frames > 10_000 {
        return Err(format!(
            "--time {time} at --fps {} would draw {frames} frames, more than 10000; lower --fps or shorten --time",
            r.fps
        ));
    }
    let mut times: Vec<f64> = (0..=frames).map(|k| k as f64 * interval).collect();
    if time - times[times.len() - 1] > 1e-9 * interval {
        times.push(time);
    }
    simulate(scene, &times, r)
}

/// The scene's run recorded at `times` (with its contacts on `--contacts`, refused for a
/// scene where nothing can touch), refused when predicted past
/// [`super::work::MAX_STEPS`] steps without `--force`.
fn simulate(scene: &Scene, times: &[f64], r: &Request) -> Result<Frames, String> {
    let (force, contacts) = (r.force, r.contacts);
    let stop = times.last().copied().unwrap_or(0.0);
    let interval = times.get(1).map_or(stop, |t| t - times[0]);
    Frames::from_checked_run(scene, times, contacts, |sim| {
        if contacts && !has_contacts(sim.model()) {
            return Err(format!(
                "--contacts: scene {} has no terrain, collisions or [ground], so nothing can touch; drop --contacts (or add one of them to the scene)",
                scene.name
            ));
        }
        let refused = "render refused, nothing drawn";
        super::work::predict(sim, stop, interval.max(f64::MIN_POSITIVE), force, refused).map(|_| ())
    })
}
