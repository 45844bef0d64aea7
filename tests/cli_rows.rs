//! CSV rows: writing them allocates nothing once the row buffer has grown (a counting
//! global allocator watches `RowWriter::write_row` and `RowThread::send_row` on tower20,
//! 574 columns), `RowReader` reads the bits each output reads, the writer thread writes the
//! very bytes `RowWriter` writes, and its failures (a write error, a panic) come back as
//! errors without hanging.

mod alloc_support;
use alloc_support::{allocations, watch_this_thread};

use std::io::{self, Write};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tensegrity_fmu::outputs::{self, Output, RowReader, RowThread, RowWriter};
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

/// Held by the tests that count allocations: the count is the watched threads' together.
static COUNTING: Mutex<()> = Mutex::new(());

/// Holds [`COUNTING`] (whether or not another counting test failed).
fn counting_alone() -> std::sync::MutexGuard<'static, ()> {
    COUNTING
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// tower20 pushed sideways at node 1, and its outputs.
fn tower20() -> (Simulation, Vec<Output>) {
    let mut sim = Simulation::new(Model::new(&builtin("tower20").unwrap()).unwrap());
    sim.inputs.node_force[0].x = 1.0;
    let table = outputs::outputs(&sim);
    (sim, table)
}

#[test]
fn rows_allocate_nothing_after_the_first() {
    let _counting = counting_alone();
    watch_this_thread();
    let (mut sim, table) = tower20();
    // A writer that drops the bytes: the allocations counted are the row's own.
    let mut sink = std::io::sink();
    let mut rows = RowWriter::new(&table);
    rows.write_row(&mut sink, &table, &sim).unwrap();
    let mut text = Vec::new();
    let mut during = 0;
    for k in 1..=20 {
        sim.advance_to(k as f64 * 1e-3).unwrap();
        sim.refresh();
        let before = allocations();
        rows.write_row(&mut sink, &table, &sim).unwrap();
        during += allocations() - before;
    }
    assert_eq!(during, 0, "{during} allocations in 20 rows");
    // And the rows are what was asked for: 574 values, the time first.
    rows.write_row(&mut text, &table, &sim).unwrap();
    let line = String::from_utf8(text).unwrap();
    let cells: Vec<&str> = line.trim_end().split(',').collect();
    assert_eq!(cells.len(), table.len() + 1);
    assert_eq!(cells.len(), 574);
    assert_eq!(cells[0], "0.02");
}

/// A writer that takes `delay` over every write, as a slow disk does.
struct Slow {
    delay: Duration,
    /// Dropped with the writer: tells when the writer thread has let go of it.
    _alive: Arc<()>,
}

