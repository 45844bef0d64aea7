//! What accuracy costs in time, for one scene: a work-precision report.
//!
//! [`accuracy`] runs the scene under a fixed excitation, computes a reference solution,
//! sweeps every integration method over its settings with the constraint correction on
//! and off, and writes into an output folder:
//!
//! - `accuracy.csv`, one row per run, with the columns [`COLUMNS`]: `method` (`rk4`,
//!   `rattle`, `dopri5`), `setting` (the step size in s for rk4 and rattle, `rtol = atol`
//!   for dopri5), `correction` (`on`/`off`), `status` (`ok` or `failed`; a failed run, one
//!   that stopped with a step error, leaves the other columns empty), the wall time of
//!   the integration in s, the largest node-position error against the reference over all
//!   compared output times and nodes in m, the largest bar-length error in m and
//!   orthogonality error `|b·ḃ|` in m²/s over the output times, the relative energy drift
//!   `max |E − E₀| / |E₀|`, and the number of right-hand-side evaluations;
//! - `work_precision.png`: position error against wall time on log-log axes, one curve
//!   per method (correction on), points joined in order of cost;
//! - `constraint_error.png`: the paper's Fig. 4/5 for this scene, the bar-length error
//!   against time for RK4 at the scene's step size with and without the correction (plus
//!   RK4 at the largest swept step without it), exact zeros drawn at 1e-17 m.
//!
//! **Excitation.** The scene as given (its initial velocities, gravity and prestress)
//! plus a constant load of [`Options::load`] N (1 N by default) along +x on every
//! force-input node, if it has any: a prestressed scene at rest would otherwise stay at
//! rest and every method would be exact. Energy `E` is the model's energy (kinetic, cable
//! strain, gravity) plus the potential `−F·(x − x₀)` of these constant loads, so that `E`
//! is conserved by the exact solution of an undamped scene and its drift measures the
//! integrator.
//!
//! **Output times.** `t_k = k Δ` up to the horizon (rounded down to a multiple of Δ). A
//! fixed-step run is compared only at the output times that lie on its own step grid (for
//! 8 ms steps and Δ = 10 ms, every 40 ms), so that every step it takes has its nominal
//! size; dopri5 is compared at every output time, where it clips its steps.
//!
//! **Reference.** dopri5 at `rtol = atol =` [`Options::reference_tol`] (1e-12) with the
//! correction on; its convergence is checked against [`Options::check_tol`] (1e-11): the
//! largest node-position difference between the two over all output times is reported as
//! [`ReferenceCheck::max_difference_m`]. Errors near that figure are not resolved.
//!
//! **Wall time** is measured around `advance_to` only (not the model build nor the
//! sampling), as the fastest of several repetitions made in rounds over the sweep
//! ([`Options::min_repeats`], [`Options::min_timing_s`]). Because every advance ends at
//! an output time, the output interval caps dopri5's step: tolerances whose natural step
//! is longer all take the same steps, and the Markdown says so.

mod plot;
pub(crate) use plot::register_font;
mod run;
mod table;

use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use crate::integrator::Method;
use crate::model::effects::ForceEffect;
use crate::model::Model;
use crate::scene::Scene;
use crate::sim::{stability_limit, Simulation};
use run::{Grid, Sampled};

pub use table::{recommend, COLUMNS, TARGETS};

/// Settings of an accuracy report.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Simulated time T, s.
    pub horizon: f64,
    /// Output interval Δ, s.
    pub interval: f64,
    /// Constant load along +x on every force-input node, N.
    pub load: f64,
    /// Steps of each fixed-step sweep. rk4's and rattle's start at their stability limit
    /// for this scene (the largest step that divides the output interval and keeps
    /// `h ω` within the limit, ω the scene's fastest rate), sdirk3's, stable at any step,
    /// at the output interval; each next step is half the last.
    pub fixed_steps: usize,
    /// dopri5 tolerances (`rtol = atol`).
    pub dopri5_tols: Vec<f64>,
    /// Tolerance of the reference (dopri5, `rtol = atol`).
    pub reference_tol: f64,
    /// Looser tolerance the reference is checked against.
    pub check_tol: f64,
    /// Each run is repeated at least `min_repeats` times and until its integrations add
    /// up to `min_timing_s` of wall time (at most 20 times), in rounds over the whole
    /// sweep; the fastest repetition's wall time is reported (the runs are
    /// deterministic, so only the timing changes).
    pub min_repeats: usize,
    /// See `min_repeats`, s.
    pub min_timing_s: f64,
    /// Print one line per run to stderr as it finishes.
    pub progress: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            horizon: 2.0,
            interval: 0.01,
            load: 1.0,
            fixed_steps: 6,
            dopri5_tols: (3..=10).map(|e| 10f64.powi(-e)).collect(),
            reference_tol: 1e-12,
            check_tol: 1e-11,
            min_repeats: 3,
            min_timing_s: 0.1,
            progress: false,
        }
    }
}

