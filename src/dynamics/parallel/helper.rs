//! The second thread of a two-thread evaluation.
//!
//! One thread per workspace, started when it first evaluates and joined when it is dropped,
//! so an FMU leaves no thread behind when its instance is freed (a global pool's threads
//! would outlive the library). Handing it work allocates nothing: the job is a function
//! pointer and a pointer to a closure on the caller's stack, and the caller waits for it
//! before that frame returns (as `std::thread::scope` does).

use std::any::Any;
use std::cell::UnsafeCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::thread::{JoinHandle, Thread};
use std::time::{Duration, Instant};

/// No job (the helper waits for one).
const IDLE: u32 = 0;
/// A caller holds the helper and is writing its job.
const CLAIMED: u32 = 4;
/// A job is posted (the helper runs it, the poster waits).
const POSTED: u32 = 1;
/// The job is done (the poster takes its result and sets `IDLE`).
const DONE: u32 = 2;
/// The helper returns.
const EXIT: u32 = 3;

// Waking a sleeping thread costs a system call on both sides and, on a shared virtual
// machine, tens of microseconds or more before it runs; with waits that slept after 50 µs,
// a 60,000-bar step took 1.12–1.3× as long as with these (paired medians; see
// docs/benchmarks.md). The price: a waiting thread keeps its core busy, yielding it to
// any other thread runnable there, for up to the patience below after its last job.

/// How long the helper waits for its next job before it sleeps: the stages of one
/// evaluation follow each other within microseconds, and the work between evaluations that
/// runs on one thread (the correction, at 60,000 bars) within a couple of milliseconds.
const JOB_PATIENCE: Duration = Duration::from_millis(2);
/// How long a caller waits for the helper's half of a join before it sleeps: a half takes
/// a few milliseconds at most at the sizes measured.
const RESULT_PATIENCE: Duration = Duration::from_millis(10);
/// Checks of the state before a waiting thread starts yielding its core between checks.
const SPINS: u32 = 1_000;

/// A job: a function that runs the closure behind the pointer.
#[derive(Clone, Copy)]
struct Job {
    run: unsafe fn(*mut ()),
    data: *mut (),
}

struct Shared {
    state: AtomicU32,
    job: UnsafeCell<Option<Job>>,
    /// The thread waiting for the job (woken when it is done).
    waiter: UnsafeCell<Option<Thread>>,
    panic: Mutex<Option<Box<dyn Any + Send>>>,
}

// SAFETY: `job` and `waiter` are written by the posting thread before it publishes
// `POSTED` (release) and read by the helper after it sees it (acquire); the posting thread
// reads nothing back until it sees `DONE`.
unsafe impl Sync for Shared {}
unsafe impl Send for Shared {}

/// The helper thread, started on first use.
#[derive(Default)]
pub struct Helper {
    started: OnceLock<Option<Started>>,
}

struct Started {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for Helper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Helper")
    }
}

