//! Panics never cross the C ABI and never reach the host's stderr: the default panic hook
//! prints, so a hook installed once stays silent for panics inside an FMI call (their
//! message and place go to the importer's logger instead) and defers to the host's own
//! hook for every other panic in the process.

use std::cell::{Cell, RefCell};
use std::panic::{self, UnwindSafe};
use std::sync::Once;

thread_local! {
    static IN_CALL: Cell<bool> = const { Cell::new(false) };
    static LAST_PANIC: RefCell<String> = const { RefCell::new(String::new()) };
}

fn install() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let host = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if IN_CALL.with(Cell::get) {
                let what = info
                    .payload()
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| info.payload().downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "panic".to_string());
                let place = info
                    .location()
                    .map(|l| format!(" at {}:{}", l.file(), l.line()))
                    .unwrap_or_default();
                LAST_PANIC.with(|m| *m.borrow_mut() = format!("{what}{place}"));
            } else if !tensegrity_fmu::dynamics::parallel::on_helper_thread() {
                // A large structure's second thread is silent too: its panic is resumed in
                // the FMI call that handed it the work, and reported there.
                host(info);
            }
        }));
    });
}

/// Runs `body`, turning a panic into `Err(its message and place)`, silently.
pub fn quietly<R>(body: impl FnOnce() -> R + UnwindSafe) -> Result<R, String> {
    install();
    let outer = IN_CALL.with(|c| c.replace(true));
    let result = panic::catch_unwind(body);
    IN_CALL.with(|c| c.set(outer));
    result.map_err(|payload| {
        let here = LAST_PANIC.with(|m| std::mem::take(&mut *m.borrow_mut()));
        if !here.is_empty() {
            return here;
        }
        // Resumed from the second thread: the message is in the payload.
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".to_string());
        format!("{what} (on the evaluation's second thread)")
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    static HOST_HOOK_CALLS: AtomicUsize = AtomicUsize::new(0);

    #[test]
    fn panics_inside_a_call_are_caught_silently_and_others_reach_the_host_hook() {
        // The host's hook (the one that would print to stderr) counts its calls.
        panic::set_hook(Box::new(|_| {
            HOST_HOOK_CALLS.fetch_add(1, Ordering::SeqCst);
        }));
        let caught = quietly(|| -> u32 { panic!("boom {}", 7) });
        let message = caught.expect_err("the panic is caught");
        assert!(message.starts_with("boom 7 at "), "{message}");
        assert!(message.contains("guard.rs:"), "{message}");
        assert_eq!(HOST_HOOK_CALLS.load(Ordering::SeqCst), 0, "nothing printed");
        assert_eq!(quietly(|| 5), Ok(5));
        // On a large structure's second thread, inside a call: caught, silent, reported.
        let helper = tensegrity_fmu::dynamics::parallel::Helper::default();
        let caught = quietly(std::panic::AssertUnwindSafe(|| {
            helper.join(|| 1, || -> u32 { panic!("on the helper") })
        }));
        assert_eq!(
            caught.expect_err("the helper's panic is caught"),
            "on the helper (on the evaluation's second thread)"
        );
        assert_eq!(HOST_HOOK_CALLS.load(Ordering::SeqCst), 0, "nothing printed");
        // Outside an FMI call the host's own hook still sees the panic.
        let outside = std::thread::spawn(|| panic!("host panic")).join();
        assert!(outside.is_err());
        assert_eq!(HOST_HOOK_CALLS.load(Ordering::SeqCst), 1);
        let _ = panic::take_hook();
    }
}