/// Measured figures of a run that reached the horizon.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metrics {
    /// Wall time spent integrating, s.
    pub wall_time_s: f64,
    /// Largest node-position error against the reference, m.
    pub max_position_error_m: f64,
    /// Largest bar-length error `|‖b‖ − l|` at the output times, m.
    pub max_length_error_m: f64,
    /// Largest orthogonality error `|b·ḃ|` at the output times, m²/s.
    pub max_orthogonality_error_m2_s: f64,
    /// `max |E − E₀| / |E₀|` (E including the load potential).
    pub energy_drift_rel: f64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
}

/// One run of the sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct RunRecord {
    /// Integration method.
    pub method: Method,
    /// Step size in s (rk4, rattle) or `rtol = atol` (dopri5).
    pub setting: f64,
    /// Whether the paper's correction was applied after each step.
    pub correction: bool,
    /// The figures, or the step error that stopped the run.
    pub result: Result<Metrics, String>,
    /// `(t, bar-length error)` at each compared output time, s and m.
    pub length_error_series: Vec<(f64, f64)>,
}

impl RunRecord {
    /// "h = 1 ms" or "tol = 1e-6".
    pub fn setting_label(&self) -> String {
        setting_label(self.method, self.setting)
    }
}

/// How the reference was checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceCheck {
    /// Tolerance of the reference.
    pub tolerance: f64,
    /// Tolerance of the check run.
    pub check_tolerance: f64,
    /// Largest node-position difference between the two over all output times, m.
    pub max_difference_m: f64,
    /// Right-hand-side evaluations of the reference.
    pub rhs_evaluations: u64,
    /// Wall time of the reference, s.
    pub wall_time_s: f64,
}

/// A finished report.
#[derive(Debug, Clone)]
pub struct Report {
    /// Scene name.
    pub scene: String,
    /// Number of loaded (force-input) nodes.
    pub loaded_nodes: usize,
    /// Simulated time actually covered, s.
    pub horizon: f64,
    /// Output interval, s.
    pub interval: f64,
    /// Reference solution and its convergence check.
    pub reference: ReferenceCheck,
    /// Every run of the sweep, in sweep order.
    pub runs: Vec<RunRecord>,
    /// The RK4 step of the constraint-error figure (the scene's step size), s.
    pub constraint_step: f64,
    /// Markdown summary: excitation, reference check, recommendations.
    pub markdown: String,
    /// Path of `accuracy.csv`.
    pub csv: PathBuf,
    /// Path of `work_precision.png`; `None` (and not drawn) when no run with the correction
    /// on reached the horizon.
    pub work_precision: Option<PathBuf>,
    /// Path of `constraint_error.png`; `None` (and not drawn) when neither RK4 run at
    /// [`Report::constraint_step`] reached the horizon.
    pub constraint_error: Option<PathBuf>,
}

/// "h = 1 ms" (fixed-step methods) or "tol = 1e-6" (dopri5).
pub fn setting_label(method: Method, setting: f64) -> String {
    match method {
        Method::Dopri5 => format!("tol = {setting:.0e}"),
        Method::Rk4 | Method::Rattle | Method::Sdirk3 => format!("h = {} ms", short(setting * 1e3)),
    }
}

/// Four significant digits without trailing zeros: "10", "0.3125", "0.7143", "0.02232".
pub(crate) fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let decimals = (3.0 - x.abs().log10().floor()).clamp(0.0, 15.0) as usize;
    let text = format!("{x:.decimals$}");
    match text.contains('.') {
        true => text.trim_end_matches('0').trim_end_matches('.').to_string(),
        false => text,
    }
}

