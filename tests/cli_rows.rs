//! Writing CSV rows allocates nothing once the row buffer has grown: a counting global
//! allocator watches `RowWriter::write_row` on tower20 (574 columns).

mod alloc_support;
use alloc_support::{allocations, watch_this_thread};

use tensegrity_fmu::outputs::{self, RowWriter};
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

#[test]
fn rows_allocate_nothing_after_the_first() {
    watch_this_thread();
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
