//! Why talking to a bridge failed: [`BridgeError`], its kind, and what a
//! restarted bridge says restarted it.

use crate::backend::target::{TargetError, TargetErrorKind};
use crate::time::Instant;
use ppmc_core::bridge::wire::BridgeErrorCode;
use std::io;

/// Why talking to a bridge failed.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// The link did not open; its error names it and says why (a
    /// [`super::super::LinkDriver`]'s `open`).
    #[error(transparent)]
    Open(#[from] io::Error),
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: io::Error,
    },
    #[error("{link}: no bridge answering: no valid reply to {what} after {tries} tries in {secs:.1} s ({heard})")]
    NoAnswer {
        link: String,
        what: String,
        tries: u32,
        /// Wall time spent on the request.
        secs: f64,
        /// What the link brought instead: nothing, noise, replies to other
        /// requests, errors.
        heard: String,
    },
    #[error("{link}: bridge speaks protocol version {theirs}, this ppmc speaks {ours}")]
    Version {
        link: String,
        ours: u16,
        theirs: u16,
    },
    #[error("{link}: the bridge answered {code} to {what}: {detail}")]
    Bridge {
        link: String,
        what: String,
        code: BridgeErrorCode,
        detail: String,
    },
    #[error("{link}: the bridge's capture buffer overran; pulses were lost ({detail})")]
    CaptureOverrun { link: String, detail: String },
    #[error("{link}: unexpected reply to {what}: {detail}")]
    Protocol {
        link: String,
        what: String,
        detail: String,
    },
    #[error("{link}: link lost and not back after {attempts} reopen attempts ({last})")]
    LinkLost {
        link: String,
        attempts: u32,
        last: String,
    },
    #[error("{link}: the bridge restarted (session {old:08x} -> {new:08x}){}; the chip's state is unknown", why.as_ref().map(|w| format!(" after {w}")).unwrap_or_default())]
    Restarted {
        link: String,
        old: u32,
        new: u32,
        /// What the bridge says restarted it, from its new HELLO (the RP2350
        /// image's panic record: `a panic at cycles.rs:123`).
        why: Option<String>,
    },
    /// After a reconnect the bridge no longer held this host's cached
    /// request: another host said HELLO to it while the link was down, and
    /// may have used the chip.
    #[error("{link}: after reconnecting, the bridge no longer holds this host's requests (another host used it while the link was down); the chip's state is unknown")]
    Displaced { link: String },
    /// The link gave up on too many requests in this run to be trusted
    /// with another.
    #[error("{link}: the link gave up on {failures} requests in this run, and is not used for more (the last: {last})")]
    Exhausted {
        link: String,
        failures: u32,
        last: String,
    },
    /// A stop was asked for (SIGINT, SIGTERM) while waiting on the link.
    #[error("{link}: interrupted by a stop request{}", abort.note())]
    Interrupted {
        link: String,
        /// What became of the ABORT sent for the request in flight.
        abort: AbortOutcome,
    },
    #[error("{link}: the scenario's --timeout passed during {what}{}", abort.note())]
    PastDeadline {
        link: String,
        what: String,
        /// What became of the ABORT sent for it.
        abort: AbortOutcome,
    },
    #[error("{link}: the bridge's clock went back from {was} to {now} without a chip reset (its reply to `{op}`): the bridge restarted behind the open port and the chip's state is unknown")]
    ClockWentBack {
        link: String,
        was: Instant,
        now: Instant,
        /// The op whose reply went back.
        op: String,
    },
    #[error("{link}: health check failed: {detail}")]
    Unhealthy { link: String, detail: String },
    /// A request of `len` bytes kept arriving garbled; the bridge has not
    /// run it. Batches are then sent in smaller requests.
    #[error("{link}: a {len}-byte request keeps arriving garbled")]
    Garbled { link: String, len: usize },
}

impl BridgeError {
    /// Whether the bridge fell silent: no answer, a link that would not
    /// come back, a port that failed. That is how a hung board looks from
    /// the host, and what a power cycle may cure. A bridge that answers
    /// wrongly, a link given up too often, another host's use of the
    /// bridge, or a stop is not.
    pub fn is_silence(&self) -> bool {
        matches!(
            self,
            BridgeError::NoAnswer { .. }
                | BridgeError::LinkLost { .. }
                | BridgeError::Io { .. }
                | BridgeError::Open(_)
        )
    }
}

/// What became of the ABORT a host sends for a request it stopped waiting
/// for (`docs/bridge-protocol.md` section 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AbortOutcome {
    /// None was sent: the request had not gone out, or could not be
    /// running (the link was lost), or a second stop request hurried.
    NotSent,
    /// Sent; no ABORT_REPLY within its wait (or a bridge that does not
    /// know ABORT).
    Unanswered,
    /// The bridge stopped the request (its reply: ERROR `ABORTED`).
    Stopped,
    /// The bridge had no such request running: it had ended.
    NothingRunning,
}

impl AbortOutcome {
    /// What an error message says of it.
    pub fn note(self) -> &'static str {
        match self {
            AbortOutcome::NotSent => "",
            AbortOutcome::Unanswered => "; ABORT sent, unanswered",
            AbortOutcome::Stopped => "; the bridge stopped the request in flight (ABORT)",
            AbortOutcome::NothingRunning => "; the bridge had no request running (ABORT)",
        }
    }
}

impl BridgeError {
    pub fn kind(&self) -> TargetErrorKind {
        match self {
            BridgeError::Version { .. } => TargetErrorKind::Unsupported,
            BridgeError::Interrupted { .. } => TargetErrorKind::Interrupted,
            // The user's limit, not a verdict on the board or the link.
            BridgeError::PastDeadline { .. } => TargetErrorKind::Other,
            // An error or a reply of the wrong kind to a well-formed
            // request is the bridge's or the link's doing (a firmware bug,
            // something else answering on the port), never the chip's.
            _ => TargetErrorKind::Link,
        }
    }
}

impl From<BridgeError> for TargetError {
    fn from(e: BridgeError) -> Self {
        TargetError::new(e.kind(), e)
    }
}

/// What a bridge's firmware text says restarted it: the RP2350 image ends
/// it in `; restarted after CAUSE`, the cause a panic at FILE:LINE, a hard
/// fault at a PC (its record, kept across the watchdog's reset) or a hang
/// (the watchdog's timer ran out).
pub fn restart_cause(firmware: &str) -> Option<String> {
    let (_, cause) = firmware.rsplit_once("restarted after ")?;
    Some(cause.trim().to_string())
}
