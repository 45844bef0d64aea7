//! SIGINT, SIGTERM and SIGHUP, and panics. A signal removes the hidden temporary files
//! being written (see `tensegrity_fmu::partial`) and ends the process with 128 + the
//! signal's number; committed files stay. Inside a loop that polls [`stop_requested`]
//! (`simulate`'s), the first SIGINT only asks it to stop: the loop ends at its current row
//! and the file written so far is completed. A second one, or SIGTERM or SIGHUP, ends the
//! process as above. A panic is a bug: one line says so, then the temporaries go.

use std::sync::atomic::{AtomicBool, Ordering};

use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use signal_hook::iterator::Signals;
use tensegrity_fmu::partial::remove_temps_and_exit;

/// Whether a loop polls [`stop_requested`] now.
static STOPPABLE: AtomicBool = AtomicBool::new(false);
/// Whether the first SIGINT asked that loop to stop.
static STOP: AtomicBool = AtomicBool::new(false);

/// Handles the signals on a thread of their own (so the handler may take locks and remove
/// files) and reports panics as bugs.
pub fn install() -> Result<(), String> {
    report_panics_as_bugs();
    let mut signals = Signals::new([SIGINT, SIGTERM, SIGHUP])
        .map_err(|e| format!("cannot handle signals: {e}"))?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                if signal == SIGINT
                    && STOPPABLE.load(Ordering::SeqCst)
                    && !STOP.swap(true, Ordering::SeqCst)
                {
                    eprintln!(
                        "interrupted: ending at the current row (Ctrl-C again to abandon the run)"
                    );
                    continue;
                }
                remove_temps_and_exit(128 + signal, true);
            }
        })
        .map_err(|e| format!("cannot handle signals: {e}"))?;
    Ok(())
}

/// Marks the start (true) and the end (false) of a loop that polls [`stop_requested`].
pub fn stoppable(on: bool) {
    STOPPABLE.store(on, Ordering::SeqCst);
}

/// Whether a SIGINT asked the polling loop to stop.
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// Forgets a stop asked for too late: the loop had already reached its end.
pub fn forget_stop() {
    STOP.store(false, Ordering::SeqCst);
}

/// The panic message on one line: that it is a bug, where, and where to report it.
fn report_panics_as_bugs() {
    std::panic::set_hook(Box::new(|info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<&str>()
            .copied()
            .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
            .unwrap_or("no message");
        let place = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        let tracker = match env!("CARGO_PKG_REPOSITORY") {
            "" => "the project's issue tracker".to_string(),
            url => format!("{url}/issues"),
        };
        eprintln!(
            "error: internal error, a bug in tensegrity-fmu {} ({}{place}); please report it, \
             with the command and scene that caused it, on {tracker}",
            env!("CARGO_PKG_VERSION"),
            message.split_whitespace().collect::<Vec<_>>().join(" "),
        );
        // Its thread may hold the list of temporaries: do not wait for it.
        remove_temps_and_exit(101, false);
    }));
}
