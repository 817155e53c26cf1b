//! SIGINT and SIGTERM as a request to stop: a long command finishes what it
//! is doing, writes its reports and cleans up. A second signal ends the
//! process at once (exit 130) for a user who really means it.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// A flag that turns true on the first SIGINT or SIGTERM.
pub fn stop_requested() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    #[cfg(unix)]
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // The order matters: the shutdown checks the flag before the
        // second registration sets it, so only a repeated signal exits.
        let _ = signal_hook::flag::register_conditional_shutdown(sig, 130, Arc::clone(&flag));
        let _ = signal_hook::flag::register(sig, Arc::clone(&flag));
    }
    flag
}
