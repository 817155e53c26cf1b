//! A board behind the bus bridge: the [`Target`] backend that speaks the
//! bridge protocol (`docs/bridge-protocol.md`) over any [`Link`] (a serial
//! port, TCP, telnet with RFC 2217, a labgrid place's port).
//!
//! Every request carries a sequence number and the bridge answers a
//! retransmitted request from its cache without running it again, so a
//! lost or corrupted reply is simply asked for again. A link that vanishes
//! (a USB re-enumeration, a dropped TCP connection) is reopened with
//! backoff a bounded number of times, and the host says HELLO with its own
//! host session again: the bridge keeps its cache across that, so the
//! request in flight, sent again, still runs at most once. If the bridge
//! comes back as a different session (it restarted) or without this host's
//! cache (another host used it), the run cannot go on safely and the error
//! says so.
//!
//! Every wait has an end (`docs/bridge-protocol.md` section 8): a request
//! gives up after `retries` silent attempts, after a stretch without
//! progress however much noise arrives, and at an absolute deadline; a
//! reconnection is a loop of at most `reopen_attempts`; after
//! [`MAX_GIVE_UPS`] requests given up the link is not trusted for the rest
//! of the run. A [`StopRequest`] ends any wait within [`StopRequest::SLICE`].

mod abort;
mod batch;
mod error;
mod exchange;
mod options;
mod target;
#[cfg(test)]
mod tests;

pub use self::error::{restart_cause, AbortOutcome, BridgeError};
pub use self::options::{BridgeOptions, MAX_GIVE_UPS};
pub use self::target::{BridgeTarget, LinkStats};
