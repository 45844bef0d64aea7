//! CSV rows formatted and written on a thread of their own, so that the stepping thread
//! only copies a row's values (formatting tower20's 574 doubles costs more than half of a
//! step).
//!
//! The values travel in chunks of whole rows from a fixed pool: the stepping thread fills
//! a free chunk and sends it, the writer formats it, sends it back and writes the text.
//! The pool bounds the memory, a slow disk holds the stepping thread back once every
//! chunk is waiting to be written, and a chunk of several rows wakes the writer once for
//! all of them. The text is made by the same function as [`RowWriter`]'s, so the bytes are
//! the same.
//!
//! [`RowWriter`]: super::RowWriter

use std::any::Any;
use std::io::{self, Write};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::thread::{self, JoinHandle};

use super::{push_row, Output, RowReader, MAX_CELL};
use crate::sim::Simulation;

/// Values per chunk (at least one row): tower20's 575-value rows go 56 to a chunk. Large,
/// because waking the writer costs the stepping thread several µs (an interrupt to the
/// other core: about 10 µs on a 2-vCPU virtual machine), paid once per chunk.
const CHUNK_VALUES: usize = 1 << 15;
/// Values of all chunks together (1 MB), when that still leaves two chunks (one being
/// filled, one being written).
const POOL_VALUES: usize = 4 * CHUNK_VALUES;

/// Rows handed to a writer thread that formats them as [`RowWriter`](super::RowWriter)
/// does and writes them to `W`. Handing a row over allocates nothing (but the first wait
/// for a free chunk, where std's channel sets up its waiter, once). [`Self::finish`]
/// returns the writer; dropping it without finishing stops the thread and discards the
/// rows not yet written.
pub struct RowThread<W: Write + Send + 'static> {
    reader: RowReader,
    row_len: usize,
    chunk_len: usize,
    /// The chunk being filled, taken from `free`.
    chunk: Option<Vec<f64>>,
    /// To the writer; `None` once closed.
    filled: Option<SyncSender<Vec<f64>>>,
    /// From the writer, written and ready to be filled again.
    free: Receiver<Vec<f64>>,
    /// `None` once joined.
    writer: Option<JoinHandle<io::Result<W>>>,
}

