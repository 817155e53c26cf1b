//! The retry and timeout policy of a bridge link ([`BridgeOptions`]), the
//! round-trip estimate the waits follow, and the sizes and limits the host
//! keeps to.

use crate::stop::StopRequest;
use std::time::Duration as WallDuration;

/// Retry and timeout policy.
///
/// The host learns the link's round-trip time from clean exchanges and
/// waits for a reply a few times that (never less than `min_reply_timeout`,
/// never more than `reply_timeout`), plus the time the batch's own waits
/// take on a real-time bridge. Each attempt in a row that brings nothing
/// new doubles the pause before the next try, and one that heard nothing at
/// all also doubles the wait (exponential backoff, as TCP's retransmission
/// timer does). `retries` silent attempts in a row end the request as a
/// link error; a line that answers, however garbled, is alive and gets ten
/// times as many.
#[derive(Debug, Clone)]
pub struct BridgeOptions {
    /// The longest wait for a reply beyond the time the batch itself needs
    /// (the first waits, before the round-trip time is known, and the cap
    /// of the backoff).
    pub reply_timeout: WallDuration,
    /// The shortest wait for a reply, however fast the link has been.
    pub min_reply_timeout: WallDuration,
    /// Silent attempts in a row before a request is given up (after the
    /// first try); ten times as many that heard only garbage.
    pub retries: u32,
    /// Reopen attempts after the link vanished, with doubling backoff.
    pub reopen_attempts: u32,
    /// The first reopen backoff.
    pub backoff: WallDuration,
    /// After a corrupted frame, how long the line must stay silent before
    /// the host asks again (rather than waiting out the reply timeout); at
    /// most this, and less on a link that answers faster.
    pub quiet: WallDuration,
    /// Ask the bridge to pad every reply with empty frames to a multiple of
    /// this many bytes (LINK), so that a serial server in between that
    /// holds a partly filled buffer (ser2net's 64 bytes) sends it at once;
    /// 0 for none.
    pub pad: u16,
    /// Asked for, every wait on the link ends within [`StopRequest::SLICE`] with
    /// [`BridgeError::Interrupted`](super::BridgeError::Interrupted).
    pub stop: StopRequest,
}

impl BridgeOptions {
    /// How long a request may go without progress (no new reply or
    /// fragment), however much noise arrives, before it is given up:
    /// `reply_timeout` for every attempt it may make in silence.
    pub fn stall_limit(&self) -> WallDuration {
        self.reply_timeout * (self.retries + 1)
    }

    /// The longest a request may take beyond its own waits, progress or
    /// not: three stall limits.
    pub fn request_limit(&self) -> WallDuration {
        self.stall_limit() * 3
    }
}

impl Default for BridgeOptions {
    fn default() -> Self {
        BridgeOptions {
            reply_timeout: WallDuration::from_millis(1000),
            min_reply_timeout: WallDuration::from_millis(20),
            retries: 10,
            reopen_attempts: 6,
            backoff: WallDuration::from_millis(100),
            quiet: WallDuration::from_millis(30),
            pad: 0,
            stop: StopRequest::default(),
        }
    }
}

/// Requests a link may give up on in one run: past that it is not used
/// for more, so that a link that only works now and then ends a run in
/// bounded time instead of costing every scenario its stall limit.
pub const MAX_GIVE_UPS: u32 = 3;

/// The pause before the first retry after a fruitless attempt; it doubles
/// with each one in a row, up to [`MAX_RETRY_PAUSE`].
pub(super) const FIRST_RETRY_PAUSE: WallDuration = WallDuration::from_millis(1);
pub(super) const MAX_RETRY_PAUSE: WallDuration = WallDuration::from_millis(16);

/// The link's round-trip time, smoothed as TCP does (RFC 6298): from
/// exchanges answered at the first try whose batch had no waits of its own.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct RoundTrip {
    srtt: Option<WallDuration>,
    rttvar: WallDuration,
}

impl RoundTrip {
    pub(super) fn sample(&mut self, rtt: WallDuration) {
        match self.srtt {
            None => {
                self.srtt = Some(rtt);
                self.rttvar = rtt / 2;
            }
            Some(s) => {
                let err = s.abs_diff(rtt);
                self.rttvar = (self.rttvar * 3 + err) / 4;
                self.srtt = Some((s * 7 + rtt) / 8);
            }
        }
    }

    /// How long to wait for a reply: `srtt + 4 rttvar`, within the bounds.
    pub(super) fn timeout(&self, opts: &BridgeOptions) -> WallDuration {
        match self.srtt {
            None => opts.reply_timeout,
            Some(s) => (s + self.rttvar * 4)
                .max(opts.min_reply_timeout)
                .min(opts.reply_timeout),
        }
    }
}

/// Request payload sizes the host adapts between: large on a clean line
/// (fewer round trips), small on a noisy one (small frames survive it). A
/// batch split over several requests runs the same.
pub(super) const MAX_REQUEST: usize = 2048;
pub(super) const MIN_REQUEST: usize = 16;

/// A line that answers, however garbled, is alive: a request gets this
/// many times `retries` attempts that bring nothing new before it is given
/// up, where a silent one gets `retries`.
pub(super) const NOISY_RETRIES: u32 = 10;

/// Most fragments one RESEND asks for.
pub(super) const MAX_RESEND: usize = 8;

/// After this many requests in a row that needed no second try, the host
/// asks for reply fragments twice as large again (up to the largest).
pub(super) const CLEAN_TO_GROW: u32 = 8;

/// The most bytes the reply entries to one request may take, at worst:
/// with the capture chunk the bridge adds (which it shrinks to fit), a
/// reply stays within [`wire::MAX_REPLY`].
pub(super) const REPLY_ENTRIES_BUDGET: usize = 10 * 1024;

/// The most capture records (pulse runs and pin changes) the host takes
/// from one bridge between chip resets, whatever its HELLO says: a
/// 16,777,216-step move is a few hundred.
pub(super) const MAX_CAPTURE_RECORDS: usize = 4_000_000;

/// Records asked for per capture request.
pub(super) const CAPTURE_CHUNK: u16 = 300;
