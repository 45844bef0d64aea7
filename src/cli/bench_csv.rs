//! `bench csv`: what a CSV row of `simulate` costs next to a tower20 step, in one process.
//!
//! tower20 as shipped with 1 N on its top nodes (574 columns). Timed, interleaved
//! `repeats` times and the best kept (this machine's slow spells only ever add time):
//!
//! - a step: rk4 at 1 ms with the correction (`Simulation::advance`);
//! - a row written on the stepping thread, as `simulate` wrote it before its writer thread
//!   (the same bytes): the outputs, formatted as shortest round-trip decimals into a
//!   `BufWriter` (`outputs::RowWriter`), here over `io::sink()` so that the disk's speed is
//!   not what is measured;
//! - a row of `{:e}` numbers, for comparison: `write!(w, ",{:e}", value)` per value into the same
//!   kind of writer (kept here only to show the difference);
//! - reading the row's values alone (what is left of a row without the formatting), output
//!   by output as `RowWriter` does, and with `outputs::RowReader` as `RowThread` does;
//! - the `refresh` before each row (one evaluation at the row's state, so that tensions,
//!   bar forces and reactions belong to it; the FMU does the same before returning such
//!   outputs, and neither evaluates for positions and velocities, read from the state);
//! - a row of the node positions alone (a scene with `outputs = ["positions"]`), which
//!   needs no refresh;
//! - what a row costs the stepping thread when, as in `simulate`, it is evaluated at
//!   (refreshed; the next step takes that evaluation as its first stage) and handed to a
//!   writer thread (`outputs::RowThread`) that formats and writes it: pairs of blocks of
//!   [`BLOCK`] steps, one without rows and one with a row handed over after every step (or
//!   every 10th), interleaved; the median over the pairs of the difference per row (which
//!   includes what the rows do to the steps' caches), and of the time inside the refresh
//!   and `send_row`; and the same with the rows refreshed and only read into a buffer, no
//!   writer thread: the floor of
//!   any scheme that copies the values out, so that what the hand-over adds shows;
//! - the writer thread's own CPU time per row: the process's CPU time less the stepping
//!   thread's, over all rows handed over (the formatting moved to the other core, it did
//!   not vanish).

use std::io::{BufWriter, Sink, Write};
use std::time::Instant;

use tensegrity_fmu::outputs::{self, Output, RowReader, RowThread, RowWriter};
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

/// Step size, s.
const STEP: f64 = 1e-3;

/// Steps per timed block of the threaded scheme: at both row spacings a whole number of
/// tower20's 56-row chunks (20 at every step, 2 at every 10th), so every block hands the
/// writer the same number of them.
const BLOCK: u64 = 1120;
/// Untimed steps after a block with rows, while the writer formats its last chunk (about
/// 1 ms), so that the next block does not share the machine with it.
const SETTLE: u64 = 100;
/// Rows in the threaded scheme go after every `SPACINGS[i]`-th step.
const SPACINGS: [u64; 2] = [1, 10];

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
    let c = measure(&mut sim, &table, seconds, repeats)?;
    println!(
        "tower20 ({} columns), best of {repeats} interleaved measurements of ≥ {} s each:\n",
        table.len() + 1,
        seconds / repeats as f64
    );
    println!("| what | µs | ratio to a step |");
    println!("|---|---:|---:|");
    let [every_step, every_10th] = &c.threaded;
    let [read_every_step, read_every_10th] = &c.read_only;
    let read_only = |what: &str, h: &Handover| {
        format!(
            "the same rows, refreshed and only read into a buffer after {what}, no writer thread (the \
             floor; median of {} pairs)",
            h.pairs
        )
    };
    let handed = |what: &str, h: &Handover| {
        format!(
            "CSV row handed to the writer thread after {what}: the stepping thread's cost \
             (median of {} pairs of {BLOCK}-step blocks)",
            h.pairs
        )
    };
    for (what, us) in [
        ("rk4 step (1 ms, with correction)".to_string(), c.step),
        (
            "CSV row on the stepping thread: shortest round-trip decimals (`outputs::RowWriter`)"
                .into(),
            c.row,
        ),
        (
            "of which reading the values (the rest is formatting)".into(),
            c.values,
        ),
        (
            "CSV row of `{:e}` numbers: `write!(w, \",{:e}\", value)` per value".into(),
            c.old_row,
        ),
        ("refresh before a row (one evaluation)".into(), c.refresh),
        (
            "CSV row of the node positions alone (no refresh needed)".into(),
            c.positions,
        ),
        (
            "reading the values with `outputs::RowReader` (a node's x, y, z together), as \
             `RowThread` does"
                .into(),
            c.reader_values,
        ),
        (handed("every step", every_step), every_step.per_row),
        (
            "time inside the refresh and `RowThread::send_row` (timed around both; median)".into(),
            every_step.inside,
        ),
        (
            read_only("every step", read_every_step),
            read_every_step.per_row,
        ),
        (handed("every 10th step", every_10th), every_10th.per_row),
        (
            "time inside the refresh and `RowThread::send_row` (timed around both; median)".into(),
            every_10th.inside,
        ),
        (
            read_only("every 10th step", read_every_10th),
            read_every_10th.per_row,
        ),
        (
            "the writer thread's CPU per row (formatting it, taking and returning its chunk; \
             on the other core; mean over all rows)"
                .into(),
            c.writer_cpu,
        ),
    ] {
        println!("| {what} | {us:.2} | {:.3} |", us / c.step);
    }
    println!(
        "\nThe writer thread (as `simulate` runs it) moved the formatting's CPU time to the \
         other core, it did not vanish: {:.2} µs of writer CPU per row, against {:.2} µs for \
         the whole row on the stepping thread. A handed-over row's cost to the stepping \
         thread is (a block of steps with rows − the same steps without) per row, the \
         steps' own slowing included; the writer's text goes to io::sink() here.",
        c.writer_cpu, c.row
    );
    Ok(())
}