impl<W: Write + Send + 'static> RowThread<W> {
    /// Starts a writer thread for rows of `table` (the time, then each output) to `w`.
    pub fn spawn(w: W, table: &[Output]) -> io::Result<Self> {
        let row_len = table.len() + 1;
        let rows_per_chunk = (CHUNK_VALUES / row_len).max(1);
        let chunk_len = rows_per_chunk * row_len;
        let chunks = (POOL_VALUES / chunk_len).max(2);
        let (filled, to_format) = sync_channel(chunks);
        let (written, free) = sync_channel(chunks);
        for _ in 0..chunks {
            written
                .send(Vec::with_capacity(chunk_len))
                .expect("the pool fits its channel");
        }
        let writer = thread::Builder::new()
            .name("csv-writer".into())
            .spawn(move || write_chunks(w, &to_format, &written, row_len, chunk_len))?;
        Ok(Self {
            reader: RowReader::new(table),
            row_len,
            chunk_len,
            chunk: None,
            filled: Some(filled),
            free,
            writer: Some(writer),
        })
    }

    /// Hands over one row for the current state of `sim` (whose outputs are fresh). An
    /// error is the writer's: its write failed, or it panicked.
    pub fn send_row(&mut self, sim: &Simulation) -> io::Result<()> {
        let mut chunk = self.take_chunk()?;
        self.reader.read(sim, &mut chunk);
        self.put_back(chunk)
    }

    /// Hands over one row of `values` (the time first) as [`Self::send_row`] does.
    pub fn send_values(&mut self, values: &[f64]) -> io::Result<()> {
        assert_eq!(values.len(), self.row_len, "a row of another length");
        let mut chunk = self.take_chunk()?;
        chunk.extend_from_slice(values);
        self.put_back(chunk)
    }

    /// Sends the rows not sent yet, waits until all are written and flushed, and returns
    /// the writer.
    pub fn finish(mut self) -> io::Result<W> {
        if let Some(chunk) = self.chunk.take().filter(|c| !c.is_empty()) {
            self.send_chunk(chunk)?;
        }
        // Closing the channel ends the writer's loop once it has written everything sent.
        self.filled = None;
        self.join()
    }

    /// The chunk being filled, or a free one.
    fn take_chunk(&mut self) -> io::Result<Vec<f64>> {
        if self.filled.is_none() {
            // Free chunks may be left, but the writer has stopped.
            return Err(already_stopped());
        }
        match self.chunk.take() {
            Some(chunk) => Ok(chunk),
            // Blocks while the writer holds every chunk: back-pressure from a slow disk.
            None => self.free.recv().map_err(|_| self.stopped()),
        }
    }

    /// Keeps the chunk to fill further, or sends it once full.
    fn put_back(&mut self, chunk: Vec<f64>) -> io::Result<()> {
        if chunk.len() < self.chunk_len {
            self.chunk = Some(chunk);
            return Ok(());
        }
        self.send_chunk(chunk)
    }

    fn send_chunk(&mut self, chunk: Vec<f64>) -> io::Result<()> {
        let Some(filled) = &self.filled else {
            return Err(already_stopped());
        };
        // Never blocks: the channel holds the whole pool.
        filled.send(chunk).map_err(|_| self.stopped())
    }

    /// The writer's error once its end of a channel is gone (it returns only on an error
    /// before the channel is closed).
    fn stopped(&mut self) -> io::Error {
        self.filled = None;
        match self.join() {
            Err(e) => e,
            Ok(_) => io::Error::other("the CSV writer thread stopped before the last row"),
        }
    }

    /// Waits for the writer thread and returns what it returned; a panic is an error.
    fn join(&mut self) -> io::Result<W> {
        let Some(writer) = self.writer.take() else {
            return Err(already_stopped());
        };
        writer.join().unwrap_or_else(|panic| Err(panicked(&*panic)))
    }
}

impl<W: Write + Send + 'static> std::fmt::Debug for RowThread<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RowThread")
            .field("row_len", &self.row_len)
            .field("chunk_len", &self.chunk_len)
            .field("running", &self.writer.is_some())
            .finish_non_exhaustive()
    }
}

impl<W: Write + Send + 'static> Drop for RowThread<W> {
    /// Stops the writer without leaving its thread behind (after a simulation error, say).
    fn drop(&mut self) {
        self.filled = None;
        if let Some(writer) = self.writer.take() {
            let _ = writer.join();
        }
    }
}

/// The writer thread: formats each chunk, returns it to the pool and writes its text,
/// until the stepping thread closes the channel; then flushes and returns `w`.
fn write_chunks<W: Write>(
    mut w: W,
    to_format: &Receiver<Vec<f64>>,
    written: &SyncSender<Vec<f64>>,
    row_len: usize,
    chunk_len: usize,
) -> io::Result<W> {
    let mut text = Vec::with_capacity(MAX_CELL * chunk_len);
    for mut chunk in to_format {
        text.clear();
        for row in chunk.chunks_exact(row_len) {
            push_row(&mut text, row.iter().copied());
        }
        chunk.clear();
        // Returned before the write, so that the stepping thread can fill it meanwhile. It
        // cannot fail while the stepping thread holds `free`, which it does until it joins.
        let _ = written.send(chunk);
        w.write_all(&text)?;
    }
    w.flush()?;
    Ok(w)
}

/// What a row handed over after the writer has stopped gets (the first error said why).
fn already_stopped() -> io::Error {
    io::Error::other("the CSV writer thread has already stopped")
}

/// A writer-thread panic as an error (its message was printed by the panic hook).
fn panicked(panic: &(dyn Any + Send)) -> io::Error {
    let message = panic
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| panic.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("no message");
    io::Error::other(format!("the CSV writer thread panicked: {message}"))
}
