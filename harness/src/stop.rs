//! A request to stop, shared between whoever asks for it (a signal
//! handler, a test) and whoever may wait long (a link waiting for a reply
//! from a real-time board, a connection attempt, the runner between
//! scenarios).
//!
//! It has levels: the first request asks every wait to end within about
//! [`StopRequest::SLICE`] and the run to wind down (the scenario under way is
//! interrupted, the rest not run, the reports written); a second one says
//! hurry: no health checks, no reconnecting, no more waiting on a link.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A stop request that any number of clones share.
#[derive(Debug, Clone, Default)]
pub struct StopRequest(Arc<AtomicU8>);

impl StopRequest {
    /// The longest any wait that watches a [`StopRequest`] goes without looking.
    pub const SLICE: Duration = Duration::from_millis(100);

    pub fn new() -> StopRequest {
        StopRequest::default()
    }

    /// Asks to stop; a second call asks to hurry.
    pub fn request(&self) {
        let _ = self
            .0
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |l| {
                Some(l.saturating_add(1))
            });
    }

    /// How many times a stop was asked for.
    pub fn level(&self) -> u8 {
        self.0.load(Ordering::SeqCst)
    }

    /// A stop was asked for.
    pub fn requested(&self) -> bool {
        self.level() >= 1
    }

    /// A stop was asked for twice: wind down without waiting on anything.
    pub fn urgent(&self) -> bool {
        self.level() >= 2
    }

    /// Sleeps for `d`, in slices, ending early when a stop is asked for;
    /// true when it did.
    pub fn sleep(&self, d: Duration) -> bool {
        let end = Instant::now() + d;
        loop {
            if self.requested() {
                return true;
            }
            let now = Instant::now();
            if now >= end {
                return false;
            }
            std::thread::sleep((end - now).min(Self::SLICE));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_request_and_a_second_one_hurries() {
        let a = StopRequest::new();
        let b = a.clone();
        assert!(!b.requested());
        a.request();
        assert!(b.requested() && !b.urgent());
        a.request();
        assert!(b.urgent());
    }

    #[test]
    fn a_sleep_ends_at_once_when_a_stop_is_asked_for() {
        let s = StopRequest::new();
        s.request();
        // Nothing to wait for: the answer comes before any sleep.
        assert!(s.sleep(Duration::from_secs(3600)));
        assert!(!StopRequest::new().sleep(Duration::ZERO));
    }
}