/// Best µs of each measured quantity; for the writer thread, medians and a mean.
struct Costs {
    step: f64,
    row: f64,
    old_row: f64,
    refresh: f64,
    values: f64,
    positions: f64,
    /// Reading a row's values with `RowReader`, as the writer thread's rows are read.
    reader_values: f64,
    /// Rows handed to the writer thread after every step, then after every 10th.
    threaded: [Handover; 2],
    /// The same rows only read into a buffer.
    read_only: [Handover; 2],
    /// The writer thread's CPU time per row, µs (a mean over all rows).
    writer_cpu: f64,
}

/// What a row handed to the writer thread (or only read) costs the stepping thread, µs:
/// medians over `pairs` pairs of blocks.
struct Handover {
    /// A block with rows less the block without, per row.
    per_row: f64,
    /// Inside the refresh and `send_row`, per row.
    inside: f64,
    pairs: usize,
}

/// The pairs timed for one row spacing, µs per row.
#[derive(Default)]
struct Pairs {
    per_row: Vec<f64>,
    inside: Vec<f64>,
}

impl Pairs {
    fn medians(mut self) -> Handover {
        Handover {
            pairs: self.per_row.len(),
            per_row: median(&mut self.per_row),
            inside: median(&mut self.inside),
        }
    }
}

fn median(xs: &mut [f64]) -> f64 {
    xs.sort_by(f64::total_cmp);
    match xs.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => xs[n / 2],
        n => 0.5 * (xs[n / 2 - 1] + xs[n / 2]),
    }
}

/// The writer thread as benchmarked: its text goes nowhere.
type BenchThread = RowThread<BufWriter<Sink>>;

/// What happens to a row after every `every`-th step.
struct Rows<'a> {
    sink: RowSink<'a>,
    every: u64,
    /// Evaluate at the row's state first, as `simulate` does for such outputs.
    refresh: bool,
}

enum RowSink<'a> {
    /// Handed to the writer thread, as `simulate` does.
    Thread(&'a mut BenchThread),
    /// Only read into a buffer: the floor of any scheme that copies the values out.
    ReadOnly(&'a RowReader, &'a mut Vec<f64>),
}

impl RowSink<'_> {
    fn take(&mut self, sim: &Simulation) -> Result<(), String> {
        match self {
            Self::Thread(thread) => thread
                .send_row(sim)
                .map_err(|e| format!("writing the benchmark rows: {e}")),
            Self::ReadOnly(reader, values) => {
                values.clear();
                reader.read(sim, values);
                std::hint::black_box(&**values);
                Ok(())
            }
        }
    }
}

/// `n` steps, with `rows`: the seconds spent on them (in the refresh and `send_row`), and
/// their number.
fn steps(sim: &mut Simulation, n: u64, mut rows: Option<&mut Rows>) -> Result<(f64, u64), String> {
    let mut inside = 0.0;
    let mut handed = 0;
    for i in 1..=n {
        sim.advance(1, STEP).map_err(|e| e.to_string())?;
        if let Some(rows) = rows.as_deref_mut().filter(|r| i % r.every == 0) {
            let started = Instant::now();
            if rows.refresh {
                sim.refresh();
            }
            rows.sink.take(sim)?;
            inside += started.elapsed().as_secs_f64();
            handed += 1;
        }
    }
    Ok((inside, handed))
}

/// Pairs of blocks, each [`BLOCK`] steps without rows then as many with `rows`, and
/// [`SETTLE`] untimed steps, for at least `seconds`: the rows handed over.
fn time_pairs(
    sim: &mut Simulation,
    mut rows: Rows,
    seconds: f64,
    pairs: &mut Pairs,
) -> Result<u64, String> {
    let started = Instant::now();
    let mut handed_in_all = 0;
    while handed_in_all == 0 || started.elapsed().as_secs_f64() < seconds {
        let block = Instant::now();
        steps(sim, BLOCK, None)?;
        let without = block.elapsed().as_secs_f64();
        let block = Instant::now();
        let (inside, handed) = steps(sim, BLOCK, Some(&mut rows))?;
        let with = block.elapsed().as_secs_f64();
        steps(sim, SETTLE, None)?;
        pairs.per_row.push((with - without) * 1e6 / handed as f64);
        pairs.inside.push(inside * 1e6 / handed as f64);
        handed_in_all += handed;
    }
    Ok(handed_in_all)
}