impl Write for Slow {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        std::thread::sleep(self.delay);
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

fn slow(delay_ms: u64) -> (Slow, Arc<()>) {
    let alive = Arc::new(());
    let w = Slow {
        delay: Duration::from_millis(delay_ms),
        _alive: Arc::clone(&alive),
    };
    (w, alive)
}

/// Allocations on this thread while it hands over `rows` rows, after `warm_up` rows.
fn handover_allocations(
    w: impl Write + Send + 'static,
    sim: &Simulation,
    table: &[Output],
    warm_up: usize,
    rows: usize,
) -> usize {
    let mut thread = RowThread::spawn(w, table).unwrap();
    for _ in 0..warm_up {
        thread.send_row(sim).unwrap();
    }
    let before = allocations();
    for _ in 0..rows {
        thread.send_row(sim).unwrap();
    }
    let during = allocations() - before;
    thread.finish().unwrap();
    during
}

#[test]
fn handing_rows_to_the_writer_thread_allocates_nothing() {
    let (mut sim, table) = tower20();
    sim.advance_to(1e-3).unwrap();
    sim.refresh();
    let _counting = counting_alone();
    watch_this_thread();
    // Rows of a state that does not change are handed over faster than even io::sink()'s
    // writer formats them (and far faster than a slow disk's), so the warm-up fills the
    // pool and waits for free chunks: the first wait allocates (std's channel sets up its
    // waiter, once per thread and channel), the ones counted after it do not.
    let during = handover_allocations(io::sink(), &sim, &table, 1000, 1000);
    assert_eq!(during, 0, "{during} allocations in 1000 rows to io::sink()");
    let (w, _) = slow(1);
    let during = handover_allocations(w, &sim, &table, 1000, 500);
    assert_eq!(
        during, 0,
        "{during} allocations in 500 rows to a slow writer"
    );
}

#[test]
fn the_writer_thread_writes_the_bytes_the_row_writer_writes() {
    let (mut sim, table) = tower20();
    let mut rows = RowWriter::new(&table);
    let mut direct = Vec::new();
    let mut thread = RowThread::spawn(Vec::new(), &table).unwrap();
    // 101 rows: several chunks, the last one part-filled.
    for k in 0..=100 {
        sim.advance_to(k as f64 * 1e-3).unwrap();
        sim.refresh();
        rows.write_row(&mut direct, &table, &sim).unwrap();
        thread.send_row(&sim).unwrap();
    }
    same_text(&thread.finish().unwrap(), &direct);
    assert_eq!(direct.iter().filter(|&&b| b == b'\n').count(), 101);

    // Every kind of number in every column: zeros of both signs, non-finite values, the
    // extremes, exponents of both signs.
    let specials = [
        0.0,
        -0.0,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e-7,
        1.5e20,
        -2.2250738585072014e-308,
        5e-324,
        f64::MAX,
        1.0 / 3.0,
        100.0,
        -12.5,
    ];
    let texts = [
        "0",
        "-0",
        "NaN",
        "inf",
        "-inf",
        "1e-7",
        "1.5e+20",
        "-2.2250738585072014e-308",
        "5e-324",
        "1.7976931348623157e+308",
        "0.3333333333333333",
        "100",
        "-12.5",
    ];
    let mut direct = Vec::new();
    let mut thread = RowThread::spawn(Vec::new(), &table).unwrap();
    let mut values = vec![0.0; table.len() + 1];
    for shift in 0..specials.len() {
        for (i, v) in values.iter_mut().enumerate() {
            *v = specials[(i + shift) % specials.len()];
        }
        rows.write_values(&mut direct, values.iter().copied())
            .unwrap();
        thread.send_values(&values).unwrap();
    }
    let threaded = thread.finish().unwrap();
    same_text(&threaded, &direct);
    let first = String::from_utf8(threaded).unwrap();
    let cells: Vec<&str> = first.lines().next().unwrap().split(',').collect();
    assert_eq!(cells[..texts.len()], texts);
}

/// `a == b`, or where they first differ.
fn same_text(a: &[u8], b: &[u8]) {
    if a != b {
        let at = a.iter().zip(b).take_while(|(x, y)| x == y).count();
        let line = a[..at].iter().filter(|&&c| c == b'\n').count() + 1;
        panic!(
            "the texts differ at byte {at} (line {line}); lengths {} and {}",
            a.len(),
            b.len()
        );
    }
}

/// Takes `room` bytes, then fails as a full disk does; or fails only when flushed.
#[derive(Debug)]
struct Full {
    room: usize,
    fail_flush: bool,
}

impl Write for Full {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.room == 0 {
            return Err(io::Error::new(
                io::ErrorKind::StorageFull,
                "the disk is full",
            ));
        }
        let n = buf.len().min(self.room);
        self.room -= n;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        if self.fail_flush {
            return Err(io::Error::new(io::ErrorKind::StorageFull, "flush failed"));
        }
        Ok(())
    }
}

/// Hands over rows until one fails: the error and the rows handed over before it.
fn rows_until_error(w: impl Write + Send + 'static) -> (io::Error, usize) {
    let (mut sim, table) = tower20();
    sim.refresh();
    let mut thread = RowThread::spawn(w, &table).unwrap();
    for k in 0..100_000 {
        if let Err(e) = thread.send_row(&sim) {
            // Once stopped, it stays stopped.
            assert!(thread.send_row(&sim).is_err());
            assert!(thread.finish().is_err());
            return (e, k);
        }
    }
    panic!("100000 rows and no error");
}

