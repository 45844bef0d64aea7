//! A global allocator that counts the allocations of the threads that ask to be watched
//! (the test harness's own threads allocate at will and are not counted).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
/// Count every thread's allocations (a library thread, which no test can ask to watch).
static ALL: AtomicBool = AtomicBool::new(false);

thread_local! {
    static WATCHED: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if ALL.load(Ordering::SeqCst) || WATCHED.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        }
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Starts counting this thread's allocations.
pub fn watch_this_thread() {
    WATCHED.with(|w| w.set(true));
}

/// Counts every thread's allocations while `on` (the test binary's other threads must be
/// idle meanwhile).
#[allow(dead_code)]
pub fn watch_all_threads(on: bool) {
    ALL.store(on, Ordering::SeqCst);
}

/// Allocations counted so far.
pub fn allocations() -> usize {
    ALLOCATIONS.load(Ordering::SeqCst)
}
