//! Writing CSV rows allocates nothing once the row buffer has grown: a counting global
//! allocator watches `RowWriter::write_row` on tower20 (574 columns).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use tensegrity_fmu::outputs::{self, RowWriter};
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn rows_allocate_nothing_after_the_first() {
    let mut sim = Simulation::new(Model::new(&builtin("tower20").unwrap()).unwrap());
    sim.inputs.node_force[0].x = 1.0;
    let table = outputs::outputs(&sim);
    // A writer that drops the bytes: the allocations counted are the row's own.
    let mut sink = std::io::sink();
    let mut rows = RowWriter::new(&table);
    rows.write_row(&mut sink, &table, &sim).unwrap();
    let mut text = Vec::new();
    let mut during = 0;
    for k in 1..=20 {
        sim.advance_to(k as f64 * 1e-3).unwrap();
        sim.refresh();
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        rows.write_row(&mut sink, &table, &sim).unwrap();
        during += ALLOCATIONS.load(Ordering::SeqCst) - before;
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
