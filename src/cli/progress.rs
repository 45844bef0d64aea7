//! A progress bar with an ETA on stderr for runs predicted to take longer than
//! [`AFTER`]: drawn only when stderr is a terminal, so it never mixes into redirected
//! output. `TENSEGRITY_FMU_PROGRESS=always` draws it to any stderr and for any run (for
//! tests and logs), `=never` turns it off.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Runs predicted to take longer than this, s, show the bar.
pub const AFTER: f64 = 2.0;

/// Ticks of the bar over the whole run.
const TICKS: u64 = 10_000;

/// The bar of a run to `stop` s predicted to take `seconds` (none when not shown).
pub struct Progress {
    bar: Option<ProgressBar>,
    stop: f64,
}

impl Progress {
    /// A bar for a run of `stop` s of simulated time and a predicted wall time.
    pub fn new(stop: f64, seconds: Option<f64>) -> Self {
        let setting = std::env::var("TENSEGRITY_FMU_PROGRESS").unwrap_or_default();
        let target = match setting.as_str() {
            "always" => ProgressDrawTarget::term_like(Box::new(console::Term::stderr())),
            "never" => ProgressDrawTarget::hidden(),
            _ if seconds.is_some_and(|s| s > AFTER) => ProgressDrawTarget::stderr(),
            _ => ProgressDrawTarget::hidden(),
        };
        if target.is_hidden() || stop <= 0.0 {
            return Self { bar: None, stop };
        }
        let bar = ProgressBar::with_draw_target(Some(TICKS), target);
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:30} {percent:>3}% of {msg} s simulated, {elapsed} elapsed, ETA {eta}",
            )
            .expect("a valid template"),
        );
        bar.set_message(format!("{stop}"));
        bar.enable_steady_tick(Duration::from_millis(200));
        Self {
            bar: Some(bar),
            stop,
        }
    }

    /// The run reached `time`, s.
    pub fn reached(&self, time: f64) {
        if let Some(bar) = &self.bar {
            bar.set_position((time / self.stop * TICKS as f64) as u64);
        }
    }

    /// The run ended (or failed): the bar is cleared from the terminal.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
