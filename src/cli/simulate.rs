//! `simulate`: run a scene and write a CSV whose columns are the FMU's output names.
//!
//! Rows are at `k · --interval` (computed as a product, not a running sum) and at
//! `--time`; between them `Simulation::advance_to` integrates exactly as `fmi2DoStep` does
//! (steps of `solver.step_size`, the last one shortened). With `--inputs`, the
//! communication points and input values are fmpy's (see [`super::inputs`]). The rows are
//! formatted and written by a thread of their own (`outputs::RowThread`), the same bytes
//! as on the stepping thread.

use std::io::BufWriter;
use std::path::PathBuf;
use tensegrity_fmu::partial::Partial;

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::outputs::RowThread;
use tensegrity_fmu::scene::Scene;
use tensegrity_fmu::{outputs, Simulation, StepError};

use super::inputs::{isclose, InputTable};
use super::interrupt;
use super::progress::Progress;
use super::work;

/// Most rows one `simulate` writes.
pub const MAX_ROWS: f64 = 1e7;
/// Most values (rows × columns) one `simulate` writes: about 2–4 GB of CSV.
pub const MAX_VALUES: f64 = 2.5e8;
/// Most internal fixed steps one `simulate` takes.
pub const MAX_STEPS: f64 = 1e9;

/// What `simulate` was asked for, beyond the scene.
pub struct Request {
    /// Simulated time, s.
    pub time: f64,
    /// Row interval, s (default: the step size).
    pub interval: Option<f64>,
    /// Input CSV.
    pub inputs: Option<PathBuf>,
    /// CSV to write (default: `<scene name>.csv`).
    pub output: Option<PathBuf>,
    /// Run past [`super::work::MAX_STEPS`] predicted steps.
    pub force: bool,
}

/// Runs the scene and writes the CSV; on failure no CSV is left behind. Stopped by Ctrl-C,
/// it keeps the rows written so far as a whole CSV.
pub fn simulate(scene: Scene, request: Request) -> Result<(), String> {
    let Request {
        time,
        interval,
        inputs,
        output,
        force,
    } = request;
    let model = tensegrity_fmu::analysis::load(&scene).map_err(|e| e.to_string())?;
    let h = model.solver.step_size;
    if !(h > 0.0 && h.is_finite()) {
        return Err(format!(
            "--step-size must be positive and finite (got {h}); pass e.g. --step-size 0.001"
        ));
    }
    if !(time >= 0.0 && time.is_finite()) {
        return Err(format!(
            "--time must be zero or positive and finite (got {time}); pass e.g. --time 1"
        ));
    }
    let interval = interval.unwrap_or(h);
    if !(interval > 0.0 && interval.is_finite()) {
        return Err(format!(
            "--interval must be positive and finite (got {interval}); pass e.g. --interval 0.01"
        ));
    }
    let mut sim = Simulation::new(model);
    if let Some(why) = sim.step_size_problem() {
        return Err(why);
    }
    let table = outputs::outputs(&sim);
    check_size(&sim, time, interval, table.len() + 1)?;
    let inputs = match &inputs {
        Some(path) => Some(InputTable::read(path, &sim)?),
        None => None,
    };
    for w in sim.warnings() {
        eprintln!("warning: {w}");
    }
    if let Some(start) = sim.model().start {
        eprintln!("{start}");
    }
    // The guard refuses the first step exactly as `stability_problem` says, unless the
    // inputs change the stiffness first: refuse now, or warn once and point back to it.
    let unstable = sim.stability_problem();
    if let Some(why) = &unstable {
        if inputs.is_none() {
            return Err(format!("simulate refused, no CSV written: {why}"));
        }
        eprintln!("warning: {why}");
    }
    if let Some(why) = sim.accuracy_problem() {
        eprintln!("warning: {why}");
    }
    let refused = "simulate refused, no CSV written";
    let predicted = work::predict(&mut sim, time, interval, force, refused)?;
    let progress = Progress::new(time, predicted.seconds);
    let path = output.unwrap_or_else(|| PathBuf::from(format!("{}.csv", scene.name)));
    let (partial, file) = Partial::create(&path)?;
    // A hidden hook for the tests: a bug (a panic) while a temporary file is open.
    if std::env::var_os("TENSEGRITY_FMU_TEST_PANIC").is_some() {
        panic!("deliberate panic (TENSEGRITY_FMU_TEST_PANIC is set)");
    }
    let io = |e: std::io::Error| format!("writing {}: {e}", path.display());
    let mut w = BufWriter::new(file);
    outputs::write_header(&mut w, &table).map_err(io)?;
    // Formatting a row costs most of a step: a thread of its own does it. On an error
    // below, dropping `rows` stops it before `partial` removes the file.
    let mut rows = RowThread::spawn(w, &table).map_err(io)?;
    let warned = unstable.as_deref();
    let evaluate = outputs::needs_evaluation(&table);
    let (mut written, mut last) = (0u64, 0.0);
    interrupt::stoppable(true);
    let ran = run(
        &mut sim,
        inputs.as_ref(),
        time,
        interval,
        warned,
        evaluate,
        |sim| {
            (written, last) = (written + 1, sim.time());
            progress.reached(last);
            rows.send_row(sim).map_err(io)
        },
    );
    interrupt::stoppable(false);
    progress.finish();
    ran?;
    let w = rows.finish().map_err(io)?;
    drop(w.into_inner().map_err(|e| io(e.into_error()))?);
    partial.commit()?;
    // A Ctrl-C during the last row came too late to stop anything: the run is whole.
    if interrupt::stop_requested() && (last > time || isclose(last, time)) {
        interrupt::forget_stop();
    }
    if interrupt::stop_requested() {
        eprintln!(
            "interrupted at t = {last} s of {time} s: {} holds the {written} rows from t = 0 to {last} s",
            path.display()
        );
    }
    println!("{}", path.display());
    Ok(())
}

