//! `bench csv`: what a CSV row of `simulate` costs next to a tower20 step, in one process.
//!
//! tower20 as shipped with 1 N on its top nodes (574 columns). Timed, interleaved
//! `repeats` times and the best kept (this machine's slow spells only ever add time):
//!
//! - a step: rk4 at 1 ms with the correction (`Simulation::advance`);
//! - a row as `simulate` writes it now: the outputs, formatted as shortest round-trip
//!   decimals into a `BufWriter` (`outputs::RowWriter`), here over `io::sink()` so that
//!   the disk's speed is not what is measured;
//! - a row as it was written before: `write!(w, ",{:e}", value)` per value into the same
//!   kind of writer (kept here only to show the difference);
//! - reading the row's values alone (what is left of a row without the formatting);
//! - the `refresh` before each row (one evaluation at the row's state, so that tensions,
//!   bar forces and reactions belong to it; the FMU does the same before returning such
//!   outputs, and neither evaluates for positions and velocities, read from the state);
//! - a row of the node positions alone (a scene with `outputs = ["positions"]`), which
//!   needs no refresh.

use std::io::{BufWriter, Sink, Write};
use std::time::Instant;

use tensegrity_fmu::outputs::{self, Output, RowWriter};
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

/// Step size, s.
const STEP: f64 = 1e-3;

/// Runs the benchmark and prints the table.
pub fn run(seconds: f64, repeats: usize) -> Result<(), String> {
    if !(seconds > 0.0 && seconds.is_finite()) || repeats == 0 {
        return Err(format!(
            "--seconds must be positive and --repeats at least 1 (got {seconds}, {repeats})"
        ));
    }
    let scene = super::bench::with_rk4(builtin("tower20").expect("built-in"));
    let model = Model::new(&scene).map_err(|e| e.to_string())?;
    let mut sim = Simulation::new(model);
    for f in &mut sim.inputs.node_force {
        f.x = 1.0;
    }
    sim.advance(100, STEP).map_err(|e| e.to_string())?;
    sim.refresh();
    let table = outputs::outputs(&sim);
    let mut w = BufWriter::new(std::io::sink());
    let [step, row, old, refresh, values, positions] =
        measure(&mut sim, &table, &mut w, seconds, repeats)?;
    println!(
        "tower20 ({} columns), best of {repeats} interleaved measurements of ≥ {} s each:\n",
        table.len() + 1,
        seconds / repeats as f64
    );
    println!("| what | µs | ratio to a step |");
    println!("|---|---:|---:|");
    for (what, us) in [
        ("rk4 step (1 ms, with correction)", step),
        (
            "CSV row: shortest round-trip decimals (`outputs::RowWriter`)",
            row,
        ),
        (
            "of which reading the values (the rest is formatting)",
            values,
        ),
        (
            "CSV row as before: `write!(w, \",{:e}\", value)` per value",
            old,
        ),
        ("refresh before a row (one evaluation)", refresh),
        (
            "CSV row of the node positions alone (no refresh needed)",
            positions,
        ),
    ] {
        println!("| {what} | {us:.2} | {:.3} |", us / step);
    }
    Ok(())
}

/// Best µs per step, per row, per old-style row, per refresh, per reading of the values and
/// per row of the positions alone.
fn measure(
    sim: &mut Simulation,
    table: &[Output],
    w: &mut BufWriter<Sink>,
    seconds: f64,
    repeats: usize,
) -> Result<[f64; 6], String> {
    let io = |e: std::io::Error| format!("writing the benchmark file: {e}");
    let mut best = [f64::INFINITY; 6];
    let mut rows = RowWriter::new(table);
    let positions: Vec<Output> = table
        .iter()
        .filter(|o| o.quantity.group() == outputs::OutputGroup::Positions)
        .cloned()
        .collect();
    let mut position_rows = RowWriter::new(&positions);
    let budget = seconds / repeats as f64;
    for _ in 0..repeats {
        let us = timed(budget, 10, |n| {
            sim.advance(n, STEP).map_err(|e| e.to_string())
        })?;
        best[0] = best[0].min(us);
        let us = timed(budget, 100, |n| {
            for _ in 0..n {
                rows.write_row(w, table, sim).map_err(io)?;
            }
            Ok(())
        })?;
        best[1] = best[1].min(us);
        let us = timed(budget, 100, |n| {
            for _ in 0..n {
                old_row(w, table, sim).map_err(io)?;
            }
            Ok(())
        })?;
        best[2] = best[2].min(us);
        let us = timed(budget, 100, |n| {
            for _ in 0..n {
                sim.refresh();
            }
            Ok(())
        })?;
        best[3] = best[3].min(us);
        let us = timed(budget, 100, |n| {
            for _ in 0..n {
                let sum: f64 = table.iter().map(|o| o.quantity.value(sim)).sum();
                std::hint::black_box(sum);
            }
            Ok(())
        })?;
        best[4] = best[4].min(us);
        let us = timed(budget, 100, |n| {
            for _ in 0..n {
                position_rows.write_row(w, &positions, sim).map_err(io)?;
            }
            Ok(())
        })?;
        best[5] = best[5].min(us);
    }
    w.flush().map_err(io)?;
    Ok(best)
}

/// µs per unit of `work(n)` (which does `n` units), run for at least `seconds`.
fn timed(
    seconds: f64,
    n: u64,
    mut work: impl FnMut(u64) -> Result<(), String>,
) -> Result<f64, String> {
    let started = Instant::now();
    let mut done = 0u64;
    while done == 0 || started.elapsed().as_secs_f64() < seconds {
        work(n)?;
        done += n;
    }
    Ok(started.elapsed().as_secs_f64() * 1e6 / done as f64)
}

/// The row writer `simulate` used before: `{:e}` through `write!` per value.
fn old_row(w: &mut impl Write, table: &[Output], sim: &Simulation) -> std::io::Result<()> {
    write!(w, "{}", sim.time())?;
    for o in table {
        write!(w, ",{:e}", o.quantity.value(sim))?;
    }
    writeln!(w)
}
