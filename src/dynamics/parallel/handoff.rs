//! The word by which the first thread tells the second that the columns it hands off are
//! factored, so the second can run their backward substitution.

use std::sync::atomic::{AtomicU8, Ordering};
use std::time::Duration;

use super::helper::spin_then_yield;

/// The first thread's word that the columns it hands off are factored (and how).
#[derive(Default)]
pub(super) struct Handoff(AtomicU8);

/// Sends its outcome once; a failure if dropped unsent (a panic), so the waiter ends.
pub(super) struct Signal<'a>(Option<&'a Handoff>);

const PENDING: u8 = 0;
const FACTORED: u8 = 1;
const FAILED: u8 = 2;

impl Handoff {
    pub(super) fn signal(&self) -> Signal<'_> {
        Signal(Some(self))
    }

    /// Waits for the outcome; true if the columns were factored. It spins (the other
    /// thread's factor is about a millisecond away at most), yielding its core after a
    /// while in case the other thread needs it; it never sleeps (nothing would wake it).
    pub(super) fn wait(&self) -> bool {
        let outcome = || self.0.load(Ordering::Acquire);
        spin_then_yield(|| outcome() != PENDING, 1 << 16, Duration::MAX);
        outcome() == FACTORED
    }
}

impl Signal<'_> {
    pub(super) fn send(&mut self, factored: bool) {
        if let Some(handoff) = self.0.take() {
            let outcome = if factored { FACTORED } else { FAILED };
            handoff.0.store(outcome, Ordering::Release);
        }
    }
}

impl Drop for Signal<'_> {
    fn drop(&mut self) {
        self.send(false);
    }
}