/// fmpy's co-simulation loop (`fmpy.simulation.simulateCS` with a variable communication
/// step) from 0 to `stop`: `row` is called at 0, at every `k · interval` and at `stop`.
/// A refusal that repeats the `warned` message says so instead of repeating it. With
/// `evaluate`, each row is preceded by an evaluation at its state (see
/// [`outputs::needs_evaluation`]).
fn run(
    sim: &mut Simulation,
    inputs: Option<&InputTable>,
    stop: f64,
    interval: f64,
    warned: Option<&str>,
    evaluate: bool,
    mut row: impl FnMut(&Simulation) -> Result<(), String>,
) -> Result<(), String> {
    if let Some(table) = inputs {
        // As in initialization mode: the value before a step at the start time.
        table.apply(0.0, false, &mut sim.inputs);
    }
    sim.refresh();
    row(sim)?;
    let mut time = 0.0;
    let mut k = 0u64;
    // A Ctrl-C ends the run at the last row written (see `interrupt`).
    while !(time > stop || isclose(time, stop) || interrupt::stop_requested()) {
        let regular = (k + 1) as f64 * interval;
        let mut next = regular;
        let event = inputs.map_or(f64::INFINITY, |t| t.next_event(time));
        if next > event && !isclose(next, event) {
            next = event;
        }
        // The last point is exactly --time (fmpy would keep a product within 1e-9 of it).
        let last = next > stop || isclose(next, stop);
        if last {
            next = stop;
        }
        if let Some(table) = inputs {
            table.apply(time, true, &mut sim.inputs);
        }
        sim.advance_to(next).map_err(|e| match e {
            StepError::Unstable { message } if Some(message.as_str()) == warned => format!(
                "simulate stopped at t = {time} s, no CSV written: the fixed step is above the \
                 stability limit (the warning above names the cause and the fixes)"
            ),
            e => format!("simulate stopped, no CSV written: {e}"),
        })?;
        time = next;
        let on_grid = isclose(time, regular);
        if on_grid {
            k += 1;
        }
        if on_grid || last {
            // Positions and velocities are read from the state; only other outputs need
            // an evaluation.
            if evaluate {
                sim.refresh();
            }
            row(sim)?;
        }
    }
    Ok(())
}

/// Refuses runs whose output or work would be absurd, before anything is written.
fn check_size(sim: &Simulation, time: f64, interval: f64, columns: usize) -> Result<(), String> {
    let rows = (time / interval).ceil() + 1.0;
    let values = rows * columns as f64;
    if rows > MAX_ROWS || values > MAX_VALUES {
        return Err(format!(
            "--time {time} with --interval {interval} would write {rows:.0} rows of {columns} columns ({values:.2e} values, about {:.0} GB), more than the limit of {MAX_ROWS:.0e} rows and {MAX_VALUES:.1e} values; raise --interval or shorten --time",
            values * 16.0 / 1e9
        ));
    }
    let solver = &sim.model().solver;
    if solver.method != Method::Dopri5 {
        let h = solver.step_size;
        let per_row = (interval.min(time.max(h)) / h).ceil();
        if per_row > solver.max_steps as f64 {
            return Err(format!(
                "--interval {interval} takes {per_row:.0} internal steps of {h} s per row, more than solver.max_steps = {}; lower --interval, raise --step-size, or raise solver.max_steps in the scene",
                solver.max_steps
            ));
        }
        let steps = (time / h).ceil() + rows;
        if steps > MAX_STEPS {
            return Err(format!(
                "--time {time} takes {steps:.2e} internal steps of {h} s, more than the limit of {MAX_STEPS:.0e}; shorten --time or raise --step-size"
            ));
        }
    }
    Ok(())
}