/// A clone starts its own thread when it first joins (FMU snapshots clone workspaces, and
/// most are never stepped).
impl Clone for Helper {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl Helper {
    /// Runs `a` here and `b` on the helper thread, and returns both results when both are
    /// done; a panic in either is resumed here. Without a thread (the system refused one),
    /// or while the helper is busy (a join from another thread, or from inside a join), both
    /// run here, one after the other.
    pub fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA,
        B: FnOnce() -> RB + Send,
        RB: Send,
    {
        let Some(started) = self.started.get_or_init(Started::spawn) else {
            return (a(), b());
        };
        let shared = &started.shared;
        if shared
            .state
            .compare_exchange(IDLE, CLAIMED, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            return (a(), b());
        }
        let mut slot: (Option<B>, Option<RB>) = (Some(b), None);
        unsafe fn run<B: FnOnce() -> RB, RB>(data: *mut ()) {
            let slot = &mut *(data as *mut (Option<B>, Option<RB>));
            let b = slot.0.take().expect("a job runs once");
            slot.1 = Some(b());
        }
        // SAFETY: this thread claimed the helper; the helper only reads these after
        // `POSTED`, and this frame (which owns `slot`) waits for `DONE` before it returns,
        // even if `a` panics.
        unsafe {
            *shared.job.get() = Some(Job {
                run: run::<B, RB>,
                data: &mut slot as *mut _ as *mut (),
            });
            *shared.waiter.get() = Some(std::thread::current());
        }
        shared.state.store(POSTED, Ordering::Release);
        if let Some(thread) = &started.thread {
            thread.thread().unpark();
        }
        let ra = catch_unwind(AssertUnwindSafe(a));
        wait_until(&shared.state, |s| s != POSTED, RESULT_PATIENCE);
        let helper_panic = shared.panic.lock().map(|mut p| p.take()).unwrap_or(None);
        shared.state.store(IDLE, Ordering::Release);
        match (ra, helper_panic) {
            (Err(payload), _) | (Ok(_), Some(payload)) => resume_unwind(payload),
            (Ok(ra), None) => (ra, slot.1.expect("the job ran")),
        }
    }
}

impl Started {
    fn spawn() -> Option<Self> {
        let shared = Arc::new(Shared {
            state: AtomicU32::new(IDLE),
            job: UnsafeCell::new(None),
            waiter: UnsafeCell::new(None),
            panic: Mutex::new(None),
        });
        let theirs = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("tensegrity-helper".into())
            .spawn(move || serve(&theirs))
            .ok()?;
        Some(Self {
            shared,
            thread: Some(thread),
        })
    }
}

thread_local! {
    static ON_HELPER: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether this thread is a workspace's second thread (whose panics are resumed on the
/// thread that handed it the work: an FMU's panic hook keeps them off the host's stderr).
pub fn on_helper_thread() -> bool {
    ON_HELPER.with(std::cell::Cell::get)
}

/// The helper's loop: each posted job runs once, then `DONE` and its waiter woken.
fn serve(shared: &Shared) {
    ON_HELPER.with(|h| h.set(true));
    loop {
        wait_until(&shared.state, |s| s == POSTED || s == EXIT, JOB_PATIENCE);
        match shared.state.load(Ordering::Acquire) {
            EXIT => return,
            POSTED => {
                // SAFETY: posted before `POSTED` was published; the poster waits.
                let (job, waiter) =
                    unsafe { ((*shared.job.get()).take(), (*shared.waiter.get()).take()) };
                if let Some(job) = job {
                    // SAFETY: `data` points at the poster's slot for `run`'s closure type.
                    let result = catch_unwind(|| unsafe { (job.run)(job.data) });
                    if let Err(payload) = result {
                        if let Ok(mut p) = shared.panic.lock() {
                            *p = Some(payload);
                        }
                    }
                }
                shared.state.store(DONE, Ordering::Release);
                if let Some(waiter) = waiter {
                    waiter.unpark();
                }
            }
            _ => unreachable!("waited for a job or the exit"),
        }
    }
}

/// Returns once `state` satisfies `ready`: spins and yields as [`spin_then_yield`] does
/// for [`SPINS`] checks and `patience`, then sleeps until woken (every change this waits
/// for is followed by an unpark, whose token a later park consumes, so no wake-up is lost;
/// parking may also wake spuriously, so it checks again).
fn wait_until(state: &AtomicU32, ready: impl Fn(u32) -> bool, patience: Duration) {
    let ready = || ready(state.load(Ordering::Acquire));
    if spin_then_yield(ready, SPINS, patience) {
        return;
    }
    while !ready() {
        std::thread::park();
    }
}

/// Waits for `ready()` without sleeping: spins for `spins` checks, then yields its core
/// between checks (to another thread runnable on it, if any) until `patience` has passed.
/// Whether `ready()` held.
pub(super) fn spin_then_yield(ready: impl Fn() -> bool, spins: u32, patience: Duration) -> bool {
    for _ in 0..spins {
        if ready() {
            return true;
        }
        std::hint::spin_loop();
    }
    let yielding_since = Instant::now();
    while !ready() {
        if yielding_since.elapsed() >= patience {
            return false;
        }
        std::thread::yield_now();
    }
    true
}

impl Drop for Started {
    fn drop(&mut self) {
        self.shared.state.store(EXIT, Ordering::Release);
        if let Some(thread) = self.thread.take() {
            thread.thread().unpark();
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both closures run, on two threads, and return their results.
    #[test]
    fn runs_both_sides_on_two_threads() {
        let helper = Helper::default();
        let here = std::thread::current().id();
        for k in 0..100 {
            let (a, (b, id)) = helper.join(|| k * 2, move || (k + 1, std::thread::current().id()));
            assert_eq!((a, b), (2 * k, k + 1));
            assert_ne!(id, here, "the second closure ran on the helper");
        }
    }

    /// A panic on the helper reaches the caller, and the helper serves the next job.
    #[test]
    fn a_panic_on_the_helper_reaches_the_caller() {
        let helper = Helper::default();
        let caught = catch_unwind(AssertUnwindSafe(|| {
            helper.join(|| 1, || -> i32 { panic!("on the helper") })
        }));
        let message = caught.expect_err("resumed here");
        assert_eq!(message.downcast_ref::<&str>(), Some(&"on the helper"));
        assert_eq!(helper.join(|| 3, || 4), (3, 4));
    }

    /// Dropping the helper joins its thread: the thread's share of the state is gone
    /// when the drop returns.
    #[test]
    fn dropping_joins_the_thread() {
        let helper = Helper::default();
        assert_eq!(helper.join(|| 1, || 2), (1, 2));
        let started = helper.started.get().and_then(Option::as_ref);
        let state = Arc::downgrade(&started.expect("started").shared);
        drop(helper);
        assert!(
            state.upgrade().is_none(),
            "the thread still holds its state"
        );
    }

    /// A panic in the caller's half waits for the helper's half (whose closure borrows the
    /// caller's frame) before it is resumed.
    #[test]
    fn a_panic_here_waits_for_the_helper() {
        use std::sync::atomic::AtomicBool;
        let helper = Helper::default();
        let done = AtomicBool::new(false);
        let caught = catch_unwind(AssertUnwindSafe(|| {
            helper.join(
                || -> u32 { panic!("here") },
                || {
                    std::thread::sleep(Duration::from_millis(50));
                    done.store(true, Ordering::SeqCst);
                },
            )
        }));
        assert!(caught.is_err());
        assert!(
            done.load(Ordering::SeqCst),
            "resumed before the helper finished"
        );
    }

    /// Joins from two threads at once, or from inside a join, run safely (the second one on
    /// its caller's thread) and give every result.
    #[test]
    fn concurrent_and_nested_joins_are_safe() {
        let helper = Helper::default();
        std::thread::scope(|scope| {
            for t in 0..2u64 {
                let helper = &helper;
                scope.spawn(move || {
                    for k in 0..2000u64 {
                        assert_eq!(helper.join(|| k + t, || k * 2 + t), (k + t, k * 2 + t));
                    }
                });
            }
        });
        let nested = helper.join(|| helper.join(|| 1, || 2), || 3);
        assert_eq!(nested, ((1, 2), 3));
    }
}