/// Runs the report for `scene` and writes its files into `out_dir` (created if missing).
pub fn accuracy(scene: &Scene, options: &Options, out_dir: &Path) -> Result<Report, String> {
    let o = options;
    if !(o.interval > 0.0 && o.interval.is_finite() && o.horizon >= o.interval) {
        return Err(format!(
            "the horizon ({} s) must be at least one output interval ({} s)",
            o.horizon, o.interval
        ));
    }
    if o.dopri5_tols.iter().any(|&s| !(s > 0.0 && s.is_finite())) {
        return Err("tolerances must be positive and finite".into());
    }
    let model = crate::analysis::load(scene).map_err(|e| e.to_string())?;
    let omega = Simulation::new(model.clone())
        .fastest_rates()
        .first()
        .map(|r| r.omega);
    let grid = Grid {
        interval: o.interval,
        n: (o.horizon / o.interval + 1e-9).floor() as usize,
        load: Vector3::new(o.load, 0.0, 0.0),
    };
    let say = |what: &str, s: &Sampled| {
        if o.progress {
            eprintln!(
                "  {what}: {:.3} s, {} evaluations{}",
                s.wall_time,
                s.rhs_evaluations,
                s.failure
                    .as_deref()
                    .map_or(String::new(), |e| format!(", failed: {e}"))
            );
        }
    };
    let reference = run::simulate(&model, Method::Dopri5, o.reference_tol, true, &grid);
    say(
        &format!("reference dopri5 tol = {:.0e}", o.reference_tol),
        &reference,
    );
    let check = run::simulate(&model, Method::Dopri5, o.check_tol, true, &grid);
    say(&format!("check dopri5 tol = {:.0e}", o.check_tol), &check);
    for (what, r) in [("reference", &reference), ("check", &check)] {
        if let Some(e) = &r.failure {
            return Err(format!("the {what} run failed: {e}"));
        }
    }
    let reference_check = ReferenceCheck {
        tolerance: o.reference_tol,
        check_tolerance: o.check_tol,
        max_difference_m: run::position_error(&check, &reference),
        rhs_evaluations: reference.rhs_evaluations,
        wall_time_s: reference.wall_time,
    };

    let mut specs = Vec::new();
    for method in SWEPT {
        let settings = match method {
            Method::Dopri5 => o.dopri5_tols.clone(),
            _ => fixed_steps(method, omega, o.interval, o.fixed_steps),
        };
        for setting in settings {
            specs.push((method, setting, true));
            specs.push((method, setting, false));
        }
    }
    // The figure of the paper: RK4 at the scene's own step (at the sweep's first, stable
    // one when the scene's is above the limit), with and without correction.
    let rk4_start = fixed_steps(Method::Rk4, omega, o.interval, 1)[0];
    let constraint_step = match omega {
        Some(w) if stability_limit(Method::Rk4).is_some_and(|l| scene.solver.step_size * w > l) => {
            rk4_start
        }
        _ => scene.solver.step_size,
    };
    for correction in [true, false] {
        let spec = (Method::Rk4, constraint_step, correction);
        if !specs.contains(&spec) {
            specs.push(spec);
        }
    }
    let mut runs = Vec::new();
    for &(method, setting, correction) in &specs {
        let r = record(&model, method, setting, correction, &grid, &reference);
        if o.progress {
            eprintln!(
                "  {} {} correction {}: {}",
                method.name(),
                r.setting_label(),
                if correction { "on" } else { "off" },
                match &r.result {
                    Ok(m) => format!(
                        "{:.3} s, error {:.2e} m, {} evaluations",
                        m.wall_time_s, m.max_position_error_m, m.rhs_evaluations
                    ),
                    Err(e) => format!("failed: {e}"),
                }
            );
        }
        runs.push(r);
    }
    if o.progress {
        eprintln!("  repeating the runs in rounds for their wall times (fastest kept)");
    }
    retime(&model, &mut runs, &grid, o);

    std::fs::create_dir_all(out_dir)
        .map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    let mut report = Report {
        scene: scene.name.clone(),
        loaded_nodes: model.force_inputs.len(),
        horizon: grid.n as f64 * grid.interval,
        interval: grid.interval,
        reference: reference_check,
        runs,
        constraint_step,
        markdown: String::new(),
        csv: out_dir.join("accuracy.csv"),
        work_precision: None,
        constraint_error: None,
    };
    let reached = |r: &&RunRecord| r.result.is_ok();
    if report
        .runs
        .iter()
        .filter(|r| r.correction)
        .any(|r| reached(&r))
    {
        report.work_precision = Some(out_dir.join("work_precision.png"));
    }
    let at_step = |r: &&RunRecord| r.method == Method::Rk4 && r.setting == constraint_step;
    if report.runs.iter().filter(at_step).any(|r| reached(&r)) {
        report.constraint_error = Some(out_dir.join("constraint_error.png"));
    }
    report.markdown = table::markdown(&report, o.load, &unconserved_terms(&model));
    crate::partial::write(&report.csv, table::csv(&report.runs).as_bytes())?;
    if let Some(path) = &report.work_precision {
        plot::work_precision(&report, path)?;
    }
    if let Some(path) = &report.constraint_error {
        plot::constraint_error(&report, path)?;
    }
    Ok(report)
}

