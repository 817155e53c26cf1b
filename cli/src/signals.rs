//! SIGINT and SIGTERM as a request to stop.
//!
//! [`install`] serves the commands that write reports (`ppmc run`): the
//! first signal asks every wait to end within a second and the run to wind
//! down (the scenario under way is interrupted, the rest not run, the
//! reports written); a second, as GNU `timeout` and CI runners send one,
//! hurries that along (no health checks, no reconnecting) and still writes
//! the reports; only a third ends the process at once (exit 130). The
//! handlers go in before any target is opened, so a signal during the
//! open still leaves reports.
//!
//! [`stop_requested`] serves commands with nothing to save: a second
//! signal ends them at once.
//!
//! From the process's first instruction until a command's handlers are in
//! place, SIGINT and SIGTERM are held ([`hold`]): one that comes while the
//! arguments are read waits, and reaches the handler the moment it is
//! installed, so a run stopped in its first milliseconds still leaves its
//! reports (it left none in 11 of 40 tries, issue 44). A command that
//! installs no handler lets them go ([`release`]) and ends as any process
//! does.

use ppmc::stop::StopRequest;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Signals this close together are one request (a sender that signals
/// both the process and its group).
const SAME_REQUEST: std::time::Duration = std::time::Duration::from_millis(200);

/// The two signals a command stops on.
#[cfg(unix)]
fn stop_signals() -> nix::sys::signal::SigSet {
    use nix::sys::signal::{SigSet, Signal};
    let mut set = SigSet::empty();
    set.add(Signal::SIGINT);
    set.add(Signal::SIGTERM);
    set
}

/// Holds SIGINT and SIGTERM until [`release`]: call it first, before any
/// thread is started (each thread takes the mask of the one that started
/// it).
pub fn hold() {
    #[cfg(unix)]
    let _ = stop_signals().thread_block();
}

/// Lets held signals go: one that came meanwhile is delivered now, to the
/// handler installed, or with its default action where there is none.
pub fn release() {
    #[cfg(unix)]
    let _ = stop_signals().thread_unblock();
}

/// Installs the handlers of a command that writes reports; the [`StopRequest`]
/// they raise. A thread of its own takes the signals (the handler itself
/// only wakes it), raises the stop for the first two and ends the process
/// at the third.
pub fn install() -> StopRequest {
    let stop = StopRequest::new();
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGINT, SIGTERM};
        if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) {
            let raised = stop.clone();
            let _ = std::thread::Builder::new()
                .name("signals".into())
                .spawn(move || {
                    let mut last: Option<std::time::Instant> = None;
                    for _ in signals.forever() {
                        // GNU timeout sends its signal to ppmc and again to
                        // its process group: one request, delivered twice.
                        let now = std::time::Instant::now();
                        if last.is_some_and(|t| now - t < SAME_REQUEST) {
                            continue;
                        }
                        last = Some(now);
                        if raised.urgent() {
                            // No lease will be dropped: let go of the
                            // places this run acquired first.
                            ppmc::backend::link::lease::release_all();
                            std::process::exit(130);
                        }
                        raised.request();
                    }
                });
        }
    }
    // The handler is in: a signal held since the start arrives now.
    release();
    stop
}

/// A flag that turns true on the first SIGINT or SIGTERM; a second one
/// ends the process at once (exit 130).
pub fn stop_requested() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    #[cfg(unix)]
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // The order matters: the shutdown checks the flag before the
        // second registration sets it, so only a repeated signal exits.
        let _ = signal_hook::flag::register_conditional_shutdown(sig, 130, Arc::clone(&flag));
        let _ = signal_hook::flag::register(sig, Arc::clone(&flag));
    }
    release();
    flag
}