#[test]
fn a_write_error_on_the_writer_thread_comes_back() {
    let (e, rows) = rows_until_error(Full {
        room: 100_000,
        fail_flush: false,
    });
    assert_eq!(e.kind(), io::ErrorKind::StorageFull);
    assert_eq!(e.to_string(), "the disk is full");
    // Soon, not at the end: within the pool's worth of rows (4 chunks of 56) and a chunk
    // or two after the ones that fit.
    assert!(rows < 400, "{rows} rows before the error");
    // One that only shows when the last rows are flushed comes back from `finish`.
    let (sim, table) = tower20();
    let w = Full {
        room: usize::MAX,
        fail_flush: true,
    };
    let mut thread = RowThread::spawn(w, &table).unwrap();
    thread.send_row(&sim).unwrap();
    let e = thread.finish().unwrap_err();
    assert_eq!(e.to_string(), "flush failed");
}

/// Panics at its first write, or at its flush.
#[derive(Debug)]
struct Panics {
    at_flush: bool,
}

impl Write for Panics {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if !self.at_flush {
            panic!("a bug in the writer");
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        panic!("a bug at the flush");
    }
}

#[test]
fn a_panic_on_the_writer_thread_is_an_error_not_a_hang() {
    let (e, rows) = rows_until_error(Panics { at_flush: false });
    assert_eq!(
        e.to_string(),
        "the CSV writer thread panicked: a bug in the writer"
    );
    assert!(rows < 400, "{rows} rows before the error");
    let (sim, table) = tower20();
    let mut thread = RowThread::spawn(Panics { at_flush: true }, &table).unwrap();
    thread.send_row(&sim).unwrap();
    let e = thread.finish().unwrap_err();
    assert_eq!(
        e.to_string(),
        "the CSV writer thread panicked: a bug at the flush"
    );
}

#[test]
fn dropping_it_unfinished_stops_the_writer_thread() {
    let (sim, table) = tower20();
    let (w, alive) = slow(1);
    let mut thread = RowThread::spawn(w, &table).unwrap();
    // More than the pool holds (4 chunks of 56 rows): the last rows wait for the slow
    // writer, and some are still queued when it is dropped.
    for _ in 0..1000 {
        thread.send_row(&sim).unwrap();
    }
    let started = Instant::now();
    drop(thread);
    // The writer thread has ended: it dropped its writer.
    assert_eq!(Arc::strong_count(&alive), 1);
    assert!(started.elapsed() < Duration::from_secs(5));
}

#[test]
fn the_row_reader_reads_the_bits_each_output_reads() {
    let dropped = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fmu/scenes/icosahedron-dropped.toml"
    );
    for name in [
        "prism2",
        "prism2-elastic",
        "icosahedron",
        "tower20",
        dropped,
    ] {
        let scene = tensegrity_fmu::Scene::from_name_or_file(name).unwrap();
        let mut sim = Simulation::new(tensegrity_fmu::analysis::load(&scene).unwrap());
        for f in &mut sim.inputs.node_force {
            f.x = 0.5;
        }
        let full = outputs::outputs(&sim);
        // The full table; positions alone; and one with its node triples broken up.
        let positions: Vec<Output> = full
            .iter()
            .filter(|o| o.quantity.group() == outputs::OutputGroup::Positions)
            .cloned()
            .collect();
        let mut shuffled = full.clone();
        shuffled.reverse();
        shuffled.swap(0, 4);
        let mut values = Vec::new();
        for k in 0..=30 {
            sim.advance_to(k as f64 * 1e-3).unwrap();
            sim.refresh();
            for table in [&full, &positions, &shuffled] {
                // Appended after what the buffer holds, as a chunk of rows is filled.
                values.clear();
                values.push(-1.0);
                RowReader::new(table).read(&sim, &mut values);
                let each =
                    std::iter::once(sim.time()).chain(table.iter().map(|o| o.quantity.value(&sim)));
                assert_eq!(values.len(), table.len() + 2);
                assert_eq!(values[0], -1.0, "what the buffer held is kept");
                for ((read, one), column) in values[1..].iter().zip(each).zip(0..) {
                    assert_eq!(read.to_bits(), one.to_bits(), "{name}, column {column}");
                }
            }
        }
    }
}