/// The process's and this thread's CPU time, s.
struct CpuTimes {
    process: f64,
    this_thread: f64,
}

impl CpuTimes {
    fn now() -> Self {
        Self {
            process: cpu_seconds(Clock::Process),
            this_thread: cpu_seconds(Clock::ThisThread),
        }
    }

    /// CPU time of the process's other threads since `self`, s (NaN where unknown).
    fn elapsed_elsewhere(&self) -> f64 {
        let now = Self::now();
        (now.process - self.process) - (now.this_thread - self.this_thread)
    }
}

enum Clock {
    Process,
    ThisThread,
}

#[cfg(any(target_os = "linux", target_os = "macos"))]
fn cpu_seconds(clock: Clock) -> f64 {
    let id = match clock {
        Clock::Process => libc::CLOCK_PROCESS_CPUTIME_ID,
        Clock::ThisThread => libc::CLOCK_THREAD_CPUTIME_ID,
    };
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes the timespec it is given and nothing else.
    if unsafe { libc::clock_gettime(id, &mut t) } != 0 {
        return f64::NAN;
    }
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

#[cfg(not(any(target_os = "linux", target_os = "macos")))]
fn cpu_seconds(_: Clock) -> f64 {
    f64::NAN
}

/// Times every quantity of [`Costs`], interleaved, `repeats` times.
fn measure(
    sim: &mut Simulation,
    table: &[Output],
    seconds: f64,
    repeats: usize,
) -> Result<Costs, String> {
    let io = |e: std::io::Error| format!("writing the benchmark file: {e}");
    let mut w = BufWriter::new(std::io::sink());
    let mut best = [f64::INFINITY; 7];
    let mut rows = RowWriter::new(table);
    let positions: Vec<Output> = table
        .iter()
        .filter(|o| o.quantity.group() == outputs::OutputGroup::Positions)
        .cloned()
        .collect();
    let mut position_rows = RowWriter::new(&positions);
    let reader = RowReader::new(table);
    let mut values = Vec::with_capacity(table.len() + 1);
    let cpu_before = CpuTimes::now();
    let mut thread: BenchThread =
        RowThread::spawn(BufWriter::new(std::io::sink()), table).map_err(io)?;
    let mut pairs = [Pairs::default(), Pairs::default()];
    let mut read_only = [Pairs::default(), Pairs::default()];
    let mut handed_in_all = 0;
    let budget = seconds / repeats as f64;
    let refresh = outputs::needs_evaluation(table);
    for _ in 0..repeats {
        let us = timed(budget, 100, |n| steps(sim, n, None).map(drop))?;
        best[0] = best[0].min(us);
        for (i, every) in SPACINGS.into_iter().enumerate() {
            let sink = RowSink::Thread(&mut thread);
            let rows = Rows {
                sink,
                every,
                refresh,
            };
            handed_in_all += time_pairs(sim, rows, budget, &mut pairs[i])?;
            let sink = RowSink::ReadOnly(&reader, &mut values);
            let rows = Rows {
                sink,
                every,
                refresh,
            };
            time_pairs(sim, rows, budget, &mut read_only[i])?;
        }
        let us = timed(budget, 100, |n| {
            for _ in 0..n {
                rows.write_row(&mut w, table, sim).map_err(io)?;
            }
            Ok(())
        })?;
        best[1] = best[1].min(us);
        let us = timed(budget, 100, |n| {
            for _ in 0..n {
                old_row(&mut w, table, sim).map_err(io)?;
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
                position_rows
                    .write_row(&mut w, &positions, sim)
                    .map_err(io)?;
            }
            Ok(())
        })?;
        best[5] = best[5].min(us);
        let us = timed(budget, 100, |n| {
            for _ in 0..n {
                values.clear();
                reader.read(sim, &mut values);
                std::hint::black_box(&values);
            }
            Ok(())
        })?;
        best[6] = best[6].min(us);
    }
    w.flush().map_err(io)?;
    thread.finish().map_err(io)?;
    let writer_cpu = cpu_before.elapsed_elsewhere() * 1e6 / handed_in_all as f64;
    let [step, row, old_row, refresh, values, positions, reader_values] = best;
    Ok(Costs {
        step,
        row,
        old_row,
        refresh,
        values,
        positions,
        reader_values,
        threaded: pairs.map(Pairs::medians),
        read_only: read_only.map(Pairs::medians),
        writer_cpu,
    })
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