/// Repeats the runs in rounds over the whole sweep (so that a slow spell of the machine
/// does not hit every repetition of one run) and keeps each run's fastest wall time.
fn retime(model: &Model, runs: &mut [RunRecord], grid: &Grid, o: &Options) {
    let mut total: Vec<f64> = runs.iter().map(wall_time).collect();
    for round in 1..MAX_REPEATS {
        let mut again = false;
        for (r, spent) in runs.iter_mut().zip(&mut total) {
            let enough = round >= o.min_repeats && *spent >= o.min_timing_s;
            let Ok(m) = &mut r.result else { continue };
            if enough {
                continue;
            }
            again = true;
            let s = run::simulate(model, r.method, r.setting, r.correction, grid);
            *spent += s.wall_time;
            if s.failure.is_none() {
                m.wall_time_s = m.wall_time_s.min(s.wall_time);
            }
        }
        if !again {
            break;
        }
    }
}

fn wall_time(r: &RunRecord) -> f64 {
    r.result.as_ref().map_or(0.0, |m| m.wall_time_s)
}

/// What the energy `E` of the drift column leaves out in this model: the terms that make
/// even the exact solution's `E` change.
fn unconserved_terms(model: &Model) -> Vec<&'static str> {
    let mut terms = Vec::new();
    for effect in &model.pipeline.forces {
        match effect {
            ForceEffect::DampedCables(_) => terms.push("cable damping losses"),
            ForceEffect::GroundContact(g) => {
                if g.damping > 0.0 {
                    terms.push("ground damping losses");
                }
                if g.friction > 0.0 {
                    terms.push("friction losses");
                }
            }
            ForceEffect::ScriptedLoads(_) => terms.push("the work of the scripted loads"),
            _ => {}
        }
    }
    terms
}

/// The methods a report sweeps, in the order of its tables.
pub const SWEPT: [Method; 4] = [Method::Rk4, Method::Rattle, Method::Sdirk3, Method::Dopri5];

/// `count` halving steps of a fixed-step method: from the largest step `Δ / k` (whole
/// `k`) with `h ω` inside the method's stability limit, or from `Δ` without a limit.
fn fixed_steps(method: Method, omega: Option<f64>, interval: f64, count: usize) -> Vec<f64> {
    let parts = match (stability_limit(method), omega) {
        (Some(limit), Some(w)) if w > 0.0 => (interval * w / limit).ceil().max(1.0),
        _ => 1.0,
    };
    (0..count)
        .map(|i| interval / (parts * 2f64.powi(i as i32)))
        .collect()
}

/// Most repetitions of one run for its wall time.
const MAX_REPEATS: usize = 20;

fn record(
    model: &Model,
    method: Method,
    setting: f64,
    correction: bool,
    grid: &Grid,
    reference: &Sampled,
) -> RunRecord {
    let s = run::simulate(model, method, setting, correction, grid);
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let result = match &s.failure {
        Some(e) => Err(e.clone()),
        None => Ok(Metrics {
            wall_time_s: s.wall_time,
            max_position_error_m: run::position_error(&s, reference),
            max_length_error_m: max(&s.length_error),
            max_orthogonality_error_m2_s: max(&s.orthogonality_error),
            energy_drift_rel: run::energy_drift(&s),
            rhs_evaluations: s.rhs_evaluations,
        }),
    };
    let series = s
        .index
        .iter()
        .zip(&s.length_error)
        .map(|(&k, &e)| (k as f64 * grid.interval, e))
        .collect();
    RunRecord {
        method,
        setting,
        correction,
        result,
        length_error_series: series,
    }
}
